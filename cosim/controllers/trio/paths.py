"""The geometry of a move: where the axes are after a distance ``s`` along the path.

A move's profile (:mod:`~cosim.controllers.trio.profile`) gives the distance ``s`` travelled
along the path at each servo cycle; the path turns it into one displacement per axis [user units
of each axis], from the position the move started at:

* :class:`LinearPath` (``MOVE``, ``MOVEABS``): the straight line, ``d_i * s / L`` with
  ``L = sqrt(sum d_i**2)`` (exact, or rounded down to ``2**-64`` when irrational);
* :class:`ArcPath` (``MOVECIRC``): the circle through the start around the centre, ``s / r``
  radians from the start angle, anticlockwise (direction 0) or clockwise (1) in the plane of the
  first two axes; angles, sines and cosines from :mod:`~cosim.controllers.trio.trig`;
* :class:`RayPath` (``FORWARD``, ``REVERSE``): one axis, without an end.

At the full length a path returns its programmed end exactly, so a move always ends on target.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property

from cosim.controllers.trio.profile import sqrt_down
from cosim.controllers.trio.trig import WORK_BITS, atan2, cos_sin, cos_sin_fixed_of, pi_down
from cosim.errors import ConfigurationError


@dataclass(frozen=True)
class LinearPath:
    """A straight line by ``deltas`` [units of each axis]."""

    deltas: tuple[Fraction, ...]

    @property
    def length(self) -> Fraction:
        """Path length [units] (the base axis' units for the profile)."""
        if len(self.deltas) == 1:
            return abs(self.deltas[0])
        return sqrt_down(sum((d * d for d in self.deltas), Fraction(0)))

    def offset(self, s: Fraction) -> tuple[Fraction, ...]:
        """Displacement of each axis after ``s`` along the path [units]."""
        length = self.length
        if s >= length or length == 0:
            return self.deltas
        share = s / length
        return tuple(d * share for d in self.deltas)


@dataclass(frozen=True)
class RayPath:
    """One axis without an end: ``+s`` (FORWARD) or ``-s`` (REVERSE)."""

    sign: int

    @property
    def length(self) -> None:
        """No length: the move runs until it is cancelled."""
        return None

    def offset(self, s: Fraction) -> tuple[Fraction, ...]:
        """Displacement after ``s`` [units]."""
        return (self.sign * s,)


@dataclass(frozen=True)
class ArcPath:
    """An arc from the start to ``end`` around ``centre`` (both relative to the start) [units].

    Parameters
    ----------
    end, centre : tuple of Fraction
        End point and centre relative to the start, in the plane of the first two axes.
    clockwise : bool
        MOVECIRC direction 1 (clockwise, negative about the third axis); 0 is anticlockwise.
    radius, start_angle, sweep : Fraction
        Radius [units], angle of the start seen from the centre [rad] and the signed angle swept
        (a full circle when the end is the start) [rad].
    """

    end: tuple[Fraction, Fraction]
    centre: tuple[Fraction, Fraction]
    clockwise: bool
    radius: Fraction
    start_angle: Fraction
    sweep: Fraction

    @classmethod
    def plan(cls, end: tuple[Fraction, Fraction], centre: tuple[Fraction, Fraction], *, clockwise: bool,
             tolerance: Fraction) -> ArcPath:
        """Plan the arc; the end must lie on the circle within ``tolerance`` [units].

        Raises
        ------
        ConfigurationError
            A centre at the start (no circle), or an end whose distance from the centre differs
            from the start's by more than ``tolerance``.
        """
        (e1, e2), (c1, c2) = end, centre
        r2_start = c1 * c1 + c2 * c2
        if r2_start == 0:
            raise ConfigurationError("MOVECIRC centre is the start point: there is no circle (give the centre "
                                     "relative to the start)")
        r2_end = (e1 - c1) ** 2 + (e2 - c2) ** 2
        radius, r_end = sqrt_down(r2_start), sqrt_down(r2_end)
        if abs(r_end - radius) > tolerance:
            raise ConfigurationError(
                f"MOVECIRC end point is not on the circle: radius {float(radius):g} at the start, "
                f"{float(r_end):g} at the end (allowed: the same within {float(tolerance):g} units, one step)")
        a0, a1 = atan2(-c2, -c1), atan2(e2 - c2, e1 - c1)
        two_pi = 2 * pi_down()
        full = e1 == 0 and e2 == 0
        turn = two_pi if full else ((a0 - a1) if clockwise else (a1 - a0)) % two_pi
        sweep = -turn if clockwise else turn
        return cls((e1, e2), (c1, c2), clockwise, radius, a0, sweep)

    @cached_property
    def length(self) -> Fraction:
        """Arc length [units]: radius * |sweep| (computed once: every servo cycle of the arc asks)."""
        return self.radius * abs(self.sweep)

    def cycle_terms(self, den: int) -> tuple[int, int, int, int, int]:
        """The integers of :meth:`cos_sin_at` for distances ``p / den`` along the arc (see there)."""
        length, radius, angle = self.length, self.radius, self.start_angle
        sign = -1 if self.clockwise else 1
        an, ad, rn, rd = angle.numerator, angle.denominator, radius.numerator, radius.denominator
        return (length.numerator * den, length.denominator, an * den * rn, sign * rd * ad, ad * den * rn)

    @staticmethod
    def cos_sin_at(p: int, terms: tuple[int, int, int, int, int]) -> tuple[int, int] | None:
        """``cos`` and ``sin`` of the angle after ``s = p / den`` along the arc, as integers ``x`` of the values
        ``x / 2**RESULT_BITS`` that :func:`.trig.cos_sin` gives for it; None at or past the full length.

        The same numbers as :meth:`offset`'s, in integers: the angle ``a0 + sign s / r`` is the one rational
        ``(a0n den rn + sign p rd a0d) / (a0d den rn)``, made fixed point by one division.
        """
        length_den_num, length_den, angle_a, angle_b, angle_den = terms
        if p * length_den >= length_den_num:
            return None
        return cos_sin_fixed_of((((angle_a + angle_b * p)) << WORK_BITS) // angle_den)

    def offset(self, s: Fraction) -> tuple[Fraction, ...]:
        """Displacement of the two axes after ``s`` along the arc [units]; the exact end at the full length."""
        if s >= self.length:
            return self.end
        turn = s / self.radius
        cos, sin = cos_sin(self.start_angle + (-turn if self.clockwise else turn))
        return (self.centre[0] + self.radius * cos, self.centre[1] + self.radius * sin)


@dataclass(frozen=True)
class PolylinePath:
    """Straight lines one after the other (merged moves, ``MERGE = ON``): ``segments`` of deltas [units].

    Examples
    --------
    >>> p = PolylinePath(((Fraction(3), Fraction(4)), (Fraction(0), Fraction(10))))
    >>> p.length, p.offset(Fraction(5)), p.offset(Fraction(10))
    (Fraction(15, 1), (Fraction(3, 1), Fraction(4, 1)), (Fraction(3, 1), Fraction(9, 1)))
    """

    segments: tuple[tuple[Fraction, ...], ...]

    @property
    def lengths(self) -> tuple[Fraction, ...]:
        return tuple(LinearPath(deltas).length for deltas in self.segments)

    @property
    def length(self) -> Fraction:
        """Path length [units]: the sum of the segments'."""
        return sum(self.lengths, Fraction(0))

    @property
    def deltas(self) -> tuple[Fraction, ...]:
        """The displacement of the whole path."""
        return tuple(sum(column, Fraction(0)) for column in zip(*self.segments, strict=True))

    def offset(self, s: Fraction) -> tuple[Fraction, ...]:
        """Displacement of each axis after ``s`` along the path [units]; the exact end at the full length."""
        done = [Fraction(0)] * len(self.segments[0])
        for deltas, length in zip(self.segments, self.lengths, strict=True):
            if s >= length:
                done = [a + d for a, d in zip(done, deltas, strict=True)]
                s -= length
                continue
            part = LinearPath(deltas).offset(s)
            return tuple(a + d for a, d in zip(done, part, strict=True))
        return tuple(done)
