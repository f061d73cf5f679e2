"""Pulse-train timing: minimum spacing, maximum rate, pulses per time slot.

All three read the pulse instants of a pulse train chunk by chunk (:meth:`Trace.pulse_chunks`) and
work on whole chunks at once: no Python loop per pulse, memory bounded by a chunk. Rates are
compared in exact integer arithmetic.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from cosim import validate
from cosim.checks.base import (
    TICKS,
    Check,
    Clock,
    Findings,
    Ints,
    fmt,
    pulse_chunks,
)
from cosim.checks.result import MAX_REPORTED, Number, Violation
from cosim.tracecursor import Int8s, with_previous

if TYPE_CHECKING:
    from cosim.trace import Trace


def _rate_hz(pulses: int, ticks: int, clock: Clock) -> float:
    """``pulses`` per ``ticks`` as a rate [Hz] (inf for zero ticks); for reports only."""
    if ticks == 0:
        return float("inf")
    return float(pulses * clock.timebase.ticks_per_second / ticks)


def _number(x: Fraction) -> Number:
    return x.numerator if x.denominator == 1 else float(x)


@dataclass(frozen=True)
class MinPulseSpacing(Check):
    """Consecutive pulses are at least ``min_spacing`` apart.

    Parameters
    ----------
    signal : str
        A pulse train, e.g. ``pokeys.x.step``.
    min_spacing : int
        Smallest allowed time from one pulse to the next [ticks], >= 1.

    Notes
    -----
    One violation per pulse that comes too early: ``t_ns`` is that pulse, ``value`` the spacing
    to the pulse before it [ns], ``limit`` the minimum spacing [ns]. Measured: ``min_spacing_ns``.

    Examples
    --------
    >>> from cosim.trace import Trace
    >>> trace = Trace()
    >>> trace.declare("dev.x.step", "pulse")
    >>> for t in (0, 1000, 1400, 2400):
    ...     trace.record_pulse("dev.x.step", t, 1)
    >>> result = MinPulseSpacing("dev.x.step", 500).evaluate(trace)
    >>> result.passed, [(v.t_ns, v.value, v.limit) for v in result.violations]
    (False, [(1400, 400, 500)])
    """

    signal: str
    min_spacing: int

    def __post_init__(self) -> None:
        validate.integer(self.min_spacing, "min_spacing", low=1, unit="ticks", kind=TICKS, where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        limit = clock.ns(self.min_spacing)
        found = Findings(self.signal, description=f"{self.signal}: pulses at least {limit} ns apart")
        smallest: int | None = None
        for t, _, base in with_previous(pulse_chunks(trace, self.signal, self)):
            found.checked = base + t.size
            gaps = np.diff(t)
            bad = np.flatnonzero(gaps < self.min_spacing)
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                gap = clock.ns(gaps[i])
                found.violations.append(Violation(
                    clock.t_ns(t[i + 1]), gap, limit,
                    f"pulse {base + i + 1} only {fmt(gap)} ns after pulse {base + i} at {clock.t_ns(t[i])} ns",
                    unit="ns"))
            if gaps.size:
                smallest = int(gaps.min()) if smallest is None else min(smallest, int(gaps.min()))
        if smallest is not None:
            found.measured["min_spacing_ns"] = clock.ns(smallest)
        return found


@dataclass(frozen=True)
class MaxPulseRate(Check):
    """The pulse rate never exceeds ``max_rate_hz``.

    Parameters
    ----------
    signal : str
        A pulse train.
    max_rate_hz : int, float or Fraction
        Highest allowed rate [Hz] (> 0). A float is taken as the decimal it prints as.
    window : int, optional
        Without it, the *instantaneous* rate (1 / spacing of consecutive pulses) is checked, exactly:
        ``spacing * max_rate_hz >= ticks_per_second``. With it [ticks], the *average* rate over every
        window ``[t, t + window)`` that starts at a pulse is checked: it may hold at most
        ``floor(max_rate_hz * window)`` pulses.

    Notes
    -----
    One violation per offending pulse (instantaneous: the pulse that came too early; windowed: the
    pulse that starts an overfull window). ``value`` is the rate [Hz] (``inf`` for two pulses at
    the same tick), ``limit`` is ``max_rate_hz``. Measured: ``max_rate_hz`` (and, with a window,
    ``max_pulses_per_window``).
    """

    signal: str
    max_rate_hz: int | float | Fraction
    window: int | None = None

    def __post_init__(self) -> None:
        validate.positive(self.max_rate_hz, "max_rate_hz", where=self.where)
        if self.window is not None:
            validate.integer(self.window, "window", low=1, unit="ticks", kind=TICKS, where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        chunks = pulse_chunks(trace, self.signal, self)
        rate = validate.positive(self.max_rate_hz, "max_rate_hz", where=self.where)
        limit = _number(rate)
        if self.window is None:
            return self._instantaneous(chunks, rate, limit, clock)
        return self._windowed(chunks, rate, limit, self.window, clock)

    def _instantaneous(self, chunks: Iterable[tuple[Ints, Int8s]], rate: Fraction, limit: Number,
                       clock: Clock) -> Findings:
        # spacing * rate >= ticks_per_second  <=>  spacing >= ceil(ticks_per_second / rate) for integer spacing
        bound = clock.timebase.ticks_per_second / rate
        min_gap = -((-bound.numerator) // bound.denominator)
        found = Findings(self.signal, description=f"{self.signal}: instantaneous pulse rate at most {fmt(limit)} Hz")
        smallest: int | None = None
        for t, _, base in with_previous(chunks):
            found.checked = base + t.size
            gaps = np.diff(t)
            bad = np.flatnonzero(gaps < min_gap)
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                found.violations.append(Violation(
                    clock.t_ns(t[i + 1]), _rate_hz(1, int(gaps[i]), clock), limit,
                    f"pulse {base + i + 1} {fmt(clock.ns(gaps[i]))} ns after the one before "
                    f"(at least {fmt(clock.ns(min_gap))} ns needed)", unit="Hz"))
            if gaps.size:
                smallest = int(gaps.min()) if smallest is None else min(smallest, int(gaps.min()))
        if smallest is not None:
            found.measured["max_rate_hz"] = _rate_hz(1, smallest, clock)
        return found

    def _windowed(self, chunks: Iterable[tuple[Ints, Int8s]], rate: Fraction, limit: Number, window: int,
                  clock: Clock) -> Findings:
        allowed = rate * window * clock.timebase.resolution_s
        most = allowed.numerator // allowed.denominator
        w_ns = clock.ns(window)
        found = Findings(self.signal, description=f"{self.signal}: pulse rate over any {fmt(w_ns)} ns at most "
                                                  f"{fmt(limit)} Hz ({most} pulses)")
        fullest = -1

        def count(pending: Ints, ready: int) -> None:
            # pulses in [t, t + window) for the first `ready` pulses of `pending` (all later ones known)
            nonlocal fullest
            counts = np.searchsorted(pending, pending[:ready] + window, side="left") - np.arange(ready)
            bad = np.flatnonzero(counts > most)
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                start = clock.t_ns(pending[i])
                found.violations.append(Violation(
                    start, _rate_hz(int(counts[i]), window, clock), limit,
                    f"{counts[i]} pulses in [{start}, {start + w_ns}) ns, at most {most} allowed", unit="Hz"))
            if counts.size:
                fullest = max(fullest, int(counts.max()))

        pending = np.empty(0, dtype=np.int64)
        for t, _ in chunks:
            found.checked += t.size
            pending = np.concatenate([pending, t])
            # a window is complete once a pulse at or after its end has been read
            ready = int(np.searchsorted(pending, pending[-1] - window, side="right"))
            count(pending, ready)
            pending = pending[ready:]
        count(pending, pending.size)
        if fullest >= 0:
            found.measured["max_rate_hz"] = _rate_hz(fullest, window, clock)
            found.measured["max_pulses_per_window"] = fullest
        return found


@dataclass(frozen=True)
class PulsesPerWindow(Check):
    """At most ``max_count`` pulses in each aligned window (e.g. 25 per 1 ms slot).

    Parameters
    ----------
    signal : str
        A pulse train.
    max_count : int
        Most pulses allowed in one window (>= 0).
    window : int
        Window length [ticks], >= 1.
    start : int
        Start of window 0 [ticks]; windows are ``[start + k*window, start + (k+1)*window)`` for
        every integer k (negative k for pulses before ``start``), so every pulse is counted.

    Notes
    -----
    One violation per overfull window: ``t_ns`` is its start, ``value`` its pulse count, ``limit``
    ``max_count``. Measured: ``max_pulses_per_window`` and ``windows_with_pulses``.
    """

    signal: str
    max_count: int
    window: int
    start: int = 0

    def __post_init__(self) -> None:
        validate.integer(self.max_count, "max_count", low=0, kind="an integer", where=self.where)
        validate.integer(self.window, "window", low=1, unit="ticks", kind=TICKS, where=self.where)
        validate.integer(self.start, "start", unit="ticks", kind=TICKS, where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        w_ns = clock.ns(self.window)
        found = Findings(self.signal, description=f"{self.signal}: at most {self.max_count} pulses per "
                                                  f"{fmt(w_ns)} ns window")
        fullest, windows = -1, 0
        open_k, open_count = 0, 0  # the last window seen, which the next chunk may continue

        def close(k: Ints, counts: Ints) -> None:
            nonlocal fullest, windows
            bad = np.flatnonzero(counts > self.max_count)
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                begin = self.start + int(k[i]) * self.window
                found.violations.append(Violation(
                    clock.t_ns(begin), int(counts[i]), self.max_count,
                    f"{counts[i]} pulses in [{clock.t_ns(begin)}, {clock.t_ns(begin + self.window)}) ns",
                    unit="pulses"))
            if counts.size:
                fullest, windows = max(fullest, int(counts.max())), windows + counts.size

        for t, _ in pulse_chunks(trace, self.signal, self):
            found.checked += t.size
            k = (t - self.start) // self.window
            first = np.flatnonzero(np.diff(k, prepend=k[:1] - 1))
            counts = np.diff(np.append(first, k.size))
            k = k[first]
            if open_count and int(k[0]) == open_k:
                counts[0] += open_count
            elif open_count:
                close(np.array([open_k]), np.array([open_count]))
            close(k[:-1], counts[:-1])
            open_k, open_count = int(k[-1]), int(counts[-1])
        if open_count:
            close(np.array([open_k]), np.array([open_count]))
        if windows:
            found.measured["max_pulses_per_window"] = fullest
            found.measured["windows_with_pulses"] = windows
        return found
