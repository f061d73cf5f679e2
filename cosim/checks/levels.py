"""Checks on values: bounds, intervals below or above a threshold (buffer underrun), a value at an instant.

They read bit/int/real signals as recorded: a bit or int signal (and a real value change) holds
its value until the next record; a sampled real signal is judged at its samples, and an interval
between samples takes the value of the sample that starts it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from cosim import validate
from cosim.checks.base import (
    TICKS,
    Check,
    Clock,
    Findings,
    Floats,
    Ints,
    as_number,
    fmt,
    pulse_chunks,
    record_chunks,
    signed_position,
    unit_of,
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
        rule = " and ".join(part for part in (
            None if self.lower is None else f">= {fmt(self.lower)}",
            None if self.upper is None else f"<= {fmt(self.upper)}") if part)
        found = Findings(self.signal, description=f"{self.signal} {rule}")
        top = bottom = largest = np.nan
        for t, v in record_chunks(trace, self.signal, self):
            found.checked += v.size
            low = v < self.lower if self.lower is not None else np.zeros(v.size, dtype=bool)
            high = v > self.upper if self.upper is not None else np.zeros(v.size, dtype=bool)
            bad = np.flatnonzero(low | high | np.isnan(v))
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                limit: float | str = rule
                side = "is not a number"
                if low[i] and self.lower is not None:
                    limit, side = self.lower, "is below the lower bound"
                elif high[i] and self.upper is not None:
                    limit, side = self.upper, "is above the upper bound"
                found.violations.append(Violation(clock.t_ns(t[i]), as_number(v[i]),
                                                  limit if isinstance(limit, str) else as_number(limit),
                                                  f"{self.signal} = {fmt(v[i])} {side}",
                                                  unit=unit_of(trace, self.signal)))
            finite = v[~np.isnan(v)]
            if finite.size:
                top, bottom = np.fmax(top, finite.max()), np.fmin(bottom, finite.min())
                largest = np.fmax(largest, np.abs(finite).max())
        if not np.isnan(top):
            found.measured.update(max=as_number(top), min=as_number(bottom), max_abs=as_number(largest))
        return found


@dataclass(frozen=True)
class _Intervals(Check):
    """Shared search for intervals where a signal is below or above a threshold."""

    def _scan(self, trace: Trace, clock: Clock, signal: str, threshold: float, *, below: bool,
              max_duration: int | None, start: int | None, until: int | None, allow_final: bool) -> Findings:
        sign = "<" if below else ">"
        limit: int | float | str = f"never {sign} {fmt(threshold)}" if max_duration is None else clock.ns(max_duration)
        rule = "never" if max_duration is None else f"at most {fmt(clock.ns(max_duration))} ns at a time"
        found = Findings(signal, description=f"{signal} {sign} {fmt(threshold)}: {rule}"
                                             + (" (the final interval is allowed)" if allow_final else ""))
        totals = {"intervals": 0, "total": 0, "longest": 0, "final": -1}
        extreme_value = np.nan
        last_t: int | None = None

        def judge(t_start: Ints, t_stop: Ints, still: npt.NDArray[np.bool_], extreme: Floats) -> None:
            if until is not None:
                keep = t_start < until
                t_start, t_stop, still, extreme = t_start[keep], np.minimum(t_stop[keep], until), still[keep], \
                    extreme[keep]
            if start is not None:
                keep = (t_stop > start) | (t_start >= start)
                t_start, t_stop, still, extreme = np.maximum(t_start[keep], start), t_stop[keep], still[keep], \
                    extreme[keep]
            length = t_stop - t_start
            bad = length > max_duration if max_duration is not None else np.ones(length.size, dtype=bool)
            allowed = bad & still if allow_final else np.zeros(length.size, dtype=bool)
            bad &= ~allowed
            hits = np.flatnonzero(bad)
            found.n_violations += hits.size
            for i in hits[:MAX_REPORTED - len(found.violations)]:
                tail = ", still at the end" if still[i] else ""
                found.violations.append(Violation(
                    clock.t_ns(t_start[i]), clock.ns(length[i]), limit,
                    f"{signal} {sign} {fmt(threshold)} from {clock.t_ns(t_start[i])} to {clock.t_ns(t_stop[i])} ns "
                    f"({'lowest' if below else 'highest'} {fmt(extreme[i])}{tail})", unit="ns"))
            totals["intervals"] += hits.size
            totals["total"] += int(length[bad].sum())
            if hits.size:
                totals["longest"] = max(totals["longest"], int(length[bad].max()))
            if allowed.any():
                totals["final"] = max(totals["final"], int(length[allowed].max()))

        runs = _Runs(below=below, threshold=threshold)
        for t, v in record_chunks(trace, signal, self):
            if not t.size:
                continue
            found.checked += v.size if until is None else int(np.count_nonzero(t < until))
            if not np.isnan(v).all():
                extreme_value = (np.fmin if below else np.fmax)(extreme_value, np.nanmin(v) if below else np.nanmax(v))
            judge(*runs.closed(t, v))
            last_t = int(t[-1])
        if last_t is not None:
            judge(*runs.still_open(max(trace.end_t, last_t)))
        found.measured["intervals"] = totals["intervals"]
        found.measured["total_ns"] = clock.ns(totals["total"])
        found.measured["longest_ns"] = clock.ns(totals["longest"]) if totals["intervals"] else 0
        if totals["final"] >= 0:
            found.measured["final_ns"] = clock.ns(totals["final"])
        if not np.isnan(extreme_value):
            found.measured["min_value" if below else "max_value"] = as_number(extreme_value)
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
    ``checked`` is 1, or 0 (examined nothing, so neither a pass nor a shown hazard) when the
    signal has no records or pulses at all, when ``t`` lies after the run's end (not simulated;
    a trace built by hand without an end, ``end_t`` 0, has no such limit),
    or when the value at ``t`` is not a number (no record before ``t``, or a NaN recorded: no value
    to compare). Violation: ``value`` = the value, ``limit`` = ``expected`` or ``'expected ± tol'``.
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
        any_record = False
        last = None
        if info is not None and info.kind == "pulse":
            what, value_f = "position", 0.0
            count = 0
            for times, d in pulse_chunks(trace, self.signal, self):
                any_record, last = True, int(times[-1])
                upto = d if self.t is None else d[:np.searchsorted(times, self.t, side="right")]
                count += int(signed_position(upto)[-1]) if upto.size else 0
            value_f = float(count)
        else:
            what, value_f = "value", float("nan")
            for times, v in record_chunks(trace, self.signal, self):
                if not times.size:
                    continue
                any_record, last = True, int(times[-1])
                i = int(np.searchsorted(times, self.t, side="right")) - 1 if self.t is not None else times.size - 1
                if i >= 0:
                    value_f = float(v[i])
        at = self.t if self.t is not None else max(trace.end_t, trace.end_t if last is None else last)
        value = value_f
        limit = as_number(self.expected) if self.tol == 0 else f"{fmt(self.expected)} ± {fmt(self.tol)}"
        found = Findings(self.signal, checked=1 if any_record else 0,
                         description=f"{what} of {self.signal} at {clock.t_ns(at)} ns is {limit}")
        if any_record and 0 < trace.end_t < at:  # (a trace built by hand may have no end: end_t 0)
            found.checked = 0
            found.empty_detail = (f"t = {clock.t_ns(at)} ns lies after the run's end ({clock.t_ns(trace.end_t)} ns): "
                                  "nothing was simulated there")
        elif any_record and np.isnan(value):
            found.checked = 0
            found.empty_detail = f"{what} of {self.signal} at {clock.t_ns(at)} ns is not a number: nothing to compare"
        if found.checked and not abs(value - self.expected) <= self.tol:
            found.n_violations = 1
            found.violations.append(Violation(clock.t_ns(at), as_number(value), limit,
                                              f"{what} of {self.signal} is {fmt(value)}, expected {limit}",
                                              unit=unit_of(trace, self.signal)))
        if not np.isnan(value):
            found.measured["value"] = as_number(value)
        return found


class _Runs:
    """Runs of records below (or above) a threshold, found chunk by chunk.

    A run starts at the first record outside the threshold and stops at the next record inside it;
    its extreme is the lowest (highest) value in it. A run still open at the end of a chunk is
    carried to the next.
    """

    def __init__(self, *, below: bool, threshold: float) -> None:
        self.below = below
        self.threshold = threshold
        self.open_t: int | None = None  # start of the run still open
        self.open_extreme = np.inf if below else -np.inf

    def closed(self, t: Ints, v: Floats) -> tuple[Ints, Ints, npt.NDArray[np.bool_], Floats]:
        """The runs that stop in this chunk: ``(start, stop, still open at the end (False), extreme)``."""
        outside = v < self.threshold if self.below else v > self.threshold
        was_open = self.open_t is not None
        edges = np.diff(outside.astype(np.int8), prepend=np.int8(was_open), append=np.int8(0))
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        reduce = np.minimum if self.below else np.maximum
        masked = np.where(outside, v, np.inf if self.below else -np.inf)
        firsts = np.concatenate([[0], starts]) if was_open else starts
        extreme = reduce.reduceat(masked, firsts) if firsts.size else masked[:0]
        t_start = t[starts]
        if was_open:
            assert self.open_t is not None
            extreme[0] = reduce(extreme[0], self.open_extreme)
            t_start = np.concatenate([[self.open_t], t_start])
        ends_open = stops.size and stops[-1] == v.size  # the last run reaches the chunk's end
        if ends_open:
            self.open_t, self.open_extreme = int(t_start[-1]), float(extreme[-1])
            t_start, extreme, stops = t_start[:-1], extreme[:-1], stops[:-1]
        else:
            self.open_t, self.open_extreme = None, (np.inf if self.below else -np.inf)
        return t_start.astype(np.int64), t[stops].astype(np.int64), np.zeros(stops.size, dtype=bool), extreme

    def still_open(self, end: int) -> tuple[Ints, Ints, npt.NDArray[np.bool_], Floats]:
        """The run open at the end of the records, stopped at ``end`` (none if there is none)."""
        if self.open_t is None:
            return np.empty(0, np.int64), np.empty(0, np.int64), np.zeros(0, bool), np.empty(0)
        return (np.array([self.open_t], dtype=np.int64), np.array([end], dtype=np.int64), np.ones(1, dtype=bool),
                np.array([self.open_extreme]))
