"""The numbers of Trio BASIC: exact values within what a Trio variable holds.

A Trio variable is a 32-bit integer part and a 32-bit fraction (TRM 11-13 gives that format for a
variable's value on the network; the model takes it as the format of every BASIC value). The
model keeps values exact (``int`` or :class:`~fractions.Fraction`) and applies the format after
every operation:

* the magnitude must stay in ``-2**31 <= value < 2**31``; beyond it the program stops with an
  error naming the value and the range (:class:`~cosim.errors.ConfigurationError`), rather than
  wrapping or growing without bound (``x = x * x`` forty times would otherwise take hours);
* a value whose exact denominator exceeds ``2**32`` is rounded to the nearest multiple of
  ``2**-32`` (half away from zero): ``1/3`` stays exact, ``(1/3)**40`` becomes 0, as in the register.

Logical operators act on the integer parts, bit by bit (TRM 8-146 ``OR``, 8-149 ``XOR``:
``10 OR 18.9`` is 26); comparisons give TRUE (-1) or FALSE (0) (TRM 8-137).

Number literals are read with the same bounds before a program runs: ``1e99999999`` is an error
with its line and column, not a number with a hundred million digits.
"""

from __future__ import annotations

import re
from fractions import Fraction
from math import trunc

from cosim import validate
from cosim.errors import ConfigurationError

Value = int | Fraction

#: Bits of the integer part (signed) and of the fraction of a BASIC value.
INT_BITS = 32
FRACTION_BITS = 32
LIMIT = 1 << (INT_BITS - 1)
RESOLUTION = 1 << FRACTION_BITS
#: The allowed range, as messages say it.
RANGE_TEXT = f"-{LIMIT} <= value < {LIMIT} (a 32-bit integer part)"
#: Significant digits a literal may have (2**-32 needs fewer than 20).
MAX_DIGITS = 30

_NUMBER = re.compile(r"(?P<int>[0-9]*)(?:\.(?P<frac>[0-9]*))?(?:[eE](?P<exp>[-+]?[0-9]+))?")


def fit(value: Value, what: str = "value") -> Value:
    """``value`` in the variable format: refused beyond the range, rounded to ``2**-32`` if finer.

    Examples
    --------
    >>> fit(Fraction(1, 3)), fit(Fraction(1, 2**40)), fit(Fraction(6, 3))
    (Fraction(1, 3), 0, 2)
    """
    if type(value) is int:
        if -LIMIT <= value < LIMIT:
            return value
        raise ConfigurationError.out_of_range(what, validate.shown(value), RANGE_TEXT)
    assert isinstance(value, Fraction)
    if not -LIMIT <= value < LIMIT:
        raise ConfigurationError.out_of_range(what, validate.shown(value), RANGE_TEXT)
    den = value.denominator
    if den == 1:
        return value.numerator
    if den > RESOLUTION:
        num = value.numerator * RESOLUTION
        scaled = (2 * abs(num) + den) // (2 * den)
        value = Fraction(scaled if num >= 0 else -scaled, RESOLUTION)
        if value.denominator == 1:
            return value.numerator
    return value


def integer_part(value: Value) -> int:
    """The integer part (towards zero) that logical operators act on."""
    return value if type(value) is int else trunc(value)


def literal(text: str) -> Value:
    """A decimal literal (``12``, ``.5``, ``1.25e-3``) as an exact value in the variable format.

    Raises
    ------
    ConfigurationError
        Beyond the range, or with more than :data:`MAX_DIGITS` significant digits.

    Examples
    --------
    >>> literal("1.25e-3"), literal("2e9"), literal("1e-99999")
    (Fraction(1, 800), 2000000000, 0)
    """
    match = _NUMBER.fullmatch(text)
    if match is None or not (match["int"] or match["frac"]):
        raise ConfigurationError.out_of_range("number", text, "a decimal number")
    frac = match["frac"] or ""
    exp_text = match["exp"] or "0"
    digits = ((match["int"] or "") + frac).lstrip("0")
    if not digits:
        return 0
    if len(exp_text.lstrip("+-")) > 9:
        exponent = 10**10 if not exp_text.startswith("-") else -(10**10)
    else:
        exponent = int(exp_text)
    scale = exponent - len(frac)
    magnitude = len(digits) + scale  # the value is below 10**magnitude
    if magnitude > 10:
        raise ConfigurationError.out_of_range("number", text, RANGE_TEXT)
    if magnitude < -12:  # below 10**-12 < 2**-33: rounds to 0
        return 0
    if len(digits.rstrip("0")) > MAX_DIGITS:
        raise ConfigurationError.out_of_range("number", text, f"at most {MAX_DIGITS} significant digits")
    number = int(digits)
    value = Fraction(number * 10**scale) if scale >= 0 else Fraction(number, 10**-scale)
    if not -LIMIT <= value < LIMIT:
        raise ConfigurationError.out_of_range("number", text, RANGE_TEXT)
    return fit(value, "number")


def hex_literal(text: str) -> int:
    """A ``$``-hex literal (``$1F``), at most ``$7FFFFFFF``."""
    digits = text[1:].lstrip("0") or "0"
    if len(digits) > 8 or int(digits, 16) >= LIMIT:
        raise ConfigurationError.out_of_range("number", text, f"$0..$7FFFFFFF ({RANGE_TEXT})")
    return int(digits, 16)


def to_text(value: Value) -> str:
    """A value as ``PRINT`` shows it: four decimal places, rounded half away from zero.

    Examples
    --------
    >>> to_text(47104), to_text(Fraction(-1, 3)), to_text(Fraction(1, 20000))
    ('47104.0000', '-0.3333', '0.0001')
    """
    scaled = abs(Fraction(value)) * 10_000
    rounded = int(scaled + Fraction(1, 2))
    sign = "-" if value < 0 and rounded else ""
    return f"{sign}{rounded // 10_000}.{rounded % 10_000:04d}"
