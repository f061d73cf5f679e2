"""A wide CSV of a trace for spreadsheets: one row per instant, one column per signal, time in seconds.

``trace_wide.csv``::

    time_s,pokeys.x.step,pokeys.x.dir,pokeys.x.position,...,laser.power
    0.000000000,0,0,0,...,0.0
    0.001000000,25,1,25,...,

* ``time_s``: the instant in seconds, written exactly (``0.001000000`` at a 1 ns resolution: as many
  decimals as the resolution needs; a resolution that is no decimal fraction of a second is
  written as the nearest float);
* one row per instant at which a bit, int or real signal has a record, a pulse segment starts or a
  single pulse falls, plus the start (0) and the end of the run;
* a bit/int/real column holds the value in effect at that instant (the last record at or before
  it; empty before the first record), so a sampled signal repeats its last sample;
* a pulse train's column holds its position: the signed count of its pulses at or before the
  instant (direction 1 counts up), from every pulse, also those between rows.

Written chunk by chunk (the rows of about one chunk of records at a time), like the VCD.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
import pandas as pd

from cosim.timebase import TimeBase
from cosim.trace import Trace
from cosim.tracecursor import Held, Position
from cosim.tracestore import merge_sorted

Ints = npt.NDArray[np.int64]


def write_wide_csv(trace: Trace, path: str | Path) -> Path:
    """Write ``trace`` as one wide CSV table (see the module documentation)."""
    path = Path(path)
    names = list(trace.info)
    readers: list[Any] = [Position(trace.pulse_chunks(n)) if trace.info[n].kind == "pulse"
                          else Held(trace.edge_chunks(n)) for n in names]
    seconds = _seconds(trace.timebase)
    with path.open("w", newline="") as stream:
        header = True
        for t in _instants(trace):
            columns: dict[str, Any] = {"time_s": seconds(t)}
            for name, reader in zip(names, readers, strict=True):
                kind = trace.info[name].kind
                if kind == "pulse":
                    columns[name] = reader.at(t)
                    continue
                value = reader.values_at(t)
                missing = np.isnan(value)
                columns[name] = value if kind == "real" else pd.arrays.IntegerArray(
                    np.where(missing, 0, value).astype(np.int64), missing)
            pd.DataFrame(columns).to_csv(stream, index=False, header=header, na_rep="")
            header = False
    return path


def _instants(trace: Trace) -> Iterator[Ints]:
    """The rows' instants, sorted and unique, chunk by chunk."""
    streams: list[Iterator[tuple[Ints]]] = [iter([(np.array([0, max(trace.end_t, 0)], dtype=np.int64),)])]
    for name, info in trace.info.items():
        if info.kind != "pulse":
            streams.append(_times(trace.edge_chunks(name), trace.in_time_order(name)))
        else:
            segments = ((c["t0"],) for c in trace.segment_chunks(name))
            singles = ((t,) for t, _ in trace.single_pulse_chunks(name))
            ordered = trace.in_time_order(name)
            streams += [_times(segments, ordered), _times(singles, ordered)]
    last: int | None = None
    for (t,) in merge_sorted(streams):
        t = np.unique(t)
        if last is not None and t.size and t[0] == last:
            t = t[1:]
        if t.size:
            last = int(t[-1])
            yield t


def _times(chunks: Iterator[tuple[Any, ...]], ordered: bool) -> Iterator[tuple[Ints]]:
    """The first column of each chunk (all of them sorted at once if the records are out of order)."""
    if ordered:
        for chunk in chunks:
            yield (chunk[0].astype(np.int64),)
        return
    parts = [c[0] for c in chunks]
    if parts:
        yield (np.sort(np.concatenate(parts)).astype(np.int64),)


def _seconds(timebase: TimeBase) -> Callable[[Ints], list[str]]:
    """``ticks -> list of str``: instants in seconds, exact where the resolution is a decimal fraction."""
    resolution = timebase.resolution_s
    decimals = next((d for d in range(19) if 10**d % resolution.denominator == 0), None)
    if decimals is None:
        return lambda t: [repr(float(x * resolution)) for x in t.tolist()]
    return partial(_decimal_seconds, scale=resolution.numerator * (10**decimals // resolution.denominator),
                   decimals=decimals)


def _decimal_seconds(t: Ints, *, scale: int, decimals: int) -> list[str]:
    """Ticks as seconds with ``decimals`` decimals; ``scale`` = units of 10**-decimals s per tick."""
    units = [int(x) * scale for x in t.tolist()]
    if not decimals:
        return [str(u) for u in units]
    one = 10**decimals
    return [f"{'-' if u < 0 else ''}{abs(u) // one}.{abs(u) % one:0{decimals}d}" for u in units]
