"""Moves of a coordinate system, evaluated at an elapsed time advanced by the time base.

Every servo cycle the coordinate system adds its time-base value (2^-23 ms units) to the
elapsed time of the current move; positions are exact functions (:class:`~fractions.Fraction`)
of that time, so a move under external time base is an exact function of master travel.

* :class:`LinearMove` -- LINEAR of one axis with feedrate F [units/s, Ix90 = 1000 ms],
  acceleration time TA and S-curve time TS [ms]; :class:`Move` -- the same for any set of axes,
  with F (vector feedrate over every axis of the move) or a move time TM. No blending: each move
  starts and ends at rest; its profile is :class:`~cosim.controllers.pmac.profile.Profile`.
* :class:`RapidMove` -- RAPID: every axis on its own profile at its motor's jog speed (Ixx22)
  with its jog TA/TS (Ixx20, Ixx21); the move ends when the last axis stops.
* :class:`Delay` -- DELAY: holds position for a time that runs with the time base.
* :class:`Dwell` -- DWELL: holds position for a time in *real* time (I10 per servo cycle),
  whatever the time base; under external time base it breaks synchronism with the master.

Carry rules: the part of a cycle's time-base value that overruns a time-base segment carries
into the next time-base segment; a dwell starts and ends on servo cycles (no carry across it).
A negative time base never moves a segment before its start.

A multi-axis LINEAR move's path length is ``sqrt(sum of squares)``: exact when it is rational,
otherwise truncated to ``2^-32`` axis units (a deterministic stand-in for the controller's
floating-point square root); one axis is always exact.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction

from cosim import validate
from cosim.controllers.pmac.paths import Arc, AxisPath, CirclePath, HermitePath, Path, SampledPath
from cosim.controllers.pmac.profile import Profile
from cosim.controllers.pmac.units import UNITS_PER_MS
from cosim.errors import ConfigurationError

Number = int | Fraction


@dataclass(frozen=True)
class LinearMove:
    """LINEAR move of one axis to an absolute target.

    Parameters
    ----------
    target : int or Fraction
        End position [axis units] (a float is taken as the decimal it prints as, see :mod:`cosim.validate`).
    feedrate : int or Fraction
        F [axis units/s] (Ix90 = 1000 ms), > 0.
    ta_ms : int or Fraction
        TA, acceleration time [ms], >= 0.
    axis : str
        Axis letter of the coordinate system.
    ts_ms : int or Fraction
        TS, S-curve time [ms], >= 0 (the acceleration takes ``max(TA, 2 TS)``).
    """

    target: Number
    feedrate: Number
    ta_ms: Number = 10
    axis: str = "X"
    ts_ms: Number = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "target", validate.exact(self.target, "target"))
        object.__setattr__(self, "feedrate", validate.positive(self.feedrate, "F (feedrate)", unit="axis units/s"))
        object.__setattr__(self, "ta_ms", validate.positive(self.ta_ms, "TA (ta_ms)", unit="ms", zero=True))
        object.__setattr__(self, "ts_ms", validate.positive(self.ts_ms, "TS (ts_ms)", unit="ms", zero=True))


@dataclass(frozen=True)
class Move:
    """LINEAR move of several axes to absolute targets, at a vector feedrate or in a move time.

    Parameters
    ----------
    targets : mapping axis -> target
        End positions [axis units].
    feedrate : int or Fraction, optional
        F [axis units/s] along the path, > 0.
    tm_ms : int or Fraction, optional
        TM, move time [ms], >= 0 (exactly one of ``feedrate`` and ``tm_ms``).
    ta_ms, ts_ms : int or Fraction
        TA and TS [ms], >= 0.
    """

    targets: Mapping[str, Number]
    feedrate: Number | None = None
    tm_ms: Number | None = None
    ta_ms: Number = 10
    ts_ms: Number = 0
    followers: Mapping[str, Fraction] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if (self.feedrate is None) == (self.tm_ms is None):
            raise ConfigurationError("a LINEAR move takes a feedrate F or a move time TM (exactly one)")
        object.__setattr__(self, "targets", {a: validate.exact(v, f"{a} target") for a, v in self.targets.items()})
        if self.feedrate is not None:
            object.__setattr__(self, "feedrate", validate.positive(self.feedrate, "F (feedrate)",
                                                                   unit="axis units/s"))
        if self.tm_ms is not None:
            object.__setattr__(self, "tm_ms", validate.positive(self.tm_ms, "TM (move time)", unit="ms", zero=True))
        object.__setattr__(self, "ta_ms", validate.positive(self.ta_ms, "TA", unit="ms", zero=True))
        object.__setattr__(self, "ts_ms", validate.positive(self.ts_ms, "TS", unit="ms", zero=True))


@dataclass(frozen=True)
class RapidAxis:
    """One axis of a RAPID move: target [units], speed [units/ms] (> 0), TA and TS [ms]."""

    target: Fraction
    speed: Fraction
    ta_ms: Fraction
    ts_ms: Fraction


@dataclass(frozen=True)
class RapidMove:
    """RAPID: each axis to its target on its own profile (not coordinated); followers on the longest one."""

    axes: Mapping[str, RapidAxis]
    followers: Mapping[str, Fraction] = field(default_factory=dict)


@dataclass(frozen=True)
class PvtMove:
    """PVT / SPLINE1: each axis from its position and velocity ``v0`` to ``targets`` at ``v1`` in ``t_ms``.

    Velocities in axis units/ms. Followers (kinematic motors) move linearly in time.
    """

    targets: Mapping[str, Fraction]
    v0: Mapping[str, Fraction]
    v1: Mapping[str, Fraction]
    t_ms: Fraction
    followers: Mapping[str, Fraction] = field(default_factory=dict)


@dataclass(frozen=True)
class CircleMove:
    """CIRCLE1 (clockwise) / CIRCLE2: an arc in the plane ``plane`` (two axes), other axes helical.

    The centre is given as ``centre`` (the vector from the start point to it, in the plane's axes)
    or as ``radius`` (> 0: the short arc, < 0: the long one). Speed F [units/s] along the path, or
    move time TM, with TA and TS as a LINEAR move.
    """

    targets: Mapping[str, Fraction]
    plane: tuple[str, str]
    clockwise: bool
    centre: tuple[Fraction, Fraction] | None = None
    radius: Fraction | None = None
    feedrate: Fraction | None = None
    tm_ms: Fraction | None = None
    ta_ms: Fraction = Fraction(10)
    ts_ms: Fraction = Fraction(0)
    followers: Mapping[str, Fraction] = field(default_factory=dict)


@dataclass(frozen=True)
class Delay:
    """DELAY: hold for ``ms`` of time-base time [ms]."""

    ms: Number

    def __post_init__(self) -> None:
        object.__setattr__(self, "ms", validate.positive(self.ms, "DELAY time", unit="ms", zero=True))


@dataclass(frozen=True)
class Dwell:
    """DWELL: hold for ``ms`` of real time [ms] (not scaled by the time base)."""

    ms: Number

    def __post_init__(self) -> None:
        object.__setattr__(self, "ms", validate.positive(self.ms, "DWELL time", unit="ms", zero=True))


@dataclass(frozen=True)
class Segmented:
    """A move whose kinematic motors follow ``inverse`` of the axis positions every ``segment_ms`` (Isx13).

    ``inverse`` takes every axis position [axis units] and returns the kinematic motors' counts
    (``#n`` keys); between segment points the motors move in straight lines.
    """

    item: LinearMove | Move | RapidMove | PvtMove | CircleMove
    segment_ms: Fraction
    inverse: Callable[[dict[str, Fraction]], dict[str, Fraction]]


Item = LinearMove | Move | RapidMove | PvtMove | CircleMove | Delay | Dwell | Segmented


@dataclass(frozen=True)
class Segment:
    """One compiled program segment.

    Attributes
    ----------
    real_time : bool
        True for a dwell (advances by I10 per cycle), False for time-base segments.
    duration_units : Fraction
        Length [2^-23 ms].
    paths : tuple of AxisPath
        The moving axes (empty for holds).
    """

    real_time: bool
    duration_units: Fraction
    paths: tuple[Path, ...] = ()
    _by_axis: dict[str, Path] = field(default_factory=dict, compare=False, repr=False, init=False)

    def __post_init__(self) -> None:
        self._by_axis.update({p.axis: p for p in reversed(self.paths)})

    def path(self, axis: str) -> Path | None:
        """The path of ``axis`` in this segment (None: it does not move here)."""
        return self._by_axis.get(axis)

    @property
    def axis(self) -> str | None:
        """The (first) moving axis, None for holds."""
        return self.paths[0].axis if self.paths else None

    @property
    def target(self) -> Fraction:
        """Target of the first axis [axis units]."""
        return self.paths[0].target if self.paths else Fraction(0)

    @property
    def profile(self) -> Profile | None:
        """The first axis's profile (None for holds and PVT/spline segments)."""
        return getattr(self.paths[0], "profile", None) if self.paths else None

    @property
    def speed(self) -> Fraction:
        """Plateau speed of the first axis's profile [units/ms]."""
        return self.profile.speed if self.profile is not None else Fraction(0)

    @property
    def ta_ms(self) -> Fraction:
        """Acceleration time of the first axis's profile [ms]."""
        return self.profile.accel_ms if self.profile is not None else Fraction(0)

    @property
    def move_ms(self) -> Fraction:
        """Move time of the first axis's profile [ms]."""
        return self.profile.move_ms if self.profile is not None else Fraction(0)

    def position(self, tau_ms: Fraction, axis: str | None = None) -> Fraction:
        """Position of ``axis`` (default: the first moving axis) at ``tau_ms`` into the segment (exact)."""
        for path in self.paths:
            if axis is None or path.axis == axis:
                return path.position(tau_ms)
        raise ConfigurationError.out_of_range("axis of Segment.position", axis, ", ".join(p.axis for p in self.paths))


def path_length(deltas: Iterable[Fraction]) -> Fraction:
    """``sqrt(sum of squares)``: exact if rational, else truncated to 2^-32 [axis units]."""
    squares = sum((d * d for d in deltas), Fraction(0))
    num, den = squares.numerator, squares.denominator
    root_num, root_den = math.isqrt(num), math.isqrt(den)
    if root_num * root_num == num and root_den * root_den == den:
        return Fraction(root_num, root_den)
    return Fraction(math.isqrt(num * (1 << 64) // den), 1 << 32)


def _check_axes(axes: Iterable[str], current: Mapping[str, Fraction], what: str) -> None:
    for axis in axes:
        if axis not in current:
            raise ConfigurationError.out_of_range(f"axis of {what}", axis, ", ".join(current) or "none")


def compile_item(item: Item, current: dict[str, Fraction]) -> Segment:
    """One item as a segment starting from ``current`` [axis units]; updates ``current`` to its end."""
    if isinstance(item, LinearMove):
        item = Move({item.axis: item.target}, feedrate=item.feedrate, ta_ms=item.ta_ms, ts_ms=item.ts_ms)
    if isinstance(item, Move):
        _check_axes(item.targets, current, "LINEAR move")
        targets = {axis: Fraction(t) for axis, t in item.targets.items()}
        distance = path_length(t - current[a] for a, t in targets.items())
        speed = Fraction(item.feedrate) / 1000 if item.feedrate is not None else None
        profile = Profile.plan(distance, ta_ms=Fraction(item.ta_ms), ts_ms=Fraction(item.ts_ms), speed=speed,
                               tm_ms=None if item.tm_ms is None else Fraction(item.tm_ms))
        paths = tuple(AxisPath(a, current[a], t, profile) for a, t in targets.items())
        current.update(targets)
        return Segment(False, profile.total_ms * UNITS_PER_MS, paths + _followers(item.followers, profile, current))
    if isinstance(item, RapidMove):
        _check_axes(item.axes, current, "RAPID move")
        paths = tuple(AxisPath(a, current[a], r.target,
                               Profile.plan(abs(r.target - current[a]), ta_ms=r.ta_ms, ts_ms=r.ts_ms, speed=r.speed))
                      for a, r in item.axes.items())
        current.update({a: r.target for a, r in item.axes.items()})
        longest = max((p.profile for p in paths), key=lambda p: p.total_ms, default=None)
        followers = _followers(item.followers, longest, current) if longest is not None else ()
        return Segment(False, (longest.total_ms if longest is not None else Fraction(0)) * UNITS_PER_MS,
                       paths + followers)
    if isinstance(item, PvtMove):
        _check_axes(item.targets, current, "PVT/SPLINE move")
        t = item.t_ms
        pvt: tuple[Path, ...] = tuple(HermitePath(a, current[a], target, item.v0.get(a, Fraction(0)),
                                                  item.v1.get(a, Fraction(0)), t) for a, target in item.targets.items())
        pvt += tuple(HermitePath(a, current.get(a, Fraction(0)), target, (target - current.get(a, Fraction(0))) / t,
                                 (target - current.get(a, Fraction(0))) / t, t) for a, target in item.followers.items())
        current.update(item.targets)
        current.update(item.followers)
        return Segment(False, t * UNITS_PER_MS, pvt)
    if isinstance(item, CircleMove):
        return compile_circle(item, current)
    if isinstance(item, Segmented):
        return compile_segmented(item, current)
    if isinstance(item, Delay):
        return Segment(False, Fraction(item.ms) * UNITS_PER_MS)
    if isinstance(item, Dwell):
        return Segment(True, Fraction(item.ms) * UNITS_PER_MS)
    raise ConfigurationError(f"program item {item!r} is not a LinearMove, Move, RapidMove, Delay or Dwell")


def _followers(followers: Mapping[str, Fraction], profile: Profile, current: dict[str, Fraction]
               ) -> tuple[Path, ...]:
    """Kinematic motors of a move: each from its count now to its end count along the move's profile."""
    paths = tuple(AxisPath(name, current.get(name, Fraction(0)), target, profile) for name, target in followers.items())
    current.update(followers)
    return paths


def _arc(item: CircleMove, start: tuple[Fraction, Fraction], end: tuple[Fraction, Fraction]) -> Arc:
    """The arc from ``start`` to ``end`` (plane coordinates) about the item's centre or with its radius."""
    sx, sy = float(start[0]), float(start[1])
    ex, ey = float(end[0]), float(end[1])
    direction = -1.0 if item.clockwise else 1.0
    if item.centre is not None:
        cx, cy = sx + float(item.centre[0]), sy + float(item.centre[1])
    else:
        assert item.radius is not None
        r = abs(float(item.radius))
        mx, my = (sx + ex) / 2, (sy + ey) / 2
        half = math.hypot(ex - sx, ey - sy) / 2
        if half == 0 or half > r * (1 + 1e-12):
            raise ConfigurationError(f"CIRCLE with R{item.radius}: the end point is {2 * half:.6g} units from the "
                                     f"start, farther than the diameter {2 * r:.6g}")
        h = math.sqrt(max(r * r - half * half, 0.0))
        ux, uy = (ex - sx) / (2 * half), (ey - sy) / (2 * half)
        side = direction * (1.0 if item.radius > 0 else -1.0)  # the short arc turns the centre to this side
        cx, cy = mx - side * h * uy, my + side * h * ux
    r0, r1 = math.hypot(sx - cx, sy - cy), math.hypot(ex - cx, ey - cy)
    if r0 == 0:
        raise ConfigurationError("CIRCLE: the centre is the start point (radius 0)")
    a0, a1 = math.atan2(sy - cy, sx - cx), math.atan2(ey - cy, ex - cx)
    sweep = (a1 - a0) * direction % (2 * math.pi)
    if sweep < 1e-12 and item.centre is not None:
        sweep = 2 * math.pi  # end = start about a centre: a full circle
    return Arc((cx, cy), a0, direction * sweep, r0, r1)


def compile_circle(item: CircleMove, current: dict[str, Fraction]) -> Segment:
    """A CIRCLE move as a segment: the plane's axes on the arc, the others (and followers) linearly along it."""
    _check_axes(item.targets, current, "CIRCLE move")
    first, second = item.plane
    for axis in item.plane:
        current.setdefault(axis, Fraction(0))
    start = (current[first], current[second])
    end = (item.targets.get(first, current[first]), item.targets.get(second, current[second]))
    arc = _arc(item, start, end)
    linear = {a: t for a, t in item.targets.items() if a not in item.plane}
    arc_length = abs(arc.sweep) * (arc.radius0 + arc.radius1) / 2
    distance = Fraction(math.sqrt(arc_length**2 + sum(float(t - current[a]) ** 2 for a, t in linear.items())))
    speed = item.feedrate / 1000 if item.feedrate is not None else None
    profile = Profile.plan(distance, ta_ms=item.ta_ms, ts_ms=item.ts_ms, speed=speed, tm_ms=item.tm_ms)
    paths: tuple[Path, ...] = (CirclePath(first, start[0], end[0], profile, arc, 0),
                               CirclePath(second, start[1], end[1], profile, arc, 1))
    paths += tuple(AxisPath(a, current[a], t, profile) for a, t in linear.items())
    current.update({first: end[0], second: end[1], **linear})
    return Segment(False, profile.total_ms * UNITS_PER_MS, paths + _followers(item.followers, profile, current))


def compile_segmented(item: Segmented, current: dict[str, Fraction]) -> Segment:
    """A move of a kinematic coordinate system: its axes as usual, its motors through ``inverse`` every segment."""
    before = dict(current)
    inner = compile_item(item.item, current)
    total = inner.duration_units / UNITS_PER_MS
    steps = max(1, math.ceil(total / item.segment_ms)) if total > 0 else 1
    taus = [min(total, item.segment_ms * j) for j in range(1, steps + 1)]
    axes = {a: p for a, p in before.items() if not a.startswith("#")}
    samples: dict[str, list[tuple[Fraction, Fraction]]] = {}
    for tau in taus:
        positions = dict(axes)
        positions.update({p.axis: Fraction(p.position(tau)) for p in inner.paths})
        for motor, counts in item.inverse(positions).items():
            samples.setdefault(motor, []).append((tau, counts))
    motors = tuple(SampledPath(motor, before.get(motor, Fraction(0)), tuple(points))
                   for motor, points in samples.items())
    current.update({p.axis: p.target for p in motors})
    return Segment(inner.real_time, inner.duration_units, inner.paths + motors)


def compile_items(items: Iterable[Item], positions: Mapping[str, Fraction]) -> list[Segment]:
    """Turn program items into segments, starting from ``positions`` [axis units]."""
    current = dict(positions)
    return [compile_item(item, current) for item in items]


