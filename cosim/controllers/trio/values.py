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
    return value if isinstance(value, int) else trunc(value)


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


# -- strings, types ---------------------------------------------------------------------------------
#: Longest string a STRING variable holds by default [characters] [?: a model choice].
DEFAULT_STRING_LENGTH = 255

Datum = int | Fraction | str


def is_text(value: object) -> bool:
    """Is ``value`` a string (a STRING value) rather than a number?"""
    return isinstance(value, str)


def number(value: Datum, what: str = "value") -> Value:
    """``value`` as a number; a string is an error naming ``what``."""
    if isinstance(value, str):
        raise ConfigurationError(f"{what} is the string {value!r} where a number is needed (use VAL)")
    return value


def text(value: Datum, what: str = "value") -> str:
    """``value`` as a string; a number is an error naming ``what``."""
    if not isinstance(value, str):
        raise ConfigurationError(f"{what} is the number {to_text(value)} where a string is needed (use STR)")
    return value


def typed(value: Datum, kind: str, name: str, length: int = DEFAULT_STRING_LENGTH) -> Datum:
    """``value`` stored in a variable declared ``DIM name AS kind``.

    INTEGER keeps the integer part (towards zero), BOOLEAN is TRUE (-1) for any non-zero value and
    FALSE (0) otherwise, FLOAT keeps the value, STRING keeps at most ``length`` characters.

    Examples
    --------
    >>> typed(Fraction(-7, 2), "INTEGER", "n"), typed(5, "BOOLEAN", "b"), typed("abcdef", "STRING", "s", 3)
    (-3, -1, 'abc')
    """
    if kind == "STRING":
        return text(value, name)[:length]
    value = number(value, name)
    if kind == "INTEGER":
        return integer_part(value)
    if kind == "BOOLEAN":
        return -1 if value else 0
    return value


def parse_number(chars: str) -> Value:
    """The number at the start of ``chars`` as ``VAL`` and ``INPUT`` read it (0 when there is none).

    Examples
    --------
    >>> parse_number(" 12.5xyz"), parse_number("-3"), parse_number("abc"), parse_number("$1F")
    (Fraction(25, 2), -3, 0, 31)
    """
    stripped = chars.strip()
    sign = 1
    if stripped[:1] in "+-" and stripped[:1]:
        sign, stripped = (-1 if stripped[0] == "-" else 1), stripped[1:].lstrip()
    hex_match = re.match(r"\$[0-9a-fA-F]{1,8}", stripped)
    if hex_match:
        return fit(sign * int(hex_match.group()[1:], 16), "VAL")
    match = re.match(r"([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][-+]?[0-9]{1,3})?", stripped)
    if not match:
        return 0
    value = literal(match.group())
    return fit(-value if sign < 0 else value, "VAL")


def hex_text(value: Value) -> str:
    """``HEX(value)``: the integer part in upper-case hexadecimal (two's complement for a negative one, 32 bits).

    Examples
    --------
    >>> hex_text(255), hex_text(-1), hex_text(Fraction(33, 2))
    ('FF', 'FFFFFFFF', '10')
    """
    n = integer_part(value)
    return f"{n & 0xFFFFFFFF if n < 0 else n:X}"


def formatted(value: Value, width: int, decimals: int) -> str:
    """``PRINT value[width, decimals]``: right-aligned in ``width`` characters with ``decimals`` decimal places
    (rounded half away from zero).

    Examples
    --------
    >>> formatted(Fraction(314159, 100000), 8, 2), formatted(-2, 5, 0), formatted(12345, 3, 0)
    ('    3.14', '   -2', '12345')
    """
    scale = 10**decimals
    scaled = abs(Fraction(value)) * scale
    rounded = int(scaled + Fraction(1, 2))
    sign = "-" if value < 0 and rounded else ""
    body = f"{rounded // scale}" + (f".{rounded % scale:0{decimals}d}" if decimals else "")
    return f"{sign}{body}".rjust(width)
