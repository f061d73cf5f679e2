"""The rows of a run's waveform, in the order a reader needs, each with its data prepared once.

No plotting here (numpy only), so each rule is tested on its own:

* **order** (:func:`reader_order`): first the signals a check names (its ``signal``, or a trace
  signal named in its name, description, hazard or violations; the failed checks' first), then
  the rest grouped by device and axis, the groups of the named signals first, in each group the
  pulse trains, bits, integers and reals in the order they were declared;
* **quiet** rows (:attr:`Row.quiet`): a signal that holds one value the whole run (or was never
  recorded), or a train without pulses, is folded into one "quiet signals" line, unless a check
  names it: then it is drawn as a labelled line;
* a **value** row (bit, int, real) is its records held to the run's end (:func:`value_row`); past
  :data:`EMBED_POINTS` records the page holds a reduced overview (the first, last, smallest and
  largest record of each of :data:`BUCKETS` slices) and the finer levels and the records themselves
  go to side files (:mod:`cosim.report.levels`);
* a **pulse train** row (:func:`train_row`) keeps its segments ``(t0, duration, count, dir,
  width)`` when they are few (the browser expands the visible ones into pulses by the rule of
  :mod:`cosim.pulses`), and its rate (pulses/s, signed by direction) per segment, or per slice of
  the run for a PWM output; a longer train keeps its rate per slice at several resolutions and its
  segments in side files.

All times are ticks of the trace's resolution.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim.report.text import state_names
from cosim.trace import Trace

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
#: Slices of the run in a reduced overview (about the pixels of a wide screen).
BUCKETS = 1024
#: Records of a value signal embedded as they are; a longer signal gets levels in side files.
EMBED_POINTS = 8000
#: Segments (with single pulses) of a pulse train embedded for expansion into pulses.
EMBED_SEGMENTS = 20_000
DIGITAL = ("bit", "pulse")
_RANK = {"pulse": 0, "bit": 1, "int": 2, "real": 3}
_NAME = re.compile(r"\b[a-z][a-z0-9_]*(?:\.[a-z0-9_]+)+\b")


@dataclass
class Row:
    """One signal of the waveform as drawn.

    ``t, v``: a value row's points held to the run's end (the last at ``end_t``), exact or reduced
    (``exact``); ``low, high``: its smallest and largest finite value. A train's ``segments`` (empty
    when not embedded) and rate blocks ``left, right, rate_hz``. ``quiet``: no activity (``value``
    is what it held). ``detail``: the finer levels written to side files (filled by
    :mod:`cosim.report.levels`).
    """

    name: str
    kind: str
    unit: str = ""
    description: str = ""
    states: dict[int, str] = field(default_factory=dict)
    records: int = 0
    t: Ints = field(default_factory=lambda: np.empty(0, np.int64))
    v: Floats = field(default_factory=lambda: np.empty(0))
    exact: bool = True
    low: float = 0.0
    high: float = 1.0
    first_t: int = -1
    distinct: int = 0
    segments: dict[str, Ints] = field(default_factory=dict)
    left: Ints = field(default_factory=lambda: np.empty(0, np.int64))
    right: Ints = field(default_factory=lambda: np.empty(0, np.int64))
    rate_hz: Floats = field(default_factory=lambda: np.empty(0))
    pulses: int = 0
    pulse_width: int = 1
    checked: bool = False
    detail: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def group(self) -> str:
        """The device or axis the signal belongs to (its name without the last part)."""
        return self.name.rsplit(".", 1)[0]

    @property
    def quiet(self) -> bool:
        """No activity: one value the whole run (or never recorded), or a train without pulses."""
        if self.kind == "pulse":
            return self.pulses == 0
        return self.distinct <= 1 and self.first_t <= 0

    @property
    def value(self) -> float:
        """The value a quiet or constant row holds (0 if never recorded)."""
        return float(self.v[0]) if self.v.size else 0.0


def named_signals(checks: Sequence[Mapping[str, Any]], names: Sequence[str]) -> list[str]:
    """The trace signals the checks name, the failed checks' first, each once.

    A check names its ``signal`` (and ``signals``, if it lists several), and any trace signal its
    name, description, hazard or violation details mention.

    Examples
    --------
    >>> checks = [{"name": "ok", "signal": "a.x", "passed": True},
    ...           {"name": "late", "signal": "b.y", "passed": False, "description": "b.y before a.z"}]
    >>> named_signals(checks, ["a.x", "a.z", "b.y", "c"])
    ['b.y', 'a.z', 'a.x']
    """
    known = set(names)
    order = sorted(range(len(checks)), key=lambda k: bool(checks[k].get("passed")))
    found: dict[str, None] = {}
    for k in order:
        c = checks[k]
        listed = [c.get("signal") or "", *(c.get("signals") or [])]
        text = " ".join(str(c.get(key) or "") for key in ("name", "description", "hazard"))
        text += " " + " ".join(str(v.get("detail") or "") for v in c.get("violations", []))
        for name in [*listed, *_NAME.findall(text)]:
            if name in known:
                found.setdefault(name)
    return list(found)


def reader_order(trace: Trace, named: Sequence[str] = ()) -> list[str]:
    """Every signal of ``trace``: ``named`` first, then per device and axis (the groups of the named
    signals first), in each group pulse trains, bits, integers, reals, in declaration order.

    Examples
    --------
    >>> trace = Trace()
    >>> for name, kind in [("a.x.pos", "real"), ("a.x.dir", "bit"), ("a.x.step", "pulse"), ("b.level", "int"),
    ...                    ("b.under", "bit")]:
    ...     trace.declare(name, kind)
    >>> reader_order(trace, ["b.under"])
    ['b.under', 'b.level', 'a.x.step', 'a.x.dir', 'a.x.pos']
    """
    groups: dict[str, int] = {}
    for name in named:
        groups.setdefault(name.rsplit(".", 1)[0], len(groups))
    for name in trace.info:
        groups.setdefault(name.rsplit(".", 1)[0], len(groups))
    declared = {name: k for k, name in enumerate(trace.info)}
    rest = sorted((n for n in trace.info if n not in set(named)),
                  key=lambda n: (groups[n.rsplit(".", 1)[0]], _RANK[trace.info[n].kind], declared[n]))
    return [n for n in named if n in trace.info] + rest


def reduce_min_max(t: Ints, value: Floats, *, start: int = 0, end_t: int,
                   buckets: int = BUCKETS) -> tuple[Ints, Floats]:
    """The first, last, smallest and largest record of each of ``buckets`` slices of ``[start, end_t]``.

    ``t`` must be in time order. The result is in time order, and reducing it again changes
    nothing, so a long signal can be reduced chunk by chunk.

    Examples
    --------
    >>> t, v = reduce_min_max(np.arange(8), np.array([0., 5, -1, 2, 3, 9, 4, 1]), end_t=8, buckets=2)
    >>> t.tolist(), v.tolist()
    ([0, 1, 2, 3, 4, 5, 7], [0.0, 5.0, -1.0, 2.0, 3.0, 9.0, 1.0])
    """
    if t.size <= 4:
        return t, value
    span = max(end_t - start, 1)
    bucket = np.clip(((t - start).astype(np.float64) * buckets / span).astype(np.int64), 0, buckets - 1)
    first = np.flatnonzero(np.r_[True, bucket[1:] != bucket[:-1]])
    last = np.r_[first[1:], t.size] - 1
    order = np.lexsort((value, bucket))  # by slice, then value: each slice's smallest first, largest last
    keep = np.unique(np.concatenate([first, last, order[first], order[last]]))
    return t[keep], value[keep]


def records(trace: Trace, name: str) -> tuple[Ints, Floats]:
    """A value signal's records in time order (bits as 0/1)."""
    if trace.in_time_order(name):
        parts = list(trace.edge_chunks(name))
        t = np.concatenate([p[0] for p in parts]) if parts else np.empty(0, np.int64)
        v = np.concatenate([p[1] for p in parts]) if parts else np.empty(0)
    else:
        t, v = trace.edges(name)
        order = np.argsort(t, kind="stable")
        t, v = t[order], v[order]
    if trace.info[name].kind == "bit":
        v = (v != 0).astype(np.float64)
    return t.astype(np.int64, copy=False), v.astype(np.float64, copy=False)


def value_row(trace: Trace, name: str, *, t: Ints | None = None, v: Floats | None = None,
              embed_points: int = EMBED_POINTS, buckets: int = BUCKETS) -> Row:
    """A bit/int/real signal held to the run's end; reduced to an overview past ``embed_points`` records."""
    info = trace.info[name]
    end_t = max(trace.end_t, 1)
    if t is None or v is None:
        t, v = records(trace, name)
    row = Row(name, info.kind, info.unit, info.description, records=int(t.size))
    if info.kind == "int":
        row.states = state_names(info.description)
    if not t.size:
        row.t, row.v, row.distinct = np.array([0, end_t], np.int64), np.zeros(2), 0
        row.low, row.high = (0.0, 1.0)
        return row
    row.first_t = int(t[0])
    finite = v[np.isfinite(v)]
    row.distinct = 1 if (v == v[0]).all() or np.isnan(v).all() else 2
    row.low, row.high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if info.kind == "bit":
        row.low, row.high = 0.0, 1.0
    if t.size > embed_points:
        rt, rv = reduce_min_max(t, v, end_t=end_t, buckets=buckets)
        row.exact = False
        row.notes.append(f"{t.size:,} records: the page holds the first, last, smallest and largest of each of "
                         f"{buckets:,} slices of the run, and loads finer ones from waveform/ when zoomed in")
    else:
        rt, rv = t, v
    last_t = max(end_t, int(rt[-1]))
    row.t = np.r_[rt, last_t].astype(np.int64)
    row.v = np.r_[rv, rv[-1]].astype(np.float64)
    return row


def train_row(trace: Trace, name: str, *, embed_segments: int = EMBED_SEGMENTS, buckets: int = BUCKETS) -> Row:
    """A pulse train's segments (when at most ``embed_segments``) and rate blocks."""
    info = trace.info[name]
    row = Row(name, "pulse", info.unit, info.description, pulse_width=max(info.pulse_width, 1))
    rate_scale = 1 / float(trace.timebase.resolution_s)  # ticks per second
    parts: dict[str, list[Ints]] = {k: [] for k in ("t0", "duration", "count", "dir", "width")}
    n_segments = n_singles = 0
    for seg in trace.segment_chunks(name):
        live = seg["count"] > 0
        n_segments += int(live.sum())
        row.pulses += int(seg["count"][live].sum())
        if n_segments <= embed_segments:
            for k in parts:
                parts[k].append(seg[k][live])
    singles_t: list[Ints] = []
    singles_d: list[Ints] = []
    for t, d in trace.single_pulse_chunks(name):
        n_singles += t.size
        row.pulses += t.size
        if n_segments + n_singles <= embed_segments:
            singles_t.append(t)
            singles_d.append(d.astype(np.int64))
    row.records = n_segments + n_singles
    if n_segments + n_singles > embed_segments:  # the page: the rate per slice; the rest goes to side files
        row.left, row.right, row.rate_hz = binned_rate(trace, name, buckets=buckets, rate_scale=rate_scale)
        row.exact = False
        row.notes.append(f"{n_segments:,} segments and {n_singles:,} single pulses: the page holds the rate per "
                         f"slice of the run, and loads finer rates and the pulses from waveform/ when zoomed in")
        return row
    t0, duration, count, direction, width = (np.concatenate(parts[k]) if parts[k] else np.empty(0, np.int64)
                                             for k in ("t0", "duration", "count", "dir", "width"))
    if info.varying_width:  # a PWM output: a pulse cut by the gate is a segment of its high time only, not a rate
        left, right, rate = binned_rate(trace, name, buckets=buckets, rate_scale=rate_scale)
    else:
        left, right = t0, t0 + duration
        rate = np.where(direction == 1, 1.0, -1.0) * count / np.maximum(duration, 1) * rate_scale
    if singles_t:
        st, sd = np.concatenate(singles_t), np.concatenate(singles_d)
        if not info.varying_width:  # (the binned rate above counts them already)
            bl, br, brate = _binned(st, sd, end_t=max(trace.end_t, int(st.max()) + 1), buckets=buckets,
                                    rate_scale=rate_scale)
            left, right, rate = np.r_[left, bl], np.r_[right, br], np.r_[rate, brate]
        order = np.argsort(np.r_[t0, st], kind="stable")
        t0 = np.r_[t0, st][order]
        duration = np.r_[duration, np.ones_like(st)][order]
        count = np.r_[count, np.ones_like(st)][order]
        direction = np.r_[direction, sd][order]
        width = np.r_[width, np.full_like(st, max(info.pulse_width, 1))][order]
    row.segments = {"t0": t0, "duration": duration, "count": count, "dir": direction, "width": np.maximum(width, 1)}
    row.left, row.right, row.rate_hz = left, right, rate
    return row


def _binned(t: Ints, d: Ints, *, end_t: int, buckets: int, rate_scale: float) -> tuple[Ints, Ints, Floats]:
    """Signed pulses per slice of ``[0, end_t)`` as rate blocks (empty slices left out)."""
    width = max(-(-end_t // buckets), 1)
    k = t // width
    signed = np.where(d == 1, 1, -1)
    slots, inverse = np.unique(k, return_inverse=True)
    total = np.bincount(inverse, weights=signed)
    left = (slots * width).astype(np.int64)
    return left, left + width, total / width * rate_scale


def pulse_counts(trace: Trace, name: str, *, width: int) -> Floats:
    """Every pulse of a train counted per slice ``[k width, (k + 1) width)`` of the run, signed by direction."""
    end_t = max(trace.end_t, 1)
    n = -(-end_t // width) + 1
    total = np.zeros(n, np.float64)
    for t, d in trace.pulse_chunks(name):
        k = np.clip(t // width, 0, n - 1)
        total += np.bincount(k, weights=np.where(d == 1, 1.0, -1.0), minlength=n)
    return total


def binned_rate(trace: Trace, name: str, *, buckets: int, rate_scale: float) -> tuple[Ints, Ints, Floats]:
    """Every pulse of a train counted per slice of the run, as rate blocks (empty slices left out)."""
    width = max(-(-max(trace.end_t, 1) // buckets), 1)
    total = pulse_counts(trace, name, width=width)
    used = np.flatnonzero(total)
    left = (used * width).astype(np.int64)
    return left, left + width, total[used] / width * rate_scale


def ticks_of_ns(t_ns: int, resolution_s: Fraction) -> int:
    """A time in ns as ticks of ``resolution_s`` (nearest tick)."""
    return round(Fraction(int(t_ns), 10**9) / resolution_s)
