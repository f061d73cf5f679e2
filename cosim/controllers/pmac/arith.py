"""Numbers in PMAC program text: literals and the arithmetic of expressions, exact and bounded.

The controller computes program expressions in 48-bit words. The model keeps every value exact --
an ``int`` while it is whole (the common case, and the fast one), else a
:class:`~fractions.Fraction` -- while it fits what a 48-bit word can hold, and bounds it so that no
expression, loop or literal can grow a number without limit:

* **Magnitude**: ``|value| < 2^47`` (a signed 48-bit double word). A literal, an intermediate
  result or a stored value outside is an error naming the value and the range (the program stops).
* **Resolution**: a value whose denominator exceeds ``2^48`` is replaced by the nearest fraction
  whose denominator does not (:meth:`~fractions.Fraction.limit_denominator`, within ``2^-49``):
  ``P1=1/3`` stays exact, ``P1=P1/3`` is exact 30 times (``3^30 < 2^48``) and then rounded, and
  the numerator and denominator of every stored value stay below ``2^95`` and ``2^48``.
* **Literals**: decimal (``64000``, ``0.25``, ``.5``), hex (``$9F8018``); at most 15 integer
  digits and 30 fraction digits (more cannot be held), no exponent notation (PMAC has none).

Operators (PMAC precedence: ``* / % &`` bind tighter than ``+ - | ^``, left to right):
``%`` is the floor modulo, ``& | ^`` act on the integer and the fraction bits (two's complement); ``INT`` is
the floor and ``ABS`` the magnitude. Division by zero is an error.

The transcendental functions (``SIN COS TAN ASIN ACOS ATAN ATAN2 SQRT LN EXP``) have no exact
result: they are computed in binary floating point (deterministic) and the float is taken exactly,
then fitted as above. Angles are in degrees, or radians with I15 = 1 (the Turbo reference's
degree/radian control). ``ATAN2(e)`` is the angle of the point (Q0, e), as the controller takes its
cosine argument from Q0. An argument outside a function's domain (``SQRT(-1)``, ``LN(0)``,
``ASIN(2)``) is an error naming it.
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


Value = int | Fraction


def fit(value: Value, *, what: str = "value", where: str = "") -> Value:
    """``value`` as a 48-bit word holds it: refused beyond ``2^47``, rounded to a denominator <= ``2^48``.

    Whole values come back as ``int``.
    """
    if type(value) is int:
        if -MAGNITUDE < value < MAGNITUDE:
            return value
        raise _error(f"{float(value):.6g}" if value.bit_length() < 997 else "a number of more than 300 digits",
                     what, RANGE_TEXT, where)
    value = Fraction(value)
    if abs(value) >= MAGNITUDE:
        shown = f"{float(value):.6g}" if abs(value) < 10**300 else "a number of more than 300 digits"
        raise _error(shown, what, RANGE_TEXT, where)
    if value.denominator > DENOMINATOR:
        value = value.limit_denominator(DENOMINATOR)
    return value.numerator if value.denominator == 1 else value


def literal(text: str, *, where: str = "") -> Value:
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
    if not fraction.strip("0"):
        return fit(int(whole or "0"), what=text, where=where)
    value = Fraction(int(whole or "0")) + Fraction(int(fraction), 10 ** len(fraction))
    return fit(value, what=text, where=where)


def _integer_part(value: Value) -> int:
    return value if type(value) is int else math.trunc(value)


def binary(op: str, a: Value, b: Value, *, where: str = "") -> Value:
    """``a op b`` for the PMAC operators ``+ - * / % & | ^``, fitted to 48 bits (integers stay integers)."""
    if type(a) is int and type(b) is int:  # the common case: no fraction is built
        if op == "+":
            result: Value = a + b
        elif op == "-":
            result = a - b
        elif op == "*":
            result = a * b
        elif op == "/" or op == "%":
            if b == 0:
                raise ConfigurationError(f"{where + ': ' if where else ''}division by zero ({a} {op} 0)")
            if op == "%":
                result = a % b
            else:
                q, r = divmod(a, b)
                result = q if r == 0 else Fraction(a, b)
        elif op == "&":
            result = a & b
        elif op == "|":
            result = a | b
        elif op == "^":
            result = a ^ b
        else:  # the grammar allows no other operator
            raise ConfigurationError(f"{where + ': ' if where else ''}operator {op!r} is not supported")
        if type(result) is int and -MAGNITUDE < result < MAGNITUDE:
            return result
        return fit(result, what=f"{a} {op} {b}", where=where)
    if op == "+":
        result = a + b
    elif op == "-":
        result = a - b
    elif op == "*":
        result = a * b
    elif op in "/%":
        if b == 0:
            raise ConfigurationError(f"{where + ': ' if where else ''}division by zero ({a} {op} 0)")
        result = Fraction(a) / b if op == "/" else a % b
    elif op in "&|^":
        result = _bitwise(op, a, b)
    else:  # the grammar allows no other operator
        raise ConfigurationError(f"{where + ': ' if where else ''}operator {op!r} is not supported")
    return fit(result, what=f"{a} {op} {b}", where=where)


def _bitwise(op: str, a: Value, b: Value) -> Value:
    """``a & b``, ``a | b``, ``a ^ b`` on the integer and the fraction bits, two's complement.

    Both values are taken as fixed-point words with as many fraction bits as the finer needs (a
    binary fraction is exact; another is cut toward minus infinity at ``2^-48``), so
    ``0.875 & -1.75`` is ``0.25`` and ``0.875 | -1.75`` is ``-0.375``, as the Turbo reference shows.
    """
    scale = 1
    for value in (a, b):
        denominator = Fraction(value).denominator
        if denominator & (denominator - 1):  # not a power of two: the finest fraction the word holds
            scale = DENOMINATOR
            break
        scale = max(scale, denominator)
    x, y = math.floor(a * scale), math.floor(b * scale)
    bits = x & y if op == "&" else x | y if op == "|" else x ^ y
    return Fraction(bits, scale)


_DOMAIN = {"SQRT": (">= 0", lambda x: x >= 0), "LN": ("> 0", lambda x: x > 0),
           "ASIN": ("-1..1", lambda x: -1 <= x <= 1), "ACOS": ("-1..1", lambda x: -1 <= x <= 1)}


def function(name: str, value: Value, *, radians: bool = False, q0: Value = 0) -> Value:
    """``ABS`` (magnitude), ``INT`` (floor), or a transcendental function (see the module doc)."""
    if name == "ABS":
        return -value if value < 0 else value
    if name == "INT":
        return math.floor(value)
    domain = _DOMAIN.get(name)
    if domain is not None and not domain[1](value):
        raise ConfigurationError(f"{name}({float(value):.6g}) is not defined (allowed argument: {domain[0]})")
    x = float(value)
    angle_in = x if radians else math.radians(x)
    if name == "SIN":
        result = math.sin(angle_in)
    elif name == "COS":
        result = math.cos(angle_in)
    elif name == "TAN":
        result = math.tan(angle_in)
    elif name == "SQRT":
        result = math.sqrt(x)
    elif name == "LN":
        result = math.log(x)
    elif name == "EXP":
        if x > 32.6:  # e^32.6 > 2^47: beyond any 48-bit word
            raise ConfigurationError(f"EXP({x:.6g}) = {math.exp(min(x, 700)):.6g} is not allowed ({RANGE_TEXT})")
        result = math.exp(x)
    else:
        if name == "ASIN":
            angle = math.asin(x)
        elif name == "ACOS":
            angle = math.acos(x)
        elif name == "ATAN":
            angle = math.atan(x)
        else:  # ATAN2: the angle of (Q0, value)
            angle = math.atan2(x, float(q0))
        result = angle if radians else math.degrees(angle)
    return fit(Fraction(result), what=f"{name}({x:.6g})")
