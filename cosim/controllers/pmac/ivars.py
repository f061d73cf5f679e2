"""I-variable setup text: the assignments users keep in their PMAC setup files.

Accepted syntax, one or more assignments per line, case-insensitive::

    I10=3713707            ; decimal
    I8010=$978008 I8011=64 ; hex with $, several on a line
    I5193=@I8011           ; @In = address of a conversion-table line (I8000..I8191)

``;`` starts a comment. Every variable must be one the model knows; anything else is an error
naming the file and line (silently ignoring a setting would give a different machine).

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

import re
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from fractions import Fraction

from cosim import validate
from cosim.controllers.pmac.ect import TURBO_ECT_BASE, TURBO_ECT_LINES
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
_ASSIGNMENT = re.compile(r"I(\d+)\s*=\s*(\S+)", re.IGNORECASE)
_KNOWN = ("I10; Ix87..Ix89 and Ix93..Ix95 for coordinate system x = 1..8 (I187..I895, Turbo I5187..I5895); "
          f"Ixx20..Ixx22 for motor xx = 1..{MOTORS}; I{ECT_FIRST}..I{ECT_LAST} (conversion table)")
_MS_ALLOWED = f"integers 0..{REG_MAX} (ms)"


@dataclass(frozen=True)
class Assignment:
    """One ``In=value`` of a setup file.

    Attributes
    ----------
    number : int
        I-variable number n.
    value : int or Fraction
        Parsed value (a Fraction only for Ix89 and Ixx22).
    line : int
        Line number (1-based).
    source : str
        File name (or a label) for messages.
    """

    number: int
    value: int | Fraction
    line: int
    source: str

    @property
    def where(self) -> str:
        """``file line N`` for error messages."""
        return f"{self.source} line {self.line}"


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


def _parse_value(text: str, name: str, where: str) -> int | Fraction:
    if text.startswith("$"):
        try:
            return int(text[1:], 16)
        except ValueError:
            pass
    elif text[:2].upper() == "@I" and text[2:].isdigit():
        target = int(text[2:])
        if ECT_FIRST <= target <= ECT_LAST:
            return TURBO_ECT_BASE + target - ECT_FIRST
        raise ConfigurationError.out_of_range(f"{name} (address of {text[1:]})", text,
                                              f"@I{ECT_FIRST}..@I{ECT_LAST}", where=where)
    else:
        try:
            Decimal(text)
        except InvalidOperation:
            pass
        else:  # a number, finite and of sane size (else refused here), checked against the range by check_ivar
            number = validate.exact(text, name, where=where)
            return number.numerator if number.denominator == 1 else number
    raise ConfigurationError(f"{where}: {name} = {text!r} is not a number (write decimal, $hex or @In)")


def parse_setup(text: str, *, source: str = "setup") -> tuple[Assignment, ...]:
    """Parse setup text into assignments (in file order), checking every name and range.

    Parameters
    ----------
    text : str
        The setup file's content.
    source : str
        File name for messages.

    Raises
    ------
    ConfigurationError
        ``<source> line <n>: ...`` for unknown variables, bad syntax or values out of range.
    """
    assignments: list[Assignment] = []
    for line_no, raw in enumerate(text.splitlines(), 1):
        code = raw.split(";", 1)[0].strip()
        if not code:
            continue
        where = f"{source} line {line_no}"
        rest = _ASSIGNMENT.sub("", code).strip()
        if rest:
            raise ConfigurationError(
                f"{where}: {rest.split()[0]!r} is not an I-variable assignment "
                "(this loader reads assignments like I10=3713707 or I8010=$978008)")
        for match in _ASSIGNMENT.finditer(code):
            number = int(match.group(1))
            name = f"I{number}"
            if not is_known(number):
                check_ivar(number, 0, where=where)  # raises: unknown variable
            value = _parse_value(match.group(2), name, where)
            assignments.append(Assignment(number, check_ivar(number, value, where=where), line_no, source))
    return tuple(assignments)
