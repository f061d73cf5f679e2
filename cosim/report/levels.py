"""Finer levels of a long row, in side files the page loads when the view is zoomed in on them.

A page holds an overview of each row (:mod:`cosim.report.rows`): the records themselves when
they are few, else :data:`~cosim.report.rows.BUCKETS` slices of the run. For a row with more, the
finer levels go into ``waveform/`` next to the page, each cut in blocks of time, one file a block:

* a **value** row: the first, last, smallest and largest record of each slice, with slices
  :data:`FACTOR` times narrower from one level to the next, then the records themselves in blocks
  of :data:`BLOCK_RECORDS`; each block starts with the value held at its start;
* a **pulse train**: the pulses counted per slice (the rate), each level :data:`FACTOR` times
  finer, down to about :data:`FINEST_SLICE_NS`, then the segments (single pulses as segments of
  one) in blocks of :data:`BLOCK_RECORDS`, which the browser expands into pulses when few are in
  view.

A side file is a script, ``cosimData("<file>", {...})``, whose arrays are packed by :func:`pack`
(integers as int32 steps, else float64; deflated, in base64; exact for ticks below 2**53): a page
opened from disk may load scripts but not read files.
A level is described in the page as ``{"w": slice width [ticks] (0: records or segments),
"blocks": [[from, to, file], ...]}`` where ``[from, to]`` bounds the times the block can show.
"""

from __future__ import annotations

import base64
import json
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim.report.rows import BUCKETS, Row, pulse_counts, reduce_min_max
from cosim.trace import Trace

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
#: How much finer each level is than the one above it.
FACTOR = 16
#: Records (or segments) in a block of the finest level.
BLOCK_RECORDS = 16_384
#: The finest slice of a train's rate levels [ns]: below it the pulses themselves are shown.
FINEST_SLICE_NS = 100_000
SIDE = "waveform"


def b64(values: npt.ArrayLike) -> str:
    """An array as little-endian float64 in base64 (what the page decodes into a ``Float64Array``)."""
    return base64.b64encode(np.ascontiguousarray(values, dtype="<f8").tobytes()).decode("ascii")


def pack(values: npt.ArrayLike) -> dict[str, Any]:
    """An array for a side file, compressed: integers as their first value and the int32 steps between
    them (``enc`` ``i``), else float64 (``f``), deflated (zlib) and in base64 (``z``); the page inflates
    it with the browser's ``DecompressionStream``.

    Examples
    --------
    >>> packed = pack([3_600_000_000_000, 3_600_001_000_000, 3_600_002_000_000])
    >>> packed["enc"], packed["first"], np.frombuffer(zlib.decompress(base64.b64decode(packed["z"])), "<i4").tolist()
    ('i', 3600000000000.0, [1000000, 1000000])
    """
    a = np.asarray(values, dtype=np.float64)
    if a.size and np.isfinite(a).all() and (a == np.round(a)).all():
        steps = np.diff(a)
        if not steps.size or np.abs(steps).max() < 2**31:
            raw = steps.astype("<i4").tobytes()
            return {"enc": "i", "first": float(a[0]), "n": int(a.size), "z": _deflate(raw)}
    return {"enc": "f", "n": int(a.size), "z": _deflate(a.astype("<f8").tobytes())}


def _deflate(raw: bytes) -> str:
    return base64.b64encode(zlib.compress(raw, 1)).decode("ascii")


class SideFiles:
    """The side files of one page, in ``<folder>/waveform/`` (made on the first file)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder / SIDE
        self.count = 0
        self.bytes = 0

    def write(self, key: str, arrays: Mapping[str, npt.ArrayLike]) -> str:
        """Write one block; returns its path relative to the page."""
        self.folder.mkdir(parents=True, exist_ok=True)
        payload = json.dumps({k: pack(v) for k, v in arrays.items()})
        text = f"cosimData({json.dumps(key)}, {payload});\n"
        (self.folder / key).write_text(text, encoding="ascii")
        self.count += 1
        self.bytes += len(text)
        return f"{SIDE}/{key}"


def value_levels(row: Row, t: Ints, v: Floats, *, end_t: int, side: SideFiles, index: int) -> None:
    """The finer levels of a reduced value row into side files (``row.detail``)."""
    end_t = max(end_t, 1)
    k = 1
    while BUCKETS * FACTOR**k * 2 < t.size and end_t // (BUCKETS * FACTOR**k) >= 1:
        blocks = FACTOR**k
        span = -(-end_t // blocks)
        level = []
        bounds = np.searchsorted(t, np.arange(blocks + 1, dtype=np.int64) * span, side="left")
        for b in range(blocks):
            i0, i1 = int(bounds[b]), int(bounds[b + 1])
            if i1 <= i0:
                continue
            rt, rv = reduce_min_max(t[i0:i1], v[i0:i1], start=b * span, end_t=(b + 1) * span, buckets=BUCKETS)
            rt, rv = _held_from(t, v, i0, b * span, rt, rv)
            file = side.write(f"r{index}_l{k}_{b}.js", {"t": rt, "v": rv})
            level.append([b * span, min((b + 1) * span, end_t), file])
        row.detail.append({"w": span / BUCKETS, "blocks": level})
        k += 1
    level = []
    for b, i0 in enumerate(range(0, t.size, BLOCK_RECORDS)):
        i1 = min(i0 + BLOCK_RECORDS, t.size)
        rt, rv = _held_from(t, v, i0, int(t[i0]), t[i0:i1], v[i0:i1])
        to = int(t[i1]) if i1 < t.size else end_t
        level.append([int(t[i0]), to, side.write(f"r{index}_raw_{b}.js", {"t": rt, "v": rv})])
    row.detail.append({"w": 0, "blocks": level})


def _held_from(t: Ints, v: Floats, i0: int, start: int, bt: Ints, bv: Floats) -> tuple[Ints, Floats]:
    """A block's points with the value held at its ``start`` first (when a record came before)."""
    if i0 > 0 and (not bt.size or bt[0] > start):
        return np.r_[start, bt].astype(np.int64), np.r_[v[i0 - 1], bv]
    return bt, bv


def train_levels(row: Row, trace: Trace, *, side: SideFiles, index: int) -> None:
    """A long train's rate levels and segment blocks into side files (``row.detail``), and its
    overview rate (``row.left, right, rate_hz``) at the coarsest of those levels."""
    end_t = max(trace.end_t, 1)
    ticks_per_ns = float(1 / (trace.timebase.resolution_s * 10**9))
    finest = max(int(FINEST_SLICE_NS * ticks_per_ns), 1)
    levels = 0
    while end_t / (BUCKETS * FACTOR**(levels + 1)) >= finest:
        levels += 1
    finest = -(-end_t // (BUCKETS * FACTOR**levels))  # the overview (level 0) has at most BUCKETS slices
    counts = pulse_counts(trace, row.name, width=finest)
    rate_scale = 1 / float(trace.timebase.resolution_s)
    per_level = []
    for k in range(levels, -1, -1):  # finest first, each level summing FACTOR slices of the one below
        width = finest * FACTOR**(levels - k)
        per_level.append((k, width, counts))
        pad = (-counts.size) % FACTOR
        counts = np.r_[counts, np.zeros(pad)].reshape(-1, FACTOR).sum(axis=1)
    for k, width, level_counts in reversed(per_level):
        used = np.flatnonzero(level_counts)
        left = used * width
        rate = level_counts[used] / width * rate_scale
        if k == 0:
            row.left, row.right, row.rate_hz = left.astype(np.int64), (left + width).astype(np.int64), rate
            continue
        span = width * BUCKETS * FACTOR
        blocks = []
        cut = np.searchsorted(left, np.arange(0, end_t + span, span), side="left")
        for b in range(cut.size - 1):
            i0, i1 = int(cut[b]), int(cut[b + 1])
            if i1 > i0:
                blocks.append([b * span, min((b + 1) * span, end_t),
                               side.write(f"r{index}_l{k}_{b}.js", {"left": left[i0:i1], "rate": rate[i0:i1]})])
        row.detail.append({"w": width, "blocks": blocks})
    row.detail.append({"w": 0, "blocks": _segment_blocks(trace, row, side=side, index=index)})


def _segment_blocks(trace: Trace, row: Row, *, side: SideFiles, index: int) -> list[list[Any]]:
    """The train's segments (single pulses as segments of one) in time order, in blocks."""
    parts = [seg for seg in trace.segment_chunks(row.name)]
    seg = {k: np.concatenate([p[k] for p in parts]) if parts else np.empty(0, np.int64)
           for k in ("t0", "duration", "count", "dir", "width")}
    live = seg["count"] > 0
    seg = {k: a[live] for k, a in seg.items()}
    singles = list(trace.single_pulse_chunks(row.name))
    if singles:
        st = np.concatenate([s[0] for s in singles])
        sd = np.concatenate([s[1] for s in singles]).astype(np.int64)
        one = np.ones_like(st)
        seg = {"t0": np.r_[seg["t0"], st], "duration": np.r_[seg["duration"], one], "count": np.r_[seg["count"], one],
               "dir": np.r_[seg["dir"], sd], "width": np.r_[seg["width"], np.full_like(st, row.pulse_width)]}
    order = np.argsort(seg["t0"], kind="stable")
    seg = {k: a[order] for k, a in seg.items()}
    seg["width"] = np.maximum(seg["width"], 1)
    reach = seg["t0"] + seg["duration"] + seg["width"]
    blocks = []
    for b, i0 in enumerate(range(0, seg["t0"].size, BLOCK_RECORDS)):
        i1 = min(i0 + BLOCK_RECORDS, seg["t0"].size)
        part = {k: a[i0:i1] for k, a in seg.items()}
        blocks.append([int(seg["t0"][i0]), int(reach[i0:i1].max()), side.write(f"r{index}_seg_{b}.js", part)])
    return blocks
