"""Numbers in PMAC program text: literals and the arithmetic of expressions, exact and bounded.

The controller computes program expressions in 48-bit words. The model keeps every value an
exact :class:`~fractions.Fraction` while it fits what a 48-bit word can hold, and bounds it so
that no expression, loop or literal can grow a number without limit:

* **Magnitude**: ``|value| < 2^47`` (a signed 48-bit double word). A literal, an intermediate
  result or a stored value outside is an error naming the value and the range (the program stops).
* **Resolution**: a value whose denominator exceeds ``2^48`` is replaced by the nearest fraction
  whose denominator does not (:meth:`~fractions.Fraction.limit_denominator`, within ``2^-49``):
  ``P1=1/3`` stays exact, ``P1=P1/3`` is exact 30 times (``3^30 < 2^48``) and then rounded, and
  the numerator and denominator of every stored value stay below ``2^95`` and ``2^48``.
* **Literals**: decimal (``64000``, ``0.25``, ``.5``), hex (``$9F8018``); at most 15 integer
  digits and 30 fraction digits (more cannot be held), no exponent notation (PMAC has none).

Operators (PMAC precedence: ``* / % &`` bind tighter than ``+ - | ^``, left to right):
``%`` is the floor modulo, ``& | ^`` act on the integer parts (truncated toward zero); ``INT`` is
the floor and ``ABS`` the magnitude. Division by zero is an error.
"""

from __future__ import annotations

import math
from fractions import Fraction

from cosim.errors import ConfigurationError

#: Values must stay below this magnitude (a signed 48-bit double word).
MAGNITUDE = 1 << 47
#: Largest denominator a value keeps (finer values are rounded to the nearest such fraction).
DENOMINATOR = 1 << 48
#: Longest integer part and fraction part of a decimal literal [digits].
INT_DIGITS = 15
FRACTION_DIGITS = 30
RANGE_TEXT = "|value| < 2^47 (a signed 48-bit word)"


def _error(value: object, what: str, allowed: str, where: str) -> ConfigurationError:
    prefix = f"{where}: " if where else ""
    return ConfigurationError(f"{prefix}{what} = {value} is not allowed (allowed: {allowed})")


def fit(value: Fraction | int, *, what: str = "value", where: str = "") -> Fraction:
    """``value`` as a 48-bit word holds it: refused beyond ``2^47``, rounded to a denominator <= ``2^48``."""
    value = Fraction(value)
    if abs(value) >= MAGNITUDE:
        shown = f"{float(value):.6g}" if abs(value) < 10**300 else "a number of more than 300 digits"
        raise _error(shown, what, RANGE_TEXT, where)
    if value.denominator > DENOMINATOR:
        value = value.limit_denominator(DENOMINATOR)
    return value


def literal(text: str, *, where: str = "") -> Fraction:
    """The value of a numeric literal: decimal or ``$`` hex (the grammar guarantees the form)."""
    if text.startswith("$"):
        digits = text[1:].lstrip("0")
        if len(digits) > 12:
            raise _error(text, "number", "hex literals of at most 12 digits (48 bits)", where)
        return fit(int(digits or "0", 16), what=text, where=where)
    whole, _dot, fraction = text.partition(".")
    whole = whole.lstrip("0")
    if len(whole) > INT_DIGITS or len(fraction) > FRACTION_DIGITS:
        raise _error(text if len(text) <= 40 else text[:37] + "...", "number",
                     f"at most {INT_DIGITS} integer and {FRACTION_DIGITS} fraction digits; {RANGE_TEXT}", where)
    value = Fraction(int(whole or "0")) + (Fraction(int(fraction), 10 ** len(fraction)) if fraction else 0)
    return fit(value, what=text, where=where)


def _integer_part(value: Fraction) -> int:
    return math.trunc(value)


def binary(op: str, a: Fraction, b: Fraction, *, where: str = "") -> Fraction:
    """``a op b`` for the PMAC operators ``+ - * / % & | ^``, fitted to 48 bits."""
    if op == "+":
        result = a + b
    elif op == "-":
        result = a - b
    elif op == "*":
        result = a * b
    elif op in "/%":
        if b == 0:
            raise ConfigurationError(f"{where + ': ' if where else ''}division by zero ({a} {op} 0)")
        result = a / b if op == "/" else a % b
    elif op == "&":
        result = Fraction(_integer_part(a) & _integer_part(b))
    elif op == "|":
        result = Fraction(_integer_part(a) | _integer_part(b))
    elif op == "^":
        result = Fraction(_integer_part(a) ^ _integer_part(b))
    else:  # the grammar allows no other operator
        raise ConfigurationError(f"{where + ': ' if where else ''}operator {op!r} is not supported")
    if abs(result) >= MAGNITUDE or result.denominator > DENOMINATOR:
        return fit(result, what=f"{a} {op} {b}", where=where)
    return result


def function(name: str, value: Fraction) -> Fraction:
    """``ABS`` (magnitude) or ``INT`` (floor)."""
    return abs(value) if name == "ABS" else Fraction(math.floor(value))
