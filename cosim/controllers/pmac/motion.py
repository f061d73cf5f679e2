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
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction

from cosim import validate
from cosim.controllers.pmac.pieces import IntegerPieces, Piece, scale
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
    """RAPID: each axis to its target on its own profile (not coordinated)."""

    axes: Mapping[str, RapidAxis]


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


Item = LinearMove | Move | RapidMove | Delay | Dwell


@dataclass(frozen=True)
class AxisPath:
    """What one axis does in a segment: from ``start`` to ``target`` along ``profile``.

    The axis is at ``start + (target - start) * travelled / profile.distance`` (a LINEAR move of
    several axes shares one profile over the path length).
    """

    axis: str
    start: Fraction
    target: Fraction
    profile: Profile

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
    paths: tuple[AxisPath, ...] = ()
    _integer: dict[tuple[str, int], IntegerPieces] = field(default_factory=dict, compare=False, repr=False)

    @property
    def axis(self) -> str | None:
        """The (first) moving axis, None for holds."""
        return self.paths[0].axis if self.paths else None

    @property
    def target(self) -> Fraction:
        """Target of the first axis [axis units]."""
        return self.paths[0].target if self.paths else Fraction(0)

    @property
    def speed(self) -> Fraction:
        """Plateau speed of the first axis's profile [units/ms]."""
        return self.paths[0].profile.speed if self.paths else Fraction(0)

    @property
    def ta_ms(self) -> Fraction:
        """Acceleration time of the first axis's profile [ms]."""
        return self.paths[0].profile.accel_ms if self.paths else Fraction(0)

    @property
    def move_ms(self) -> Fraction:
        """Move time of the first axis's profile [ms]."""
        return self.paths[0].profile.move_ms if self.paths else Fraction(0)

    def position(self, tau_ms: Fraction, axis: str | None = None) -> Fraction:
        """Position of ``axis`` (default: the first moving axis) at ``tau_ms`` into the segment (exact)."""
        for path in self.paths:
            if axis is None or path.axis == axis:
                return path.position(tau_ms)
        raise ConfigurationError.out_of_range("axis of Segment.position", axis, ", ".join(p.axis for p in self.paths))

    def integer_pieces(self, axis: str, scale_units: int) -> IntegerPieces | None:
        """``axis``'s position for elapsed times of ``m / scale_units`` time-base units (None: not moving here)."""
        key = (axis, scale_units)
        found = self._integer.get(key)
        if found is None:
            path = next((p for p in self.paths if p.axis == axis), None)
            if path is None:
                return None
            found = self._integer[key] = IntegerPieces(path.pieces(), scale_units * UNITS_PER_MS)
        return found


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
        return Segment(False, profile.total_ms * UNITS_PER_MS, paths)
    if isinstance(item, RapidMove):
        _check_axes(item.axes, current, "RAPID move")
        paths = tuple(AxisPath(a, current[a], r.target,
                               Profile.plan(abs(r.target - current[a]), ta_ms=r.ta_ms, ts_ms=r.ts_ms, speed=r.speed))
                      for a, r in item.axes.items())
        current.update({a: r.target for a, r in item.axes.items()})
        longest = max((p.profile.total_ms for p in paths), default=Fraction(0))
        return Segment(False, longest * UNITS_PER_MS, paths)
    if isinstance(item, Delay):
        return Segment(False, Fraction(item.ms) * UNITS_PER_MS)
    if isinstance(item, Dwell):
        return Segment(True, Fraction(item.ms) * UNITS_PER_MS)
    raise ConfigurationError(f"program item {item!r} is not a LinearMove, Move, RapidMove, Delay or Dwell")


def compile_items(items: Iterable[Item], positions: Mapping[str, Fraction]) -> list[Segment]:
    """Turn program items into segments, starting from ``positions`` [axis units]."""
    current = dict(positions)
    return [compile_item(item, current) for item in items]


class ProgramRunner:
    """Runs compiled segments, advanced once per servo cycle, in integers.

    Segments may be appended while it runs (a motion program calculates ahead): the list is
    shared with a second runner advanced by another clock (the coordinate system's ideal,
    master-derived one). A segment that ends with nothing queued after it loses its overrun.

    The time into the current segment is ``m / scale`` time-base units (2^-23 ms) with integers
    ``m`` and ``scale``: ``scale`` is 1 unless time carried over from the segment before has a
    denominator (a move whose length is not a whole number of units), and each cycle adds
    ``value * scale`` to ``m``. Positions are read as exact ratios of integers
    (:meth:`position_ratio`, from :meth:`Segment.integer_pieces`).

    Parameters
    ----------
    segments : list of Segment
        The program's segments (appended to as the program is calculated).
    positions : mapping
        Starting position of every axis of the coordinate system [axis units].
    """

    def __init__(self, segments: list[Segment], positions: Mapping[str, Fraction]) -> None:
        self.segments = segments
        self.positions = positions
        self.index = 0
        self._m = 0
        self._scale = 1
        self._limit: int | None = None  # ceil(duration * scale) of the current segment, once known
        self._held = dict(positions)

    @classmethod
    def of(cls, items: Iterable[Item], positions: Mapping[str, Fraction]) -> ProgramRunner:
        """A runner over ``items`` compiled from ``positions``."""
        return cls(compile_items(items, positions), positions)

    @property
    def local_units(self) -> Fraction:
        """Time into the current segment [2^-23 ms] (exact)."""
        return Fraction(self._m, self._scale)

    @property
    def done(self) -> bool:
        """True once every queued segment has finished."""
        return self.index >= len(self.segments)

    @property
    def in_dwell(self) -> bool:
        """True while the current segment is a DWELL."""
        return self.index < len(self.segments) and self.segments[self.index].real_time

    def queued_ahead(self) -> int:
        """Segments not finished yet (the current one included) that take time or wait in real time."""
        return sum(1 for s in self.segments[self.index:] if s.real_time or s.duration_units > 0)

    def advance(self, timebase_units: int, real_units: int) -> None:
        """Advance by one servo cycle: ``timebase_units`` (time base) or ``real_units`` (I10) in a dwell."""
        segments = self.segments
        if self.index >= len(segments):
            return
        segment = segments[self.index]
        m = self._m + (real_units if segment.real_time else timebase_units) * self._scale
        if m < 0:
            m = 0
        limit = self._limit
        if limit is None:
            exact = segment.duration_units * self._scale
            limit = self._limit = -((-exact.numerator) // exact.denominator)
        self._m = m
        if m >= limit:
            self._next_segments()

    def _next_segments(self) -> None:
        """The current segment has ended (``m >= limit``): go on, carrying the overrun (exact, once per segment)."""
        local = Fraction(self._m, self._scale)
        segment = self.segments[self.index]
        while local >= segment.duration_units:
            leftover = local - segment.duration_units
            for path in segment.paths:
                self._held[path.axis] = path.target
            self.index += 1
            if self.done:
                local = Fraction(0)
                break
            carry = not segment.real_time and not self.segments[self.index].real_time
            segment = self.segments[self.index]
            local = leftover if carry else Fraction(0)
        self._m, self._scale, self._limit = local.numerator, local.denominator, None

    def position(self, axis: str) -> Fraction:
        """Commanded position of ``axis`` now [axis units] (exact)."""
        numerator, denominator = self.position_ratio(axis)
        return Fraction(numerator, denominator)

    def position_ratio(self, axis: str) -> tuple[int, int]:
        """Commanded position of ``axis`` now as ``(numerator, denominator)`` integers [axis units]."""
        if self.index < len(self.segments):
            pieces = self.segments[self.index].integer_pieces(axis, self._scale)
            if pieces is not None:
                return pieces.numerator(self._m), pieces.denominator
        held = self._held.get(axis)
        if held is None:
            return 0, 1
        return held.numerator, held.denominator
