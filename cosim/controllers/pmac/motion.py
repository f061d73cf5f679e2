"""Moves of a coordinate system, evaluated at an elapsed time advanced by the time base.

Every servo cycle the coordinate system adds its time-base value (2^-23 ms units) to the
elapsed time of the current move; positions are exact functions (:class:`~fractions.Fraction`)
of that time, so a move under external time base is an exact function of master travel.

* :class:`LinearMove` -- LINEAR with feedrate F [units/s, Ix90 = 1000 ms] and acceleration time
  TA [ms] (TS = 0, no blending: each move starts and ends at rest). The move time is
  ``max(distance / F, TA)`` (a short move spends its whole time accelerating, the manual's
  triangular profile) plus TA to decelerate to a stop.
* :class:`Delay` -- DELAY: holds position for a time that runs with the time base.
* :class:`Dwell` -- DWELL: holds position for a time in *real* time (I10 per servo cycle),
  whatever the time base; under external time base it breaks synchronism with the master.

Carry rules: the part of a cycle's time-base value that overruns a time-base segment carries
into the next time-base segment; a dwell starts and ends on servo cycles (no carry across it).
A negative time base never moves a segment before its start.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction

from cosim import validate
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
    """

    target: Number
    feedrate: Number
    ta_ms: Number = 10
    axis: str = "X"

    def __post_init__(self) -> None:
        object.__setattr__(self, "target", validate.exact(self.target, "target"))
        object.__setattr__(self, "feedrate", validate.positive(self.feedrate, "F (feedrate)", unit="axis units/s"))
        object.__setattr__(self, "ta_ms", validate.positive(self.ta_ms, "TA (ta_ms)", unit="ms", zero=True))


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


Item = LinearMove | Delay | Dwell


@dataclass(frozen=True)
class Segment:
    """One compiled program segment.

    Attributes
    ----------
    real_time : bool
        True for a dwell (advances by I10 per cycle), False for time-base segments.
    duration_units : Fraction
        Length [2^-23 ms].
    axis : str or None
        Moving axis (None for holds).
    start, target : Fraction
        Positions [axis units].
    speed : Fraction
        Plateau speed [axis units/ms] after the short-move rule.
    ta_ms, move_ms : Fraction
        Acceleration time and move time (boundary to boundary) [ms].
    """

    real_time: bool
    duration_units: Fraction
    axis: str | None = None
    start: Fraction = Fraction(0)
    target: Fraction = Fraction(0)
    speed: Fraction = Fraction(0)
    ta_ms: Fraction = Fraction(0)
    move_ms: Fraction = Fraction(0)

    def position(self, tau_ms: Fraction) -> Fraction:
        """Axis position at ``tau_ms`` into the segment [axis units] (exact)."""
        if self.axis is None or tau_ms <= 0:
            return self.start
        total = self.move_ms + self.ta_ms
        if tau_ms >= total:
            return self.target
        sign = 1 if self.target >= self.start else -1
        v, ta = self.speed, self.ta_ms
        if ta == 0:
            return self.start + sign * v * tau_ms
        if tau_ms < ta:
            return self.start + sign * v * tau_ms * tau_ms / (2 * ta)
        if tau_ms <= self.move_ms:
            return self.start + sign * v * (ta / 2 + tau_ms - ta)
        rest = total - tau_ms
        return self.target - sign * v * rest * rest / (2 * ta)


def compile_items(items: Iterable[Item], positions: Mapping[str, Fraction]) -> list[Segment]:
    """Turn program items into segments, starting from ``positions`` [axis units]."""
    current = dict(positions)
    segments: list[Segment] = []
    for item in items:
        if isinstance(item, LinearMove):
            if item.axis not in current:
                raise ConfigurationError.out_of_range("axis of LINEAR move", item.axis, ", ".join(current) or "none")
            start, target = current[item.axis], Fraction(item.target)
            distance = abs(target - start)
            speed = Fraction(item.feedrate) / 1000
            ta = Fraction(item.ta_ms)
            move_ms = max(distance / speed, ta)
            plateau = distance / move_ms if move_ms > 0 else Fraction(0)
            segments.append(Segment(False, (move_ms + ta) * UNITS_PER_MS, item.axis, start, target, plateau, ta,
                                    move_ms))
            current[item.axis] = target
        elif isinstance(item, Delay):
            segments.append(Segment(False, Fraction(item.ms) * UNITS_PER_MS))
        elif isinstance(item, Dwell):
            segments.append(Segment(True, Fraction(item.ms) * UNITS_PER_MS))
        else:
            raise ConfigurationError(f"program item {item!r} is not a LinearMove, Delay or Dwell")
    return segments


class ProgramRunner:
    """Runs compiled segments, advanced once per servo cycle.

    Parameters
    ----------
    items : iterable of LinearMove, Delay, Dwell
    positions : mapping
        Starting position of every axis of the coordinate system [axis units].
    """

    def __init__(self, items: Iterable[Item], positions: Mapping[str, Fraction]) -> None:
        self.segments = compile_items(items, positions)
        self.index = 0
        self.local_units = Fraction(0)
        self._held = dict(positions)

    @property
    def done(self) -> bool:
        """True once every segment has finished."""
        return self.index >= len(self.segments)

    @property
    def in_dwell(self) -> bool:
        """True while the current segment is a DWELL."""
        return not self.done and self.segments[self.index].real_time

    def advance(self, timebase_units: int, real_units: int) -> None:
        """Advance by one servo cycle: ``timebase_units`` (time base) or ``real_units`` (I10) in a dwell."""
        if self.done:
            return
        segment = self.segments[self.index]
        self.local_units = max(Fraction(0), self.local_units + (real_units if segment.real_time else timebase_units))
        while self.local_units >= segment.duration_units:
            leftover = self.local_units - segment.duration_units
            if segment.axis is not None:
                self._held[segment.axis] = segment.target
            self.index += 1
            if self.done:
                self.local_units = Fraction(0)
                return
            carry = not segment.real_time and not self.segments[self.index].real_time
            segment = self.segments[self.index]
            self.local_units = leftover if carry else Fraction(0)

    def position(self, axis: str) -> Fraction:
        """Commanded position of ``axis`` now [axis units]."""
        if not self.done:
            segment = self.segments[self.index]
            if segment.axis == axis:
                return segment.position(self.local_units / UNITS_PER_MS)
        return self._held[axis]
