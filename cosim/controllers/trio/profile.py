"""Trapezoidal velocity profiles in exact rational arithmetic.

A move of path length ``L`` [units] from rest to rest with speed ``V``, acceleration ``A`` and
deceleration ``D`` has three phases (acceleration, constant speed, deceleration)::

    speed
      Vp |     ______________
         |    /              \\
         |   /                \\
         |__/__________________\\____ t
           0  t_a          t_a+t_c  t_end = t_a + t_c + t_d

    t_a = Vp/A,  t_d = Vp/D,  t_c = (L - Vp^2/(2A) - Vp^2/(2D)) / Vp

with ``Vp = V`` when the move is long enough, else the triangular peak ``sqrt(2 L A D / (A + D))``.
Every phase boundary and every position at a rational time is rational, except that peak speed
and the length of a multi-axis path, which need a square root. Those two roots are taken by
:func:`sqrt_down`: exact when the radicand is the square of a rational, otherwise rounded *down*
to a multiple of ``2**-SQRT_BITS`` (as a fixed-point controller would). Rounding the peak down
leaves a constant-speed phase a few 1e-20 s long, so the move still ends exactly on its target;
everything after the root is exact.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from math import isqrt

from cosim.controllers.trio.piecewise import Piecewise

#: Fraction bits of a rounded square root (see :func:`sqrt_down`).
SQRT_BITS = 64


def sqrt_down(value: Fraction, *, bits: int = SQRT_BITS) -> Fraction:
    """The square root of ``value`` >= 0: exact if it is rational, else rounded down to ``2**-bits``.

    Examples
    --------
    >>> sqrt_down(Fraction(9, 4))
    Fraction(3, 2)
    >>> r = sqrt_down(Fraction(2))
    >>> r * r <= 2 < (r + Fraction(1, 2**64)) ** 2
    True
    """
    if value < 0:
        raise ValueError(f"sqrt_down of a negative value {value}")
    num, den = value.numerator, value.denominator
    rn, rd = isqrt(num), isqrt(den)
    if rn * rn == num and rd * rd == den:
        return Fraction(rn, rd)
    scale = 1 << bits
    return Fraction(isqrt(num * scale * scale // den), scale)


@dataclass(frozen=True)
class Trapezoid:
    """A rest-to-rest trapezoidal (or triangular) profile over a path of ``length`` units.

    Parameters
    ----------
    length : Fraction
        Path length [units], >= 0.
    speed, accel, decel : Fraction
        Programmed speed [units/s] (> 0), acceleration and deceleration [units/s^2] (> 0).

    Examples
    --------
    >>> p = Trapezoid.plan(Fraction(300), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(500))
    >>> p.peak, p.t_accel, p.t_const, p.t_decel, p.t_end
    (Fraction(100, 1), Fraction(1, 10), Fraction(57, 20), Fraction(1, 5), Fraction(63, 20))
    >>> p.position(Fraction(1, 10)), p.position(p.t_end)
    (Fraction(5, 1), Fraction(300, 1))
    """

    length: Fraction
    peak: Fraction
    accel: Fraction
    decel: Fraction
    t_accel: Fraction
    t_const: Fraction
    t_decel: Fraction

    @classmethod
    def plan(cls, length: Fraction, *, speed: Fraction, accel: Fraction, decel: Fraction) -> Trapezoid:
        """Plan the profile (see the module docstring for the formulas)."""
        if length < 0 or speed <= 0 or accel <= 0 or decel <= 0:
            raise ValueError(f"Trapezoid needs length >= 0 and speed, accel, decel > 0; got "
                             f"{length}, {speed}, {accel}, {decel}")
        if length == 0:
            zero = Fraction(0)
            return cls(zero, zero, accel, decel, zero, zero, zero)
        ramps = speed * speed / (2 * accel) + speed * speed / (2 * decel)
        peak = speed if length >= ramps else sqrt_down(2 * length * accel * decel / (accel + decel))
        d_ramps = peak * peak / (2 * accel) + peak * peak / (2 * decel)
        return cls(length, peak, accel, decel, peak / accel, (length - d_ramps) / peak, peak / decel)

    @property
    def t_end(self) -> Fraction:
        """Duration of the move [s]."""
        return self.t_accel + self.t_const + self.t_decel

    def pieces(self) -> Piecewise:
        """The profile as polynomial pieces of ``t`` (see :mod:`.piecewise`): the same exact positions."""
        a, v, d, ta, te = self.accel, self.peak, self.decel, self.t_accel, self.t_end
        zero = Fraction(0)
        return Piecewise(((zero, (zero, zero, a / 2)),
                          (ta, (-v * ta / 2, v)),
                          (ta + self.t_const, (self.length - d * te * te / 2, d * te, -d / 2))), te, self.length)

    def position(self, t: Fraction) -> Fraction:
        """Distance travelled along the path at ``t`` [s] after the start [units]."""
        if t <= 0:
            return Fraction(0)
        if t >= self.t_end:
            return self.length
        if t < self.t_accel:
            return self.accel * t * t / 2
        d_accel = self.peak * self.t_accel / 2
        if t < self.t_accel + self.t_const:
            return d_accel + self.peak * (t - self.t_accel)
        left = self.t_end - t
        return self.length - self.decel * left * left / 2

    def speed(self, t: Fraction) -> Fraction:
        """Profile speed at ``t`` [s] after the start [units/s] (VP_SPEED)."""
        if t <= 0 or t >= self.t_end:
            return Fraction(0)
        if t < self.t_accel:
            return self.accel * t
        if t < self.t_accel + self.t_const:
            return self.peak
        return self.decel * (self.t_end - t)


@dataclass(frozen=True)
class Ramp:
    """A continuous move (``FORWARD`` / ``REVERSE``): accelerate at ``accel`` to ``speed`` and hold it.

    Examples
    --------
    >>> r = Ramp(Fraction(100), Fraction(1000))
    >>> r.position(Fraction(1, 10)), r.position(Fraction(1, 5)), r.t_end is None
    (Fraction(5, 1), Fraction(15, 1), True)
    """

    peak: Fraction
    accel: Fraction

    @property
    def t_end(self) -> Fraction | None:
        """A continuous move has no end of its own (only CANCEL stops it)."""
        return None

    def pieces(self) -> Piecewise:
        """The ramp as polynomial pieces (endless)."""
        zero = Fraction(0)
        ta = self.peak / self.accel
        return Piecewise(((zero, (zero, zero, self.accel / 2)), (ta, (-self.peak * ta / 2, self.peak))), None, zero)

    def position(self, t: Fraction) -> Fraction:
        """Distance travelled at ``t`` [s] after the start [units]."""
        if t <= 0:
            return Fraction(0)
        t_accel = self.peak / self.accel
        if t < t_accel:
            return self.accel * t * t / 2
        return self.peak * t_accel / 2 + self.peak * (t - t_accel)

    def speed(self, t: Fraction) -> Fraction:
        """Speed at ``t`` [s] after the start [units/s]."""
        return Fraction(0) if t <= 0 else min(self.accel * t, self.peak)


@dataclass(frozen=True)
class Stop:
    """The rest of a cancelled move: from ``start`` [units] at ``speed`` [units/s], decelerate to rest.

    Times are those of the move (``t0`` [s] after its start, where the cancel takes effect).

    Examples
    --------
    >>> s = Stop(t0=Fraction(1), start=Fraction(50), start_speed=Fraction(100), decel=Fraction(1000))
    >>> s.t_end, s.position(Fraction(11, 10)), s.length
    (Fraction(11, 10), Fraction(55, 1), Fraction(55, 1))
    """

    t0: Fraction
    start: Fraction
    start_speed: Fraction
    decel: Fraction

    @property
    def t_end(self) -> Fraction:
        """When the move is at rest [s after the move's start]."""
        return self.t0 + self.start_speed / self.decel

    @property
    def length(self) -> Fraction:
        """Distance along the path where it stops [units]."""
        return self.start + self.start_speed * self.start_speed / (2 * self.decel)

    def pieces(self) -> Piecewise:
        """The stop as polynomial pieces: at ``start`` until ``t0``, then decelerating."""
        zero = Fraction(0)
        t0, v, d, s0 = self.t0, self.start_speed, self.decel, self.start
        return Piecewise(((zero, (s0,)), (t0, (s0 - v * t0 - d * t0 * t0 / 2, v + d * t0, -d / 2))), self.t_end,
                         self.length)

    def position(self, t: Fraction) -> Fraction:
        """Distance along the path at ``t`` [s after the move's start] [units]."""
        if t >= self.t_end:
            return self.length
        tau = max(t - self.t0, Fraction(0))
        return self.start + self.start_speed * tau - self.decel * tau * tau / 2

    def speed(self, t: Fraction) -> Fraction:
        """Speed at ``t`` [s after the move's start] [units/s]."""
        if t >= self.t_end:
            return Fraction(0)
        return self.start_speed - self.decel * max(t - self.t0, Fraction(0))



# -- moves planned from a moving state ----------------------------------------------------------
def plan_from(distance: Fraction, *, v0: Fraction, speed: Fraction, accel: Fraction, decel: Fraction,
              v1: Fraction = Fraction(0)) -> Piecewise:
    """A move over ``distance`` [units] from a state moving at ``v0`` >= 0 [units/s], ending at ``v1``.

    For a re-planned move (``MOVEMODIFY``, a merged move): accelerate at ``accel`` (or decelerate
    at ``decel`` when ``v0`` exceeds ``speed``) towards ``speed``, hold it, decelerate to ``v1`` so
    as to end exactly at ``distance``. When the axis cannot stop before ``distance`` it stops at
    ``decel`` beyond it and comes back with a rest-to-rest move. Time and distance from 0.

    Examples
    --------
    >>> p = plan_from(Fraction(10), v0=Fraction(0), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000))
    >>> p.position(p.t_end), p.t_end == Trapezoid.plan(Fraction(10), speed=Fraction(100), accel=Fraction(1000),
    ...                                                 decel=Fraction(1000)).t_end
    (Fraction(10, 1), True)
    >>> back = plan_from(Fraction(1), v0=Fraction(100), speed=Fraction(100), accel=Fraction(1000),
    ...                  decel=Fraction(1000))
    >>> back.position(Fraction(1, 10)), back.length        # stops at 5, comes back to 1
    (Fraction(5, 1), Fraction(1, 1))
    """
    zero = Fraction(0)
    stopping = v0 * v0 / (2 * decel)
    if v1 == 0 and v0 == 0:
        rest = Trapezoid.plan(abs(distance), speed=speed, accel=accel, decel=decel).pieces()
        return rest if distance >= 0 else _backwards(rest)
    if distance < stopping - v1 * v1 / (2 * decel) or distance < 0:  # cannot stop in time: stop, come back
        stop = Stop(zero, zero, v0, decel)
        back = Trapezoid.plan(stop.length - distance, speed=speed, accel=accel, decel=decel).pieces()
        return stop.pieces().switched(stop.t_end, _backwards(back))
    if v0 > speed:  # slow down to speed first
        peak = speed
        first = (v0 - peak) / decel
        first_piece: tuple[Fraction, tuple[Fraction, ...]] = (zero, (zero, v0, -decel / 2))
    else:
        peak_sq = (2 * accel * decel * distance + decel * v0 * v0 + accel * v1 * v1) / (accel + decel)
        peak = speed if peak_sq >= speed * speed else sqrt_down(peak_sq)
        peak = max(peak, v0, v1)
        first = (peak - v0) / accel
        first_piece = (zero, (zero, v0, accel / 2))
    d_first = (v0 + peak) * first / 2
    last = (peak - v1) / decel
    d_last = (peak + v1) * last / 2
    cruise = (distance - d_first - d_last) / peak if peak else zero
    t_c, t_d = first, first + cruise
    t_end = t_d + last
    pieces = [first_piece,
              (t_c, (d_first - peak * t_c, peak)),
              (t_d, (d_first + peak * cruise - peak * t_d - decel * t_d * t_d / 2, peak + decel * t_d, -decel / 2))]
    pieces = [p for i, p in enumerate(pieces) if i + 1 == len(pieces) or pieces[i + 1][0] > p[0]]
    return Piecewise(tuple(pieces), t_end, distance)  # with v1 > 0: the junction where the next move takes over


def _backwards(profile: Piecewise) -> Piecewise:
    return Piecewise(tuple((t, tuple(-c for c in poly)) for t, poly in profile.pieces), profile.t_end,
                     -profile.length)
