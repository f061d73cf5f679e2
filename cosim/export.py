"""Exports of a :class:`~cosim.trace.Trace`: waveforms for viewers, Parquet/CSV tables, a wide CSV.

:func:`write_trace` writes a trace into a folder; :func:`read_trace` reads the tables back into a
:class:`~cosim.trace.Trace`. Both use only the trace's public methods, and both go chunk by chunk:
their memory does not grow with the length of the run.

What is written (``formats``):

``trace_meta.json``     always: the resolution, the run's end and each signal's kind, unit and description
``console.txt``         (by the runner, :func:`write_console`) every console line: time, source, text
``vcd``                 ``trace.vcd`` (every signal), ``trace_digital.vcd`` (bits and pulse trains only,
                        for sigrok / PulseView) and ``trace.gtkw`` (a GTKWave view of ``trace.vcd``);
                        for a long run ``trace.vcd.gz`` and its ``trace.gtkw`` instead; see
                        :mod:`cosim.export_vcd` (``vcd-plain``: always the plain files)
``parquet`` / ``csv``   the four tables below, as ``<table>.parquet`` or ``<table>.csv``; ``csv`` also
                        writes ``trace_wide.csv`` (one column per signal, time in seconds, for
                        spreadsheets; see :mod:`cosim.export_wide`)

Tables:

``edges``     signal, t, value (int64)       bit and int signals: every change
``values``    signal, t, value (float64)     real signals: every change or sample
``segments``  signal, t0, duration, count,     pulse-train segments (see :mod:`cosim.pulses`); ``width``:
              dir, width                     how long each pulse is high [ticks] (the train's
                                             ``pulse_width``, or the segment's own in a PWM output)
``pulses``    signal, t, dir                 pulses recorded one by one

All ``t`` columns are integer ticks. Rows come signal by signal in declaration order, each
signal's in recording order.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from cosim.errors import ConfigurationError
from cosim.export_vcd import write_waveforms
from cosim.export_wide import write_wide_csv
from cosim.trace import Trace

_TABLES = ("edges", "values", "segments", "pulses")
_COLUMNS = {"edges": ("signal", "t", "value"), "values": ("signal", "t", "value"),
            "segments": ("signal", "t0", "duration", "count", "dir", "width"), "pulses": ("signal", "t", "dir")}
FORMATS = ("vcd", "vcd-plain", "parquet", "csv")
META = "trace_meta.json"
#: Rows gathered before a Parquet row group (or a CSV block) is written.
_BLOCK_ROWS = 1 << 17


def write_console(trace: Trace, path: str | Path) -> Path:
    """Write the trace's console lines as text, one per line: ``<t> ms  [<source>]  <text>``.

    The time is the instant the line was written, in ms with ns digits (exact at 1 ns resolution).
    An empty console writes an empty file, so that the file always belongs to this run.
    """
    path = Path(path)
    seconds = trace.timebase.seconds
    with path.open("w", encoding="utf-8") as out:
        out.writelines(f"{float(seconds(line.t)) * 1e3:14.6f} ms  [{line.source}]  {line.text}\n"
                       for line in trace.console())
    return path


def write_trace(trace: Trace, folder: str | Path, *, formats: tuple[str, ...] = ("vcd", "parquet")) -> Path:
    """Write ``trace`` into ``folder``: ``trace_meta.json`` and the given formats (vcd, parquet, csv)."""
    for fmt in formats:
        if fmt not in FORMATS:
            raise ConfigurationError.out_of_range("trace format", fmt, ", ".join(FORMATS))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / META).write_text(json.dumps(trace.header(), indent=1, default=str))
    for fmt in formats:
        if fmt in ("vcd", "vcd-plain"):
            write_waveforms(trace, folder, compress=False if fmt == "vcd-plain" else None)
        else:
            write_tables(trace, folder, fmt)
            if fmt == "csv":
                write_wide_csv(trace, folder / "trace_wide.csv")
    return folder


def read_trace(folder: str | Path, **options: Any) -> Trace:
    """Read a trace written by :func:`write_trace` (Parquet or CSV tables) back.

    ``options`` go to :class:`~cosim.trace.Trace` (``spill_rows``, ``spool``...).
    """
    folder = Path(folder)
    trace = Trace.from_header(json.loads((folder / META).read_text()), **options)
    read_tables(trace, folder)
    return trace


def _rows(trace: Trace, table: str) -> Iterator[dict[str, Any]]:
    """The rows of one table, chunk by chunk, as columns."""
    for name, info in trace.info.items():
        if info.kind == "pulse":
            if table == "segments":
                for seg in trace.segment_chunks(name):
                    yield {"signal": name, **seg}
            elif table == "pulses":
                for t, d in trace.single_pulse_chunks(name):
                    yield {"signal": name, "t": t, "dir": d.astype(np.int64)}
        elif table == ("values" if info.kind == "real" else "edges"):
            for t, v in trace.edge_chunks(name):
                yield {"signal": name, "t": t, "value": v if info.kind == "real" else v.astype(np.int64)}


def _blocks(trace: Trace, table: str) -> Iterator[pd.DataFrame]:
    """The rows of one table in frames of about ``_BLOCK_ROWS`` rows (at least one frame, maybe empty)."""
    parts: list[pd.DataFrame] = []
    size, emitted = 0, False
    for columns in _rows(trace, table):
        n = len(columns["t0" if table == "segments" else "t"])
        if not n:
            continue
        parts.append(pd.DataFrame({k: np.full(n, v, dtype=object) if k == "signal" else v
                                   for k, v in columns.items()}))
        size += n
        if size >= _BLOCK_ROWS:
            yield _typed(pd.concat(parts, ignore_index=True), table)
            parts, size, emitted = [], 0, True
    if parts or not emitted:
        yield _typed(pd.concat(parts, ignore_index=True) if parts else
                     pd.DataFrame({c: [] for c in _COLUMNS[table]}), table)


def _typed(frame: pd.DataFrame, table: str) -> pd.DataFrame:
    for column in frame.columns:
        if column == "signal":
            frame[column] = frame[column].astype(str)
        elif column == "value" and table == "values":
            frame[column] = frame[column].astype(np.float64)
        else:
            frame[column] = frame[column].astype(np.int64)
    return frame


def write_tables(trace: Trace, folder: str | Path, fmt: str = "parquet") -> list[Path]:
    """Write the four tables as Parquet or CSV files into ``folder``, a block of rows at a time."""
    folder = Path(folder)
    written = []
    for table in _TABLES:
        path = folder / f"{table}.{fmt}"
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            writer = None
            try:
                for frame in _blocks(trace, table):
                    batch = pa.Table.from_pandas(frame, preserve_index=False)
                    if writer is None:
                        writer = pq.ParquetWriter(path, batch.schema)
                    writer.write_table(batch)
            finally:
                if writer is not None:
                    writer.close()
        else:
            with path.open("w", newline="") as stream:
                for k, frame in enumerate(_blocks(trace, table)):
                    frame.to_csv(stream, index=False, header=k == 0)
        written.append(path)
    return written


def read_tables(trace: Trace, folder: str | Path) -> None:
    """Fill a freshly declared ``trace`` from the tables in ``folder`` (Parquet preferred), a block at a time."""
    folder = Path(folder)
    fmt = "parquet" if (folder / "edges.parquet").exists() else "csv"

    def read(table: str) -> Iterator[pd.DataFrame]:
        path = folder / f"{table}.{fmt}"
        if fmt == "csv":
            yield from pd.read_csv(path, chunksize=_BLOCK_ROWS)
            return
        import pyarrow.parquet as pq

        for batch in pq.ParquetFile(path).iter_batches(batch_size=_BLOCK_ROWS):
            yield batch.to_pandas()

    for table in ("edges", "values"):
        for frame in read(table):
            for name, group in frame.groupby("signal", sort=False):
                trace.extend(str(name), group["t"].to_numpy(np.int64), group["value"].to_numpy(np.float64))
    for frame in read("segments"):
        for name, group in frame.groupby("signal", sort=False):
            trace.extend_segments(str(name), group["t0"].to_numpy(np.int64), group["duration"].to_numpy(np.int64),
                                  group["count"].to_numpy(np.int64), group["dir"].to_numpy(np.int64),
                                  group["width"].to_numpy(np.int64) if "width" in group else None)
    for frame in read("pulses"):
        for name, group in frame.groupby("signal", sort=False):
            trace.extend_single_pulses(str(name), group["t"].to_numpy(np.int64), group["dir"].to_numpy(np.int64))
