"""Numbers with names, units and ranges: the one place where user values are checked and converted.

Every value that enters cosim from a user (a scenario parameter, a controller setting, a BASIC or
setup-file value, a check's threshold) passes through one of these functions. Each either returns
the value in the form the model computes with (an ``int`` or an exact :class:`~fractions.Fraction`,
never a float that lost digits) or raises :class:`~cosim.errors.ConfigurationError` with the one
message shape users see everywhere::

    [WHERE: ]NAME = VALUE is not allowed (allowed: RANGE)

==================  ===========================================  =================================
function            accepts                                      returns
==================  ===========================================  =================================
:func:`exact`       int, Fraction, Decimal, float, numeric str   Fraction (a float as it prints)
:func:`integer`     int (and, with ``whole=True``, 400.0, 4/1)   int in ``low..high``
:func:`in_range`    any number :func:`exact` takes                Fraction in the (half-)open range
:func:`positive`    any number :func:`exact` takes                Fraction > 0 (or >= 0)
:func:`finite`      any real number                              float, finite
:func:`flag`        bool, 0, 1 (or a language's other yes: -1)   bool
:func:`choice`      one of the allowed values                    the option it equals
==================  ===========================================  =================================

Non-finite values (``inf``, ``nan``) and magnitudes beyond :data:`MAX_MAGNITUDE` are refused by
all of them: no controller register or physical quantity in cosim comes near, and refusing them
here keeps later arithmetic (exact fractions, float conversions at the FMI boundary) bounded.

Examples
--------
>>> integer(25, "pulses per slot", low=-25, high=25)
25
>>> integer(26, "pulses per slot", low=-25, high=25, where="fill slot 3")
Traceback (most recent call last):
...
cosim.errors.ConfigurationError: fill slot 3: pulses per slot = 26 is not allowed (allowed: -25..25)
>>> exact(0.1, "UNITS")
Fraction(1, 10)
>>> positive(0, "accel", unit="pulses/s^2")
Traceback (most recent call last):
...
cosim.errors.ConfigurationError: accel = 0 is not allowed (allowed: > 0 pulses/s^2)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from typing import TypeVar

from cosim.errors import ConfigurationError

T = TypeVar("T")

MAX_MAGNITUDE = Fraction(10) ** 300
"""Largest magnitude any number may have (floats reach 1.8e308; registers are far smaller)."""


_SHOWN_IN_FULL = Fraction(10) ** 30


class _Approximately(str):
    """A number too large to print in full, shown as ``1e+5000`` (without quotes)."""

    def __repr__(self) -> str:
        return str(self)


def _approximately(value: int | Fraction) -> _Approximately:
    log = math.log10(abs(value.numerator)) - math.log10(value.denominator) if isinstance(value, Fraction) else (
        math.log10(abs(value)))
    exponent = math.floor(log)
    mantissa = f"{10 ** (log - exponent):.6g}"
    if mantissa == "10":
        mantissa, exponent = "1", exponent + 1
    return _Approximately(f"{'-' if value < 0 else ''}{mantissa}e+{exponent}")


def shown(value: object) -> object:
    """A value as the user most likely wrote it, for messages (``2184.5`` rather than ``4369/2``).

    numpy scalars are shown as the Python numbers they hold, and numbers beyond 1e30 in the form
    ``1e+5000`` (six significant digits; printing a huge number in full can take minutes).

    Examples
    --------
    >>> shown(Fraction(4369, 2)), shown(Fraction(8)), shown(Fraction(1, 3)), shown(Fraction(10**5000))
    (2184.5, 8, Fraction(1, 3), 1e+5000)
    """
    if isinstance(value, numbers.Integral) and not isinstance(value, int):
        value = int(value)
    elif isinstance(value, float) and type(value) is not float:
        value = float(value)
    if isinstance(value, bool):
        return value
    if isinstance(value, int | Fraction) and abs(Fraction(value)) > _SHOWN_IN_FULL:
        return _approximately(value)
    if isinstance(value, Fraction):
        if value.denominator == 1:
            return value.numerator
        as_float = float(value)
        if Fraction(Decimal(str(as_float))) == value:
            return as_float
        if max(value.numerator.bit_length(), value.denominator.bit_length()) > 1000:
            return _Approximately(f"about {as_float!r}")
    return value


def _refuse(name: str, value: object, allowed: str, where: str) -> ConfigurationError:
    return ConfigurationError.out_of_range(name, shown(value), allowed, where=where)


def exact(value: object, name: str, *, where: str = "") -> Fraction:
    """A finite number as an exact :class:`~fractions.Fraction`.

    A float is taken as the decimal it prints as (``0.1`` is 1/10, not the binary 0.1000...0555),
    which is what the user wrote. ``bool`` is not a number here.

    Raises
    ------
    ConfigurationError
        For anything that is not a finite number of magnitude at most :data:`MAX_MAGNITUDE`.
    """
    allowed = "a finite number"
    if isinstance(value, bool) or not isinstance(value, numbers.Real | Decimal | str):
        raise _refuse(name, value, allowed, where)
    bounded = f"{allowed} of magnitude <= 1e300"
    if isinstance(value, Fraction):
        number = value
    elif isinstance(value, numbers.Integral):
        number = Fraction(int(value))
    else:
        try:
            decimal = Decimal(value.strip() if isinstance(value, str) else str(value))
        except (InvalidOperation, ValueError):
            raise _refuse(name, value, allowed, where) from None
        if not decimal.is_finite():
            raise _refuse(name, value, allowed, where)
        if decimal.adjusted() > 300:
            raise _refuse(name, value, bounded, where)
        if decimal.as_tuple().exponent < -300:  # type: ignore[operator]
            raise _refuse(name, value, f"{allowed} with at most 300 decimal places", where)
        number = Fraction(decimal)
    if abs(number) > MAX_MAGNITUDE:
        raise _refuse(name, value, bounded, where)
    return number


def _bounds(low: object, high: object, unit: str, *, low_open: bool = False, high_open: bool = False) -> str:
    suffix = f" {unit}" if unit else ""
    if low is not None and high is not None and not low_open and not high_open:
        return f"{shown(low)}..{shown(high)}{suffix}"
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {shown(low)}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {shown(high)}")
    return (" and ".join(parts) or "any number") + suffix


def integer(value: object, name: str, *, low: int | None = None, high: int | None = None, unit: str = "",
            where: str = "", allowed: str | None = None, kind: str | None = None, whole: bool = False) -> int:
    """An integer in ``low..high`` (inclusive; either bound may be None).

    Parameters
    ----------
    value : object
        The value given. By default it must be an ``int`` (or a numpy integer): ``400.0`` is
        refused, as a count or a tick number written as a float is usually a mistake.
    name : str
        Parameter name as the user wrote it (vendor name alongside where useful).
    low, high : int, optional
        Inclusive bounds.
    unit : str
        Unit appended to the allowed range in messages.
    where : str
        Location prefix (file and line, key, or the object the value belongs to).
    allowed : str, optional
        The allowed range as text, when it says more than ``low..high unit``.
    kind : str, optional
        What the value must be, said when it is no integer at all (``"an integer number of ticks"``);
        by default the allowed range is said then too.
    whole : bool
        Also accept any number with a whole value (``400.0``, ``Fraction(8, 2)``), as a
        controller's language does.
    """
    if type(value) is int:  # the common case, first: this runs on every emitted pulse segment
        number = value
    elif isinstance(value, numbers.Integral) and not isinstance(value, bool):
        number = int(value)
    else:
        fraction = None
        if whole and isinstance(value, Fraction):
            fraction = value  # exact already, however large: the range says what is wrong
        elif whole and not isinstance(value, bool):
            fraction = exact(value, name, where=where)
        if fraction is None or fraction.denominator != 1:
            raise _refuse(name, value, kind or _integer_text(low, high, unit, allowed), where)
        number = fraction.numerator
    if (low is not None and number < low) or (high is not None and number > high):
        raise _refuse(name, number, _integer_text(low, high, unit, allowed), where)
    return number


def integer_range(low: int | None, high: int | None, unit: str = "") -> str:
    """The range ``low..high`` of an integer as messages say it (``any integer`` without bounds)."""
    return _integer_text(low, high, unit, None).replace("an integer", "any integer")


def _integer_text(low: int | None, high: int | None, unit: str, allowed: str | None) -> str:
    if allowed is not None:
        return allowed
    if low is None and high is None:
        return "an integer" + (f" [{unit}]" if unit else "")
    return _bounds(low, high, unit)


def in_range(value: object, name: str, *, low: object = None, high: object = None, low_open: bool = False,
             high_open: bool = False, unit: str = "", where: str = "", allowed: str | None = None) -> Fraction:
    """A number within bounds, exactly (see :func:`exact`).

    ``low_open`` / ``high_open`` make a bound strict (``> low`` / ``< high``). A refusal shows the
    value as it was given (``0.0`` stays ``0.0``).
    """
    number = exact(value, name, where=where)
    lo = None if low is None else exact(low, f"lower bound of {name}")
    hi = None if high is None else exact(high, f"upper bound of {name}")
    bad = (lo is not None and (number <= lo if low_open else number < lo)) or (
        hi is not None and (number >= hi if high_open else number > hi))
    if bad:
        text = allowed or _bounds(lo, hi, unit, low_open=low_open, high_open=high_open)
        raise _refuse(name, value, text, where)
    return number


def positive(value: object, name: str, *, unit: str = "", where: str = "", zero: bool = False,
             allowed: str | None = None) -> Fraction:
    """A number > 0 (``zero=True``: >= 0), exactly."""
    return in_range(value, name, low=0, low_open=not zero, unit=unit, where=where, allowed=allowed)


def finite(value: object, name: str, *, where: str = "", allowed: str = "a finite number") -> float:
    """A finite real number as a float (thresholds, physical values that are floats anyway)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real | Decimal):
        raise _refuse(name, value, allowed, where)
    try:
        number = float(value)
    except (OverflowError, ValueError):
        raise _refuse(name, value, allowed, where) from None
    if not math.isfinite(number) or abs(number) > float(MAX_MAGNITUDE):
        raise _refuse(name, value, allowed, where)
    return number


def flag(value: object, name: str, *, where: str = "", true: Sequence[int] = (1,), allowed: str | None = None) -> bool:
    """A yes/no setting: ``True``/``False``, or a number equal to 0 (no) or to one of ``true`` (yes).

    A controller's language may have more than one value for yes (Trio BASIC: ON = 1, TRUE = -1).
    """
    if isinstance(value, bool):
        return value
    if isinstance(value, numbers.Real):
        if value == 0:
            return False
        if any(value == option for option in true):
            return True
    raise _refuse(name, value, allowed or "True/False (or 1/0)", where)


def choice(value: object, name: str, options: Sequence[T], *, where: str = "", allowed: str | None = None) -> T:
    """The option equal to ``value`` (compared with ``==``; ``True`` is not taken for ``1``)."""
    for option in options:
        if type(value) is bool and type(option) is not bool:
            continue
        if value == option:
            return option
    raise _refuse(name, value, allowed or ", ".join(str(o) for o in options), where)
