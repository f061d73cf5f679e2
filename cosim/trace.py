"""The trace: the single record of everything a simulation did.

Signal names follow one scheme, the same in the Python API, VCD, Parquet and CSV::

    <device>.<axis>.<signal>      e.g. pokeys.x.step, trio.axis3.gate, pmac.cs1.timebase
    <device>.<signal>             for devices without axes, e.g. laser.power, pokeys.buffer_level

lower case, dot-separated, each part ``[a-z0-9_]``. In a waveform viewer the dots are scopes,
so ``trio.axis3.gate`` appears as signal ``gate`` in scope ``trio`` > ``axis3``.

Kinds of record (all times are integer ticks of the trace's resolution):

* ``bit`` / ``int`` signals: exact edge lists ``(t, value)``, value held until the next edge;
* ``real`` signals: value changes or samples ``(t, value)`` (analog outputs at requested times);
* ``pulse`` trains: segments ``(t0, duration, count, dir)`` placed by the rule of
  :mod:`cosim.pulses`, plus any pulses given one by one; :meth:`Trace.pulses` materialises them.

The trace is a leaf: it imports nothing of cosim but the pulse rule, the time base and the
errors. Exports (:mod:`cosim.export`: VCD, Parquet/CSV, the ``trace_meta.json`` header) read and
fill it through its public methods only.
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from fractions import Fraction
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from cosim.errors import ConfigurationError
from cosim.pulses import materialize_pulses
from cosim.timebase import TimeBase

Kind = Literal["bit", "int", "real", "pulse"]
KINDS: tuple[str, ...] = ("bit", "int", "real", "pulse")
_NAME = re.compile(r"^[a-z][a-z0-9_]*(\.[a-z0-9_]+)*$")


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
        For pulse trains: width of each drawn pulse [ticks] (VCD only).
    """

    kind: str
    unit: str = ""
    description: str = ""
    pulse_width: int = 1


@dataclass
class _Channel:
    t: array = field(default_factory=lambda: array("q"))
    v: array = field(default_factory=lambda: array("d"))


@dataclass
class _PulseChannel:
    t0: array = field(default_factory=lambda: array("q"))
    duration: array = field(default_factory=lambda: array("q"))
    count: array = field(default_factory=lambda: array("q"))
    direction: array = field(default_factory=lambda: array("b"))
    single_t: array = field(default_factory=lambda: array("q"))
    single_dir: array = field(default_factory=lambda: array("b"))


class Trace:
    """Columnar record of edges, values and pulse segments, in integer ticks.

    Parameters
    ----------
    timebase : TimeBase
        Resolution of the recorded times.
    """

    def __init__(self, timebase: TimeBase | None = None) -> None:
        self.timebase = timebase or TimeBase()
        self.info: dict[str, SignalInfo] = {}
        self._values: dict[str, _Channel] = {}
        self._pulses: dict[str, _PulseChannel] = {}
        self._pulse_cache: dict[str, tuple[tuple[int, int], npt.NDArray[np.int64], npt.NDArray[np.int8]]] = {}
        self.end_t = 0
        self.meta: dict[str, object] = {}

    # -- declaring and recording -------------------------------------------------------------
    def declare(self, name: str, kind: str, *, unit: str = "", description: str = "",
                pulse_width: int = 1) -> None:
        """Declare a signal before recording it (names are checked against the scheme)."""
        if not _NAME.match(name):
            raise ConfigurationError(
                f"signal name {name!r} does not follow the scheme <device>.<axis>.<signal> "
                "(lower case, dot-separated, [a-z0-9_])"
            )
        if kind not in KINDS:
            raise ConfigurationError.out_of_range(f"kind of {name}", kind, ", ".join(KINDS))
        if name in self.info:
            raise ConfigurationError(f"signal {name!r} is declared twice")
        self.info[name] = SignalInfo(kind, unit, description, pulse_width)
        if kind == "pulse":
            self._pulses[name] = _PulseChannel()
        else:
            self._values[name] = _Channel()

    def record(self, name: str, t: int, value: float) -> None:
        """Record a value change (bit/int/real) or a sample (real) at tick ``t``."""
        channel = self._values[name]
        channel.t.append(t)
        channel.v.append(value)

    def record_segment(self, name: str, t0: int, duration: int, count: int, direction: int) -> None:
        """Record ``count`` pulses spread over ``[t0, t0+duration)`` (rule of :mod:`cosim.pulses`)."""
        channel = self._pulses[name]
        channel.t0.append(t0)
        channel.duration.append(duration)
        channel.count.append(count)
        channel.direction.append(direction)

    def recorder(self, name: str) -> Callable[[int, float], None]:
        """``record(t, value)`` for one declared value signal, bound once (for per-slot hot paths)."""
        channel = self._values[name]
        t_append, v_append = channel.t.append, channel.v.append

        def record(t: int, value: float) -> None:
            t_append(t)
            v_append(value)

        return record

    def segment_recorder(self, name: str) -> Callable[[int, int, int, int], None]:
        """``record_segment(t0, duration, count, direction)`` for one declared pulse train, bound once."""
        channel = self._pulses[name]
        appends = (channel.t0.append, channel.duration.append, channel.count.append, channel.direction.append)
        t0_append, duration_append, count_append, direction_append = appends

        def record(t0: int, duration: int, count: int, direction: int) -> None:
            t0_append(t0)
            duration_append(duration)
            count_append(count)
            direction_append(direction)

        return record

    def record_pulse(self, name: str, t: int, direction: int) -> None:
        """Record one pulse at tick ``t`` (for trains that are not evenly spread)."""
        channel = self._pulses[name]
        channel.single_t.append(t)
        channel.single_dir.append(direction)

    # -- reading ----------------------------------------------------------------------------
    def names(self, kind: str | None = None) -> list[str]:
        """Declared signal names (optionally of one kind), in declaration order."""
        return [n for n, i in self.info.items() if kind is None or i.kind == kind]

    def _channel(self, name: str) -> _Channel:
        if name not in self._values:
            raise KeyError(_unknown(name, self.info))
        return self._values[name]

    def edges(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
        """``(t, value)`` of a bit/int/real signal: its changes (or samples) in time order."""
        channel = self._channel(name)
        return np.frombuffer(channel.t, dtype=np.int64).copy(), np.frombuffer(channel.v).copy()

    samples = edges

    def value_at(self, name: str, t: int) -> float:
        """Value of a piecewise-constant signal at tick ``t`` (NaN before its first record)."""
        times, values = self.edges(name)
        i = int(np.searchsorted(times, t, side="right")) - 1
        return float(values[i]) if i >= 0 else float("nan")

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
        times, values = self.edges(name)
        i = np.searchsorted(times, np.asarray(t, dtype=np.int64), side="right") - 1
        return np.where(i >= 0, values[np.maximum(i, 0)] if values.size else np.nan, np.nan)

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
        times, direction = self.pulses(name)
        position = np.concatenate(([0], np.cumsum(np.where(direction == 1, 1, -1), dtype=np.int64)))
        return position[np.searchsorted(times, np.asarray(t, dtype=np.int64), side="right")]

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
        times, _ = self.pulses(name)
        last = max(self.end_t, int(times[-1]) + 1 if times.size else 0) if end is None else end
        n = max(-(-(last - start) // window), 0)
        inside = times[(times >= start) & (times < min(last, start + n * window))]
        counts = np.bincount((inside - start) // window, minlength=n).astype(np.int64)
        return start + window * np.arange(n, dtype=np.int64), counts

    def segments(self, name: str) -> dict[str, npt.NDArray[np.int64]]:
        """Raw pulse segments of a pulse train: arrays ``t0, duration, count, dir``."""
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        ch = self._pulses[name]
        return {
            "t0": np.frombuffer(ch.t0, dtype=np.int64).copy(),
            "duration": np.frombuffer(ch.duration, dtype=np.int64).copy(),
            "count": np.frombuffer(ch.count, dtype=np.int64).copy(),
            "dir": np.frombuffer(ch.direction, dtype=np.int8).astype(np.int64),
        }

    def pulses(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
        """``(t, dir)`` of every pulse of a pulse train, materialised exactly, in time order.

        The arrays are read-only and kept until the train records more pulses, so several checks
        of one train materialise it once.
        """
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        ch = self._pulses[name]
        version = (len(ch.t0), len(ch.single_t))
        cached = self._pulse_cache.get(name)
        if cached is not None and cached[0] == version:
            return cached[1], cached[2]
        seg = self.segments(name)
        t = materialize_pulses(seg["t0"], seg["duration"], seg["count"])
        d = np.repeat(seg["dir"].astype(np.int8), seg["count"])
        if len(ch.single_t):
            t = np.concatenate([t, np.frombuffer(ch.single_t, dtype=np.int64)])
            d = np.concatenate([d, np.frombuffer(ch.single_dir, dtype=np.int8)])
        order = np.argsort(t, kind="stable")
        t, d = t[order], d[order]
        t.setflags(write=False)
        d.setflags(write=False)
        self._pulse_cache[name] = (version, t, d)
        return t, d

    def single_pulses(self, name: str) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int8]]:
        """``(t, dir)`` of the pulses of a pulse train that were recorded one by one (not as segments)."""
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        ch = self._pulses[name]
        return np.frombuffer(ch.single_t, dtype=np.int64).copy(), np.frombuffer(ch.single_dir, dtype=np.int8).copy()

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
    def from_header(cls, header: Mapping[str, Any]) -> Trace:
        """An empty trace with the resolution, end, signals and metadata of :meth:`header`."""
        num, den = header["resolution_s"]
        trace = cls(TimeBase(Fraction(num, den)))
        trace.end_t = int(header["end_t"])
        trace.meta = dict(header.get("meta", {}))
        for name, info in header["signals"].items():
            trace.declare(name, info["kind"], unit=info["unit"], description=info["description"],
                          pulse_width=info["pulse_width"])
        return trace

    def extend(self, name: str, t: npt.ArrayLike, value: npt.ArrayLike) -> None:
        """Append many records ``(t, value)`` of a bit/int/real signal at once (in time order)."""
        channel = self._channel(name)
        channel.t.extend(np.asarray(t, dtype=np.int64).tolist())
        channel.v.extend(np.asarray(value, dtype=np.float64).tolist())

    def extend_segments(self, name: str, t0: npt.ArrayLike, duration: npt.ArrayLike, count: npt.ArrayLike,
                        direction: npt.ArrayLike) -> None:
        """Append many segments of a pulse train at once (see :meth:`record_segment`)."""
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        ch = self._pulses[name]
        ch.t0.extend(np.asarray(t0, dtype=np.int64).tolist())
        ch.duration.extend(np.asarray(duration, dtype=np.int64).tolist())
        ch.count.extend(np.asarray(count, dtype=np.int64).tolist())
        ch.direction.extend(np.asarray(direction, dtype=np.int64).tolist())

    def extend_single_pulses(self, name: str, t: npt.ArrayLike, direction: npt.ArrayLike) -> None:
        """Append many pulses given one by one (see :meth:`record_pulse`)."""
        if name not in self._pulses:
            raise KeyError(_unknown(name, self.info))
        ch = self._pulses[name]
        ch.single_t.extend(np.asarray(t, dtype=np.int64).tolist())
        ch.single_dir.extend(np.asarray(direction, dtype=np.int64).tolist())


def _unknown(name: str, known: dict[str, SignalInfo]) -> str:
    import difflib

    close = difflib.get_close_matches(name, list(known), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    return f"no signal named {name!r} in the trace{hint}"
