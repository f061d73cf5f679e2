"""Exports of a :class:`~cosim.trace.Trace`: VCD for waveform viewers, Parquet/CSV tables.

:func:`write_trace` writes a trace into a folder (``trace_meta.json``, ``trace.vcd`` and the
tables); :func:`read_trace` reads the tables back into a :class:`~cosim.trace.Trace`. Both use
only the trace's public methods.

Tables (one file each, in the trace folder, ``.parquet`` or ``.csv``):

``edges``     signal, t, value (int64)       bit and int signals: every change
``values``    signal, t, value (float64)     real signals: every change or sample
``segments``  signal, t0, duration, count, dir   pulse-train segments (see :mod:`cosim.pulses`)
``pulses``    signal, t, dir                 pulses recorded one by one

All ``t`` columns are integer ticks; ``trace_meta.json`` holds the resolution and each
signal's kind, unit and description. In the VCD each pulse is drawn ``pulse_width`` ticks high.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from cosim.errors import ConfigurationError
from cosim.trace import Trace

_TABLES = ("edges", "values", "segments", "pulses")
FORMATS = ("vcd", "parquet", "csv")
META = "trace_meta.json"


def write_trace(trace: Trace, folder: str | Path, *, formats: tuple[str, ...] = ("vcd", "parquet")) -> Path:
    """Write ``trace`` into ``folder``: ``trace_meta.json`` and the given formats (vcd, parquet, csv)."""
    for fmt in formats:
        if fmt not in FORMATS:
            raise ConfigurationError.out_of_range("trace format", fmt, ", ".join(FORMATS))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / META).write_text(json.dumps(trace.header(), indent=1, default=str))
    for fmt in formats:
        if fmt == "vcd":
            write_vcd(trace, folder / "trace.vcd")
        else:
            write_tables(trace, folder, fmt)
    return folder


def read_trace(folder: str | Path) -> Trace:
    """Read a trace written by :func:`write_trace` (Parquet or CSV tables) back."""
    folder = Path(folder)
    trace = Trace.from_header(json.loads((folder / META).read_text()))
    read_tables(trace, folder)
    return trace


def write_vcd(trace: Trace, path: str | Path) -> Path:
    """Write every signal of ``trace`` to a VCD file (timescale = the trace resolution)."""
    from vcd import VCDWriter

    path = Path(path)
    times: list[np.ndarray] = []
    var_ids: list[np.ndarray] = []
    values: list[np.ndarray] = []
    variables: list[Any] = []
    with path.open("w") as stream, VCDWriter(stream, timescale=trace.timebase.unit,
                                             comment="written by cosim", date="simulation",
                                             check_values=False) as writer:
        for name, info in trace.info.items():
            scope, _, leaf = name.rpartition(".")
            index = len(variables)
            if info.kind == "pulse":
                variables.append(writer.register_var(scope or "top", leaf, "wire", size=1, init=0))
                t, _dirs = trace.pulses(name)
                width = max(1, info.pulse_width)
                t_all = np.concatenate([t, t + width])
                v_all = np.concatenate([np.ones(t.size), np.zeros(t.size)])
            else:
                t_all, v_all = trace.edges(name)
                if info.kind == "real":
                    variables.append(writer.register_var(scope or "top", leaf, "real", init=0.0))
                else:
                    size = 1 if info.kind == "bit" else 64
                    var_type = "wire" if info.kind == "bit" else "integer"
                    variables.append(writer.register_var(scope or "top", leaf, var_type, size=size, init=0))
            times.append(t_all)
            var_ids.append(np.full(t_all.size, index, dtype=np.int64))
            values.append(v_all.astype(np.float64))
        if times:
            t_cat = np.concatenate(times)
            id_cat = np.concatenate(var_ids)
            v_cat = np.concatenate(values)
            # time order; at one instant a pulse's fall (0) before the next rise (1), then by signal
            order = np.lexsort((id_cat, v_cat, t_cat))
            kinds = [trace.info[n].kind for n in trace.info]
            for t, i, v in zip(t_cat[order].tolist(), id_cat[order].tolist(), v_cat[order].tolist(),
                               strict=True):
                writer.change(variables[i], t, v if kinds[i] == "real" else int(v))
    return path


def _frames(trace: Trace) -> dict[str, pd.DataFrame]:
    parts: dict[str, list[pd.DataFrame]] = {name: [] for name in _TABLES}
    for name, info in trace.info.items():
        if info.kind == "pulse":
            seg = trace.segments(name)
            parts["segments"].append(pd.DataFrame({"signal": name, **seg}))
            t_single, dir_single = trace.single_pulses(name)
            if t_single.size:
                parts["pulses"].append(pd.DataFrame({"signal": name, "t": t_single,
                                                     "dir": dir_single.astype(np.int64)}))
        else:
            t, v = trace.edges(name)
            table = "values" if info.kind == "real" else "edges"
            value = v if info.kind == "real" else v.astype(np.int64)
            parts[table].append(pd.DataFrame({"signal": name, "t": t, "value": value}))
    empty: dict[str, dict[str, list[Any]]] = {
        "edges": {"signal": [], "t": [], "value": []},
        "values": {"signal": [], "t": [], "value": []},
        "segments": {"signal": [], "t0": [], "duration": [], "count": [], "dir": []},
        "pulses": {"signal": [], "t": [], "dir": []},
    }
    frames = {}
    for table, dfs in parts.items():
        if dfs:
            frames[table] = pd.concat(dfs, ignore_index=True)
        else:
            frames[table] = pd.DataFrame(empty[table])
        for column in frames[table].columns:
            if column == "signal":
                frames[table][column] = frames[table][column].astype(str)
            elif column == "value" and table == "values":
                frames[table][column] = frames[table][column].astype(np.float64)
            else:
                frames[table][column] = frames[table][column].astype(np.int64)
    return frames


def write_tables(trace: Trace, folder: str | Path, fmt: str = "parquet") -> list[Path]:
    """Write the four tables as Parquet or CSV files into ``folder``."""
    folder = Path(folder)
    written = []
    for table, frame in _frames(trace).items():
        path = folder / f"{table}.{fmt}"
        if fmt == "parquet":
            frame.to_parquet(path, index=False)
        else:
            frame.to_csv(path, index=False)
        written.append(path)
    return written


def read_tables(trace: Trace, folder: str | Path) -> None:
    """Fill a freshly declared ``trace`` from the tables in ``folder`` (Parquet preferred)."""
    folder = Path(folder)
    fmt = "parquet" if (folder / "edges.parquet").exists() else "csv"

    def read(table: str) -> pd.DataFrame:
        path = folder / f"{table}.{fmt}"
        return pd.read_parquet(path) if fmt == "parquet" else pd.read_csv(path)

    for table in ("edges", "values"):
        for name, group in read(table).groupby("signal", sort=False):
            trace.extend(str(name), group["t"].to_numpy(np.int64), group["value"].to_numpy(np.float64))
    for name, group in read("segments").groupby("signal", sort=False):
        trace.extend_segments(str(name), group["t0"].to_numpy(np.int64), group["duration"].to_numpy(np.int64),
                              group["count"].to_numpy(np.int64), group["dir"].to_numpy(np.int64))
    for name, group in read("pulses").groupby("signal", sort=False):
        trace.extend_single_pulses(str(name), group["t"].to_numpy(np.int64), group["dir"].to_numpy(np.int64))
