"""What one axis (or one kinematic motor) does during a program segment, as a function of the time into it.

Every path answers two questions: :meth:`position` -- exactly, at a time ``tau`` [ms] given as a
fraction (for tests, plots and the move's end) -- and :meth:`ratio` -- in the servo cycle, at ``m``
steps of ``1/k`` ms, as a ratio of integers (its float, correctly rounded, is what the trace sees).

* :class:`AxisPath` -- LINEAR and RAPID: along a :class:`~.profile.Profile` (piecewise polynomial:
  integer pieces, :mod:`.pieces`). A kinematic motor of a LINEAR move follows the move's profile
  the same way, from its start to its end count.
* :class:`HermitePath` -- PVT and SPLINE1: a cubic from a position and velocity to a position and
  velocity in a segment time (exact polynomial).
* :class:`CirclePath` -- CIRCLE1/CIRCLE2: one axis of the plane of an arc; the distance along the arc
  comes from the profile (exact), the angle and the position from it in binary floating point
  (deterministic), so the ratio is that float's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

from cosim.controllers.pmac.pieces import IntegerPieces, Piece, Poly, scale
from cosim.controllers.pmac.profile import Profile


@dataclass(frozen=True)
class _Polynomial:
    """Shared part of the polynomial paths: integer pieces per time step, made on first use."""

    _integer: dict[int, IntegerPieces] = field(default_factory=dict, compare=False, repr=False, init=False)

    def pieces(self) -> list[Piece]:
        raise NotImplementedError

    def ratio(self, m: int, k: int) -> tuple[int, int]:
        """Position at ``m / k`` ms into the segment as ``(numerator, denominator)``."""
        pieces = self._integer.get(k)
        if pieces is None:
            pieces = self._integer[k] = IntegerPieces(self.pieces(), k)
        return pieces.numerator(m), pieces.denominator


@dataclass(frozen=True)
class AxisPath(_Polynomial):
    """What one axis does in a segment: from ``start`` to ``target`` along ``profile``.

    The axis is at ``start + (target - start) * travelled / profile.distance`` (a LINEAR move of
    several axes shares one profile over the path length).
    """

    axis: str = ""
    start: Fraction = Fraction(0)
    target: Fraction = Fraction(0)
    profile: Profile = field(default_factory=lambda: Profile(Fraction(0), Fraction(0), Fraction(0), Fraction(0),
                                                             Fraction(0)))

    def position(self, tau_ms: Fraction) -> Fraction:
        """Position at ``tau_ms`` into the segment [axis units] (exact; the reference for :meth:`pieces`)."""
        if self.profile.distance == 0:
            return self.target if tau_ms >= self.profile.total_ms else self.start
        if tau_ms >= self.profile.total_ms:
            return self.target
        return self.start + (self.target - self.start) * self.profile.travelled(tau_ms) / self.profile.distance

    def pieces(self) -> list[Piece]:
        """:meth:`position` as polynomial pieces in ``tau`` [ms] (see :mod:`.pieces`)."""
        profile = self.profile
        if profile.distance == 0:
            return [Piece(profile.total_ms, False, (self.start,)), Piece(None, False, (self.target,))]
        factor = (self.target - self.start) / profile.distance
        return [Piece(p.bound, p.closed, scale(p.poly, factor, self.start)) for p in profile.pieces()]


def hermite(p0: Fraction, v0: Fraction, p1: Fraction, v1: Fraction, t_ms: Fraction) -> Poly:
    """The cubic with ``p(0) = p0``, ``p'(0) = v0``, ``p(T) = p1``, ``p'(T) = v1`` (v in units/ms)."""
    t2 = t_ms * t_ms
    return (p0, v0, 3 * (p1 - p0) / t2 - (2 * v0 + v1) / t_ms, 2 * (p0 - p1) / (t2 * t_ms) + (v0 + v1) / t2)


@dataclass(frozen=True)
class HermitePath(_Polynomial):
    """PVT / SPLINE1: from ``start`` at ``v0`` to ``target`` at ``v1`` in ``t_ms`` (velocities in units/ms)."""

    axis: str = ""
    start: Fraction = Fraction(0)
    target: Fraction = Fraction(0)
    v0: Fraction = Fraction(0)
    v1: Fraction = Fraction(0)
    t_ms: Fraction = Fraction(1)

    def poly(self) -> Poly:
        return hermite(self.start, self.v0, self.target, self.v1, self.t_ms)

    def position(self, tau_ms: Fraction) -> Fraction:
        """Position at ``tau_ms`` [axis units] (exact)."""
        if tau_ms <= 0:
            return self.start
        if tau_ms >= self.t_ms:
            return self.target
        return sum((c * tau_ms**i for i, c in enumerate(self.poly())), Fraction(0))

    def pieces(self) -> list[Piece]:
        return [Piece(Fraction(0), True, (self.start,)), Piece(self.t_ms, False, self.poly()),
                Piece(None, False, (self.target,))]


@dataclass(frozen=True)
class Arc:
    """The geometry of an arc in a plane: centre, start angle and radius, swept angle (signed), end radius."""

    centre: tuple[float, float]
    angle0: float
    sweep: float
    radius0: float
    radius1: float


@dataclass(frozen=True)
class CirclePath:
    """One axis of the plane of an arc (``index`` 0: the first plane axis, 1: the second).

    The fraction of the arc done is ``travelled / distance`` of the move's profile (exact); the
    angle ``angle0 + sweep * fraction`` and the radius (linear from start to end radius) are
    floats; at the end the axis is exactly at its target.
    """

    axis: str
    start: Fraction
    target: Fraction
    profile: Profile
    arc: Arc
    index: int
    _fraction: AxisPath = field(init=False, compare=False, repr=False)

    def __post_init__(self) -> None:  # the fraction of the arc done: a path from 0 to 1 along the profile
        object.__setattr__(self, "_fraction", AxisPath(self.axis, Fraction(0), Fraction(1), self.profile))

    def _at(self, fraction: float) -> float:
        arc = self.arc
        angle = arc.angle0 + arc.sweep * fraction
        radius = arc.radius0 + (arc.radius1 - arc.radius0) * fraction
        return arc.centre[self.index] + radius * (math.cos(angle) if self.index == 0 else math.sin(angle))

    def position(self, tau_ms: Fraction) -> Fraction:
        """Position at ``tau_ms`` [axis units]."""
        if tau_ms >= self.profile.total_ms:
            return self.target
        if tau_ms <= 0:
            return self.start
        return Fraction(self._at(float(self._fraction.position(tau_ms))))

    def ratio(self, m: int, k: int) -> tuple[int, int]:
        """Position at ``m / k`` ms as ``(numerator, denominator)`` (of the float it is)."""
        numerator, denominator = self._fraction.ratio(m, k)
        if numerator >= denominator:
            return self.target.numerator, self.target.denominator
        if numerator <= 0:
            return self.start.numerator, self.start.denominator
        return self._at(numerator / denominator).as_integer_ratio()


@dataclass(frozen=True)
class SampledPath(_Polynomial):
    """A kinematic motor of a segmented move: straight lines between its counts at the segment points.

    ``points`` are ``(tau_ms, counts)`` in time order, the last at the end of the move.
    """

    axis: str = ""
    start: Fraction = Fraction(0)
    points: tuple[tuple[Fraction, Fraction], ...] = ()

    @property
    def target(self) -> Fraction:
        return self.points[-1][1] if self.points else self.start

    def position(self, tau_ms: Fraction) -> Fraction:
        """Counts at ``tau_ms`` (exact)."""
        before_tau, before = Fraction(0), self.start
        for tau, value in self.points:
            if tau_ms < tau:
                return before + (value - before) * (tau_ms - before_tau) / (tau - before_tau)
            before_tau, before = tau, value
        return self.target

    def pieces(self) -> list[Piece]:
        out = [Piece(Fraction(0), True, (self.start,))]
        before_tau, before = Fraction(0), self.start
        for tau, value in self.points:
            if tau > before_tau:
                slope = (value - before) / (tau - before_tau)
                out.append(Piece(tau, False, (before - slope * before_tau, slope)))
            before_tau, before = tau, value
        return [*out, Piece(None, False, (self.target,))]


Path = AxisPath | HermitePath | CirclePath | SampledPath
