""""This takes N ns": the time from one event in the trace to a later one.

Events are named with references: :class:`EdgeRef` (a signal changing, optionally to a value) and
:class:`PulseRef` (the first or last pulse of a pulse train). Example: from the limit switch
tripping to the last step pulse at most 2 ms::

    Duration(EdgeRef("pokeys.x.limit", 1), PulseRef("pokeys.x.step", "last"), max=sim.ticks("2 ms"))
"""

from __future__ import annotations

from collections.abc import Iterator
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
    Ints,
    fmt,
    pulse_chunks,
    record_chunks,
)
from cosim.checks.result import MAX_REPORTED, Number, Violation
from cosim.errors import ConfigurationError
from cosim.tracecursor import Instants, change_chunks

if TYPE_CHECKING:
    from cosim.trace import Trace

WHICH = ("each", "first", "last")


@dataclass(frozen=True)
class EdgeRef:
    """The changes of a bit/int/real signal, optionally only those to ``value``.

    Parameters
    ----------
    signal : str
    value : float, optional
        Only changes to this value (e.g. 1 for a rising edge of a bit); default: every change.
    which : {'each', 'first', 'last'}
        As a start: every matching change, or only the first or last. As an end: the first
        ('each', 'first') or the last ('last') matching change in the window.

    Notes
    -----
    The first record of a signal is its initial value, not a change.
    """

    signal: str
    value: float | None = None
    which: str = "each"

    def __post_init__(self) -> None:
        if self.value is not None:  # first: str(self) shows the value as a float
            validate.finite(self.value, "value", where=f"change of {self.signal}")
        validate.choice(self.which, "which", WHICH, where=str(self))

    def instant_chunks(self, trace: Trace, check: Check) -> Iterator[tuple[Ints]]:
        """Every matching change [ticks], in time order, chunk by chunk."""
        for t, v in change_chunks(record_chunks(trace, self.signal, check)):
            yield (t if self.value is None else t[v == self.value],)

    def instants(self, trace: Trace, check: Check) -> Ints:
        """Every matching change [ticks], in time order."""
        return _joined(self.instant_chunks(trace, check))

    @property
    def where(self) -> str:
        return str(self)

    def __str__(self) -> str:
        to = "" if self.value is None else f" to {fmt(self.value)}"
        return f"change of {self.signal}{to}"


@dataclass(frozen=True)
class PulseRef:
    """A pulse of a pulse train: the first or the last (or, as a start, each).

    Parameters
    ----------
    signal : str
    which : {'first', 'last', 'each'}
        As a start: the train's first or last pulse, or every pulse. As an end: the first or the
        last pulse in the window.
    """

    signal: str
    which: str = "first"

    def __post_init__(self) -> None:
        validate.choice(self.which, "which", WHICH, where=str(self))

    def instant_chunks(self, trace: Trace, check: Check) -> Iterator[tuple[Ints]]:
        """Every pulse [ticks], in time order, chunk by chunk."""
        for t, _ in pulse_chunks(trace, self.signal, check):
            yield (t,)

    def instants(self, trace: Trace, check: Check) -> Ints:
        """Every pulse [ticks], in time order."""
        return _joined(self.instant_chunks(trace, check))

    @property
    def where(self) -> str:
        return str(self)

    def __str__(self) -> str:
        return f"{self.which} pulse of {self.signal}"


Ref = EdgeRef | PulseRef


def _joined(chunks: Iterator[tuple[Ints]]) -> Ints:
    parts = [c[0] for c in chunks]
    return np.concatenate(parts) if parts else np.empty(0, dtype=np.int64)


@dataclass(frozen=True)
class Duration(Check):
    """The time from a start event to an end event is within limits.

    Parameters
    ----------
    start : EdgeRef or PulseRef
        What starts a measurement; each selected instant starts one (see ``which``).
    end : EdgeRef or PulseRef
        What ends it: its first (or, with ``which='last'``, last) instant in the window from the
        start up to the next start (or the end of the trace). An end at the start tick counts (0 ns).
    min, max : int, optional
        Shortest and longest allowed duration [ticks].
    equals : int, optional
        Expected duration [ticks], within ``tol``; not together with ``min``/``max``.
    tol : int
        Allowed difference from ``equals`` [ticks], >= 0.

    Notes
    -----
    One violation per start whose duration breaks the rule: ``t_ns`` = the start, ``value`` = the
    duration [ns], ``limit`` = the broken limit [ns] (``'equals ± tol'`` for ``equals``). A start
    with no end in its window is a violation whose ``value`` is the window length [ns] (the
    duration is at least that). Measured: ``min_ns``, ``max_ns``, ``durations``.

    Examples
    --------
    >>> from cosim.trace import Trace
    >>> trace = Trace()
    >>> trace.declare("laser.gate", "bit"); trace.declare("laser.power_ok", "bit")
    >>> for t, v in [(0, 0), (1000, 1), (5000, 0)]:
    ...     trace.record("laser.gate", t, v)
    >>> for t, v in [(0, 0), (1800, 1), (5100, 0)]:
    ...     trace.record("laser.power_ok", t, v)
    >>> result = Duration(EdgeRef("laser.gate", 1), EdgeRef("laser.power_ok", 1), max=500).evaluate(trace)
    >>> [(v.t_ns, v.value, v.limit) for v in result.violations]
    [(1000, 800, 500)]
    """

    start: Ref
    end: Ref
    min: int | None = None
    max: int | None = None
    equals: int | None = None
    tol: int = 0

    def __post_init__(self) -> None:
        if self.min is None and self.max is None and self.equals is None:
            raise ConfigurationError(f"{self.where}: give min, max or equals")
        if self.equals is not None and (self.min is not None or self.max is not None):
            raise ConfigurationError(f"{self.where}: equals (with tol) excludes min and max")
        for name in ("min", "max", "equals"):
            if getattr(self, name) is not None:
                validate.integer(getattr(self, name), name, low=0, unit="ticks", kind=TICKS, where=self.where)
        validate.integer(self.tol, "tol", low=0, unit="ticks", kind=TICKS, where=self.where)
        if self.min is not None and self.max is not None:
            validate.integer(self.min, "min", high=self.max, allowed=f"<= max ({self.max})", where=self.where)

    @property
    def main_signal(self) -> str:
        return self.start.signal

    @property
    def label(self) -> str:
        return self.name or f"Duration({self.start.signal} -> {self.end.signal})"

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        ends = Instants(self.end.instant_chunks(trace, self))
        rule = self._rule(clock)
        found = Findings(self.start.signal, description=f"from {self.start} to {self.end}: {rule}",
                         empty_detail=f"no {self.start} in the trace: nothing was measured")
        lasting = self.end.which == "last"
        measured: list[int] = []  # durations found: [count, min, max]
        held: int | None = None  # the latest start: its window ends at the next start, or at the trace's end
        last_candidate: int | None = None
        for (candidates,) in self.start.instant_chunks(trace, self):
            if not candidates.size:
                continue
            last_candidate = int(candidates[-1])
            if self.start.which == "each":
                starts = candidates if held is None else np.concatenate([[held], candidates])
                nexts = starts[1:]
                if lasting:
                    e, has = ends.last_before(nexts)
                    has &= e >= starts[:-1]
                else:
                    e, has = ends.first_at_or_after(starts[:-1])
                    has &= e < nexts
                self._judge(found, measured, starts[:-1], np.where(has, e, nexts), has, clock, rule)
                held = int(starts[-1])
            elif self.start.which == "first" and held is None:
                held = int(candidates[0])
        if self.start.which == "last":
            held = last_candidate
        if held is not None and last_candidate is not None:
            s = np.array([held], dtype=np.int64)
            if lasting:
                last_end = ends.last()
                e, has = np.array([last_end or 0]), np.array([last_end is not None and last_end >= held])
            else:
                e, has = ends.first_at_or_after(s)
                last_end = ends.last()
            horizon = max(trace.end_t, last_candidate, *(() if last_end is None else (last_end,)))
            self._judge(found, measured, s, np.where(has, e, horizon), has, clock, rule)
        if measured:
            found.measured["durations"] = measured[0]
            found.measured["min_ns"] = clock.ns(measured[1])
            found.measured["max_ns"] = clock.ns(measured[2])
        else:
            found.measured["durations"] = 0
        return found

    def _judge(self, found: Findings, measured: list[int], starts: Ints, stops: Ints, has_end: npt.NDArray[np.bool_],
               clock: Clock, rule: str) -> None:
        """Judge the durations ``stops - starts`` (``has_end`` False: no end, the window ran to ``stops``)."""
        found.checked += starts.size
        d = stops - starts
        too_short = has_end & (d < self.min) if self.min is not None else np.zeros(d.size, dtype=bool)
        too_long = has_end & (d > self.max) if self.max is not None else np.zeros(d.size, dtype=bool)
        off = has_end & (np.abs(d - self.equals) > self.tol) if self.equals is not None else np.zeros(d.size, bool)
        bad = np.flatnonzero(~has_end | too_short | too_long | off)
        found.n_violations += bad.size
        for i in bad[:MAX_REPORTED - len(found.violations)]:
            t0 = clock.t_ns(starts[i])
            length = clock.ns(d[i])
            if not has_end[i]:
                found.violations.append(Violation(t0, length, rule, f"no {self.end} within {fmt(length)} ns",
                                                  unit="ns"))
                continue
            limit: Number | str = rule
            if too_short[i] and self.min is not None:
                limit = clock.ns(self.min)
            elif too_long[i] and self.max is not None:
                limit = clock.ns(self.max)
            found.violations.append(Violation(t0, length, limit, f"{self.end} {fmt(length)} ns after the start",
                                              unit="ns"))
        lengths = d[has_end]
        if lengths.size:
            if measured:
                measured[:] = [measured[0] + lengths.size, min(measured[1], int(lengths.min())),
                               max(measured[2], int(lengths.max()))]
            else:
                measured[:] = [lengths.size, int(lengths.min()), int(lengths.max())]

    def _rule(self, clock: Clock) -> str:
        if self.equals is not None:
            return f"{fmt(clock.ns(self.equals))} ± {fmt(clock.ns(self.tol))} ns"
        parts = [f">= {fmt(clock.ns(self.min))} ns" if self.min is not None else "",
                 f"<= {fmt(clock.ns(self.max))} ns" if self.max is not None else ""]
        return " and ".join(p for p in parts if p)
