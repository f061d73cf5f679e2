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

Parquet is written with pyarrow alone; pandas is imported only to write or read CSV and to read
tables back (a run that writes Parquet does not load it).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from cosim.errors import ConfigurationError
from cosim.export_vcd import write_waveforms
from cosim.trace import Trace

if TYPE_CHECKING:
    import pandas as pd

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
                from cosim.export_wide import write_wide_csv

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


#: Column types of each table (the ``signal`` column is text).
_TYPES: dict[str, dict[str, type[np.generic]]] = {
    "edges": {"t": np.int64, "value": np.int64}, "values": {"t": np.int64, "value": np.float64},
    "segments": {c: np.int64 for c in _COLUMNS["segments"][1:]}, "pulses": {"t": np.int64, "dir": np.int64}}

@dataclass
class _Block:
    """Rows of one table: the ``signal`` column as runs (name, rows), the others as typed arrays."""

    runs: list[tuple[str, int]]
    columns: dict[str, npt.NDArray[Any]]

    def signals(self) -> npt.NDArray[Any]:
        """The ``signal`` column as an array of Python strings."""
        names = np.array([name for name, _ in self.runs] or [""], dtype=object)
        return np.repeat(names, [n for _, n in self.runs] or [0])


def _blocks(trace: Trace, table: str) -> Iterator[_Block]:
    """The rows of one table in blocks of about ``_BLOCK_ROWS`` rows (at least one block, maybe empty)."""
    parts: list[dict[str, Any]] = []
    size, emitted = 0, False
    for columns in _rows(trace, table):
        n = len(columns["t0" if table == "segments" else "t"])
        if not n:
            continue
        parts.append(columns)
        size += n
        if size >= _BLOCK_ROWS:
            yield _joined(parts, table)
            parts, size, emitted = [], 0, True
    if parts or not emitted:
        yield _joined(parts, table)


def _joined(parts: list[dict[str, Any]], table: str) -> _Block:
    """One block of ``parts``, each column in its table's type."""
    key = "t0" if table == "segments" else "t"
    columns = {}
    for column, dtype in _TYPES[table].items():
        pieces = [part[column] for part in parts if column in part]
        columns[column] = np.concatenate(pieces).astype(dtype) if pieces else np.empty(0, dtype=dtype)
    return _Block([(part["signal"], len(part[key])) for part in parts], columns)


def _arrow_table(block: _Block, schema: Any) -> Any:
    """``block`` as a pyarrow table of ``schema``, built from its buffers (``pa.array`` would import pandas)."""
    import pyarrow as pa

    names = [name.encode() for name, _ in block.runs]
    counts = np.array([n for _, n in block.runs], dtype=np.int64)
    lengths = np.repeat(np.array([len(b) for b in names], dtype=np.int64), counts)
    offsets = np.zeros(len(lengths) + 1, dtype=np.int64)
    np.cumsum(lengths, out=offsets[1:])
    text = b"".join(b * int(n) for b, n in zip(names, counts, strict=True))
    arrays = {"signal": pa.Array.from_buffers(pa.large_string(), len(lengths),
                                              [None, pa.py_buffer(offsets), pa.py_buffer(text)])}
    for column, values in block.columns.items():
        arrays[column] = pa.Array.from_buffers(schema.field(column).type, len(values),
                                               [None, pa.py_buffer(np.ascontiguousarray(values))])
    return pa.table(arrays, schema=schema)


def write_tables(trace: Trace, folder: str | Path, fmt: str = "parquet") -> list[Path]:
    """Write the four tables as Parquet or CSV files into ``folder``, a block of rows at a time."""
    folder = Path(folder)
    written = []
    for table in _TABLES:
        path = folder / f"{table}.{fmt}"
        if fmt == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            schema = pa.schema([(c, pa.large_string() if c == "signal" else pa.from_numpy_dtype(_TYPES[table][c]))
                                for c in _COLUMNS[table]])
            with pq.ParquetWriter(path, schema) as writer:
                for block in _blocks(trace, table):
                    writer.write_table(_arrow_table(block, schema))
        else:
            import pandas as pd

            with path.open("w", newline="") as stream:
                for k, block in enumerate(_blocks(trace, table)):
                    frame = pd.DataFrame({"signal": block.signals(), **block.columns}, columns=_COLUMNS[table])
                    frame.to_csv(stream, index=False, header=k == 0)
        written.append(path)
    return written


def read_tables(trace: Trace, folder: str | Path) -> None:
    """Fill a freshly declared ``trace`` from the tables in ``folder`` (Parquet preferred), a block at a time."""
    import pandas as pd

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
