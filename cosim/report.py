"""Static HTML report of a main-job run (opens from disk, no server, plots embedded as PNG).

Per scenario: the verdict, the check table, the key figures and the plots an engineer looks at,
chosen from the signals the trace holds:

* pulse trains: pulse rate per millisecond;
* ``*.buffer_level`` / ``*.fifo_level``: buffer fill over time;
* ``*.gate`` against a ``*.position``/``*.dpos`` signal of the same axis: gate state over position;
* ``<device>.axisN.gate`` with another moving ``<device>.axisM.dpos``: the XY path, where the gate was on;
* ``laser.power`` / ``laser.energy``: optical power and energy;
* ``*.timebase_pct`` and ``*.sync_error``: time base and synchronisation error.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Callable, Iterator
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from cosim.export import read_trace
from cosim.runner import Result
from cosim.trace import Trace

MAX_POINTS = 20_000


def _figure_png(draw: Callable[[Any], None], *, title: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 2.6), dpi=90)
    draw(ax)
    ax.set_title(title, fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.tick_params(labelsize=8)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode()


def _thin(t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if t.size <= MAX_POINTS:
        return t, v
    index = np.linspace(0, t.size - 1, MAX_POINTS).astype(np.int64)
    return t[index], v[index]


def _draw_rate(ax: Any, bins: np.ndarray, rate: np.ndarray, ms: float) -> None:
    ax.step(bins[:-1] * ms, rate, where="post", lw=0.8)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("pulses / ms")


def _draw_value(ax: Any, t: np.ndarray, v: np.ndarray, ms: float, label: str) -> None:
    ax.step(t * ms, v, where="post", lw=0.8)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel(label)


def _draw_gate(ax: Any, tp: np.ndarray, p: np.ndarray, tg: np.ndarray, g: np.ndarray, ms: float,
               position: str) -> None:
    pg = p[np.clip(np.searchsorted(tp, tg, side="right") - 1, 0, None)]
    t, pt = _thin(tp, p)
    ax.plot(t * ms, pt, lw=0.8, label=position)
    on = g > 0
    ax.scatter(tg[on] * ms, pg[on], color="tab:green", s=14, label="gate on", zorder=3)
    ax.scatter(tg[~on] * ms, pg[~on], color="tab:red", s=14, label="gate off", zorder=3)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("position [counts]")
    ax.legend(fontsize=7)


def _draw_path(ax: Any, x: np.ndarray, y: np.ndarray, on: np.ndarray, x_name: str, y_name: str) -> None:
    ax.plot(x, y, lw=0.6, color="0.65", label="path")
    ax.plot(np.where(on, x, np.nan), np.where(on, y, np.nan), lw=1.8, color="tab:red", label="gate on")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(x_name)
    ax.set_ylabel(y_name)
    ax.legend(fontsize=7)


def _path_plot(trace: Trace, gate: str) -> tuple[str, str] | None:
    """The XY path of a gated axis (X) and another moving axis of the device (Y), with the gate on."""
    axis = gate.rsplit(".", 1)[0]
    device, _, leaf = axis.rpartition(".")
    x_name = f"{axis}.dpos"
    if not leaf.startswith("axis") or x_name not in trace.info:
        return None
    others = [n for n in trace.info if n.startswith(f"{device}.axis") and n.endswith(".dpos") and n != x_name]
    moving = [n for n in others if np.unique(trace.edges(n)[1]).size > 1]
    if not moving or np.unique(trace.edges(x_name)[1]).size < 2:
        return None
    y_name = moving[0]
    tx, vx = trace.edges(x_name)
    ty, vy = trace.edges(y_name)
    tg, g = trace.edges(gate)
    t = np.union1d(np.union1d(tx, ty), tg)
    held = [v[np.clip(np.searchsorted(tt, t, side="right") - 1, 0, None)] for tt, v in ((tx, vx), (ty, vy), (tg, g))]
    x, y, on = held[0], held[1], held[2] > 0
    if not on.any():
        return None
    index = np.linspace(0, t.size - 1, min(t.size, MAX_POINTS)).astype(np.int64)
    return f"{gate}: path", _figure_png(partial(_draw_path, x=x[index], y=y[index], on=on[index], x_name=x_name,
                                                y_name=y_name), title=f"XY path ({x_name}, {y_name}) and {gate}")


_VALUE_LEAVES = ("buffer_level", "fifo_level", "power", "energy", "timebase_pct", "sync_error",
                 "following_error", "slip_counts", "pwm_mark")


def _plots(trace: Trace) -> Iterator[tuple[str, str]]:
    """(title, base64 PNG) of each plot that fits the signals in ``trace``."""
    ms = 1e3 * float(trace.timebase.resolution_s)
    ticks_per_ms = round(1 / ms)
    for name in trace.names("pulse"):
        t, d = trace.pulses(name)
        if t.size:
            bins = np.arange(0, trace.end_t + ticks_per_ms, ticks_per_ms)
            rate, _ = np.histogram(t, bins=bins, weights=np.where(d > 0, 1, -1))
            yield f"{name}: pulse rate", _figure_png(partial(_draw_rate, bins=bins, rate=rate, ms=ms),
                                                     title=f"{name}: pulse rate (signed, per 1 ms)")
    for name, info in trace.info.items():
        leaf = name.rsplit(".", 1)[-1]
        if info.kind != "pulse" and leaf in _VALUE_LEAVES:
            t, v = _thin(*trace.edges(name))
            label = f"{leaf} [{info.unit}]" if info.unit else leaf
            yield name, _figure_png(partial(_draw_value, t=t, v=v, ms=ms, label=label), title=name)
        elif leaf == "gate":
            axis = name.rsplit(".", 1)[0]
            position = next((f"{axis}.{p}" for p in ("position", "dpos", "pwm_encoder")
                             if f"{axis}.{p}" in trace.info), None)
            if position is None:
                continue
            tg, g = trace.edges(name)
            tp, p = trace.edges(position)
            if tp.size:
                yield f"{name} against {position}", _figure_png(
                    partial(_draw_gate, tp=tp, p=p, tg=tg, g=g, ms=ms, position=position),
                    title=f"{name} edges on {position}")
            path = _path_plot(trace, name)
            if path is not None:
                yield path


def _check_rows(result: dict[str, Any]) -> str:
    rows = []
    for check in result["checks"]:
        first = check["violations"][0] if check["violations"] else None
        detail = (f"first at t={first['t_ns']} ns: {first['value']} vs limit {first['limit']}"
                  if first else "")
        css = "pass" if check["passed"] else "fail"
        rows.append(f"<tr class='{css}'><td>{'PASS' if check['passed'] else 'FAIL'}</td>"
                    f"<td>{html.escape(check['name'])}</td><td>{check['checked']}</td>"
                    f"<td>{check['n_violations']}</td><td>{html.escape(detail)}</td></tr>")
    return "".join(rows)


_STYLE = """body{font-family:sans-serif;margin:2em;max-width:60em}table{border-collapse:collapse;font-size:90%}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}tr.pass td:first-child{color:#080}
tr.fail td:first-child{color:#b00;font-weight:bold}.verdict-PASS{color:#080}.verdict-FAIL,.verdict-ERROR{color:#b00}
img{display:block;margin:0.5em 0}"""


def write_report(results: list[Result], out: Path) -> Path:
    """Write ``out/report.html`` for the given results (each with its trace in ``result.out``)."""
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>cosim report</title>"
             f"<style>{_STYLE}</style></head><body><h1>cosim: bundled scenarios</h1><table>"
             "<tr><th>scenario</th><th>verdict</th><th>checks passed</th><th>wall [s]</th>"
             "<th>real-time factor</th></tr>"]
    for r in results:
        parts.append(f"<tr><td><a href='#{r.scenario}'>{r.scenario}</a></td>"
                     f"<td class='verdict-{r.verdict}'>{r.verdict}</td><td>{r.passed}/{len(r.checks)}</td>"
                     f"<td>{r.wall_time_s:.2f}</td><td>{r.real_time_factor:.1f}</td></tr>")
    parts.append("</table>")
    for r in results:
        data = r.to_dict()
        parts.append(f"<h2 id='{r.scenario}'>{r.scenario} <span class='verdict-{r.verdict}'>{r.verdict}</span></h2>")
        params = ", ".join(f"{k}={v}" for k, v in r.parameters.items())
        parts.append(f"<p>parameters: {html.escape(params)}; seed {r.seed}</p>")
        if r.error:
            parts.append(f"<pre>{html.escape(r.error)}</pre>")
        parts.append("<table><tr><th></th><th>check</th><th>checked</th><th>violations</th><th>first</th></tr>"
                     f"{_check_rows(data)}</table>")
        if r.figures:
            parts.append("<ul>" + "".join(f"<li>{html.escape(k)} = {v['value']:.6g} {html.escape(v['unit'])}</li>"
                                          for k, v in r.figures.items()) + "</ul>")
        if r.out is not None and (r.out / "trace_meta.json").exists():
            for title, png in _plots(read_trace(r.out)):
                parts.append(f"<img alt='{html.escape(title)}' src='data:image/png;base64,{png}'>")
    parts.append("</body></html>")
    path = out / "report.html"
    path.write_text("\n".join(parts))
    return path
