"""Checks on values: bounds, intervals below or above a threshold (buffer underrun), a value at an instant.

They read bit/int/real signals as recorded: a bit or int signal (and a real value change) holds
its value until the next record; a sampled real signal is judged at its samples, and an interval
between samples takes the value of the sample that starts it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cosim import validate
from cosim.checks.base import (
    TICKS,
    Check,
    Clock,
    Findings,
    as_number,
    fmt,
    held_index,
    pulse_times,
    records,
    signed_position,
    trace_end,
)
from cosim.checks.result import MAX_REPORTED, Violation
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.trace import Trace


@dataclass(frozen=True)
class Bound(Check):
    """Every recorded value lies within ``[lower, upper]`` (following error, sync error, power...).

    Parameters
    ----------
    signal : str
        A bit, int or real signal (edges or samples).
    lower, upper : float, optional
        Bounds in the signal's unit (inclusive); at least one is needed.

    Notes
    -----
    One violation per record outside the bounds (NaN is outside): ``value`` = the value,
    ``limit`` = the bound it broke. Measured: ``max``, ``min``, ``max_abs``.
    """

    signal: str
    lower: float | None = None
    upper: float | None = None

    def __post_init__(self) -> None:
        if self.lower is None and self.upper is None:
            raise ConfigurationError(f"{self.where}: give lower, upper or both")
        lo = None if self.lower is None else validate.finite(self.lower, "lower", where=self.where)
        hi = None if self.upper is None else validate.finite(self.upper, "upper", where=self.where)
        if lo is not None and hi is not None:
            validate.in_range(self.lower, "lower", high=hi, allowed=f"<= upper ({self.upper})", where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        t, v = records(trace, self.signal, self)
        low = v < self.lower if self.lower is not None else np.zeros(v.size, dtype=bool)
        high = v > self.upper if self.upper is not None else np.zeros(v.size, dtype=bool)
        bad = np.flatnonzero(low | high | np.isnan(v))
        rule = " and ".join(part for part in (
            None if self.lower is None else f">= {fmt(self.lower)}",
            None if self.upper is None else f"<= {fmt(self.upper)}") if part)
        found = Findings(self.signal, checked=v.size, n_violations=bad.size, description=f"{self.signal} {rule}")
        for i in bad[:MAX_REPORTED]:
            limit: float | str = rule
            side = "is not a number"
            if low[i] and self.lower is not None:
                limit, side = self.lower, "is below the lower bound"
            elif high[i] and self.upper is not None:
                limit, side = self.upper, "is above the upper bound"
            found.violations.append(Violation(clock.t_ns(t[i]), as_number(v[i]),
                                              limit if isinstance(limit, str) else as_number(limit),
                                              f"{self.signal} = {fmt(v[i])} {side}"))
        finite = v[~np.isnan(v)]
        if finite.size:
            found.measured.update(max=as_number(finite.max()), min=as_number(finite.min()),
                                  max_abs=as_number(np.abs(finite).max()))
        return found


@dataclass(frozen=True)
class _Intervals(Check):
    """Shared search for intervals where a signal is below or above a threshold."""

    def _scan(self, trace: Trace, clock: Clock, signal: str, threshold: float, *, below: bool,
              max_duration: int | None, start: int | None, until: int | None, allow_final: bool) -> Findings:
        t, v = records(trace, signal, self)
        end = trace_end(trace, t)
        outside = v < threshold if below else v > threshold
        edges = np.diff(outside.astype(np.int8), prepend=np.int8(0), append=np.int8(0))
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        still = stops == v.size  # still outside at the last record
        t_start = t[starts]
        t_stop = np.where(still, end, t[np.minimum(stops, max(v.size - 1, 0))])
        extreme = (np.minimum if below else np.maximum).reduceat(
            np.where(outside, v, np.inf if below else -np.inf), starts) if starts.size else v[:0]
        checked = v.size
        if until is not None:
            keep = t_start < until
            t_start, t_stop, still, extreme = t_start[keep], np.minimum(t_stop[keep], until), still[keep], extreme[keep]
            checked = int(np.count_nonzero(t < until))
        if start is not None:
            keep = (t_stop > start) | (t_start >= start)
            t_start, t_stop, still, extreme = np.maximum(t_start[keep], start), t_stop[keep], still[keep], extreme[keep]
        length = t_stop - t_start
        bad = length > max_duration if max_duration is not None else np.ones(length.size, dtype=bool)
        allowed = bad & still if allow_final else np.zeros(length.size, dtype=bool)
        bad &= ~allowed
        hits = np.flatnonzero(bad)

        sign = "<" if below else ">"
        limit: int | float | str = f"never {sign} {fmt(threshold)}" if max_duration is None else clock.ns(max_duration)
        rule = "never" if max_duration is None else f"at most {fmt(clock.ns(max_duration))} ns at a time"
        found = Findings(signal, checked=checked, n_violations=hits.size,
                         description=f"{signal} {sign} {fmt(threshold)}: {rule}"
                                     + (" (the final interval is allowed)" if allow_final else ""))
        for i in hits[:MAX_REPORTED]:
            tail = ", still at the end" if still[i] else ""
            found.violations.append(Violation(
                clock.t_ns(t_start[i]), clock.ns(length[i]), limit,
                f"{signal} {sign} {fmt(threshold)} from {clock.t_ns(t_start[i])} to {clock.t_ns(t_stop[i])} ns "
                f"({'lowest' if below else 'highest'} {fmt(extreme[i])}{tail})"))
        found.measured["intervals"] = int(hits.size)
        found.measured["total_ns"] = clock.ns(length[bad].sum())
        found.measured["longest_ns"] = clock.ns(length[bad].max()) if hits.size else 0
        if allowed.any():
            found.measured["final_ns"] = clock.ns(length[allowed].max())
        if v.size and not np.isnan(v).all():
            found.measured["min_value" if below else "max_value"] = as_number(np.nanmin(v) if below else np.nanmax(v))
        return found

    def _check_options(self, threshold: float, max_duration: int | None, start: int | None,
                       until: int | None) -> None:
        validate.finite(threshold, "threshold", where=self.where)
        if max_duration is not None:
            validate.integer(max_duration, "max_duration", low=0, unit="ticks", kind=TICKS, where=self.where)
        if start is not None:
            validate.integer(start, "start", unit="ticks", kind=TICKS, where=self.where)
        if until is not None:
            validate.integer(until, "until", unit="ticks", kind=TICKS, where=self.where)
        if start is not None and until is not None:
            validate.integer(start, "start", high=until - 1, allowed=f"< until ({until})", where=self.where)


@dataclass(frozen=True)
class IntervalsBelow(_Intervals):
    """The signal is never below ``threshold`` (or not for longer than ``max_duration`` at a time).

    Parameters
    ----------
    signal : str
        A bit, int or real signal.
    threshold : float
        In the signal's unit; "below" is ``value < threshold``.
    max_duration : int, optional
        Longest allowed interval below [ticks]; default: no interval at all (even one of 0 ticks,
        two records at the same tick, is a violation).
    start : int, optional
        Start of the checked span [ticks] (e.g. when the job starts): intervals ending at or before
        it are ignored, longer ones are cut there. Default: from the first record.
    until : int, optional
        End of the checked span [ticks]: intervals starting at or after it are ignored, longer ones
        are cut there. Default: the end of the trace.
    allow_final : bool
        An interval still below at the end of the trace (the job is over) is allowed.

    Notes
    -----
    One violation per interval: ``t_ns`` its start, ``value`` its length [ns], ``limit``
    ``max_duration`` [ns] or ``'never < threshold'``. Measured: ``intervals``, ``total_ns``,
    ``longest_ns`` (of the violating intervals), ``final_ns`` (the allowed final one), ``min_value``.
    """

    signal: str
    threshold: float
    max_duration: int | None = None
    start: int | None = None
    until: int | None = None
    allow_final: bool = False

    def __post_init__(self) -> None:
        self._check_options(self.threshold, self.max_duration, self.start, self.until)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        return self._scan(trace, clock, self.signal, self.threshold, below=True, max_duration=self.max_duration,
                          start=self.start, until=self.until, allow_final=self.allow_final)


@dataclass(frozen=True)
class IntervalsAbove(_Intervals):
    """The signal is never above ``threshold`` (or not longer than ``max_duration``); see :class:`IntervalsBelow`.

    Measured: ``intervals``, ``total_ns``, ``longest_ns``, ``final_ns``, ``max_value``.
    """

    signal: str
    threshold: float
    max_duration: int | None = None
    start: int | None = None
    until: int | None = None
    allow_final: bool = False

    def __post_init__(self) -> None:
        self._check_options(self.threshold, self.max_duration, self.start, self.until)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        return self._scan(trace, clock, self.signal, self.threshold, below=False, max_duration=self.max_duration,
                          start=self.start, until=self.until, allow_final=self.allow_final)


@dataclass(frozen=True)
class NoUnderrun(_Intervals):
    """A buffer level never falls below ``minimum`` while the job runs (PoKeys fill buffer...).

    Parameters
    ----------
    signal : str
        The buffer level, an int signal [entries].
    minimum : float
        Lowest allowed level (default 1: the buffer is never empty).
    allow_final : bool
        The buffer may run empty at the end, after the job (default True).
    start, until : int, optional
        Start and end of the job [ticks]; intervals outside are ignored, longer ones cut.

    Notes
    -----
    The same as ``IntervalsBelow(signal, minimum, allow_final=..., start=..., until=...)``: one violation per
    underrun with its start, length [ns] and lowest level; measured ``intervals`` (underruns),
    ``total_ns`` (total underrun time), ``longest_ns``, ``final_ns``, ``min_value``.
    """

    signal: str
    minimum: float = 1
    allow_final: bool = True
    start: int | None = None
    until: int | None = None

    def __post_init__(self) -> None:
        self._check_options(self.minimum, None, self.start, self.until)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        return self._scan(trace, clock, self.signal, self.minimum, below=True, max_duration=None,
                          start=self.start, until=self.until, allow_final=self.allow_final)


@dataclass(frozen=True)
class ValueAt(Check):
    """The value of a signal at one instant (e.g. the final position counter).

    Parameters
    ----------
    signal : str
        A bit/int/real signal (the value held at ``t``, a record at ``t`` included) or a pulse
        train (its position: the signed count of pulses at or before ``t``).
    t : int or None
        The instant [ticks]; None: the end of the trace.
    expected : float
        Expected value, in the signal's unit (counts for a pulse train).
    tol : float
        Allowed difference, >= 0.

    Notes
    -----
    ``checked`` is 1 (0 if the signal has no records or pulses at all). Violation: ``value`` = the
    value (NaN before the first record), ``limit`` = ``expected`` or ``'expected ± tol'``.
    Measured: ``value``.
    """

    signal: str
    t: int | None
    expected: float
    tol: float = 0

    def __post_init__(self) -> None:
        if self.t is not None:
            validate.integer(self.t, "t", unit="ticks", kind=TICKS, where=self.where)
        validate.finite(self.expected, "expected", where=self.where)
        validate.positive(self.tol, "tol", zero=True, where=self.where)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        info = trace.info.get(self.signal)
        if info is not None and info.kind == "pulse":
            times, d = pulse_times(trace, self.signal, self)
            at = self.t if self.t is not None else trace_end(trace, times)
            count = np.concatenate([[0], signed_position(d)])
            value = float(count[np.searchsorted(times, at, side="right")])
            what = "position"
        else:
            times, v = records(trace, self.signal, self)
            at = self.t if self.t is not None else trace_end(trace, times)
            i = int(held_index(times, np.array([at], dtype=np.int64))[0])
            value = float(v[i]) if i >= 0 else float("nan")
            what = "value"
        limit = as_number(self.expected) if self.tol == 0 else f"{fmt(self.expected)} ± {fmt(self.tol)}"
        found = Findings(self.signal, checked=1 if times.size else 0,
                         description=f"{what} of {self.signal} at {clock.t_ns(at)} ns is {limit}")
        if times.size and not abs(value - self.expected) <= self.tol:  # NaN fails too
            found.n_violations = 1
            found.violations.append(Violation(clock.t_ns(at), as_number(value), limit,
                                              f"{what} of {self.signal} is {fmt(value)}, expected {limit}"))
        if not np.isnan(value):
            found.measured["value"] = as_number(value)
        return found
