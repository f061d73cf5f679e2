"""Moves: a profile along a path, run one servo cycle at a time in integers.

Servo cycle ``k`` of a move loaded at tick ``t_s`` runs at ``t_s + (k-1)*T`` (``T`` = SERVO_PERIOD).
It evaluates the move's exact profile (:mod:`~cosim.controllers.trio.profile`) at the *end* of the
cycle, ``k*T``, and its path (:mod:`~cosim.controllers.trio.paths`) at that distance, so every axis
of the move gets its demand position for ``t_s + k*T``::

    demand_i = start_i + offset_i(s(kT)) * UNITS_i          [counts, exact]

and ``VP_SPEED`` is the path speed the cycle executes, ``(s(kT) - s((k-1)T)) / T``: for a line and
for an arc alike. The move is over at the first cycle that reaches its end; the axes are idle from
the next servo tick on. ``CANCEL`` makes the move decelerate at DECEL from the next tick, along its
own path, and end where it comes to rest; ``MOVEMODIFY`` re-plans it to a new end the same way.

In the cycle, a straight path (``MOVE``, ``MOVEABS``, ``FORWARD``, ``REVERSE``) costs a few integer
operations per axis: with ``s(kT) = P(k) / den`` (:class:`~.piecewise.CycleProfile`),
``demand_i = (S_i + G_i P(k)) / E_i`` with integers ``S_i, G_i, E_i`` fixed when the profile is
planned. An arc's offsets need its sines and cosines (:mod:`.trig`) each cycle.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from math import lcm
from typing import TYPE_CHECKING

from cosim import validate
from cosim.controllers.trio.paths import ArcPath, LinearPath, PolylinePath, RayPath
from cosim.controllers.trio.piecewise import CycleProfile, Piecewise, smoothed
from cosim.controllers.trio.profile import Ramp, Stop, Trapezoid, plan_from
from cosim.controllers.trio.trig import RESULT_BITS

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis

Path = LinearPath | ArcPath | RayPath | PolylinePath


@dataclass(eq=False)
class Move:
    """A move of one axis or an interpolated base group.

    Parameters
    ----------
    axes : tuple of int
        The axes that move; the first is the base axis whose SPEED, ACCEL and DECEL are used.
    kind : str
        ``MOVE`` (values are distances), ``MOVEABS`` (end positions), ``MOVECIRC`` (end1, end2,
        centre1, centre2 relative to the start, direction; its :class:`ArcPath` given as ``path``),
        ``FORWARD`` or ``REVERSE``.
    values : tuple of Fraction
        The command's arguments [units].
    origin : str
        Where the move was issued (``job.bas line 12``), for error messages.
    """

    axes: tuple[int, ...]
    kind: str
    values: tuple[Fraction, ...]
    origin: str = ""
    t_start: int = -1
    path: Path | None = None
    profile: Piecewise | None = None
    start_counts: tuple[Fraction, ...] = ()
    units: tuple[Fraction, ...] = ()
    cycles: int = 0
    done: bool = False
    cancel_requested: bool = False
    #: A MOVEMODIFY's new end along the path [units], re-planned at the next servo tick (the last one given wins).
    modify_to: Fraction | None = None
    #: A CANCEL has taken effect: the move decelerates to rest.
    cancelling: bool = False
    #: Where the move ends along its path [units] (None: it does not end by itself).
    end_s: Fraction | None = None
    #: Demands of the cycle just run [counts] (numerators over :attr:`dens`) and its path speed ``v_num / v_den``.
    nums: list[int] = field(default_factory=list)
    dens: list[int] = field(default_factory=list)
    v_num: int = 0
    v_den: int = 1
    _cycle: CycleProfile | None = field(default=None, repr=False)
    _p_prev: int = field(default=0, repr=False)
    _straight: list[tuple[int, int, int]] | None = field(default=None, repr=False)
    #: An arc's cycle in integers: the terms of ArcPath.cos_sin_at, and (N, M, E) of its two axes' demands.
    _arc: tuple[tuple[int, int, int, int, int], tuple[tuple[int, int, int], ...]] | None = field(default=None,
                                                                                              repr=False)
    _period: tuple[int, int] = field(default=(1, 1000), repr=False)
    #: The path distance never decreases, and the largest path speed of the profile [units/s].
    monotonic: bool = True
    max_speed: Fraction = Fraction(0)
    axis_objects: tuple[Axis, ...] = field(default=(), repr=False)
    _per_cycle: Fraction = field(default=Fraction(0), repr=False)
    _per_cycle_key: tuple[Fraction, tuple[int, int]] | None = field(default=None, repr=False)
    #: The end and the SPEED, ACCEL, DECEL the running profile was planned with (None: another kind of profile).
    _plan_key: tuple[object, ...] | None = field(default=None, repr=False)

    def load(self, axes: dict[int, Axis], t: int, period_s: Fraction) -> None:
        """Plan the move at servo tick ``t`` from the axes' current demand positions."""
        base = axes[self.axes[0]]
        speed = validate.positive(base.params["SPEED"], f"SPEED of axis {base.number} when the {self.kind} starts")
        accel, decel = Fraction(base.params["ACCEL"]), Fraction(base.params["DECEL"])
        profile: Piecewise
        if self.kind in ("FORWARD", "REVERSE"):
            self.path = RayPath(1 if self.kind == "FORWARD" else -1)
            profile = Ramp(speed, accel).pieces()
        else:
            if self.path is None:  # an arc is planned when it is issued: its geometry is relative to the start
                self.path = LinearPath(tuple(value - axes[a].dpos if self.kind == "MOVEABS" else value
                                             for a, value in zip(self.axes, self.values, strict=True)))
            assert not isinstance(self.path, RayPath)
            self.end_s = self.path.length
            profile = Trapezoid.plan(self.end_s, speed=speed, accel=accel, decel=decel).pieces()
        sramp = base.params.get("SRAMP", 0)
        if sramp:
            profile = smoothed(profile, Fraction(sramp) / 1000)
        self.axis_objects = tuple(axes[a] for a in self.axes)
        self.start_counts = tuple(axes[a].demand for a in self.axes)
        self.units = tuple(axes[a].units for a in self.axes)
        self.t_start = t
        self._period = (period_s.numerator, period_s.denominator)
        self.set_profile(profile, period_s)
        if self.end_s is not None and not sramp:
            self._plan_key = (self.end_s, base.params["SPEED"], base.params["ACCEL"], base.params["DECEL"])

    def set_profile(self, profile: Piecewise, period_s: Fraction) -> None:
        """Run ``profile`` from the next cycle on (times from the move's start, distance along its path)."""
        old = self._cycle
        self._plan_key = None
        cycle = CycleProfile.of(profile, period_s, with_den=1 if old is None else old.den)
        if old is not None:
            self._p_prev = self._p_prev * (cycle.den // old.den)
        self.profile, self._cycle = profile, cycle
        self.max_speed, lowest = _speed_range(profile)
        self.monotonic = lowest >= 0
        path = self.path
        if isinstance(path, ArcPath | PolylinePath):
            self._straight = None
            self._arc = (_arc_terms(path, self.start_counts, self.units, cycle.den)
                         if isinstance(path, ArcPath) and len(self.start_counts) >= 2 else None)
            return
        assert path is not None
        if isinstance(path, RayPath):
            gains = [Fraction(path.sign)]
        else:
            length = path.length
            gains = [d / length if length else Fraction(0) for d in path.deltas]
        straight = []
        for start, gain, units in zip(self.start_counts, gains, self.units, strict=False):
            h = gain * units / cycle.den  # counts per unit of P
            e = lcm(start.denominator, h.denominator)
            straight.append((start.numerator * (e // start.denominator), h.numerator * (e // h.denominator), e))
        self._straight = straight

    def heading(self, axis: int) -> int:
        """The direction the move takes ``axis`` (+1, -1, 0), from its path."""
        if self._straight is None or axis not in self.axes:
            return 0
        index = self.axes.index(axis)
        if index >= len(self._straight):
            return 0
        g = self._straight[index][1]
        return (g > 0) - (g < 0)

    @property
    def per_cycle(self) -> Fraction:
        """The longest distance a cycle of this move covers [units] (max_speed x SERVO_PERIOD)."""
        key = (self.max_speed, self._period)
        if self._per_cycle_key != key:
            self._per_cycle = self.max_speed * Fraction(*self._period)
            self._per_cycle_key = key
        return self._per_cycle

    def fe_safe(self, axis: Axis) -> bool:
        """The following error of ``axis`` cannot exceed FE_LIMIT in this move: the step count lags the
        demand by less than three cycles of motion and one step."""
        units, limit = Fraction(axis.params["UNITS"]), Fraction(axis.params["FE_LIMIT"])
        return (limit - 3 * self.per_cycle) * units > 2

    def cycles_within_range(self, axis: Axis) -> int:
        """Cycles the axis surely stays inside its repeat distance (REP_DIST), moving at most max_speed.

        In integers, as :func:`~.supervise.within_range`: ``x / (den c rd)`` is DPOS and ``span / (den c rd)``
        is REP_DIST, so the room left is ``room / (den c rd)`` and the cycles ``room / (per_cycle den c rd)``.
        """
        per = self.per_cycle
        if per <= 0:
            return 1 << 40
        a, b, c = axis._scales()
        rep = axis.params["REP_DIST"]
        rn, rd = rep.numerator, rep.denominator
        den = axis.dden
        x = abs((axis.dnum * a - b * den) * rd)
        span = rn * den * c
        room = min(x, span - x) if axis.params["REP_OPTION"] & 1 else span - x
        if room < 0:
            return 0
        return max(room * per.denominator // (per.numerator * den * c * rd) - 2, 0)

    def pulses_safe(self, axis: Axis, period_ticks: int) -> bool:
        """No cycle of this move can put pulses of ``axis`` closer than two pulse widths (which is an error)."""
        most = self.per_cycle * Fraction(axis.params["UNITS"]) + 2
        return period_ticks // -(-most.numerator // most.denominator) >= 2 * axis.pulse_width

    def steps_after(self, index: int, cycle: int, steps_now: int) -> int:
        """The step count of axis ``index`` after cycle ``cycle`` of a monotonic straight move, from
        ``steps_now`` (its count now): the rule of :meth:`Axis.output_cycle`, which moves the count only in
        the direction of motion."""
        assert self._cycle is not None and self._straight is not None
        s, g, e = self._straight[index]
        num = s + g * self._cycle.numerator(cycle)
        if g > 0:
            return steps_now if num < steps_now * e else num // e
        if g < 0:
            return steps_now if num > steps_now * e else -(-num // e)
        return steps_now

    @property
    def travelled(self) -> Fraction:
        """Distance along the path at the end of the last cycle [units]."""
        assert self._cycle is not None
        return Fraction(self._p_prev, self._cycle.den)

    @property
    def t_now(self) -> Fraction:
        """Time since the move started at the end of the last cycle [s]."""
        return self.cycles * Fraction(*self._period)

    def stop(self, period_s: Fraction, decel: Fraction) -> None:
        """CANCEL takes effect at this cycle: decelerate at ``decel`` [units/s^2] from the state now."""
        assert self.profile is not None
        self.cancel_requested = False
        self.cancelling = True
        t_now = self.cycles * period_s
        speed = self.profile.speed(t_now)
        stop = Stop(t_now, self.profile.position(t_now), speed, decel)
        length = self.end_s
        if length is not None and stop.length > length:  # DECEL lowered since the move was planned
            stop = Stop(t_now, stop.start, speed, speed * speed / (2 * (length - stop.start))) \
                if length > stop.start else Stop(t_now, length, Fraction(0), decel)
        self.set_profile(stop.pieces(), period_s)

    def modify(self, end: Fraction, axes: dict[int, Axis], period_s: Fraction) -> None:
        """MOVEMODIFY: end at distance ``end`` [units] along the path instead (behind the axis: it stops and
        comes back), re-planned from the state now."""
        assert self.profile is not None
        base = axes[self.axes[0]]
        key = (end, base.params["SPEED"], base.params["ACCEL"], base.params["DECEL"])
        if key == self._plan_key:  # the end and the speeds it was planned with: nothing to re-plan
            return
        t_now = self.cycles * period_s
        s_now, v_now = self.profile.position(t_now), self.profile.speed(t_now)
        rest = plan_from(end - s_now, v0=v_now, speed=Fraction(base.params["SPEED"]),
                         accel=Fraction(base.params["ACCEL"]), decel=Fraction(base.params["DECEL"]))
        self.end_s = end
        self.set_profile(self.profile.switched(t_now, rest), period_s)
        self._plan_key = key

    def absorb(self, following: Move, axes: dict[int, Axis], period_s: Fraction) -> bool:
        """``MERGE = ON``: take the buffered linear move ``following`` (same axes) into this one, so the axes do
        not stop in between: one path of two lines, re-planned from the state now to the end of both at the
        base axis' SPEED, ACCEL and DECEL. Refused (False) for other kinds of move, or once this one
        decelerates."""
        if (self.kind not in ("MOVE", "MOVEABS") or following.kind not in ("MOVE", "MOVEABS") or self.cancelling
                or self.cancel_requested or self.modify_to is not None or self.done or self.profile is None
                or self.end_s is None):
            return False
        t_now = self.cycles * period_s
        if self.profile.accel(t_now) < 0:
            return False
        assert self.path is not None and not isinstance(self.path, ArcPath | RayPath)
        ends = [start / units + d for start, units, d in zip(self.start_counts, self.units, self.path.deltas,
                                                              strict=True)]
        origins = [axes[a].origin / axes[a].units for a in self.axes]
        second = tuple(v - (end - o) if following.kind == "MOVEABS" else v
                       for v, end, o in zip(following.values, ends, origins, strict=True))
        segments = (self.path.segments if isinstance(self.path, PolylinePath) else (self.path.deltas,)) + (second,)
        merged = PolylinePath(segments)
        s_now, v_now = self.profile.position(t_now), self.profile.speed(t_now)
        base = axes[self.axes[0]]
        rest = plan_from(merged.length - s_now, v0=v_now, speed=Fraction(base.params["SPEED"]),
                         accel=Fraction(base.params["ACCEL"]), decel=Fraction(base.params["DECEL"]))
        self.path, self.end_s = merged, merged.length
        self.set_profile(self.profile.switched(t_now, rest), period_s)
        return True

    def advance(self) -> None:
        """One servo cycle: the demands at its end (:attr:`nums` / :attr:`dens` [counts]) and its path speed."""
        cycle = self._cycle
        assert cycle is not None
        k = self.cycles = self.cycles + 1
        p = cycle.numerator(k)
        tp, tq = self._period
        self.v_num, self.v_den = (p - self._p_prev) * tq, cycle.den * tp
        self._p_prev = p
        self.done = cycle.k_end is not None and k >= cycle.k_end
        straight = self._straight
        if straight is not None:
            self.nums = [s + g * p for s, g, _ in straight]
            self.dens = [e for _, _, e in straight]
            if len(straight) < len(self.axes):  # axes of the group a path does not move
                for start in self.start_counts[len(straight):]:
                    self.nums.append(start.numerator)
                    self.dens.append(start.denominator)
            return
        arc = self._arc
        if arc is not None:  # an arc's cycle in integers: demand_i = (N_i + M_i cs_i) / E_i, cs = cos, sin
            cs = ArcPath.cos_sin_at(p, arc[0])
            if cs is not None:
                (n0, m0, e0), (n1, m1, e1) = arc[1]
                self.nums = [n0 + m0 * cs[0], n1 + m1 * cs[1]]
                self.dens = [e0, e1]
                for start in self.start_counts[2:]:
                    self.nums.append(start.numerator)
                    self.dens.append(start.denominator)
                return
        assert self.path is not None
        offsets = self.path.offset(Fraction(p, cycle.den))
        demands = [start + offset * units for start, offset, units in
                   zip(self.start_counts, offsets, self.units, strict=False)]
        demands += list(self.start_counts[len(demands):])
        self.nums = [d.numerator for d in demands]
        self.dens = [d.denominator for d in demands]


def _arc_terms(path: ArcPath, start_counts: tuple[Fraction, ...], units: tuple[Fraction, ...], den: int
               ) -> tuple[tuple[int, int, int, int, int], tuple[tuple[int, int, int], ...]]:
    """The integers of an arc's demands at ``s = p / den``: with ``cs = (cos, sin) = x / 2**RESULT_BITS``
    (:meth:`ArcPath.cos_sin_at`), axis ``i``'s demand ``start_i + (centre_i + r cs_i) units_i`` [counts] is
    ``(N_i + M_i x_i) / E_i``, exactly the value :meth:`ArcPath.offset` gives."""
    axes = []
    for start, centre, unit in zip(start_counts, path.centre, units, strict=False):
        a = start + centre * unit
        b = path.radius * unit / (1 << RESULT_BITS)
        e = lcm(a.denominator, b.denominator)
        axes.append((a.numerator * (e // a.denominator), b.numerator * (e // b.denominator), e))
    return path.cycle_terms(den), tuple(axes)


def _speed_range(profile: Piecewise) -> tuple[Fraction, Fraction]:
    """The largest and the smallest path speed of ``profile`` [units/s] (at piece ends and speed extremes)."""
    times = profile.breakpoints()
    for i, (t0, poly) in enumerate(profile.pieces):
        if len(poly) == 4 and poly[3]:  # a cubic piece: the speed has a vertex
            vertex = -poly[2] / (3 * poly[3])
            t1 = profile.pieces[i + 1][0] if i + 1 < len(profile.pieces) else profile.t_end
            if vertex > t0 and (t1 is None or vertex < t1):
                times.append(vertex)
    speeds = [profile.speed(t) for t in times] + [profile.speed(t - Fraction(1, 10**30)) for t in times if t > 0]
    return max(abs(v) for v in speeds), min(speeds)
