"""Deterministic trigonometry for circular moves, in integer fixed point.

The arcs of ``MOVECIRC`` need angles, sines and cosines; floating-point libraries may differ in
the last bit from one platform to another, and the model promises bit-identical runs. These
functions work on Python integers scaled by ``2**WORK_BITS`` (with guard bits), take and return
exact :class:`~fractions.Fraction` values, and round the result *down* to a multiple of
``2**-RESULT_BITS`` (as :func:`~cosim.controllers.trio.profile.sqrt_down` does for roots):
the same numbers on every machine.

Examples
--------
>>> float(pi_down()), float(cos_sin(pi_down() / 3)[0])
(3.141592653589793, 0.5)
>>> float(atan2(Fraction(1), Fraction(1)) * 4)
3.141592653589793
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache

#: Fraction bits of a result.
RESULT_BITS = 64
#: Working precision [bits] (results plus guard bits).
WORK_BITS = RESULT_BITS + 24
_ONE = 1 << WORK_BITS


def _fixed(value: Fraction) -> int:
    """``value`` as a fixed-point integer, rounded towards minus infinity."""
    return (value.numerator << WORK_BITS) // value.denominator


def _result(fixed: int) -> Fraction:
    """A fixed-point integer rounded down to ``2**-RESULT_BITS``."""
    return Fraction(fixed >> (WORK_BITS - RESULT_BITS), 1 << RESULT_BITS)


def _atan_fixed(x: int) -> int:
    """atan(x) for a fixed-point ``|x| <= ONE/2`` (Taylor series, on ``|x|`` so every shift rounds alike)."""
    if x < 0:
        return -_atan_fixed(-x)
    total, power, k, x2 = 0, x, 0, (x * x) >> WORK_BITS
    while power:
        term = power // (2 * k + 1)
        total += -term if k % 2 else term
        power = (power * x2) >> WORK_BITS
        k += 1
    return total


@cache
def _pi_fixed() -> int:
    """pi by Machin's formula, 16 atan(1/5) - 4 atan(1/239)."""
    return 16 * _atan_fixed(_ONE // 5) - 4 * _atan_fixed(_ONE // 239)


def pi_down() -> Fraction:
    """pi rounded down to ``2**-64``."""
    return _result(_pi_fixed())


def _cos_sin_fixed(x: int) -> tuple[int, int]:
    """cos and sin of a fixed-point ``0 <= x < pi/2`` (Taylor series)."""
    cos, sin, term, n = _ONE, x, x, 1  # term = x**n / n!
    while term:
        term = (term * x) >> WORK_BITS
        n += 1
        term //= n
        if n % 2 == 0:
            cos += term if n % 4 == 0 else -term
        else:
            sin += term if n % 4 == 1 else -term
    return cos, sin


def cos_sin(angle: Fraction) -> tuple[Fraction, Fraction]:
    """``(cos(angle), sin(angle))`` of an exact angle [rad], each rounded down to ``2**-64``."""
    c, s = cos_sin_fixed_of(_fixed(angle))
    return Fraction(c, 1 << RESULT_BITS), Fraction(s, 1 << RESULT_BITS)


def cos_sin_fixed_of(angle_fixed: int) -> tuple[int, int]:
    """:func:`cos_sin` of the angle ``angle_fixed / 2**WORK_BITS`` (rounded down from the exact angle), as the
    integers ``x`` of the results ``x / 2**RESULT_BITS``."""
    half_pi = _pi_fixed() // 2
    quadrant, rest = divmod(angle_fixed % (4 * half_pi), half_pi)
    c, s = _cos_sin_fixed(rest)
    for _ in range(quadrant % 4):
        c, s = -s, c
    shift = WORK_BITS - RESULT_BITS
    return c >> shift, s >> shift


def atan2(y: Fraction, x: Fraction) -> Fraction:
    """The angle of the point ``(x, y)`` in ``(-pi, pi]`` [rad], rounded down to ``2**-64``.

    Raises
    ------
    ValueError
        For the origin, which has no angle.
    """
    if x == 0 and y == 0:
        raise ValueError("atan2 of the origin")
    pi = _pi_fixed()
    if abs(y) <= abs(x):
        angle = _atan_reduced(y / x)
        if x < 0:
            angle += pi if y >= 0 else -pi
    else:
        angle = _atan_reduced(-x / y) + (pi // 2 if y > 0 else -(pi // 2))
    return _result(angle)


def _atan_reduced(t: Fraction) -> int:
    """atan(t) for ``|t| <= 1`` as a fixed-point integer: directly up to 1/3, else pi/4 +- atan((|t|-1)/(|t|+1))."""
    sign = -1 if t < 0 else 1
    t = abs(t)
    if t <= Fraction(1, 3):
        return sign * _atan_fixed(_fixed(t))
    return sign * (_pi_fixed() // 4 + _atan_fixed(_fixed((t - 1) / (t + 1))))


def _atanh_fixed(x: int) -> int:
    """atanh(x) for a fixed-point ``0 <= x <= ONE/3`` (odd series)."""
    total, power, k, x2 = 0, x, 0, (x * x) >> WORK_BITS
    while power:
        total += power // (2 * k + 1)
        power = (power * x2) >> WORK_BITS
        k += 1
    return total


@cache
def _ln2_fixed() -> int:
    return 2 * _atanh_fixed(_ONE // 3)  # ln 2 = 2 atanh(1/3)


def ln_down(value: Fraction) -> Fraction:
    """The natural logarithm of ``value`` > 0, rounded down to ``2**-64``.

    Examples
    --------
    >>> float(ln_down(Fraction(1))), round(float(ln_down(Fraction(10))), 12)
    (0.0, 2.302585092994)
    """
    if value <= 0:
        raise ValueError(f"ln of {value}")
    k = value.numerator.bit_length() - value.denominator.bit_length()
    m = value / Fraction(2) ** k  # 1/2 < m < 2
    x = _fixed((m - 1) / (m + 1))  # |x| < 1/3
    ln_m = 2 * (_atanh_fixed(x) if x >= 0 else -_atanh_fixed(-x))
    return _result(k * _ln2_fixed() + ln_m)


def exp_down(value: Fraction) -> Fraction:
    """``e ** value``, rounded down to ``2**-64`` (``value`` below 64).

    Examples
    --------
    >>> exp_down(Fraction(0)), round(float(exp_down(Fraction(1))), 12)
    (Fraction(1, 1), 2.718281828459)
    """
    ln2 = _ln2_fixed()
    fixed = _fixed(value)
    k = fixed // ln2
    r = fixed - k * ln2  # 0 <= r < ln 2
    total, term, n = _ONE, _ONE, 0
    while term:
        n += 1
        term = (term * r >> WORK_BITS) // n
        total += term
    scaled = total << k if k >= 0 else total >> -k
    return _result(scaled)
