"""The trace: the single record of everything a simulation did.

Signal names follow one scheme, the same in the Python API, VCD, Parquet and CSV::

    <device>.<axis>.<signal>      e.g. pokeys.x.step, trio.axis3.gate, pmac.cs1.timebase
    <device>.<signal>             for devices without axes, e.g. laser.power, pokeys.buffer_level

lower case, dot-separated, each part ``[a-z0-9_]``. In a waveform viewer the dots are scopes
(``trio`` > ``axis3``) and the signal is named by its whole path (``trio_axis3_gate``, see
:mod:`cosim.export_vcd`).

Kinds of record (all times are integer ticks of the trace's resolution):

* ``bit`` / ``int`` signals: exact edge lists ``(t, value)``, value held until the next edge;
* ``real`` signals: value changes or samples ``(t, value)`` (analog outputs at requested times);
* console lines ``(t, source, text)``: what programs print (Trio ``PRINT``, PMAC ``SEND``, G-code
  ``(MSG, ...)``) and why a job stopped, in time order (:meth:`Trace.write_line`,
  :meth:`Trace.console`); the runner writes them to ``console.txt``;
* ``pulse`` trains: segments ``(t0, duration, count, dir)`` placed by the rule of
  :mod:`cosim.pulses`, plus any pulses given one by one; :meth:`Trace.pulses` materialises them.
  Each pulse is high for the train's ``pulse_width``, or, in a train declared with
  ``varying_width`` (a PWM output, whose mark follows the duty), for its segment's own ``width``:
  :meth:`Trace.pulse_widths` gives every pulse's width, and the segments always have a ``width``.

Memory: each table (a signal's records, a train's segments, its single pulses) keeps at most
``spill_rows`` rows in memory; beyond that the rows go to disk in chunks as the run goes (see
:mod:`cosim.tracestore`), so a long run's memory does not grow with simulated time. Readers that
must stay bounded go chunk by chunk (:meth:`Trace.edge_chunks`, :meth:`Trace.pulse_chunks`,
:meth:`Trace.segment_chunks`); the whole-array readers (:meth:`Trace.edges`, :meth:`Trace.pulses`)
are there for short runs, notebooks and tests.

The trace is a leaf: it imports nothing of cosim but the pulse rule, the time base, the errors
and its own store. Exports (:mod:`cosim.export`: VCD, Parquet/CSV, the ``trace_meta.json``
header) read and fill it through its public methods only.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, Literal, cast

import numpy as np
import numpy.typing as npt

from cosim.errors import ConfigurationError
from cosim.pulses import materialize_pulses
from cosim.timebase import TimeBase
from cosim.tracestore import DTYPES, SPILL_ROWS, Columns, Spool, merge_sorted, segment_pulses

Kind = Literal["bit", "int", "real", "pulse"]
KINDS: tuple[str, ...] = ("bit", "int", "real", "pulse")
_NAME = re.compile(r"^[a-z][a-z0-9_]*(\.[a-z0-9_]+)*$")
Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
Int8s = npt.NDArray[np.int8]
#: Most pulses in one chunk of :meth:`Trace.pulse_chunks` (about 2.3 MiB of ``t, dir``).
CHUNK_PULSES = 1 << 18
#: Most pulses kept materialised between reads (about 36 MiB of ``t, dir``): several checks of one train
#: held in memory materialise it once; the trains read longest ago are forgotten first.
KEPT_PULSES = 1 << 22
#: Console lines kept in memory; more go to a file in the spill folder (an hour of PRINT in a loop stays bounded).
CONSOLE_LINES = 1 << 16
_VALUE_FIELDS = (("t", "q"), ("v", "d"))
_SEGMENT_FIELDS = (("t0", "q"), ("duration", "q"), ("count", "q"), ("dir", "b"))
_WIDTH_SEGMENT_FIELDS = (*_SEGMENT_FIELDS, ("width", "q"))
SEGMENT_COLUMNS = ("t0", "duration", "count", "dir", "width")
_SINGLE_FIELDS = (("t", "q"), ("dir", "b"))


@dataclass(frozen=True)
class ConsoleLine:
    """One line of the run's console: when [ticks], who wrote it, and the text."""

    t: int
    source: str
    text: str


@dataclass(frozen=True)
class SignalInfo:
    """What a recorded signal is.

    Parameters
    ----------
    kind : {'bit', 'int', 'real', 'pulse'}
    unit : str
        Physical unit of the value (``''`` for logic levels and counts).
    description : str
        One line for humans.
    pulse_width : int
        For pulse trains: width of each pulse [ticks] (where a pulse falls in the VCD); in a train
        with ``varying_width``, of its single pulses only.
    varying_width : bool
        For pulse trains: each segment carries its own pulse width [ticks] (a PWM output).
    """

    kind: str
    unit: str = ""
    description: str = ""
    pulse_width: int = 1
    varying_width: bool = False


@dataclass
class _PulseChannel:
    segments: Columns
    singles: Columns


class Trace:
    """Columnar record of edges, values and pulse segments, in integer ticks.

    Parameters
    ----------
    timebase : TimeBase
        Resolution of the recorded times.
    spill_rows : int
        Rows of one table kept in memory; more go to disk in chunks of this size (default 65,536:
        about 1 MiB per signal). A run shorter than that never touches the disk.
    chunk_pulses : int
        Most pulses materialised at once by :meth:`pulse_chunks` (default 262,144).
    spool : path, optional
        Folder in which to make the spill folder (default: the system's temporary folder); see
        :attr:`spool_dir`.
    """

    def __init__(self, timebase: TimeBase | None = None, *, spill_rows: int = SPILL_ROWS,
                 chunk_pulses: int = CHUNK_PULSES, spool: str | Path | None = None) -> None:
        self.timebase = timebase or TimeBase()
        self.info: dict[str, SignalInfo] = {}
        #: Signals a model declares only when the run uses them (see :meth:`may_declare`).
        self.later: set[str] = set()
        self.spill_rows = int(spill_rows)
        self.chunk_pulses = max(1, int(chunk_pulses))
        self._spool = Spool(spool)
        self._values: dict[str, Columns] = {}
        self._pulses: dict[str, _PulseChannel] = {}
        self._pulse_cache: dict[str, tuple[tuple[int, int], npt.NDArray[np.int64], npt.NDArray[np.int8]]] = {}
        self.end_t = 0
        self.meta: dict[str, object] = {}
        self._lines: list[ConsoleLine] = []
        self._lines_spilled = 0
        self._lines_file: Any = None

    # -- declaring and recording -------------------------------------------------------------
    def takes_runs(self, name: str) -> bool:
        """Whether a model may record ``name`` in runs made ahead of the simulation's now (a PoKeys
        engine's slots between host events); a trace that must see each record at its own instant
        (an exported FMU's outputs) says no for those signals."""
        return True

    def may_declare(self, name: str) -> None:
        """Announce a signal the model declares only if the run comes to it (a Trio axis's
        ``reg_pos`` after its first ``REGIST``), so that a check or figure may name it beforehand."""
        self.later.add(name)

    def declare(self, name: str, kind: str, *, unit: str = "", description: str = "",
                pulse_width: int = 1, varying_width: bool = False) -> None:
        """Declare a signal before recording it (names are checked against the scheme).

        A pulse train with ``varying_width`` takes a ``width`` with each segment
        (:meth:`record_segment`); otherwise each pulse is ``pulse_width`` ticks wide.
        """
        if not _NAME.match(name):
            raise ConfigurationError(
                f"signal name {name!r} does not follow the scheme <device>.<axis>.<signal> "
                "(lower case, dot-separated, [a-z0-9_])"
            )
        if kind not in KINDS:
            raise ConfigurationError.out_of_range(f"kind of {name}", kind, ", ".join(KINDS))
        if name in self.info:
            raise ConfigurationError(f"signal {name!r} is declared twice")
        if varying_width and kind != "pulse":
            raise ConfigurationError(f"signal {name!r} is a {kind} signal: only a pulse train has a varying width")
        self.info[name] = SignalInfo(kind, unit, description, pulse_width, varying_width)
        key = f"{len(self.info):04d}-{name}"
        if kind == "pulse":
            self._pulses[name] = _PulseChannel(
                Columns(_WIDTH_SEGMENT_FIELDS if varying_width else _SEGMENT_FIELDS, spool=self._spool,
                        key=key + ".segments", limit=self.spill_rows, segments=True),
                Columns(_SINGLE_FIELDS, spool=self._spool, key=key + ".pulses", limit=self.spill_rows))
        else:
            self._values[name] = Columns(_VALUE_FIELDS, spool=self._spool, key=key, limit=self.spill_rows)

    def record(self, name: str, t: int, value: float) -> None:
        """Record a value change (bit/int/real) or a sample (real) at tick ``t``."""
        columns = self._values[name]
        t_column, v_column = columns.arrays
        t_column.append(t)
        v_column.append(value)
        if len(t_column) >= columns.limit:
            columns.spill()

    def record_segment(self, name: str, t0: int, duration: int, count: int, direction: int, *,
                       width: int | None = None) -> None:
        """Record ``count`` pulses spread over ``[t0, t0+duration)`` (rule of :mod:`cosim.pulses`).

        ``width`` [ticks]: how long each pulse of the segment is high; required by a train declared
        with ``varying_width``, refused by the others (their pulses are ``pulse_width`` wide).
        """
        columns = self._pulses[name].segments
        row = (t0, duration, count, direction) if width is None else (t0, duration, count, direction, width)
        if len(row) != len(columns.arrays):
            raise ConfigurationError(f"a segment of {name} takes {'a' if len(row) == 4 else 'no'} width: the train "
                                     f"is declared {'with' if len(row) == 4 else 'without'} varying_width")
        for column, value in zip(columns.arrays, row, strict=True):
            column.append(value)
        columns.appended()

    def recorder(self, name: str) -> Callable[[int, float], None]:
        """``record(t, value)`` for one declared value signal, bound once (for per-slot hot paths)."""
        columns = self._values[name]
        t_column, v_column = columns.arrays
        t_append, v_append, limit, spill = t_column.append, v_column.append, columns.limit, columns.spill

        def record(t: int, value: float) -> None:
            t_append(t)
            v_append(value)
            if len(t_column) >= limit:
                spill()

        return record

    def segment_recorder(self, name: str) -> Callable[[int, int, int, int], None]:
        """``record_segment(t0, duration, count, direction)`` for one declared pulse train, bound once."""
        columns = self._pulses[name].segments
        t0_column = columns.arrays[0]
        t0_append, duration_append, count_append, direction_append = (a.append for a in columns.arrays)
        limit, spill = columns.limit, columns.spill

        def record(t0: int, duration: int, count: int, direction: int) -> None:
            t0_append(t0)
            duration_append(duration)
            count_append(count)
            direction_append(direction)
            if len(t0_column) >= limit:
                spill()

        return record

    def values_extender(self, name: str) -> Callable[[Sequence[int], Sequence[float]], None]:
        """``extend(times, values)``: many records of one declared value signal at once, bound once.

        The same rows as calling :meth:`recorder`'s ``record(t, value)`` for each pair in turn (and
        the same spills: a batch that would cross the spill limit is appended row by row).
        """
        columns = self._values[name]
        t_column, v_column = columns.arrays
        record = self.recorder(name)
        limit = columns.limit

        def extend(times: Sequence[int], values: Sequence[float]) -> None:
            if len(t_column) + len(times) < limit:  # (array.fromlist: several times array.extend's speed)
                t_column.fromlist(list(times))
                v_column.fromlist(list(values))
            else:
                for t, value in zip(times, values, strict=True):
                    record(t, value)

        return extend

    def values_extenders(self, names: Sequence[str]) -> Callable[[Sequence[int], Sequence[Sequence[float]]], None]:
        """``extend(times, columns)``: :meth:`values_extender` of several signals recorded at the same
        instants in one call (``columns[i]``: the values of ``names[i]``), bound once."""
        extenders = [self.values_extender(name) for name in names]
        tables = [self._values[name] for name in names]
        arrays = [table.arrays for table in tables]
        limit = min(table.limit for table in tables)

        def extend(times: Sequence[int], columns: Sequence[Sequence[float]]) -> None:
            n = len(times)
            t_list = list(times)
            for (t_column, v_column), values, each in zip(arrays, columns, extenders, strict=True):
                if len(t_column) + n < limit:  # (array.fromlist: several times array.extend's speed)
                    t_column.fromlist(t_list)
                    v_column.fromlist(values if type(values) is list else list(values))
                else:
                    each(times, values)

        return extend

    def segment_run_recorder(self, name: str) -> Callable[[int, int, Sequence[int], int], None]:
        """``record_run(t0, duration, counts, direction)``: contiguous segments of one pulse train at once.

        Segment ``j`` covers ``[t0 + j duration, t0 + (j + 1) duration)`` with ``counts[j]`` pulses; the
        same rows as :meth:`segment_recorder`'s ``record`` called for each segment in turn.
        """
        columns = self._pulses[name].segments
        t0_column, duration_column, count_column, direction_column = columns.arrays
        record = self.segment_recorder(name)
        limit = columns.limit

        def record_run(t0: int, duration: int, counts: Sequence[int], direction: int) -> None:
            n = len(counts)
            if len(t0_column) + n < limit:  # (array.fromlist: several times array.extend's speed)
                t0_column.fromlist(list(range(t0, t0 + n * duration, duration)))
                duration_column.fromlist([duration] * n)
                count_column.fromlist(counts if type(counts) is list else list(counts))
                direction_column.fromlist([direction] * n)
            else:
                for j, count in enumerate(counts):
                    record(t0 + j * duration, duration, count, direction)

        return record_run

    def record_pulse(self, name: str, t: int, direction: int) -> None:
        """Record one pulse at tick ``t`` (for trains that are not evenly spread)."""
        columns = self._pulses[name].singles
        t_column, d_column = columns.arrays
        t_column.append(t)
        d_column.append(direction)
        if len(t_column) >= columns.limit:
            columns.spill()

    def write_line(self, t: int, source: str, text: str) -> None:
        """Record a console line at tick ``t``: ``source`` says who wrote it (``trio.proc1``,
        ``pmac.plc3``, ``gcode``, ``trio.job``), ``text`` is one line (line breaks become spaces)."""
        line = ConsoleLine(int(t), str(source), " ".join(str(text).splitlines()))
        self._lines.append(line)
        if len(self._lines) >= CONSOLE_LINES:
            if self._lines_file is None:
                self._lines_file = (self._spool.folder() / "console.tsv").open("w", encoding="utf-8")
                self._spool.keep(self._lines_file)
            self._lines_file.writelines(f"{c.t}\t{c.source}\t{c.text.replace(chr(9), ' ')}\n" for c in self._lines)
            self._lines_spilled += len(self._lines)
            self._lines.clear()

    def console(self) -> Iterator[ConsoleLine]:
        """Every console line in the order written (spilled ones read back from disk)."""
        if self._lines_file is not None:
            self._lines_file.flush()
            with (self._spool.folder() / "console.tsv").open(encoding="utf-8") as spilled:
                for row in spilled:
                    t, source, text = row.rstrip("\n").split("\t", 2)
                    yield ConsoleLine(int(t), source, text)
        yield from self._lines

    @property
    def console_count(self) -> int:
        """How many console lines were written."""
        return self._lines_spilled + len(self._lines)

    # -- memory -------------------------------------------------------------------------------
    @property
    def spool_dir(self) -> Path | None:
        """Folder in which the spill folder is made (None: the system's temporary folder).

        Set it before the run spills anything; the runner sets it to the results folder.
        """
        return None if self._spool.parent is None else Path(self._spool.parent)

    @spool_dir.setter
    def spool_dir(self, folder: str | Path | None) -> None:
        if self._spool.used:
            raise ConfigurationError("the trace has spilled already: set spool_dir before the run")
        self._spool.parent = folder

    def memory_rows(self) -> int:
        """Rows held in memory over every table (at most ``spill_rows`` per table)."""
        tables = [*self._values.values(), *(t for ch in self._pulses.values() for t in (ch.segments, ch.singles))]
        return sum(t.in_memory for t in tables)

    def spilled_rows(self) -> int:
        """Rows written to disk so far."""
        tables = [*self._values.values(), *(t for ch in self._pulses.values() for t in (ch.segments, ch.singles))]
        return sum(t.spilled for t in tables)

    def discard_spill(self) -> None:
        """Delete the spilled chunks now (the trace can no longer be read: call it when done)."""
        self._spool.remove()

    # -- reading ----------------------------------------------------------------------------
    def names(self, kind: str | None = None) -> list[str]:
        """Declared signal names (optionally of one kind), in declaration order."""
        return [n for n, i in self.info.items() if kind is None or i.kind == kind]

    def _columns(self, name: str) -> Columns:
        if name not in self._values:
            raise KeyError(_unknown(name, self.info))
        return self._values[name]

    def _train(self, name: str) -> _PulseChannel:
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        return self._pulses[name]

    def edge_chunks(self, name: str) -> Iterator[tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]]:
        """``(t, value)`` of a bit/int/real signal chunk by chunk, in recording order (at most
        ``spill_rows`` records at a time): :meth:`edges` in bounded memory."""
        return cast("Iterator[tuple[Ints, Floats]]", self._columns(name).chunks())

    def in_time_order(self, name: str) -> bool:
        """Are the records of a signal (or the pulses of a train: segments and single pulses each) in
        time order? Recorders append in time order; a reader of :meth:`edge_chunks` relies on it."""
        if name in self._pulses:
            train = self._pulses[name]
            return train.segments.in_order() and train.singles.in_order()
        return self._columns(name).in_order()

    def edges(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
        """``(t, value)`` of a bit/int/real signal: its changes (or samples) in time order."""
        parts = list(self.edge_chunks(name))
        if len(parts) == 1 and parts[0][0].flags.writeable:
            return parts[0]
        return (np.concatenate([p[0] for p in parts]) if parts else np.empty(0, np.int64),
                np.concatenate([p[1] for p in parts]) if parts else np.empty(0, np.float64))

    samples = edges

    def value_at(self, name: str, t: int) -> float:
        """Value of a piecewise-constant signal at tick ``t`` (NaN before its first record)."""
        return float(self.values_at(name, [t])[0])

    def drop_pulse_cache(self) -> None:
        """Forget the materialised pulse arrays kept by :meth:`pulses` (to free memory, or to time it)."""
        self._pulse_cache.clear()

    def values_at(self, name: str, t: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Values of a piecewise-constant signal at the ticks ``t`` (NaN before its first record).

        The vectorised :meth:`value_at`: the value in effect at each instant is the last change at
        or before it.

        Examples
        --------
        >>> trace = Trace()
        >>> trace.declare("dev.axis1.mode", "int")
        >>> trace.record("dev.axis1.mode", 100, 1); trace.record("dev.axis1.mode", 250, 2)
        >>> trace.values_at("dev.axis1.mode", [0, 100, 249, 250, 900]).tolist()
        [nan, 1.0, 1.0, 2.0, 2.0]
        """
        query = np.asarray(t, dtype=np.int64)
        out = np.full(query.shape, np.nan)
        for times, values in self.edge_chunks(name):  # in time order: a later chunk overrides
            i = np.searchsorted(times, query, side="right") - 1
            held = i >= 0
            out[held] = values[i[held]]
        return out

    def positions_at(self, name: str, t: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Signed pulse count of a pulse train up to and including each tick of ``t`` (dir 1 counts up).

        The axis position an encoder or a driver would show at those instants, from every pulse
        (segments and single pulses).

        Examples
        --------
        >>> trace = Trace()
        >>> trace.declare("dev.x.step", "pulse")
        >>> trace.record_segment("dev.x.step", 0, 1000, 4, 1)      # pulses at 0, 250, 500, 750
        >>> trace.record_segment("dev.x.step", 1000, 1000, 2, 0)   # back at 1000, 1500
        >>> trace.positions_at("dev.x.step", [-1, 0, 600, 999, 1000, 2000]).tolist()
        [0, 1, 3, 4, 3, 2]
        """
        query = np.asarray(t, dtype=np.int64)
        out = np.zeros(query.shape, dtype=np.int64)
        for times, direction in self.pulse_chunks(name):
            position = np.concatenate(([0], np.cumsum(np.where(direction == 1, 1, -1), dtype=np.int64)))
            out += position[np.searchsorted(times, query, side="right")]
        return out

    def pulses_per_window(self, name: str, window: int, *, start: int = 0,
                          end: int | None = None) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """Pulses of a pulse train in each window ``[start + k window, start + (k + 1) window)``.

        Parameters
        ----------
        name : str
            A pulse train.
        window : int
            Window length [ticks] (> 0), e.g. a controller's slot or servo period.
        start, end : int
            First window's start; the windows cover ``[start, end)`` (default: to the trace's end,
            or its last pulse if later). The last window is shorter when ``end - start`` is not a
            whole number of windows: it ends at ``end``.

        Returns
        -------
        (window starts, counts) : two arrays of int
            Counts of both directions; divide by ``window`` for a rate.
        """
        window = self.timebase.check_ticks(window, name="window", minimum=1)
        last = end
        if last is None:
            last = self.end_t
            for times, _ in self.pulse_chunks(name):
                last = max(last, int(times[-1]) + 1)
        n = max(-(-(last - start) // window), 0)
        counts = np.zeros(n, dtype=np.int64)
        stop = min(last, start + n * window)
        for times, _ in self.pulse_chunks(name):
            inside = times[(times >= start) & (times < stop)]
            if inside.size:
                k = (inside - start) // window
                low = int(k[0]) if bool(np.all(k[1:] >= k[:-1])) else int(k.min())
                part = np.bincount(k - low)
                counts[low:low + part.size] += part
        return start + window * np.arange(n, dtype=np.int64), counts

    def segment_chunks(self, name: str) -> Iterator[dict[str, npt.NDArray[np.int64]]]:
        """Raw pulse segments of a pulse train chunk by chunk: :meth:`segments` in bounded memory."""
        train, width = self._train(name), self.info[name].pulse_width
        for chunk in train.segments.chunks():
            t0, duration, count, direction = chunk[:4]
            yield {"t0": t0, "duration": duration, "count": count, "dir": direction.astype(np.int64),
                   "width": chunk[4] if len(chunk) > 4 else np.full(t0.size, width, dtype=np.int64)}

    def segments(self, name: str) -> dict[str, npt.NDArray[np.int64]]:
        """Raw pulse segments of a pulse train: arrays ``t0, duration, count, dir, width``.

        ``width`` [ticks] is how long each pulse of the segment is high: the segment's own in a
        train declared with ``varying_width``, else the train's ``pulse_width``.
        """
        parts = list(self.segment_chunks(name))
        return {k: np.concatenate([p[k] for p in parts]) if parts else np.empty(0, np.int64) for k in SEGMENT_COLUMNS}

    def single_pulse_chunks(self, name: str) -> Iterator[tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]]:
        """``(t, dir)`` of the pulses recorded one by one, chunk by chunk, in recording order."""
        return cast("Iterator[tuple[Ints, Int8s]]", self._train(name).singles.chunks())

    def single_pulses(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
        """``(t, dir)`` of the pulses of a pulse train that were recorded one by one (not as segments)."""
        parts = list(self.single_pulse_chunks(name))
        if not parts:
            return np.empty(0, np.int64), np.empty(0, np.int8)
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])

    def pulse_chunks(self, name: str) -> Iterator[tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]]:
        """``(t, dir)`` of every pulse of a pulse train in time order, at most ``chunk_pulses`` at a time.

        What :meth:`pulses` gives, in bounded memory: a train held in memory and small enough comes
        as the one (kept) array of :meth:`pulses`; a longer one is materialised chunk by chunk from
        its segments, merged with its single pulses. A train whose records are not in time order
        (segments given out of order) is materialised whole and sorted, as :meth:`pulses` does.
        The arrays are read-only.
        """
        train = self._train(name)
        segments, singles = train.segments, train.singles
        if not segments.spilled and not singles.spilled:
            total = int(np.frombuffer(segments.arrays[2], dtype=np.int64).sum()) + len(singles)
            if total <= self.chunk_pulses:
                if total:
                    yield self.pulses(name)
                return
            if total <= KEPT_PULSES:  # the kept arrays, in the chunks segment_pulses would cut
                t, d = self.pulses(name)
                for k in range(0, t.size, self.chunk_pulses):
                    yield t[k:k + self.chunk_pulses], d[k:k + self.chunk_pulses]
                return
        if not (segments.in_order() and singles.in_order()):
            t, d = self.pulses(name)
            for k in range(0, t.size, self.chunk_pulses):
                yield t[k:k + self.chunk_pulses], d[k:k + self.chunk_pulses]
            return
        yield from self._ordered_pulses(train)

    def _ordered_pulses(self, train: _PulseChannel) -> Iterator[tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]]:
        chunks = segment_pulses(train.segments, self.chunk_pulses)
        if not len(train.singles):
            yield from chunks
            return
        yield from cast("Iterator[tuple[Ints, Int8s]]", merge_sorted([chunks, train.singles.chunks()]))

    def pulse_width_chunks(self, name: str) -> Iterator[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]]:
        """``(t, width)`` of every pulse of a pulse train in time order, chunk by chunk: each pulse's
        instant (its rising edge) and how long it is high [ticks]; it falls at ``t + width``."""
        info, train = self.info[name], self._train(name)
        if not info.varying_width:
            for t, _ in self.pulse_chunks(name):
                yield t, np.full(t.size, info.pulse_width, dtype=np.int64)
            return
        singles = ((t, np.full(t.size, info.pulse_width, dtype=np.int64)) for t, _ in train.singles.chunks())
        if train.segments.in_order() and train.singles.in_order():
            yield from cast("Iterator[tuple[Ints, Ints]]", merge_sorted(
                [segment_pulses(train.segments, self.chunk_pulses, column=4), singles]))
            return
        seg = self.segments(name)
        parts = [(materialize_pulses(seg["t0"], seg["duration"], seg["count"]), np.repeat(seg["width"], seg["count"])),
                 *singles]
        t, width = np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        order = np.argsort(t, kind="stable")
        yield t[order], width[order]

    def pulse_widths(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """``(t, width)`` of every pulse of a pulse train, whole (see :meth:`pulse_width_chunks`)."""
        parts = list(self.pulse_width_chunks(name))
        if not parts:
            return np.empty(0, np.int64), np.empty(0, np.int64)
        return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])

    def pulses(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
        """``(t, dir)`` of every pulse of a pulse train, materialised exactly, in time order.

        The arrays are read-only and kept until the train records more pulses (or, beyond
        :data:`KEPT_PULSES` in all, until other trains are read), so several checks of one train
        materialise it once. For long trains prefer :meth:`pulse_chunks`.
        """
        train = self._train(name)
        version = (len(train.segments), len(train.singles))
        cached = self._pulse_cache.pop(name, None)
        if cached is not None and cached[0] == version:
            self._pulse_cache[name] = cached  # read last: forgotten last
            return cached[1], cached[2]
        segments = train.segments
        if not segments.spilled and not len(train.singles) and segments.in_order():  # in one piece, no merge
            t0, duration, count, direction = (np.frombuffer(a, dtype=DTYPES[a.typecode]) for a in segments.arrays[:4])
            t = materialize_pulses(t0, duration, count)
            d = np.repeat(direction, count)
        elif train.segments.in_order() and train.singles.in_order():
            parts = list(self._ordered_pulses(train))
            t = np.concatenate([p[0] for p in parts]) if parts else np.empty(0, np.int64)
            d = np.concatenate([p[1] for p in parts]) if parts else np.empty(0, np.int8)
        else:
            seg = self.segments(name)
            t = materialize_pulses(seg["t0"], seg["duration"], seg["count"])
            d = np.repeat(seg["dir"].astype(np.int8), seg["count"])
            t_single, d_single = self.single_pulses(name)
            order = np.argsort(np.concatenate([t, t_single]), kind="stable")
            t, d = np.concatenate([t, t_single])[order], np.concatenate([d, d_single])[order]
        t.setflags(write=False)
        d.setflags(write=False)
        cache = self._pulse_cache
        cache[name] = (version, t, d)  # the newest last
        kept = sum(entry[1].size for entry in cache.values())
        for old in list(cache):
            if kept <= KEPT_PULSES or old == name:
                break
            kept -= cache.pop(old)[1].size
        return t, d

    # -- header and bulk filling (for readers of stored traces) --------------------------------
    def header(self) -> dict[str, Any]:
        """Resolution, end, declared signals and metadata as plain data (``trace_meta.json``)."""
        res = self.timebase.resolution_s
        return {
            "resolution_s": [res.numerator, res.denominator],
            "end_t": self.end_t,
            "signals": {n: asdict(i) for n, i in self.info.items()},
            "meta": self.meta,
        }

    @classmethod
    def from_header(cls, header: Mapping[str, Any], **options: Any) -> Trace:
        """An empty trace with the resolution, end, signals and metadata of :meth:`header`.

        ``options`` go to the constructor (``spill_rows``, ``spool``...).
        """
        num, den = header["resolution_s"]
        trace = cls(TimeBase(Fraction(num, den)), **options)
        trace.end_t = int(header["end_t"])
        trace.meta = dict(header.get("meta", {}))
        for name, info in header["signals"].items():
            trace.declare(name, info["kind"], unit=info["unit"], description=info["description"],
                          pulse_width=info["pulse_width"], varying_width=bool(info.get("varying_width", False)))
        return trace

    def extend(self, name: str, t: npt.ArrayLike, value: npt.ArrayLike) -> None:
        """Append many records ``(t, value)`` of a bit/int/real signal at once (in time order)."""
        self._columns(name).extend((np.asarray(t, dtype=np.int64), np.asarray(value, dtype=np.float64)))

    def extend_segments(self, name: str, t0: npt.ArrayLike, duration: npt.ArrayLike, count: npt.ArrayLike,
                        direction: npt.ArrayLike, width: npt.ArrayLike | None = None) -> None:
        """Append many segments of a pulse train at once (see :meth:`record_segment`).

        ``width`` is kept for a train declared with ``varying_width`` (which needs it) and ignored
        for the others (a table's ``width`` column holds their ``pulse_width``).
        """
        train, columns = self._train(name), [t0, duration, count, direction]
        if self.info[name].varying_width:
            if width is None:
                raise ConfigurationError(f"the segments of {name} need a width: the train is declared with "
                                         "varying_width")
            columns.append(width)
        train.segments.extend(tuple(np.asarray(c, dtype=np.int64) for c in columns))

    def extend_single_pulses(self, name: str, t: npt.ArrayLike, direction: npt.ArrayLike) -> None:
        """Append many pulses given one by one (see :meth:`record_pulse`)."""
        self._train(name).singles.extend((np.asarray(t, dtype=np.int64), np.asarray(direction, dtype=np.int64)))


def _unknown(name: str, known: dict[str, SignalInfo]) -> str:
    import difflib

    close = difflib.get_close_matches(name, list(known), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return f"no signal named {name!r} in the trace{hint}"
