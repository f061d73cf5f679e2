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
Ix93 (I193..I893)   CS x time-base source address            an existing time-base register
I5x93 (I5193..)     the same, Turbo numbering                (checked when applied)
Ix94, I5x94         CS x time-base slew limit [2^-23 ms/cyc] 0..8,388,607
I8000..I8191        conversion-table setup lines (Turbo)     0..$FFFFFF
==================  =======================================  ==========================

Both the PMAC numbering (Ix93 = I(100x+93)) and the Turbo numbering (I5x93) address coordinate
systems 1..8.
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
_ASSIGNMENT = re.compile(r"I(\d+)\s*=\s*(\S+)", re.IGNORECASE)
_KNOWN = ("I10; Ix93 and Ix94 for coordinate system x = 1..8 (I193..I894, Turbo I5193..I5894); "
          f"I{ECT_FIRST}..I{ECT_LAST} (conversion table)")


@dataclass(frozen=True)
class Assignment:
    """One ``In=value`` of a setup file.

    Attributes
    ----------
    number : int
        I-variable number n.
    value : int
        Parsed value.
    line : int
        Line number (1-based).
    source : str
        File name (or a label) for messages.
    """

    number: int
    value: int
    line: int
    source: str

    @property
    def where(self) -> str:
        """``file line N`` for error messages."""
        return f"{self.source} line {self.line}"


def cs_ivar(number: int) -> tuple[int, int] | None:
    """``(x, suffix)`` if I``number`` is a coordinate-system Ix93/Ix94, else None.

    Examples
    --------
    >>> cs_ivar(193), cs_ivar(5294), cs_ivar(130)
    ((1, 93), (2, 94), None)
    """
    for base in (0, 5000):
        x, suffix = divmod(number - base, 100)
        if 1 <= x <= 8 and suffix in (93, 94) and number - base >= 100:
            return x, suffix
    return None


def is_known(number: int) -> bool:
    """True if the model knows I``number``."""
    return number == 10 or cs_ivar(number) is not None or ECT_FIRST <= number <= ECT_LAST


def check_ivar(number: int, value: object, *, where: str = "") -> int:
    """Check ``value`` against the range of I``number``; raises for unknown variables.

    Ix93 is only checked to be a 24-bit address here; whether something is at that address is
    checked by the machine that applies it.
    """
    name = f"I{number}"
    if number == 10:
        return validate.integer(value, f"{name} (servo interrupt time)", low=1, high=REG_MAX, where=where,
                                allowed=I10_ALLOWED)
    cs = cs_ivar(number)
    if cs is not None:
        if cs[1] == 94:
            return validate.integer(value, f"{name} (Ix94, time-base slew limit)", low=0, high=IX94_MAX, where=where,
                                    allowed=IX94_ALLOWED)
        return validate.integer(value, f"{name} (Ix93, time-base source address)", low=0, high=REG_MASK,
                                where=where, allowed=WORD_ALLOWED)
    if ECT_FIRST <= number <= ECT_LAST:
        return validate.integer(value, f"{name} (conversion table line)", low=0, high=REG_MASK, where=where,
                                allowed=WORD_ALLOWED)
    prefix = f"{where}: " if where else ""
    raise ConfigurationError(f"{prefix}{name} is not an I-variable this model knows (known: {_KNOWN})")


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
