"""The I-variables the model knows: their numbers, ranges and meaning.

Setup text (``I10=3713707``, ``I8010=$978008 I8011=64``, ``I5193=@I8011``) is read by
:func:`cosim.controllers.pmac.setupfile.parse_setup` with the one PMAC grammar. Every variable
must be one the model knows; anything else is an error naming the file, line and column
(silently ignoring a setting would give a different machine).

Known variables and their ranges:

==================  =======================================  ==========================
Variable            Meaning                                  Allowed
==================  =======================================  ==========================
I10                 servo interrupt time [2^-23 ms]          1..8,388,607
Ix87, I5x87         CS x default TA [ms] (default 0)         0..8,388,607
Ix88, I5x88         CS x default TS [ms] (default 50)        0..8,388,607
Ix89, I5x89         CS x default F [units/s] (default 1000)  > 0
Ix93 (I193..I893)   CS x time-base source address            an existing time-base register
I5x93 (I5193..)     the same, Turbo numbering                (checked when applied)
Ix94, I5x94         CS x time-base slew limit [2^-23 ms/cyc] 0..8,388,607
Ix95, I5x95         CS x feed-hold slew rate (default 1644)  0..8,388,607
Ixx20 (I120..)      motor xx RAPID/jog TA [ms] (default 0)   0..8,388,607
Ixx21               motor xx RAPID/jog TS [ms] (default 50)  0..8,388,607
Ixx22               motor xx RAPID/jog speed [counts/ms]     > 0 (default 32)
I8000..I8191        conversion-table setup lines (Turbo)     0..$FFFFFF
==================  =======================================  ==========================

Both the PMAC numbering (Ix93 = I(100x+93)) and the Turbo numbering (I5x93) address coordinate
systems 1..8; motor variables Ixx20..Ixx22 address motors 1..32 (I120..I3222).
"""

from __future__ import annotations

from fractions import Fraction

from cosim import validate
from cosim.controllers.pmac.ect import TURBO_ECT_LINES
from cosim.controllers.pmac.units import I10_ALLOWED, IX94_ALLOWED, IX94_MAX, REG_MASK, REG_MAX, WORD_ALLOWED
from cosim.errors import ConfigurationError

ECT_FIRST = 8000
ECT_LAST = ECT_FIRST + TURBO_ECT_LINES - 1
#: Coordinate-system I-variables the model knows (Ix87..Ix89, Ix93..Ix95) and their defaults.
CS_SUFFIXES = (87, 88, 89, 93, 94, 95)
#: Motor I-variables the model knows (Ixx20..Ixx22) and their defaults (Turbo PMAC).
MOTOR_SUFFIXES = (20, 21, 22)
MOTOR_DEFAULTS = {20: 0, 21: 50, 22: 32}
MOTORS = 32
_KNOWN = ("I10; Ix87..Ix89 and Ix93..Ix95 for coordinate system x = 1..8 (I187..I895, Turbo I5187..I5895); "
          f"Ixx20..Ixx22 for motor xx = 1..{MOTORS}; I{ECT_FIRST}..I{ECT_LAST} (conversion table)")
_MS_ALLOWED = f"integers 0..{REG_MAX} (ms)"


def cs_ivar(number: int) -> tuple[int, int] | None:
    """``(x, suffix)`` if I``number`` is a coordinate-system variable the model knows, else None.

    Examples
    --------
    >>> cs_ivar(193), cs_ivar(5294), cs_ivar(130), cs_ivar(5187)
    ((1, 93), (2, 94), None, (1, 87))
    """
    for base in (0, 5000):
        x, suffix = divmod(number - base, 100)
        if 1 <= x <= 8 and suffix in CS_SUFFIXES and number - base >= 100:
            return x, suffix
    return None


def motor_ivar(number: int) -> tuple[int, int] | None:
    """``(motor, suffix)`` if I``number`` is a motor variable Ixx20..Ixx22 (motors 1..32), else None.

    Examples
    --------
    >>> motor_ivar(122), motor_ivar(3220), motor_ivar(123)
    ((1, 22), (32, 20), None)
    """
    motor, suffix = divmod(number, 100)
    if 1 <= motor <= MOTORS and suffix in MOTOR_SUFFIXES:
        return motor, suffix
    return None


def is_known(number: int) -> bool:
    """True if the model knows I``number``."""
    return (number == 10 or cs_ivar(number) is not None or motor_ivar(number) is not None
            or ECT_FIRST <= number <= ECT_LAST)


def check_ivar(number: int, value: object, *, where: str = "") -> int | Fraction:
    """Check ``value`` against the range of I``number``; raises for unknown variables.

    Ix93 is only checked to be a 24-bit address here; whether something is at that address is
    checked by the machine that applies it. Ix89 and Ixx22 are exact numbers (``Fraction``),
    every other known variable an integer.
    """
    name = f"I{number}"
    if number == 10:
        return validate.integer(value, f"{name} (servo interrupt time)", low=1, high=REG_MAX, where=where,
                                allowed=I10_ALLOWED)
    cs = cs_ivar(number)
    if cs is not None:
        suffix = cs[1]
        if suffix in (94, 95):
            what = "Ix94, time-base slew limit" if suffix == 94 else "Ix95, feed-hold slew rate"
            return validate.integer(value, f"{name} ({what})", low=0, high=IX94_MAX, where=where,
                                    allowed=IX94_ALLOWED)
        if suffix in (87, 88):
            what = "Ix87, default TA" if suffix == 87 else "Ix88, default TS"
            return validate.integer(value, f"{name} ({what})", low=0, high=REG_MAX, where=where, allowed=_MS_ALLOWED)
        if suffix == 89:
            return _positive(value, f"{name} (Ix89, default feedrate)", "axis units/s", where)
        return validate.integer(value, f"{name} (Ix93, time-base source address)", low=0, high=REG_MASK,
                                where=where, allowed=WORD_ALLOWED)
    motor = motor_ivar(number)
    if motor is not None:
        if motor[1] == 22:
            return _positive(value, f"{name} (Ixx22, jog speed)", "counts/ms", where)
        what = "Ixx20, jog acceleration time" if motor[1] == 20 else "Ixx21, jog S-curve time"
        return validate.integer(value, f"{name} ({what})", low=0, high=REG_MAX, where=where, allowed=_MS_ALLOWED)
    if ECT_FIRST <= number <= ECT_LAST:
        return validate.integer(value, f"{name} (conversion table line)", low=0, high=REG_MASK, where=where,
                                allowed=WORD_ALLOWED)
    prefix = f"{where}: " if where else ""
    raise ConfigurationError(f"{prefix}{name} is not an I-variable this model knows (known: {_KNOWN})")


def _positive(value: object, name: str, unit: str, where: str) -> Fraction:
    exact = validate.positive(value, name, unit=unit, where=where)
    if exact > REG_MAX:
        raise ConfigurationError.out_of_range(name, value, f"> 0 and <= {REG_MAX} ({unit})", where=where)
    return exact
