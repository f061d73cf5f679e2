"""Where the trace keeps its records: columns in memory up to a threshold, then chunks on disk.

Each table of a signal (a value signal's ``t, v``; a pulse train's segments and its single pulses)
is a :class:`Columns`: Python ``array`` columns that the hot recording paths append to. When a
table holds ``limit`` rows they are written to the trace's spool folder as one Arrow IPC record
batch and the arrays are emptied, so a run keeps at most ``limit`` rows of each table in memory
however long it runs. Reading goes chunk by chunk: the spilled batches in order, then the rows
still in memory.

:func:`merge_sorted` merges time-ordered chunk streams into one, in bounded memory (pulses of
segments with single pulses; every signal of a VCD).

:func:`segment_pulses` materialises the pulses of time-ordered segments a bounded number at a time.

A leaf like the trace: numpy and the pulse rule (pyarrow is imported when the first table spills).
"""

from __future__ import annotations

import contextlib
import shutil
import tempfile
import weakref
from array import array
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim.pulses import materialize_pulses

Chunk = tuple[npt.NDArray[Any], ...]
DTYPES: dict[str, type[np.generic]] = {"q": np.int64, "d": np.float64, "b": np.int8}
#: Rows of one table kept in memory before they go to disk (about 1 MiB for ``t, v``).
SPILL_ROWS = 1 << 16


class Spool:
    """The folder holding a trace's spilled chunks: made at the first spill, removed with the trace.

    Parameters
    ----------
    parent : path, optional
        Where to make the folder (default: the system's temporary folder). The runner puts it in
        the results folder, so that a long run spills to the disk the results go to (a ``/tmp`` in
        memory would defeat the purpose).
    """

    def __init__(self, parent: str | Path | None = None) -> None:
        self.parent = parent
        self._folder: Path | None = None
        self._files: list[Any] = []  # open writers and their files, closed with the folder
        self._finalizer: weakref.finalize | None = None

    def folder(self) -> Path:
        """The spool folder (made on first use)."""
        if self._folder is None:
            parent = None if self.parent is None else Path(self.parent)
            if parent is not None:
                parent.mkdir(parents=True, exist_ok=True)
            self._folder = Path(tempfile.mkdtemp(prefix="cosim-trace-", dir=parent))
            self._finalizer = weakref.finalize(self, _remove, self._folder, self._files)
        return self._folder

    def keep(self, handle: Any) -> None:
        """Close ``handle`` when the spool is removed."""
        self._files.append(handle)

    @property
    def used(self) -> bool:
        """Has anything been spilled?"""
        return self._folder is not None

    def remove(self) -> None:
        """Delete the folder now (the trace's spilled records are gone)."""
        if self._finalizer is not None:
            self._finalizer()


def _remove(folder: Path, files: list[Any]) -> None:
    for handle in reversed(files):
        with contextlib.suppress(Exception):  # closing on the way out; the folder goes anyway
            handle.close()
    files.clear()
    shutil.rmtree(folder, ignore_errors=True)


class Columns:
    """Append-only columns of one table, spilled to disk in chunks of ``limit`` rows.

    Parameters
    ----------
    fields : tuple of (name, typecode)
        Column names and ``array`` typecodes (``q`` int64, ``d`` float64, ``b`` int8).
    spool : Spool
        Where spilled chunks go.
    key : str
        File name of this table in the spool.
    limit : int
        Rows kept in memory before a spill (>= 1).
    segments : bool
        The rows are pulse segments ``t0, duration, count, dir`` (their order is that of their
        pulses); otherwise column 0 is a time and the rows are ordered by it.

    Attributes
    ----------
    arrays : list of array.array
        The rows in memory (append to them, then call :meth:`appended`).
    spilled : int
        Rows on disk.
    """

    __slots__ = ("_file", "_last", "_ordered_rows", "_schema", "_writer", "arrays", "batches", "fields", "key",
                 "limit", "ordered", "segments", "spilled", "spool")

    def __init__(self, fields: tuple[tuple[str, str], ...], *, spool: Spool, key: str, limit: int = SPILL_ROWS,
                 segments: bool = False) -> None:
        self.fields = fields
        self.arrays: list[array[Any]] = [array(code) for _, code in fields]
        self.spool = spool
        self.key = key
        self.limit = max(1, int(limit))
        self.segments = segments
        self.spilled = 0
        self.batches = 0
        self.ordered = True  # every row so far in order (see :meth:`in_order`)
        self._ordered_rows = 0
        self._last: int | None = None
        self._writer: Any = None
        self._file: Any = None
        self._schema: Any = None

    def __len__(self) -> int:
        return self.spilled + len(self.arrays[0])

    @property
    def in_memory(self) -> int:
        """Rows held in memory."""
        return len(self.arrays[0])

    def appended(self) -> None:
        """Spill if the rows in memory reached the limit (call after appending)."""
        if len(self.arrays[0]) >= self.limit:
            self.spill()

    def extend(self, columns: tuple[npt.NDArray[Any], ...]) -> None:
        """Append many rows (one array per column), spilling in chunks of at most ``limit`` rows."""
        n = len(columns[0])
        start = 0
        while start < n:
            room = max(self.limit - len(self.arrays[0]), 1)
            stop = min(n, start + room)
            for a, col in zip(self.arrays, columns, strict=True):
                a.frombytes(np.ascontiguousarray(col[start:stop], dtype=DTYPES[a.typecode]).tobytes())
            start = stop
            self.appended()

    def tail(self) -> Chunk:
        """The rows in memory, as numpy copies."""
        return tuple(np.frombuffer(a, dtype=DTYPES[a.typecode]).copy() for a in self.arrays)

    def spill(self) -> None:
        """Write the rows in memory to the spool as one record batch and forget them."""
        if not len(self.arrays[0]):
            return
        import pyarrow as pa

        chunk = self.tail()
        self._check_order(chunk, first=self._ordered_rows - self.spilled)
        if self._writer is None:
            self._schema = pa.schema([(name, pa.from_numpy_dtype(DTYPES[code])) for name, code in self.fields])
            self._file = pa.OSFile(str(self.spool.folder() / f"{self.key}.arrows"), "wb")
            self._writer = pa.ipc.new_stream(self._file, self._schema)
            self.spool.keep(self._file)
            self.spool.keep(self._writer)
        # Arrays made from the numpy buffers (pa.array would import pandas, a second or so, for nothing)
        columns = [pa.Array.from_buffers(field.type, len(c), [None, pa.py_buffer(c)])
                   for field, c in zip(self._schema, chunk, strict=True)]
        self._writer.write_batch(pa.record_batch(columns, schema=self._schema))
        self.batches += 1
        self.spilled += len(chunk[0])
        for a in self.arrays:
            del a[:]

    def chunks(self) -> Iterator[Chunk]:
        """Every row, chunk by chunk (the spilled batches, then the rows in memory), in append order."""
        if self.batches:
            import pyarrow as pa

            with pa.OSFile(str(self.spool.folder() / f"{self.key}.arrows"), "rb") as source:
                reader = pa.ipc.open_stream(source)
                for _ in range(self.batches):
                    batch = reader.read_next_batch()
                    yield tuple(_numpy(batch.column(i), DTYPES[code]) for i, (_, code) in enumerate(self.fields))
        if len(self.arrays[0]):
            yield self.tail()

    def in_order(self) -> bool:
        """Are the rows in time order (column 0; for segments, their pulses)?"""
        if self._ordered_rows < len(self):
            self._check_order(self.tail(), first=self._ordered_rows - self.spilled)
        return self.ordered

    def _check_order(self, chunk: Chunk, *, first: int) -> None:
        """Extend the order check over ``chunk[first:]`` (rows not checked yet)."""
        rows = len(chunk[0])
        if first >= rows or not self.ordered:
            self._ordered_rows = self.spilled + rows
            return
        if self.segments:
            t0, duration, count = (c[first:].astype(np.int64) for c in chunk[:3])
            some = count > 0
            t0, duration, count = t0[some], duration[some], count[some]
            begin, end = t0, t0 + ((count - 1) * duration) // np.maximum(count, 1)
            ok = bool(np.all(duration >= 0))
        else:
            begin = end = chunk[0][first:]
            ok = True
        if begin.size:
            ok = ok and bool(np.all(begin[1:] >= end[:-1])) and (self._last is None or int(begin[0]) >= self._last)
            self._last = int(end[-1])
        self.ordered = ok
        self._ordered_rows = self.spilled + rows


def merge_sorted(streams: Iterable[Iterable[Chunk]]) -> Iterator[Chunk]:
    """Merge time-ordered chunk streams into one time-ordered stream, in bounded memory.

    Each stream yields tuples of equally long arrays whose first is a time [ticks], in
    non-decreasing order over the whole stream; the columns match across streams. At one instant
    the rows keep their stream's order, and streams come in the order given. Memory: about one
    chunk per stream.

    Examples
    --------
    >>> a = [(np.array([0, 5]), np.array([1, 1])), (np.array([5, 9]), np.array([2, 2]))]
    >>> b = [(np.array([5, 7]), np.array([3, 3]))]
    >>> merged = list(merge_sorted([a, b]))
    >>> np.concatenate([t for t, _ in merged]).tolist(), np.concatenate([v for _, v in merged]).tolist()
    ([0, 5, 5, 5, 7, 9], [1, 1, 2, 3, 3, 2])
    """
    sources = [iter(s) for s in streams]
    pending: list[Chunk | None] = [None] * len(sources)
    live = [True] * len(sources)

    def pull(i: int) -> None:
        for chunk in sources[i]:
            if len(chunk[0]):
                held = pending[i]
                pending[i] = chunk if held is None or not len(held[0]) else tuple(
                    np.concatenate([a, b]) for a, b in zip(held, chunk, strict=True))
                return
        live[i] = False

    for i in range(len(sources)):
        pull(i)
    while True:
        lasts = [int(p[0][-1]) for i, p in enumerate(pending) if live[i] and p is not None and len(p[0])]
        horizon = min(lasts) if lasts else None
        parts: list[Chunk] = []
        for i, p in enumerate(pending):
            if p is None or not len(p[0]):
                continue
            k = len(p[0]) if horizon is None else int(np.searchsorted(p[0], horizon, side="left"))
            if k:
                parts.append(tuple(c[:k] for c in p))
                pending[i] = tuple(c[k:] for c in p)
        if parts:
            yield _merged(parts)
        elif horizon is None:
            return
        for i, p in enumerate(pending):
            if live[i] and (p is None or not len(p[0]) or int(p[0][-1]) == horizon):
                pull(i)


def _merged(parts: list[Chunk]) -> Chunk:
    if len(parts) == 1:
        return parts[0]
    joined = tuple(np.concatenate(cols) for cols in zip(*parts, strict=True))
    order = np.argsort(joined[0], kind="stable")
    return tuple(c[order] for c in joined)


def _numpy(column: Any, dtype: type[np.generic]) -> npt.NDArray[Any]:
    """A spilled column (primitive, no nulls) as a numpy view of its buffer (``to_numpy`` would import pandas)."""
    values = np.frombuffer(column.buffers()[1], dtype=dtype)
    return values[column.offset:column.offset + len(column)]


def segment_pulses(segments: Columns, limit: int, *, column: int = 3) -> Iterator[tuple[npt.NDArray[np.int64],
                                                                                      npt.NDArray[Any]]]:
    """Pulses of time-ordered segments, chunk by chunk, at most ``limit`` at a time (long segments split).

    Yields ``(t, value)``: each pulse's instant and its segment's column ``column`` (3: the direction;
    4: the width, for a train whose segments carry one).
    """
    for chunk in segments.chunks():
        t0, duration, count, value = chunk[0], chunk[1], chunk[2], chunk[column]
        ends = np.cumsum(count)
        total = int(ends[-1]) if ends.size else 0
        a = 0
        while a < total:
            b = min(a + limit, total)
            i0 = int(np.searchsorted(ends, a, side="right"))
            i1 = int(np.searchsorted(ends, b, side="left")) + 1
            begins = ends[i0:i1] - count[i0:i1]
            first = np.maximum(a - begins, 0)
            stop = np.minimum(b - begins, count[i0:i1])
            t = materialize_pulses(t0[i0:i1], duration[i0:i1], count[i0:i1], first=first, stop=stop)
            d = np.repeat(value[i0:i1], stop - first)
            t.setflags(write=False)
            yield t, d
            a = b
