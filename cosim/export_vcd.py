"""Waveform exports of a trace: the VCD, its digital-only companion, and a GTKWave save file.

``trace.vcd``
    Every signal, for GTKWave and other waveform viewers: bit signals and pulse trains as 1-bit
    wires (each pulse drawn its width high: the train's ``pulse_width``, or its segment's
    ``width`` in a PWM output), int signals as 64-bit integers, real
    signals as reals. Timescale = the trace's resolution. It ends at the run's end (a last
    timestamp at ``end_t``), and when a signal changes more than once at one tick it keeps the
    last value recorded there (a pulse train: a pulse starting where the previous one ends is
    high).
``trace_digital.vcd``
    The same bit signals and pulse trains, nothing else: sigrok (``sigrok-cli``, PulseView) reads
    only 1-bit wires and, in the version Debian ships (libsigrok 0.5.2), stops at the first
    integer or real value change of a file, so the full VCD would end there.
``trace.gtkw``
    A GTKWave save file for ``trace.vcd``: one group per device and axis (``pokeys``,
    ``pokeys.x``...), in each the pulse trains, then the bits, the integers (signed decimal) and the
    reals (drawn as analog steps). Open it with ``gtkwave trace.gtkw``.

Names: a signal's dotted path gives its scopes and its VCD name is the whole path with dots as
underscores (``pokeys.x.step`` is ``pokeys_x_step`` in scope ``pokeys`` > ``x``), so that every
name in a viewer's list is unique and says what it is (GTKWave shows the name without its scopes,
and shows a dot in a name as an escaped ``\\``).

Both VCDs are written in one pass over the trace, chunk by chunk (:meth:`Trace.pulse_chunks`,
:meth:`Trace.edge_chunks`, merged in time by :func:`cosim.tracestore.merge_sorted`); the text is
made with numpy for a whole chunk at once. Memory is about one chunk per signal, whatever the
length of the run. (Not pyvcd: its writer takes one value change per Python call, which for the
millions of pulse edges of a long job costs more than the simulation itself.)
"""

from __future__ import annotations

import gzip
import math
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim.trace import Trace
from cosim.tracestore import merge_sorted

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
U8 = npt.NDArray[np.uint8]
DIGITAL = ("bit", "pulse")
_BIT, _INT, _REAL = 0, 1, 2
_POW10 = 10 ** np.arange(19, dtype=np.int64)
#: Changes turned into text at once (its scratch arrays are about 40 bytes per change).
_BATCH = 1 << 16
#: Value changes (pulse edges and records) above which a trace's waveform is written compressed by default:
#: about 360 MB of VCD text. (The 1-hour 3-axis PoKeys job has 387 million: 5 GB of VCD, 0.8 GB compressed.)
COMPRESS_ABOVE_CHANGES = 20_000_000
#: gzip level of a compressed VCD: 6.4 times smaller than the text at about 150 MB/s (level 6: 6.6 times, 65 MB/s).
GZIP_LEVEL = 4


def changes(trace: Trace) -> int:
    """How many value changes a VCD of ``trace`` holds at most: two edges a pulse, one a record."""
    total = 0
    for name, info in trace.info.items():
        if info.kind == "pulse":
            total += 2 * sum(int(seg["count"].sum()) for seg in trace.segment_chunks(name))
            total += 2 * sum(t.size for t, _ in trace.single_pulse_chunks(name))
        else:
            total += sum(t.size for t, _ in trace.edge_chunks(name))
    return total


def write_waveforms(trace: Trace, folder: str | Path, *, compress: bool | None = None) -> list[Path]:
    """The waveform exports of ``trace`` into ``folder``; returns the paths written.

    Plain (``compress=False``, and by default for a run of at most :data:`COMPRESS_ABOVE_CHANGES`
    changes): ``trace.vcd``, ``trace_digital.vcd`` and ``trace.gtkw``. Compressed (``True``, and by
    default for a longer run): ``trace.vcd.gz`` (gzip, which GTKWave opens, and ``gzip -dc
    trace.vcd.gz | vcd2fst -v - -f trace.fst`` turns into GTKWave's compact format) and ``trace.gtkw``
    for it; no digital companion (``compress=False`` writes it, for sigrok).
    """
    folder = Path(folder)
    if compress is None:
        compress = changes(trace) > COMPRESS_ABOVE_CHANGES
    if compress:
        vcd = write_vcd(trace, folder / "trace.vcd.gz")
        return [vcd, write_gtkw(trace, folder / "trace.gtkw", vcd=vcd.name)]
    vcd = write_vcd(trace, folder / "trace.vcd", digital=folder / "trace_digital.vcd")
    return [vcd, folder / "trace_digital.vcd", write_gtkw(trace, folder / "trace.gtkw", vcd=vcd.name)]


def vcd_names(trace: Trace) -> dict[str, tuple[tuple[str, ...], str]]:
    """Scopes and VCD name of each signal: ``pokeys.x.step`` -> ``(('pokeys', 'x'), 'pokeys_x_step')``.

    Two paths that give the same name (``a.b_c``, ``a_b.c``) get ``_2``, ``_3``... in declaration order.
    """
    names: dict[str, tuple[tuple[str, ...], str]] = {}
    taken: set[str] = set()
    for name in trace.info:
        parts = name.split(".")
        leaf = base = "_".join(parts)
        k = 1
        while leaf in taken:
            k += 1
            leaf = f"{base}_{k}"
        taken.add(leaf)
        names[name] = (tuple(parts[:-1]), leaf)
    return names


def identifier(k: int) -> str:
    """The k-th VCD identifier code: ``!``, ``"``, ... ``~``, then two characters."""
    code = chr(33 + k % 94)
    while k >= 94:
        k = k // 94 - 1
        code = chr(33 + k % 94) + code
    return code


def write_vcd(trace: Trace, path: str | Path, *, digital: str | Path | None = None) -> Path:
    """Write ``trace`` to a VCD file, and with ``digital`` its bit signals and pulse trains to a second one.

    Parameters
    ----------
    trace : Trace
    path : path
        The VCD with every signal (gzip-compressed when its name ends in ``.gz``).
    digital : path, optional
        The digital-only companion (bit signals and pulse trains), for sigrok (compressed likewise).

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    names = vcd_names(trace)
    signals = list(trace.info)
    kinds = np.array([_BIT if trace.info[n].kind in DIGITAL else _INT if trace.info[n].kind == "int" else _REAL
                      for n in signals], dtype=np.int8)
    views = [(_View(trace, names, signals, kinds, np.ones(len(signals), dtype=bool)), path)]
    if digital is not None:
        views.append((_View(trace, names, signals, kinds, kinds == _BIT), Path(digital)))
    streams = [_First(_levels(trace, n)) for n in signals]
    initial = np.array([s.initial for s in streams])
    with ExitStack() as stack:
        handles = [stack.enter_context(_open(target)) for _, target in views]
        for (view, _), handle in zip(views, handles, strict=True):
            handle.write(view.header(initial))
        for t, v, var in merge_sorted(_tagged(s, k) for k, s in enumerate(streams)):
            for start in range(0, t.size, _BATCH):  # text is made a bounded number of lines at a time
                part = slice(start, start + _BATCH)
                for (view, _), handle in zip(views, handles, strict=True):
                    handle.write(view.changes(t[part], var[part], v[part]))
        for (view, _), handle in zip(views, handles, strict=True):
            if trace.end_t > view.last_t:
                handle.write(f"#{trace.end_t}\n".encode())
    return path


def _open(target: Path) -> Any:
    """A file to write bytes to; gzip (with no time stamp in it: the same trace, the same bytes) for ``.gz``."""
    if target.suffix == ".gz":
        return gzip.GzipFile(target, "wb", compresslevel=GZIP_LEVEL, mtime=0)
    return open(target, "wb")


def _tagged(levels: _First, k: int) -> Iterator[tuple[Ints, Floats, npt.NDArray[np.int32]]]:
    for t, v in levels:
        yield t, v, np.full(t.size, k, dtype=np.int32)


class _First:
    """A signal's level stream with its value at tick 0 taken out (it goes into ``$dumpvars``)."""

    def __init__(self, levels: Iterator[tuple[Ints, Floats]]) -> None:
        self.initial = 0.0
        self._levels = levels
        self._head: tuple[Ints, Floats] | None = None
        for t, v in levels:
            if t.size and t[0] == 0:
                self.initial = float(v[0])
                t, v = t[1:], v[1:]
            self._head = (t, v)
            break

    def __iter__(self) -> Iterator[tuple[Ints, Floats]]:
        if self._head is not None:
            yield self._head
        yield from self._levels


def _levels(trace: Trace, name: str) -> Iterator[tuple[Ints, Floats]]:
    """The levels a viewer shows for one signal: ``(t, value)`` strictly increasing in ``t``, each
    value different from the one before (the first from 0), the last value recorded at each tick."""
    info = trace.info[name]
    prev = np.zeros(1)
    events = _pulse_events(trace, name) if info.kind == "pulse" else _record_events(trace, name, info.kind)
    for t, v in events:
        if not t.size:
            continue
        last = np.append(t[1:] != t[:-1], True)  # the last record at each tick
        t, v = t[last], v[last]
        moved = v != np.concatenate([prev, v[:-1]])  # NaN always moves, as in any viewer
        prev = v[-1:]
        t, v = t[moved], v[moved]
        for start in range(0, t.size, _BATCH):  # the merge holds about one of these per signal
            yield t[start:start + _BATCH], v[start:start + _BATCH]


def _record_events(trace: Trace, name: str, kind: str) -> Iterator[tuple[Ints, Floats]]:
    """Records as written (bits 0/1, ints truncated), whole ticks at a time: the records at a chunk's
    last tick wait for the next chunk, which may hold more at that tick."""
    held_t, held_v = np.empty(0, np.int64), np.empty(0)
    chunks = trace.edge_chunks(name) if trace.in_time_order(name) else iter([_sorted(*trace.edges(name))])
    for t, v in chunks:
        if not t.size:
            continue
        if kind == "bit":
            v = (v != 0).astype(np.float64)
        elif kind == "int":
            v = v.astype(np.int64).astype(np.float64)
        t, v = np.concatenate([held_t, t]), np.concatenate([held_v, v])
        cut = int(np.searchsorted(t, t[-1], side="left"))
        yield t[:cut], v[:cut]
        held_t, held_v = t[cut:], v[cut:]
    yield held_t, held_v


def _sorted(t: Ints, v: Floats) -> tuple[Ints, Floats]:
    order = np.argsort(t, kind="stable")
    return t[order], v[order]


def _pulse_events(trace: Trace, name: str) -> Iterator[tuple[Ints, Floats]]:
    """Rises (1) at each pulse and falls (0) its width later (at least one tick), in time order, a
    fall before a rise at one tick; what lies at or after a piece's last pulse waits for the next
    piece. The pulses are taken ``_BATCH`` at a time, so that what a suspended generator holds
    stays small."""
    held_t, held_v = np.empty(0, np.int64), np.empty(0)
    for chunk, widths in trace.pulse_width_chunks(name):
        for start in range(0, chunk.size, _BATCH):
            t = chunk[start:start + _BATCH]
            times = np.concatenate([held_t, t + np.maximum(widths[start:start + _BATCH], 1), t])
            values = np.concatenate([held_v, np.zeros(t.size), np.ones(t.size)])
            order = np.argsort(times * 2 + values.astype(np.int64), kind="stable")  # three sorted runs
            times, values = times[order], values[order]
            cut = int(np.searchsorted(times, t[-1], side="left"))
            held_t, held_v = times[cut:], values[cut:]
            del order
            yield times[:cut], values[:cut]
    yield held_t, held_v


class _View:
    """One VCD file's header and its change lines, for the signals it shows."""

    def __init__(self, trace: Trace, names: dict[str, tuple[tuple[str, ...], str]], signals: list[str],
                 kinds: npt.NDArray[np.int8], shown: npt.NDArray[np.bool_]) -> None:
        self.trace = trace
        self.names = names
        self.signals = [s for s, keep in zip(signals, shown, strict=True) if keep]
        self.shown = shown
        self.index = np.cumsum(shown) - 1  # trace signal -> index among the shown ones
        self.kinds = kinds[shown]
        ids = [identifier(k).encode() for k in range(len(self.signals))]
        width = max((len(i) for i in ids), default=1)
        self.id_bytes = np.zeros((len(ids), width), dtype=np.uint8)
        for k, code in enumerate(ids):
            self.id_bytes[k, :len(code)] = np.frombuffer(code, dtype=np.uint8)
        self.id_len = np.array([len(i) for i in ids], dtype=np.int64)
        self.id_sizes = range(int(self.id_len.min()), int(self.id_len.max()) + 1) if ids else range(0)
        self.ids = [i.decode() for i in ids]
        self.last_t = 0

    def header(self, initial: Floats) -> bytes:
        """Definitions and the ``$dumpvars`` block with each signal's value at tick 0."""
        trace = self.trace
        lines = ["$comment written by cosim" + (f": {trace.meta['scenario']}" if "scenario" in trace.meta else "")
                 + " $end", "$date simulation $end", f"$timescale {trace.timebase.unit} $end"]
        tree: dict[str, Any] = {}
        for k, name in enumerate(self.signals):
            scopes, leaf = self.names[name]
            node = tree
            for scope in scopes:
                node = node.setdefault(scope, {})
            node.setdefault("", []).append((k, leaf))
        lines += self._scope_lines(tree)
        lines += ["$enddefinitions $end", "#0", "$dumpvars"]
        text = "\n".join(lines) + "\n"
        every = np.arange(len(self.signals), dtype=np.int64)
        body = self._lines(np.zeros(every.size, dtype=np.int64), every, initial[self.shown], timestamps=False)
        return text.encode() + body + b"$end\n"

    def _scope_lines(self, tree: dict[str, Any]) -> list[str]:
        lines = []
        for k, leaf in tree.get("", []):
            kind = self.kinds[k]
            var = "wire 1" if kind == _BIT else "integer 64" if kind == _INT else "real 64"
            lines.append(f"$var {var} {self.ids[k]} {leaf} $end")
        for scope, node in tree.items():
            if scope:
                lines += [f"$scope module {scope} $end", *self._scope_lines(node), "$upscope $end"]
        return lines

    def changes(self, t: Ints, var: npt.NDArray[np.int32], v: Floats) -> bytes:
        """Change lines (with their timestamps) for the merged changes of the signals this file shows."""
        keep = self.shown[var]
        if not keep.all():
            t, var, v = t[keep], var[keep], v[keep]
        if not t.size:
            return b""
        text = self._lines(t, self.index[var], v, timestamps=True)
        self.last_t = int(t[-1])
        return text

    def _lines(self, t: Ints, k: Ints, v: Floats, *, timestamps: bool) -> bytes:
        """``#t`` lines where the time moves on, then ``<value><id>`` lines, made for all rows at once.

        The short lines (timestamps, bits) are the rows of one byte matrix, each right-aligned (so a
        column is one digit place for every timestamp), taken out in order through a mask; the long
        ones (integers, reals) are formatted one by one and put in between: Python work only for those.
        """
        n = t.size
        if not n:
            return b""
        stamp = np.zeros(n, dtype=bool)
        if timestamps:
            if t[0] < 0:
                raise ValueError(f"a VCD cannot hold the negative time {int(t[0])}")
            stamp[0] = t[0] != self.last_t
            stamp[1:] = t[1:] != t[:-1]
        kind = self.kinds[k]
        long = kind != _BIT
        # the lines in order: a row's timestamp line (if any), then its change line
        change_at = np.arange(n) + np.cumsum(stamp)
        is_long = np.zeros(n + int(np.count_nonzero(stamp)), dtype=bool)
        is_long[change_at[long]] = True
        short_at = np.cumsum(~is_long) - 1  # index of each line among the short ones
        width = 21  # '#', up to 19 digits, newline; a bit line is shorter
        text = np.zeros((is_long.size - int(np.count_nonzero(long)), width), dtype=np.uint8)
        length = np.zeros(text.shape[0], dtype=np.int64)
        rows = np.flatnonzero(stamp)
        if rows.size:
            number = t[rows].astype(np.uint64)
            digits = np.maximum(np.searchsorted(_POW10, t[rows], side="right"), 1)
            lines = np.zeros((rows.size, width), dtype=np.uint8)
            for j in range(int(digits.max())):  # right to left: a division by 10 is fast
                number, digit = np.divmod(number, np.uint64(10))
                lines[:, width - 2 - j] = digit + 48  # left of a shorter number: outside its line
            lines[np.arange(rows.size), width - 2 - digits] = 35  # '#'
            lines[:, width - 1] = 10
            at = short_at[change_at[rows] - 1]
            text[at] = lines
            length[at] = digits + 2
        id_len = self.id_len[k]
        for size in self.id_sizes:
            these = np.flatnonzero(~long & (id_len == size)) if len(self.id_sizes) > 1 else np.flatnonzero(~long)
            if these.size:
                at = short_at[change_at[these]]
                text[at, width - 2 - size] = 48 + (v[these] != 0)
                text[at, width - 1 - size:width - 1] = self.id_bytes[k[these], :size]
                text[at, width - 1] = 10
                length[at] = size + 2
        # each row's last length[i] bytes, in order (a gather: cheaper than masking the whole matrix)
        total = int(length.sum())
        starts = np.arange(length.size, dtype=np.int64) * width + width - length
        short = text.ravel()[np.repeat(starts - (np.cumsum(length) - length), length)
                             + np.arange(total, dtype=np.int64)].tobytes()
        if not long.any():
            return short
        # the long lines, each after the short lines before it: formatted in one pass, then the short
        # text and theirs scattered into one byte array (a long line goes where the short text before
        # it ends, shifted by the long lines before it)
        rows = np.flatnonzero(long)
        ends = np.concatenate(([0], np.cumsum(length)))[change_at[rows] - np.arange(rows.size)]
        mask = (1 << 64) - 1
        ids = self.ids
        texts = [f"b{int(value) & mask:b} {ids[var]}\n" if is_int else f"r{value!r} {ids[var]}\n"
                 for value, var, is_int in zip(v[rows].tolist(), k[rows].tolist(), (kind[rows] == _INT).tolist(),
                                               strict=True)]
        sizes = np.fromiter(map(len, texts), dtype=np.int64, count=len(texts))
        total = int(sizes.sum())
        out = np.empty(len(short) + total, dtype=np.uint8)
        at = np.repeat(ends, sizes) + np.arange(total, dtype=np.int64)  # line i at ends[i] + its long bytes before
        is_long_byte = np.zeros(out.size, dtype=bool)
        is_long_byte[at] = True
        out[at] = np.frombuffer("".join(texts).encode(), dtype=np.uint8)
        out[~is_long_byte] = np.frombuffer(short, dtype=np.uint8)
        return out.tobytes()


#: GTKWave trace flags (``@`` lines of a save file): binary, signed decimal, analog step, group begin/end,
#: and a blank row that makes an analog trace taller.
_GTKW_FLAGS = {"pulse": "28", "bit": "28", "int": "420", "real": "8420"}
_GTKW_GROUP_BEGIN, _GTKW_GROUP_END, _GTKW_STRETCH = "800200", "1000200", "20000"
_GTKW_ORDER = {"pulse": 0, "bit": 1, "int": 2, "real": 3}


def write_gtkw(trace: Trace, path: str | Path, *, vcd: str = "trace.vcd") -> Path:
    """Write a GTKWave save file showing every signal of ``vcd`` (a path relative to ``path``'s folder).

    It opens on the whole run, with one group per scope (``pokeys``, then ``pokeys.x``,
    ``pokeys.y``...; devices in the order their first signal was declared), in each the pulse
    trains, the bits, the integers (signed decimal) and the reals (analog steps, two rows high).
    """
    path = Path(path)
    names = vcd_names(trace)
    groups: dict[tuple[str, ...], list[str]] = {}
    for name, (scopes, _) in names.items():
        for depth in range(1, len(scopes) + 1):  # a device's own group comes before its axes'
            groups.setdefault(scopes[:depth], [])
        groups[scopes].append(name)
    ordered = sorted(groups, key=lambda scopes: [list(groups).index(scopes[:d]) for d in range(1, len(scopes) + 1)])
    about = f": {trace.meta['scenario']}" if "scenario" in trace.meta else ""
    # zoom: the whole run in about 700 pixels (GTKWave shows 2**-zoom / 200 time units per pixel)
    zoom = -math.log2(max(trace.end_t, 1) * 200 / 700)
    lines = [f"[*] GTKWave save file written by cosim{about}", f'[dumpfile] "{vcd}"', f'[savefile] "{path.name}"',
             "[timestart] 0", "[size] 1200 800", "[pos] -1 -1", f"*{zoom:.6f} 0", "[sst_expanded] 1"]
    for scopes in ordered:
        members = sorted(groups[scopes], key=lambda n: _GTKW_ORDER[trace.info[n].kind])
        if not members:
            continue
        label = ".".join(scopes)
        lines += [f"@{_GTKW_GROUP_BEGIN}", f"-{label}"]
        for name in members:
            kind = trace.info[name].kind
            lines += [f"@{_GTKW_FLAGS[kind]}", ".".join((*scopes, names[name][1]))]
            if kind == "real":
                lines += [f"@{_GTKW_STRETCH}", "-"]
        lines += [f"@{_GTKW_GROUP_END}", f"-{label}"]
    path.write_text("\n".join(lines) + "\n")
    return path
