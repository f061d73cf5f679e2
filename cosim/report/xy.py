"""The XY path of a gated axis, with where the gate was on (a Bokeh figure, not on the time axis).

For a gate ``<device>.axisN.gate`` whose axis has a ``dpos`` and another axis of the device that
moves: the path ``(axisN.dpos, axisM.dpos)`` in grey and the parts where the gate was on in red,
at most :data:`MAX_POINTS` points (evenly chosen) per path.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cosim.trace import Trace

MAX_POINTS = 20_000


def xy_paths(trace: Trace) -> list[Any]:
    """One figure per gate that has such a path (named ``xy:<gate>``)."""
    figures = []
    for name, info in trace.info.items():
        if info.kind == "bit" and name.endswith(".gate"):
            plot = _path(trace, name)
            if plot is not None:
                figures.append(plot)
    return figures


def _path(trace: Trace, gate: str) -> Any:
    from bokeh.models import ColumnDataSource
    from bokeh.plotting import figure

    axis = gate.rsplit(".", 1)[0]
    device, _, leaf = axis.rpartition(".")
    x_name = f"{axis}.dpos"
    if not leaf.startswith("axis") or x_name not in trace.info or trace.info[x_name].kind == "pulse":
        return None
    others = [n for n in trace.info if n.startswith(f"{device}.axis") and n.endswith(".dpos") and n != x_name
              and trace.info[n].kind != "pulse"]
    moving = [n for n in others if np.unique(trace.edges(n)[1]).size > 1]
    if not moving or np.unique(trace.edges(x_name)[1]).size < 2:
        return None
    y_name = moving[0]
    tx, vx = trace.edges(x_name)
    ty, vy = trace.edges(y_name)
    tg, g = trace.edges(gate)
    t = np.union1d(np.union1d(tx, ty), tg)
    x, y, on = (v[np.clip(np.searchsorted(tt, t, side="right") - 1, 0, None)]
                for tt, v in ((tx, vx), (ty, vy), (tg, g)))
    if not (on > 0).any():
        return None
    index = np.linspace(0, t.size - 1, min(t.size, MAX_POINTS)).astype(np.int64)
    x, y, lit = x[index], y[index], on[index] > 0
    plot = figure(title=f"XY path ({x_name}, {y_name}); red where {gate} is on", match_aspect=True,
                  width=560, height=460, name=f"xy:{gate}", tools="pan,wheel_zoom,box_zoom,reset,save")
    plot.line(x.astype(np.float64), y.astype(np.float64), color="#a6a6a6", line_width=1, legend_label="path")
    source = ColumnDataSource({"x": np.where(lit, x, np.nan), "y": np.where(lit, y, np.nan)})
    plot.line("x", "y", source=source, color="#d62728", line_width=2.2, legend_label="gate on")
    plot.xaxis.axis_label = x_name
    plot.yaxis.axis_label = y_name
    plot.legend.location = "top_left"
    return plot
