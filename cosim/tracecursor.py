"""Walking a trace chunk by chunk: what lets checks and exports run in memory bounded by a chunk.

A reader takes its signals as time-ordered chunks (:meth:`~cosim.trace.Trace.pulse_chunks`,
:meth:`~cosim.trace.Trace.edge_chunks`) and carries what it needs from one chunk to the next.
The helpers here are the carried parts that several checks and exports share:

* :func:`with_previous`: each chunk with the last instant of the one before (for gaps);
* :func:`change_chunks`: the changes of a signal (a record whose value differs from the one
  before; the first record is the initial value, not a change);
* :class:`Held`: the value held, and the last change, at sorted query instants;
* :class:`Position`: the signed pulse count of a pulse train at sorted query instants;
* :class:`Instants`: the first instant at or after, or the last before, sorted query instants.

Queries to the cursors come in non-decreasing order across calls; each cursor keeps about one
chunk of its signal.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np
import numpy.typing as npt

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
Int8s = npt.NDArray[np.int8]
Bools = npt.NDArray[np.bool_]


def with_previous(chunks: Iterable[tuple[Ints, Int8s]]) -> Iterator[tuple[Ints, Int8s, int]]:
    """Each chunk ``(t, dir)`` preceded by the last pulse of the chunk before, and that pulse's index.

    Yields ``(t, dir, base)``: ``t[0]`` is pulse ``base`` of the train. The first chunk comes as
    it is (``base`` 0); later ones start with the pulse before them, so that ``np.diff(t)`` holds
    every gap once.
    """
    last: tuple[Ints, Int8s] | None = None
    base = 0
    for t, d in chunks:
        if not t.size:
            continue
        if last is None:
            yield t, d, 0
        else:
            yield np.concatenate([last[0], t]), np.concatenate([last[1], d]), base - 1
        base += t.size
        last = (t[-1:], d[-1:])


def change_chunks(chunks: Iterable[tuple[Ints, Floats]]) -> Iterator[tuple[Ints, Floats]]:
    """The changes of a signal chunk by chunk: records whose value differs from the record before.

    NaN differs from everything (as ``!=`` says), so a NaN record is always a change.
    """
    previous: Floats | None = None
    for t, v in chunks:
        if not t.size:
            continue
        if previous is None:
            moved = np.flatnonzero(v[1:] != v[:-1]) + 1
        else:
            moved = np.flatnonzero(v != np.concatenate([previous, v[:-1]]))
        previous = v[-1:]
        yield t[moved], v[moved]


class _Cursor:
    """A time-ordered chunk stream read forward on demand; ``buf`` holds the part not yet passed."""

    def __init__(self, chunks: Iterable[tuple[npt.NDArray[np.generic], ...]]) -> None:
        self._chunks = iter(chunks)
        self.buf: tuple[npt.NDArray[np.generic], ...] | None = None
        self.done = False

    def _pull(self) -> None:
        for chunk in self._chunks:
            if len(chunk[0]):
                self.buf = chunk if self.buf is None or not len(self.buf[0]) else tuple(
                    np.concatenate([a, b]) for a, b in zip(self.buf, chunk, strict=True))
                return
        self.done = True

    def _reach(self, t: int) -> None:
        """Read on until the buffer holds an instant after ``t`` (or the stream is over)."""
        while not self.done and (self.buf is None or not len(self.buf[0]) or int(self.buf[0][-1]) <= t):
            self._pull()


class Held(_Cursor):
    """The value of a bit/int/real signal held at query instants, and its last change before them.

    Parameters
    ----------
    chunks : iterable of (t, value)
        The signal's records in time order.
    """

    def __init__(self, chunks: Iterable[tuple[Ints, Floats]]) -> None:
        super().__init__(chunks)
        self._value = np.nan
        self._defined = False
        self._change: int | None = None

    def at(self, t: Ints) -> tuple[Floats, Bools, Ints, Bools]:
        """At each instant of ``t`` (sorted): ``(value, defined, last change, changed)``.

        A record at the instant counts. ``defined`` is False before the first record, ``changed``
        False before the first change (``last change`` is then 0).
        """
        if not t.size:
            return np.empty(0), np.zeros(0, bool), np.empty(0, np.int64), np.zeros(0, bool)
        self._reach(int(t[-1]))
        times, values = self._take(int(t[-1]))
        i = np.searchsorted(times, t, side="right") - 1
        value = np.where(i >= 0, values[np.maximum(i, 0)] if values.size else np.nan, self._value)
        defined = (i >= 0) | self._defined
        if not values.size:
            change_times = np.empty(0, np.int64)
        elif self._defined:
            change_times = times[np.flatnonzero(values != np.concatenate([[self._value], values[:-1]]))]
        else:
            change_times = times[np.flatnonzero(values[1:] != values[:-1]) + 1]
        j = np.searchsorted(change_times, t, side="right") - 1
        earlier = -1 if self._change is None else self._change
        change = np.where(j >= 0, change_times[np.maximum(j, 0)] if change_times.size else 0, earlier)
        changed = (j >= 0) | (self._change is not None)
        if values.size:
            self._value, self._defined = float(values[-1]), True
        if change_times.size:
            self._change = int(change_times[-1])
        return value, defined, np.where(changed, change, 0).astype(np.int64), changed

    def values_at(self, t: Ints) -> Floats:
        """The value held at each instant of ``t`` (sorted; NaN before the first record)."""
        value, defined, _, _ = self.at(t)
        return np.where(defined, value, np.nan)

    def _take(self, t: int) -> tuple[Ints, Floats]:
        """Remove and return the buffered records at or before ``t``."""
        if self.buf is None:
            return np.empty(0, np.int64), np.empty(0)
        times, values = self.buf
        k = int(np.searchsorted(times, t, side="right"))
        self.buf = (times[k:], values[k:])
        return times[:k].astype(np.int64), values[:k].astype(np.float64)


class Position(_Cursor):
    """Signed pulse count of a pulse train (dir 1 counts up) at query instants, pulses there included.

    Parameters
    ----------
    chunks : iterable of (t, dir)
        The train's pulses in time order (:meth:`~cosim.trace.Trace.pulse_chunks`).
    """

    def __init__(self, chunks: Iterable[tuple[Ints, Int8s]]) -> None:
        super().__init__(chunks)
        self._count = 0

    def at(self, t: Ints) -> Ints:
        """The position at each instant of ``t`` (sorted)."""
        out = np.empty(t.size, dtype=np.int64)
        i = 0
        while i < t.size:
            self._reach(int(t[i]))
            times, direction = self.buf if self.buf is not None else (np.empty(0, np.int64), np.empty(0, np.int8))
            # queries before the buffer's last pulse are answered now; the rest after reading on
            j = t.size if self.done else max(int(np.searchsorted(t, times[-1], side="left")), i + 1)
            steps = np.concatenate(([0], np.cumsum(direction.astype(np.int64) * 2 - 1)))
            k = np.searchsorted(times, t[i:j], side="right")
            out[i:j] = self._count + steps[k]
            passed = int(k[-1])
            self._count += int(steps[passed])
            self.buf = (times[passed:], direction[passed:])
            i = j
        return out


class Instants(_Cursor):
    """Sorted instants (changes to a value, pulses) asked for the first at or after, or the last before, an instant.

    Parameters
    ----------
    chunks : iterable of (t,)
        The instants in non-decreasing order, chunk by chunk.
    """

    def __init__(self, chunks: Iterable[tuple[Ints]]) -> None:
        super().__init__(chunks)
        self._before: int | None = None  # the last instant passed over

    def _drop_below(self, t: int) -> None:
        if self.buf is not None and len(self.buf[0]):
            times = self.buf[0]
            k = int(np.searchsorted(times, t, side="left"))
            if k:
                self._before = int(times[k - 1])
                self.buf = (times[k:],)

    def first_at_or_after(self, t: Ints) -> tuple[Ints, Bools]:
        """For each instant of ``t`` (sorted): the first instant at or after it, and whether there is one."""
        out, found = np.zeros(t.size, dtype=np.int64), np.zeros(t.size, dtype=bool)
        i = 0
        while i < t.size:
            self._drop_below(int(t[i]))
            if self.buf is None or not len(self.buf[0]):
                if self.done:
                    break
                self._pull()
                continue
            times = self.buf[0]  # every one at or after t[i]: the queries up to its last are answered
            j = int(np.searchsorted(t, times[-1], side="right"))
            out[i:j] = times[np.searchsorted(times, t[i:j], side="left")]
            found[i:j] = True
            i = j
        return out, found

    def last_before(self, t: Ints) -> tuple[Ints, Bools]:
        """For each instant of ``t`` (sorted): the last instant strictly before it, and whether there is one."""
        out, found = np.zeros(t.size, dtype=np.int64), np.zeros(t.size, dtype=bool)
        i = 0
        while i < t.size:
            if not self.done and (self.buf is None or not len(self.buf[0]) or int(self.buf[0][-1]) < t[i]):
                if self.buf is not None and len(self.buf[0]):
                    self._before = int(self.buf[0][-1])
                    self.buf = (self.buf[0][:0],)
                self._pull()
                continue
            times = self.buf[0] if self.buf is not None else np.empty(0, np.int64)
            j = t.size if self.done else int(np.searchsorted(t, times[-1], side="right"))
            k = np.searchsorted(times, t[i:j], side="left") - 1
            inside = k >= 0
            out[i:j] = np.where(inside, times[np.maximum(k, 0)] if times.size else 0,
                                -1 if self._before is None else self._before)
            found[i:j] = inside | (self._before is not None)
            self._drop_below(int(t[j - 1]))
            i = j
        return out, found

    def last(self) -> int | None:
        """The last instant of the stream (reads it to its end), or None if it has none."""
        while not self.done:
            if self.buf is not None and len(self.buf[0]):
                self._before = int(self.buf[0][-1])
                self.buf = (self.buf[0][:0],)
            self._pull()
        if self.buf is not None and len(self.buf[0]):
            return int(self.buf[0][-1])
        return self._before
