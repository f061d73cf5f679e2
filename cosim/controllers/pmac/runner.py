"""Running a coordinate system's program segments, one servo cycle at a time, in integers.

:class:`ProgramRunner` holds the time into the current segment as a whole number of steps and
asks the segment's paths (:mod:`.paths`) for positions as ratios of integers; segments come from
:func:`.motion.compile_item`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from fractions import Fraction

from cosim.controllers.pmac.motion import Item, Segment, compile_items
from cosim.controllers.pmac.units import UNITS_PER_MS


class ProgramRunner:
    """Runs compiled segments, advanced once per servo cycle, in integers.

    Segments may be appended while it runs (a motion program calculates ahead): the list is
    shared with a second runner advanced by another clock (the coordinate system's ideal,
    master-derived one). A segment that ends with nothing queued after it loses its overrun.

    The time into the current segment is ``m / scale`` time-base units (2^-23 ms) with integers
    ``m`` and ``scale``: ``scale`` is 1 unless time carried over from the segment before has a
    denominator (a move whose length is not a whole number of units), and each cycle adds
    ``value * scale`` to ``m``. Positions are read as exact ratios of integers
    (:meth:`position_ratio`, from each path's ``ratio``).

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
            path = self.segments[self.index].path(axis)
            if path is not None:
                return path.ratio(self._m, self._scale * UNITS_PER_MS)
        held = self._held.get(axis)
        if held is None:
            return 0, 1
        return held.numerator, held.denominator
