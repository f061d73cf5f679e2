"""Position-gated edges: each expected edge of an output happens at its axis position (and time).

The axis position is either a pulse train (position = signed count of the pulses so far, dir 1
counting up) or an int signal such as an encoder or a compare register. Expected edges are matched
to the edges found in order; what cannot be matched is reported as missing or extra.
"""

from __future__ import annotations

from collections.abc import Sequence
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
    pulse_chunks,
    record_chunks,
)
from cosim.checks.result import MAX_REPORTED, Violation
from cosim.errors import ConfigurationError
from cosim.tracecursor import Held, Position, change_chunks

if TYPE_CHECKING:
    from cosim.trace import Trace


@dataclass(frozen=True)
class EdgeAtPosition(Check):
    """Each expected edge of a bit output occurs within ``tol_counts`` of its axis position.

    Parameters
    ----------
    signal : str
        The bit output, e.g. ``trio.axis3.gate``.
    position_signal : str
        A pulse train (position = signed pulse count, starting at 0) or an int/real signal holding
        the position [counts].
    expected : sequence of (position, value)
        The expected edges in the order they should happen: axis position [counts] and the new
        level (0 or 1).
    tol_counts : int
        Allowed position error [counts], >= 0.
    tol_time : int, optional
        Allowed time error [ticks] against ``times``.
    times : sequence of int, optional
        Expected instant of each edge [ticks]; needs ``tol_time``.

    Notes
    -----
    The position at an edge includes pulses (or position records) at the same tick. The first
    record of ``signal`` is its initial level, not an edge.

    Matching, in order: expected edge k takes the first edge found after the one matched to k-1
    that has the expected level and a position within ``tol_counts``. Edges found that match no
    expected edge are *extra*; expected edges with no match are *missing*. The search is a loop
    over the expected edges (not over pulses); positions are read from the position signal chunk by
    chunk at the edges' instants.

    Violations:

    * missing: ``t_ns`` = the expected time (or that of the previous match, 0 if none),
      ``value`` = expected position [counts], ``limit`` = the rule;
    * extra: ``t_ns`` = the edge, ``value`` = its position [counts], ``limit`` ``'no edge'``;
    * off time: ``t_ns`` = the edge, ``value`` = time error [ns] (positive = late), ``limit`` = tol_time [ns].

    Measured: ``worst_position_error_counts`` and ``worst_time_error_ns`` (largest magnitudes over
    matched edges), ``edges_expected``, ``edges_found``. ``checked`` = expected edges + extra edges.
    """

    signal: str
    position_signal: str
    expected: Sequence[tuple[int, int]]
    tol_counts: int
    tol_time: int | None = None
    times: Sequence[int] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "expected", tuple((p, v) for p, v in self.expected))
        for k, (position, value) in enumerate(self.expected):
            validate.integer(position, f"expected[{k}] position", where=self.where)
            validate.integer(value, f"expected[{k}] value", low=0, high=1, allowed="0, 1", kind="an integer",
                             where=self.where)
        validate.integer(self.tol_counts, "tol_counts", low=0, kind="an integer", where=self.where)
        if (self.times is None) != (self.tol_time is None):
            raise ConfigurationError(f"{self.where}: times and tol_time go together; give both or neither")
        if self.times is not None and self.tol_time is not None:
            object.__setattr__(self, "times", tuple(self.times))
            validate.integer(self.tol_time, "tol_time", low=0, unit="ticks", kind=TICKS, where=self.where)
            n = len(self.expected)
            validate.integer(len(self.times), "len(times)", low=n, high=n, allowed=f"{n} (one per expected edge)",
                             where=self.where)
            for k, t in enumerate(self.times):
                validate.integer(t, f"times[{k}]", unit="ticks", kind=TICKS, where=self.where)

    def _positions(self, trace: Trace, t_edges: np.ndarray) -> np.ndarray:
        info = trace.info.get(self.position_signal)
        if info is not None and info.kind == "pulse":
            return Position(pulse_chunks(trace, self.position_signal, self)).at(t_edges).astype(np.float64)
        return Held(record_chunks(trace, self.position_signal, self)).values_at(t_edges)

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        edges = list(change_chunks(record_chunks(trace, self.signal, self)))  # the edges found: as many as expected
        te = np.concatenate([e[0] for e in edges]) if edges else np.empty(0, dtype=np.int64)
        ve = np.concatenate([e[1] for e in edges]) if edges else np.empty(0)
        level = (ve != 0).astype(np.int64)
        pos = self._positions(trace, te)
        match = self._match(level, pos)
        matched = match >= 0
        extra = np.ones(te.size, dtype=bool)
        extra[match[matched]] = False

        found = Findings(self.signal, checked=len(self.expected) + int(extra.sum()),
                         description=f"{self.signal} edges at positions of {self.position_signal} "
                                     f"within ±{self.tol_counts} counts")
        for missing in np.flatnonzero(~matched):
            found.violations.append(self._missing(int(missing), match, te, clock))
        for j in np.flatnonzero(extra):
            p = "unknown" if np.isnan(pos[j]) else fmt(pos[j])
            found.violations.append(Violation(clock.t_ns(te[j]), as_number(pos[j]), "no edge",
                                              f"unexpected edge to {level[j]} at position {p}", unit="counts"))
        n_bad = int((~matched).sum() + extra.sum())
        k_hit = [int(k) for k in np.flatnonzero(matched)]
        if k_hit:
            want = np.array([self.expected[k][0] for k in k_hit], dtype=np.float64)
            found.measured["worst_position_error_counts"] = as_number(np.abs(pos[match[k_hit]] - want).max())
        if self.times is not None and self.tol_time is not None and k_hit:
            err = te[match[k_hit]] - np.array([self.times[k] for k in k_hit], dtype=np.int64)
            found.measured["worst_time_error_ns"] = clock.ns(np.abs(err).max())
            off = np.flatnonzero(np.abs(err) > self.tol_time)
            n_bad += off.size
            for i in off[:MAX_REPORTED]:
                k = k_hit[i]
                found.violations.append(Violation(
                    clock.t_ns(te[match[k]]), clock.ns(err[i]), clock.ns(self.tol_time),
                    f"edge {k} to {self.expected[k][1]} {fmt(clock.ns(err[i]))} ns off its expected time "
                    f"{clock.t_ns(self.times[k])} ns", unit="ns"))
        found.n_violations = n_bad
        found.violations = sorted(found.violations, key=lambda v: v.t_ns)[:MAX_REPORTED]
        found.measured["edges_expected"] = len(self.expected)
        found.measured["edges_found"] = int(te.size)
        return found

    def _match(self, level: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """Index of the edge found for each expected edge (-1: missing), matched in order."""
        match = np.full(len(self.expected), -1, dtype=np.int64)
        nxt = 0
        for k, (position, value) in enumerate(self.expected):
            if nxt < level.size and level[nxt] == value and abs(pos[nxt] - position) <= self.tol_counts:
                hit = nxt  # the usual case: the very next edge
            else:
                ok = np.flatnonzero((level[nxt:] == value) & (np.abs(pos[nxt:] - position) <= self.tol_counts))
                if not ok.size:
                    continue
                hit = nxt + int(ok[0])
            match[k] = hit
            nxt = hit + 1
        return match

    def _missing(self, k: int, match: np.ndarray, te: np.ndarray, clock: Clock) -> Violation:
        position, value = self.expected[k]
        if self.times is not None:
            t_ns = clock.t_ns(self.times[k])
        else:
            before = match[:k][match[:k] >= 0]
            t_ns = clock.t_ns(te[before[-1]]) if before.size else 0
        return Violation(t_ns, position, f"edge to {value} at {position} ± {self.tol_counts} counts",
                         f"missing edge {k}: no change to {value} within ±{self.tol_counts} counts of "
                         f"position {position}", unit="counts")
