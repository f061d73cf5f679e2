"""What the waveform draws, as bounded arrays: one row per signal, read from the trace chunk by chunk.

No plotting here (numpy only), so each rule is tested on its own:

* a value signal (bit, int, real) is its changes held to the run's end (:func:`held`): a signal
  recorded once is a line across the whole run; one never recorded is a line at 0, said so;
* a long value signal is reduced to the first, last, smallest and largest record of each of
  ``buckets`` equal slices of the run (the shape a screen of that many pixels can show);
* a pulse train (:func:`train`) keeps its segments ``(t0, duration, count, dir)``, its pulses
  recorded one by one becoming segments of one pulse; the browser expands the segments of the
  visible window into pulses by the rule of :mod:`cosim.pulses`. Drawn zoomed out, each segment is
  its rate (pulses/s, signed by direction) over ``[t0, t0 + duration)``; single pulses are counted
  per slice. Past ``max_segments`` the segments are merged (the rate stays exact on average) and
  the train is drawn as a rate only.

All times are ticks of the trace's resolution.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from cosim.trace import Trace

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
#: Slices of the run for reducing a long signal (about the pixels of a wide screen).
BUCKETS = 2000
#: Records of a value signal drawn as they are; a longer signal is reduced.
MAX_POINTS = 8000
#: Segments (with single pulses) of a pulse train embedded for expansion into pulses.
MAX_SEGMENTS = 20_000
DIGITAL = ("bit", "pulse")


@dataclass(frozen=True)
class Held:
    """A value signal as drawn: ``t`` [ticks] and ``value``, the last point at the run's end."""

    t: Ints
    value: Floats
    records: int
    note: str = ""


@dataclass(frozen=True)
class Train:
    """A pulse train as drawn.

    ``t0, duration, count, direction, width``: the segments (and single pulses as segments of one
    pulse) in time order, for expansion into pulses, each pulse ``width`` ticks high (the declared
    pulse width, or the segment's own: a PWM output); empty when ``expandable`` is false.
    ``left, right, rate_hz``: the rate blocks drawn zoomed out [ticks, ticks, pulses/s, signed].
    """

    t0: Ints
    duration: Ints
    count: Ints
    direction: Ints
    width: Ints
    left: Ints
    right: Ints
    rate_hz: Floats
    pulses: int
    expandable: bool
    notes: list[str] = field(default_factory=list)


def signal_order(trace: Trace) -> list[str]:
    """The digital signals, then the analog ones; in each part grouped by device and axis (in the order
    each first appears), in each group the pulse trains before the bits, the integers before the reals.

    Examples
    --------
    >>> trace = Trace()
    >>> for name, kind in [("a.x.pos", "real"), ("a.x.dir", "bit"), ("a.x.step", "pulse"), ("b.level", "int")]:
    ...     trace.declare(name, kind)
    >>> signal_order(trace)
    ['a.x.step', 'a.x.dir', 'a.x.pos', 'b.level']
    """
    rank = {"pulse": 0, "bit": 1, "int": 2, "real": 3}
    groups: dict[str, int] = {}
    for name in trace.info:
        groups.setdefault(name.rsplit(".", 1)[0], len(groups))
    return sorted(trace.info, key=lambda n: (trace.info[n].kind not in DIGITAL, groups[n.rsplit(".", 1)[0]],
                                             rank[trace.info[n].kind]))


def reduce_min_max(t: Ints, value: Floats, *, end_t: int, buckets: int = BUCKETS) -> tuple[Ints, Floats]:
    """The first, last, smallest and largest record of each of ``buckets`` slices of ``[0, end_t]``.

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
    bucket = np.clip((t.astype(np.float64) * buckets / max(end_t, 1)).astype(np.int64), 0, buckets - 1)
    first = np.flatnonzero(np.r_[True, bucket[1:] != bucket[:-1]])
    last = np.r_[first[1:], t.size] - 1
    order = np.lexsort((value, bucket))  # by slice, then value: each slice's smallest first, largest last
    keep = np.unique(np.concatenate([first, last, order[first], order[last]]))
    return t[keep], value[keep]


def held(trace: Trace, name: str, *, max_points: int = MAX_POINTS, buckets: int = BUCKETS) -> Held:
    """A bit/int/real signal held to the run's end, reduced when it has more than ``max_points`` records."""
    end_t = max(trace.end_t, 1)
    kept_t: Ints = np.empty(0, np.int64)
    kept_v: Floats = np.empty(0, np.float64)
    records, reduced = 0, False
    ordered = trace.in_time_order(name)
    chunks = trace.edge_chunks(name) if ordered else iter([_sorted(*trace.edges(name))])
    for t, v in chunks:
        records += t.size
        kept_t, kept_v = np.concatenate([kept_t, t]), np.concatenate([kept_v, v])
        if kept_t.size > max_points:
            kept_t, kept_v = reduce_min_max(kept_t, kept_v, end_t=end_t, buckets=buckets)
            reduced = True
    if not records:
        return Held(np.array([0, end_t], np.int64), np.zeros(2), 0, "never recorded: drawn at 0")
    last_t = max(end_t, int(kept_t[-1]))
    t_out = np.r_[kept_t, last_t].astype(np.int64)
    v_out = np.r_[kept_v, kept_v[-1]].astype(np.float64)
    note = (f"{records:,} records drawn as the first, last, smallest and largest of {buckets:,} slices"
            if reduced else "")
    return Held(t_out, v_out, records, note)


def _sorted(t: Ints, v: Floats) -> tuple[Ints, Floats]:
    order = np.argsort(t, kind="stable")
    return t[order], v[order]


def train(trace: Trace, name: str, *, max_segments: int = MAX_SEGMENTS, buckets: int = BUCKETS) -> Train:
    """A pulse train's segments (for expansion) and rate blocks, at most ``max_segments`` of each."""
    rate_scale = 1 / float(trace.timebase.resolution_s)  # ticks per second
    parts = {k: [] for k in ("t0", "duration", "count", "dir", "width")}  # type: dict[str, list[Ints]]
    n_segments = n_singles = pulses = 0
    overflow = False
    for seg in trace.segment_chunks(name):
        live = seg["count"] > 0
        n_segments += int(live.sum())
        pulses += int(seg["count"][live].sum())
        if n_segments <= max_segments:
            for k in parts:
                parts[k].append(seg[k][live])
        else:
            overflow = True
    singles_t: list[Ints] = []
    singles_d: list[Ints] = []
    for t, d in trace.single_pulse_chunks(name):
        n_singles += t.size
        pulses += t.size
        if n_segments + n_singles <= max_segments:
            singles_t.append(t)
            singles_d.append(d.astype(np.int64))
        else:
            overflow = True
    notes: list[str] = []
    if overflow:
        notes.append(f"{n_segments:,} segments and {n_singles:,} single pulses: drawn as a rate over "
                     f"{buckets:,} slices of the run only (no single pulses here; open trace.vcd)")
        left, right, rate = _binned_rate(trace, name, buckets=buckets, rate_scale=rate_scale)
        empty = np.empty(0, np.int64)
        return Train(empty, empty, empty, empty, empty, left, right, rate, pulses, False, notes)
    t0, duration, count, direction, width = (np.concatenate(parts[k]) if parts[k] else np.empty(0, np.int64)
                                             for k in ("t0", "duration", "count", "dir", "width"))
    if trace.info[name].varying_width:  # a PWM output: a pulse cut by the gate is a segment of its high time only,
        left, right, rate = _binned_rate(trace, name, buckets=buckets, rate_scale=rate_scale)  # not a rate
    else:
        left, right = t0, t0 + duration
        rate = np.where(direction == 1, 1.0, -1.0) * count / duration * rate_scale
    if singles_t:
        st, sd = np.concatenate(singles_t), np.concatenate(singles_d)
        if not trace.info[name].varying_width:  # (the binned rate above counts them already)
            bl, br, brate = _binned(st, sd, end_t=max(trace.end_t, int(st.max()) + 1), buckets=buckets,
                                    rate_scale=rate_scale)
            left, right, rate = np.r_[left, bl], np.r_[right, br], np.r_[rate, brate]
        order = np.argsort(np.r_[t0, st], kind="stable")
        t0 = np.r_[t0, st][order]
        duration = np.r_[duration, np.ones_like(st)][order]
        count = np.r_[count, np.ones_like(st)][order]
        direction = np.r_[direction, sd][order]
        width = np.r_[width, np.full_like(st, max(trace.info[name].pulse_width, 1))][order]
    return Train(t0, duration, count, direction, width, left, right, rate, pulses, True, notes)


def _binned(t: Ints, d: Ints, *, end_t: int, buckets: int, rate_scale: float) -> tuple[Ints, Ints, Floats]:
    """Signed pulses per slice of ``[0, end_t)`` as rate blocks (empty slices left out)."""
    width = max(-(-end_t // buckets), 1)
    k = t // width
    signed = np.where(d == 1, 1, -1)
    slots, inverse = np.unique(k, return_inverse=True)
    total = np.bincount(inverse, weights=signed)
    left = (slots * width).astype(np.int64)
    return left, left + width, total / width * rate_scale


def _binned_rate(trace: Trace, name: str, *, buckets: int, rate_scale: float) -> tuple[Ints, Ints, Floats]:
    """Every pulse of a train counted per slice of the run (for a train too long to embed)."""
    end_t = max(trace.end_t, 1)
    width = max(-(-end_t // buckets), 1)
    n = -(-end_t // width) + 1
    total = np.zeros(n, np.float64)
    for t, d in trace.pulse_chunks(name):
        k = np.clip(t // width, 0, n - 1)
        total += np.bincount(k, weights=np.where(d == 1, 1.0, -1.0), minlength=n)
    used = np.flatnonzero(total)
    left = (used * width).astype(np.int64)
    return left, left + width, total[used] / width * rate_scale


def ticks_of_ns(t_ns: int, resolution_s: Fraction) -> int:
    """A time in ns as ticks of ``resolution_s`` (nearest tick)."""
    return round(Fraction(int(t_ns), 10**9) / resolution_s)
