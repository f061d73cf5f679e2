"""Piecewise polynomials of a move, planned in exact fractions once and evaluated in integers every cycle.

A move's position is a piecewise polynomial (degree <= 3) of the time into it, ``tau`` [ms]
(:mod:`.profile`). Planning a move works in :class:`~fractions.Fraction`; the servo cycle must not:
it evaluates the position at an elapsed time that is a whole number ``m`` of ``1/K`` ms (the
coordinate system's time-base units, 2^-23 ms, times the denominator of the time carried into the
segment). For a given ``K`` every piece ``c0 + c1 tau + c2 tau^2 + c3 tau^3`` becomes

    (B0 + B1 m + B2 m^2 + B3 m^3) / D          with integers B_i = c_i D / K^i and D,

so a cycle costs a bisection over integer thresholds and a Horner step in integers, and the exact
value is the ratio ``numerator / D``: ``numerator / D`` as Python's correctly rounded integer
division is the same float that ``float(Fraction(...))`` gives, so the trace does not change.

A piece applies up to a bound on ``tau``, inclusive or not (:class:`Piece`), after the pieces
before it: the same first-match order as the exact :meth:`.profile.Profile.travelled`. For ``K`` the
bound becomes the largest ``m`` it admits: ``floor(bound K)`` if inclusive, ``ceil(bound K) - 1``
if not.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

#: Polynomial coefficients ``(c0, c1, c2, c3)`` in ``tau`` [ms] (fewer for lower degrees).
Poly = tuple[Fraction, ...]


def shift(poly: Poly, offset: Fraction, sign: int = 1) -> Poly:
    """``p(offset + sign * tau)`` as a polynomial in ``tau`` (binomial expansion, exact)."""
    out = [Fraction(0)] * len(poly)
    for i, c in enumerate(poly):
        for j in range(i + 1):  # c (offset + sign tau)^i = c sum C(i, j) offset^(i-j) (sign tau)^j
            out[j] += c * math.comb(i, j) * offset ** (i - j) * sign**j
    return tuple(out)


def scale(poly: Poly, factor: Fraction, constant: Fraction = Fraction(0)) -> Poly:
    """``constant + factor * p(tau)``."""
    scaled = [c * factor for c in poly] or [Fraction(0)]
    scaled[0] += constant
    return tuple(scaled)


@dataclass(frozen=True)
class Piece:
    """``poly`` applies while ``tau < bound`` (``tau <= bound`` if ``closed``), after the pieces before it.

    ``bound`` None: for every later ``tau`` (the last piece).
    """

    bound: Fraction | None
    closed: bool
    poly: Poly


class IntegerPieces:
    """The pieces for time steps of ``1/K`` ms: ``value(m) = numerator(m) / denominator``, in integers.

    Parameters
    ----------
    pieces : sequence of Piece
        In first-match order; the last one has no bound.
    k : int
        Time steps per ms (> 0).
    """

    __slots__ = ("_coefficients", "_thresholds", "denominator")

    def __init__(self, pieces: Sequence[Piece], k: int) -> None:
        thresholds: list[int] = []
        polys: list[Poly] = []
        reached: int | None = None
        for piece in pieces:
            if piece.bound is None:
                polys.append(piece.poly)
                break
            scaled = piece.bound * k
            last = math.floor(scaled) if piece.closed else math.ceil(scaled) - 1
            if reached is not None and last <= reached:
                continue  # admits nothing the pieces before it did not take
            thresholds.append(last)
            polys.append(piece.poly)
            reached = last
        terms = [[c / Fraction(k) ** i for i, c in enumerate(poly)] for poly in polys]
        denominator = 1
        for row in terms:
            for c in row:
                denominator = math.lcm(denominator, c.denominator)
        self.denominator = denominator
        self._thresholds = thresholds
        self._coefficients = [tuple(int(c * denominator) for c in reversed(row)) for row in terms]

    def numerator(self, m: int) -> int:
        """``value(m) * denominator`` (an integer) for ``m`` steps into the move."""
        coefficients = self._coefficients[bisect_left(self._thresholds, m)]
        value = 0
        for c in coefficients:  # Horner, highest degree first
            value = value * m + c
        return value
