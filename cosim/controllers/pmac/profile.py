"""The velocity profile of a PMAC move: accelerate, run, decelerate, with TA and TS, exactly.

A programmed move (LINEAR or RAPID) starts and ends at rest (no blending). Its speed rises from
0 to the plateau speed ``v`` in the acceleration time ``A``, holds, and falls back to 0 in ``A``:

* ``A = max(TA, 2 TS)``: with ``TS > 0`` each ramp begins and ends with a jerk-limited part of
  ``TS`` (the acceleration rises linearly from 0 and falls linearly back to 0), with constant
  acceleration for the ``A - 2 TS`` between; ``TA < 2 TS`` gives a pure S-curve of ``2 TS``.
* The move time ``M`` (``distance / F``, or ``TM``) counts from the middle of the acceleration to
  the middle of the deceleration, and is at least ``A`` (a shorter move runs at a lower plateau
  speed ``v = distance / M``: the manual's triangular profile). The move takes ``M + A``.

Each ramp is point-symmetric about its middle, so it covers ``v A / 2`` whatever ``TS``: the
position on the plateau is ``v (tau - A / 2)`` for TS = 0 and TS > 0 alike. With peak
acceleration ``a = v / (A - TS)`` the distance into a ramp is

    tau <= TS              a tau^3 / (6 TS)
    TS <= tau <= A - TS    a TS^2 / 6 + a TS (tau - TS) / 2 + a (tau - TS)^2 / 2
    A - TS <= tau <= A     v tau - v A / 2 + ramp(A - tau)

All in :class:`~fractions.Fraction`: positions are exact functions of the elapsed time. The same
function as pieces of polynomials (:meth:`Profile.pieces`) is what the servo cycle evaluates, in
integers (:mod:`.pieces`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pmac.pieces import Piece, Poly, scale, shift


@dataclass(frozen=True)
class Profile:
    """Distance travelled along a move as a function of the time into it.

    Attributes
    ----------
    distance : Fraction
        Path length [axis units], >= 0.
    speed : Fraction
        Plateau speed [axis units/ms] (0 for a move of no distance).
    accel_ms : Fraction
        Acceleration time ``A = max(TA, 2 TS)`` [ms].
    ts_ms : Fraction
        S-curve time TS [ms] (``2 TS <= A``).
    move_ms : Fraction
        Move time, middle of acceleration to middle of deceleration [ms], >= ``A``.
    """

    distance: Fraction
    speed: Fraction
    accel_ms: Fraction
    ts_ms: Fraction
    move_ms: Fraction

    @classmethod
    def plan(cls, distance: Fraction, *, ta_ms: Fraction, ts_ms: Fraction, speed: Fraction | None = None,
             tm_ms: Fraction | None = None) -> Profile:
        """The profile of a move of ``distance`` at ``speed`` [units/ms] or in ``tm_ms`` [ms].

        Exactly one of ``speed`` (> 0) and ``tm_ms`` (>= 0) is given.
        """
        accel = max(ta_ms, 2 * ts_ms)
        if tm_ms is not None:
            move = max(tm_ms, accel)
        else:
            assert speed is not None and speed > 0
            move = max(distance / speed, accel)
        plateau = distance / move if move > 0 else Fraction(0)
        return cls(distance, plateau, accel, ts_ms, move)

    @property
    def total_ms(self) -> Fraction:
        """Time from start to stop [ms]: ``M + A``."""
        return self.move_ms + self.accel_ms

    def _ramp(self, tau: Fraction) -> Fraction:
        """Distance covered ``tau`` into an acceleration from rest (0 <= tau <= A)."""
        v, big_a, s = self.speed, self.accel_ms, self.ts_ms
        if s == 0:
            return v * tau * tau / (2 * big_a)
        a = v / (big_a - s)
        if tau <= s:
            return a * tau * tau * tau / (6 * s)
        if tau <= big_a - s:
            return a * s * s / 6 + a * s * (tau - s) / 2 + a * (tau - s) * (tau - s) / 2
        rest = big_a - tau
        return v * tau - v * big_a / 2 + a * rest * rest * rest / (6 * s)

    def travelled(self, tau_ms: Fraction) -> Fraction:
        """Distance along the move at ``tau_ms`` into it [axis units] (0 before, ``distance`` after)."""
        if tau_ms <= 0 or self.distance == 0:
            return Fraction(0)
        if tau_ms >= self.total_ms:
            return self.distance
        v, big_a = self.speed, self.accel_ms
        if big_a == 0:
            return v * tau_ms
        if tau_ms < big_a:
            return self._ramp(tau_ms)
        if tau_ms <= self.move_ms:
            return v * (tau_ms - big_a / 2)
        return self.distance - self._ramp(self.total_ms - tau_ms)

    def speed_at(self, tau_ms: Fraction) -> Fraction:
        """Speed at ``tau_ms`` [axis units/ms] (for tests and plots)."""
        if tau_ms <= 0 or tau_ms >= self.total_ms or self.distance == 0:
            return Fraction(0)
        v, big_a, s = self.speed, self.accel_ms, self.ts_ms
        if big_a == 0:
            return v
        rest = min(tau_ms, self.total_ms - tau_ms)
        if rest >= big_a:
            return v
        if s == 0:
            return v * rest / big_a
        a = v / (big_a - s)
        if rest <= s:
            return a * rest * rest / (2 * s)
        if rest <= big_a - s:
            return a * s / 2 + a * (rest - s)
        tail = big_a - rest
        return v - a * tail * tail / (2 * s)

    def _ramp_pieces(self) -> list[tuple[Fraction, bool, Poly]]:
        """:meth:`_ramp` as ``(bound, closed, poly)`` over ``0 <= tau < A`` (the last bound is A, open)."""
        v, big_a, s = self.speed, self.accel_ms, self.ts_ms
        zero = Fraction(0)
        if s == 0:
            return [(big_a, False, (zero, zero, v / (2 * big_a)))]
        a = v / (big_a - s)
        # a s^2/6 + a s (tau - s)/2 + a (tau - s)^2/2, expanded
        middle = (a * s * s / 6 - a * s * s / 2 + a * s * s / 2, a * s / 2 - a * s, a / 2)
        # v tau - v A/2 + a (A - tau)^3/(6 s)
        end = scale(shift((zero, zero, zero, a / (6 * s)), big_a, -1), Fraction(1), -v * big_a / 2)
        end = (end[0], end[1] + v, end[2], end[3])
        return [(s, True, (zero, zero, zero, a / (6 * s))), (big_a - s, True, middle), (big_a, False, end)]

    def pieces(self) -> list[Piece]:
        """:meth:`travelled` as polynomial pieces in first-match order (see :mod:`.pieces`)."""
        zero = Fraction(0)
        total = self.total_ms
        if self.distance == 0:
            return [Piece(None, False, (zero,))]
        out = [Piece(zero, True, (zero,))]
        v, big_a = self.speed, self.accel_ms
        if big_a == 0:
            return [*out, Piece(total, False, (zero, v)), Piece(None, False, (self.distance,))]
        out += [Piece(bound, closed, poly) for bound, closed, poly in self._ramp_pieces()]
        out.append(Piece(self.move_ms, True, (-v * big_a / 2, v)))
        # distance - ramp(total - tau): the ramp's pieces mirrored, last piece first
        ramp = self._ramp_pieces()
        for index in range(len(ramp) - 1, -1, -1):
            _bound, _closed, poly = ramp[index]
            upper = total - ramp[index - 1][0] if index > 0 else total
            out.append(Piece(upper, False, scale(shift(poly, total, -1), Fraction(-1), self.distance)))
        out.append(Piece(None, False, (self.distance,)))
        return out
