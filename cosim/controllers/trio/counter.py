"""Counters fed by the step pulses of one servo-cycle segment at a time.

The step output of a servo cycle is one segment ``(t0, duration, count, sign)`` whose pulse ``k``
is at ``t0 + (k * duration) // count`` (the rule of :mod:`cosim.pulses`). A :class:`StepCounter`
knows its value before the current segment, so its value at any instant of the cycle is exact
without an event per pulse. A pulse at exactly ``t`` has happened at ``t`` (it precedes any
command at that instant).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from cosim.pulses import materialize_pulses


def pulses_until(t0: int, duration: int, count: int, t: int) -> int:
    """How many pulses of a segment happen at or before tick ``t``.

    Examples
    --------
    >>> [pulses_until(0, 1000, 3, t) for t in (-1, 0, 332, 333, 666, 999)]
    [0, 1, 1, 2, 3, 3]
    """
    if count <= 0 or t < t0:
        return 0
    elapsed = t - t0
    # pulse k is at t0 + floor(k*duration/count) <= t  <=>  k*duration < (elapsed+1)*count
    return min(count, -((-(elapsed + 1) * count) // duration))


class StepCounter:
    """An up/down count of step pulses (unwrapped Python int), exact at every tick.

    Parameters
    ----------
    value : int
        Initial count.
    """

    def __init__(self, value: int = 0) -> None:
        self._before = value
        self.t0 = 0
        self.duration = 1
        self.count = 0
        self.sign = 1
        self._times: npt.NDArray[np.int64] | None = None

    def feed(self, t0: int, duration: int, count: int, sign: int) -> None:
        """Start counting a new segment (the previous one must be over by ``t0``)."""
        self._before = self.end_value
        self.t0, self.duration, self.count, self.sign = t0, duration, count, sign
        self._times = None

    @property
    def end_value(self) -> int:
        """The count once every pulse of the current segment has happened."""
        return self._before + self.sign * self.count

    def happened(self, t: int) -> int:
        """Pulses of the current segment at or before ``t``."""
        return pulses_until(self.t0, self.duration, self.count, t)

    def value(self, t: int) -> int:
        """The count at tick ``t`` (pulses at ``t`` included)."""
        return self._before + self.sign * self.happened(t)

    def after_pulse(self, k: int) -> int:
        """The count right after pulse ``k`` of the current segment."""
        return self._before + self.sign * (k + 1)

    def set_value(self, t: int, value: int) -> None:
        """Make the count ``value`` at ``t`` (later pulses of the segment still count)."""
        self._before += value - self.value(t)

    def times(self) -> npt.NDArray[np.int64]:
        """Exact instants of the current segment's pulses (materialised once, with numpy)."""
        if self._times is None:
            self._times = materialize_pulses([self.t0], [self.duration], [self.count])
        return self._times
