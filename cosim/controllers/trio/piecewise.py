"""Motion profiles as piecewise polynomials, and their exact evaluation at servo cycles in integers.

Every profile of :mod:`.profile` (trapezoid, ramp, stop, a re-planned move, an S-ramp) is, in the
distance ``s`` [units] travelled along its path, a polynomial of degree <= 3 of the time ``t`` [s]
on each of a few pieces::

    s(t) = c0 + c1 t + c2 t^2 + c3 t^3        for t_i <= t < t_(i+1)
    s(t) = length                             for t >= t_end (at rest)

:class:`Piecewise` holds that form with exact rational coefficients (planned once per move, where
a user's numbers enter). The servo cycle never evaluates it with :class:`~fractions.Fraction`:
:class:`CycleProfile` substitutes ``t = k T - delta`` (cycle ``k`` of the move ends ``k T`` after the
tick it was loaded at; ``delta`` is where the profile's time starts inside the first cycle, 0 but for
a merged move) and scales every piece to integer coefficients over one common denominator, so
``s(k T - delta) = P(k) / den`` exactly, with ``P(k)`` a few integer multiplications. The values are
the same rationals as the Fraction evaluation gives (the trace is bit for bit the same); only their
representation changes.

:func:`smoothed` turns a profile into its S-ramp version (``SRAMP``): the speed averaged over a
window of the S-ramp time, which ramps the acceleration linearly over that time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

Poly = tuple[Fraction, ...]
ZERO = Fraction(0)


def _eval(poly: Poly, t: Fraction) -> Fraction:
    value = ZERO
    for c in reversed(poly):
        value = value * t + c
    return value


def _derivative(poly: Poly) -> Poly:
    return tuple(k * c for k, c in enumerate(poly))[1:] or (ZERO,)


def _shift(poly: Poly, delta: Fraction) -> Poly:
    """The coefficients of ``p(t - delta)`` in powers of ``t``."""
    out = [ZERO] * len(poly)
    for n, c in enumerate(poly):
        if not c:
            continue
        for j in range(n + 1):  # c (t - d)^n = c sum_j C(n, j) t^j (-d)^(n-j)
            out[j] += c * math.comb(n, j) * (-delta) ** (n - j)
    return tuple(out)


def _integral(poly: Poly) -> Poly:
    return (ZERO, *tuple(c / (k + 1) for k, c in enumerate(poly)))


def _add(a: Poly, b: Poly, scale: Fraction = Fraction(1)) -> Poly:
    n = max(len(a), len(b))
    a, b = a + (ZERO,) * (n - len(a)), b + (ZERO,) * (n - len(b))
    return tuple(x + scale * y for x, y in zip(a, b, strict=True))


@dataclass(frozen=True)
class Piecewise:
    """A profile ``s(t)`` [units] as polynomial pieces of the time since its start [s].

    Parameters
    ----------
    pieces : tuple of (t_from, coefficients)
        Piece ``i`` holds from ``t_from`` to the next piece's ``t_from``; the first from ``t_from = 0``
        (and for earlier times). Coefficients in powers of ``t``: ``(c0, c1, c2, c3)``.
    t_end : Fraction or None
        From this time on the profile is at rest at ``length`` (None: it never ends).
    length : Fraction
        The rest position [units] (0 for an endless profile).

    Examples
    --------
    >>> from cosim.controllers.trio.profile import Trapezoid
    >>> p = Trapezoid.plan(Fraction(300), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(500))
    >>> w = p.pieces()
    >>> [w.position(t) == p.position(t) for t in (Fraction(1, 20), Fraction(2), Fraction(31, 10), w.t_end)]
    [True, True, True, True]
    """

    pieces: tuple[tuple[Fraction, Poly], ...]
    t_end: Fraction | None
    length: Fraction

    def _poly(self, t: Fraction) -> Poly:
        pieces = self.pieces
        i = len(pieces) - 1
        while i and pieces[i][0] > t:
            i -= 1
        return pieces[i][1]

    def position(self, t: Fraction) -> Fraction:
        """Distance along the path at ``t`` [s] [units]."""
        if self.t_end is not None and t >= self.t_end:
            return self.length
        return _eval(self._poly(t), t)

    def speed(self, t: Fraction) -> Fraction:
        """Speed along the path at ``t`` [s] [units/s] (0 at rest)."""
        if self.t_end is not None and t >= self.t_end:
            return ZERO
        return _eval(_derivative(self._poly(t)), t)

    def accel(self, t: Fraction) -> Fraction:
        """Acceleration along the path at ``t`` [s] [units/s^2] (0 at rest)."""
        if self.t_end is not None and t >= self.t_end:
            return ZERO
        return _eval(_derivative(_derivative(self._poly(t))), t)

    def later(self, t0: Fraction, s0: Fraction) -> Piecewise:
        """This profile started at ``t0`` [s] from ``s0`` [units] (times and positions of another profile)."""
        pieces = tuple((t0 + t if i else ZERO, _add(_shift(poly, t0), (s0,)))
                       for i, (t, poly) in enumerate(self.pieces))
        return Piecewise(pieces, None if self.t_end is None else t0 + self.t_end, s0 + self.length)

    def switched(self, t0: Fraction, new: Piecewise) -> Piecewise:
        """This profile up to ``t0`` [s], then ``new`` (its time and distance counted from ``t0`` and the
        position reached there)."""
        later = new.later(t0, self.position(t0))
        before = tuple(p for i, p in enumerate(self.pieces) if i == 0 or p[0] < t0)
        if t0 <= 0:
            before = ()
        first = later.pieces[0]
        return Piecewise((*before, (t0 if before else ZERO, first[1]), *later.pieces[1:]), later.t_end, later.length)

    def breakpoints(self) -> list[Fraction]:
        """Where the pieces start, and the end."""
        points = [t for t, _ in self.pieces]
        return points + ([self.t_end] if self.t_end is not None else [])


def smoothed(profile: Piecewise, window_s: Fraction) -> Piecewise:
    """The S-ramp version of ``profile``: ``s_S(t) = (1/W) integral of s over [t - W, t]`` (``s = 0`` before 0).

    Averaging the position over a window ``W`` averages the speed the same way: every step of the
    acceleration becomes a linear ramp over ``W`` (a trapezoid becomes an S-curve), the speed and
    acceleration never exceed the original ones, the distance is the same and the move takes ``W``
    longer. Pieces are cubic.

    Examples
    --------
    >>> from cosim.controllers.trio.profile import Trapezoid
    >>> p = Trapezoid.plan(Fraction(10), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000)).pieces()
    >>> s = smoothed(p, Fraction(1, 50))
    >>> s.t_end - p.t_end, s.position(s.t_end), s.accel(Fraction(1, 100)), s.speed(Fraction(1, 20))
    (Fraction(1, 50), Fraction(10, 1), Fraction(500, 1), Fraction(40, 1))
    """
    if window_s <= 0 or (profile.t_end is None and not profile.pieces):
        return profile
    w = window_s
    # F(t) = integral of s from 0 to t, piecewise quartic; s is 0 before t = 0.
    ends = [t for t, _ in profile.pieces[1:]] + ([profile.t_end] if profile.t_end is not None else [])
    f_pieces: list[tuple[Fraction, Poly]] = [(Fraction(-10**9), (ZERO,))]
    acc = ZERO
    for i, (t0, poly) in enumerate(profile.pieces):
        start = max(t0, ZERO) if i else ZERO
        integral = _integral(poly)
        f_pieces.append((start, _add(integral, (acc - _eval(integral, start),))))
        if i < len(ends):
            acc = _eval(f_pieces[-1][1], ends[i])
    if profile.t_end is not None:
        t_end = profile.t_end
        f_pieces.append((t_end, (acc - profile.length * t_end, profile.length)))

    def f_at(t: Fraction) -> Poly:
        i = len(f_pieces) - 1
        while f_pieces[i][0] > t:
            i -= 1
        return f_pieces[i][1]

    cuts = sorted({t for t, _ in f_pieces[1:]} | {t + w for t, _ in f_pieces[1:]})
    pieces: list[tuple[Fraction, Poly]] = []
    for t in cuts:
        if profile.t_end is not None and t >= profile.t_end + w:
            break
        upper, lower = f_at(t), _shift(f_at(t - w), w)
        pieces.append((t, tuple(c / w for c in _add(upper, lower, Fraction(-1)))))
    end = None if profile.t_end is None else profile.t_end + w
    return Piecewise(tuple(pieces), end, profile.length)


@dataclass(frozen=True)
class CycleProfile:
    """A profile at the ends of servo cycles, in integers: ``s(k T - delta) = P(k) / den`` exactly.

    Parameters
    ----------
    den : int
        Common denominator (> 0).
    pieces : tuple of (k_from, coefficients)
        ``P(k) = sum_n a_n k^n`` (integers) for ``k_from <= k`` up to the next piece.
    k_end : int or None
        From this cycle on the profile is at rest at ``p_end`` (None: it never ends).
    p_end : int
        ``P`` at rest.

    Examples
    --------
    >>> from cosim.controllers.trio.profile import Trapezoid
    >>> p = Trapezoid.plan(Fraction(300), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(500))
    >>> c = CycleProfile.of(p.pieces(), Fraction(1, 1000))
    >>> [Fraction(c.numerator(k), c.den) == p.position(Fraction(k, 1000)) for k in (1, 100, 101, 3000, 3150)]
    [True, True, True, True, True]
    >>> c.k_end
    3150
    """

    den: int
    pieces: tuple[tuple[int, tuple[int, ...]], ...]
    k_end: int | None
    p_end: int

    @classmethod
    def of(cls, profile: Piecewise, period_s: Fraction, *, with_den: int = 1,
           delta_s: Fraction = ZERO) -> CycleProfile:
        """``profile`` sampled at ``t = k period_s - delta_s``; ``with_den`` divides the denominator, so a
        position over ``with_den`` converts exactly."""
        T = period_s
        raw: list[tuple[int, Poly]] = []
        for t_from, poly in profile.pieces:
            k_from = max(_ceil((t_from + delta_s) / T), 0) if raw else 0
            in_k = _shift(tuple(c * T**n for n, c in enumerate(poly)), delta_s / T)  # s(T (k - delta/T))
            raw.append((k_from, in_k))
        k_end = None if profile.t_end is None else _ceil((profile.t_end + delta_s) / T)
        if k_end is not None:
            raw = [(min(k, k_end), p) for k, p in raw]
        kept = [p for i, p in enumerate(raw) if i + 1 == len(raw) or raw[i + 1][0] > p[0]]
        den = math.lcm(with_den, profile.length.denominator)
        for _, poly in kept:
            for c in poly:
                den = math.lcm(den, c.denominator)
        pieces = []
        for k_from, poly in kept:
            coeffs = [int(c * den) for c in poly]
            while len(coeffs) > 1 and not coeffs[-1]:
                coeffs.pop()
            pieces.append((k_from, tuple(coeffs)))
        return cls(den, tuple(pieces), k_end, int(profile.length * den))

    def numerator(self, k: int) -> int:
        """``P(k)``: the position at the end of cycle ``k`` times :attr:`den`."""
        if self.k_end is not None and k >= self.k_end:
            return self.p_end
        pieces = self.pieces
        i = len(pieces) - 1
        while i and pieces[i][0] > k:
            i -= 1
        value = 0
        for c in reversed(pieces[i][1]):
            value = value * k + c
        return value

    def piece_end(self, k: int) -> int | None:
        """The first cycle after ``k`` where another piece (or the rest) starts; None if none does."""
        for k_from, _ in self.pieces:
            if k_from > k:
                return k_from
        if self.k_end is not None and self.k_end > k:
            return self.k_end
        return None


def _ceil(x: Fraction) -> int:
    return -((-x.numerator) // x.denominator)
