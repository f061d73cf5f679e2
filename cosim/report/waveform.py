"""The waveform of one run: one Bokeh figure for every row, and the data it draws.

The rows (:mod:`cosim.report.rows`) are bands of one figure on one time axis (x in ticks, y in
pixels from the top), drawn by the page's script (``waveform.js``) from the data this module
prepares once, in ``<script id="cosim-wave">`` (JSON; arrays as float64 in base64):

1. ``violations``, when a check has any: a marker per violation on its check's line (hover: check,
   time, value and limit with their units) and a dashed red line through every row;
2. the signals a check names (shaded), then the others per device and axis
   (:func:`cosim.report.rows.reader_order`);
3. one line for the quiet signals (no activity in the whole run), with their values.

The Bokeh document holds only the figure, its (empty) sources and the callbacks, whatever the
length of the run, so that writing it costs little; the page fills the sources for the visible
window. The view opens on the first violation (a twentieth of the run around it), else on the
whole run, unless the URL says otherwise (``#t=<from ms>,<to ms>&rows=<name>,...``).
"""

from __future__ import annotations

import base64
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from cosim.report import levels as side_levels
from cosim.report.levels import SideFiles, b64
from cosim.report.rows import BUCKETS, Row, named_signals, reader_order, records, ticks_of_ns, train_row, value_row
from cosim.report.text import humanize_ns, value_text
from cosim.trace import Trace

TIME_RANGE = "time"
#: Most pulses drawn one by one in a train's row; more visible pulses are shown as the rate.
PULSE_CAP = 4000
#: Violations of one check marked (the rest are counted in the page).
MAX_VIOLATIONS = 500
UP, DOWN = "#1f77b4", "#ff7f0e"
VIOLATION = "#d62728"
JS = (Path(__file__).with_name("waveform.js")).read_text(encoding="utf-8")


@dataclass(frozen=True)
class Marked:
    """A violation to mark: the check's name, its time [ticks], what it found (in words), the check's number."""

    check: str
    t: int
    value: str = ""
    limit: str = ""
    detail: str = ""
    number: int = 0


@dataclass
class Waveform:
    """The data of a run's waveform and what the page says about it."""

    data: str
    rows: list[Row]
    start: int
    end: int
    notes: list[str] = field(default_factory=list)
    side_files: int = 0


def violation_unit(check: Mapping[str, Any], violation: Mapping[str, Any], units: Mapping[str, str]) -> str:
    """The unit of a violation's value and limit: its own ``unit`` (or the check's ``unit``), else the
    unit of the check's signal when the detail reads the signal's value (``<signal> = ...``), else
    ``ns`` when the value is a time the detail or the check's figures give in ns, else the signal's unit
    when the detail gives the value in it."""
    for source in (violation, check):
        if source.get("unit") is not None and "unit" in source:
            return str(source["unit"])
    signal = str(check.get("signal") or "")
    detail = str(violation.get("detail") or "")
    value = violation.get("value")
    if signal and re.search(rf"(?:^|\bof ){re.escape(signal)}(?: =| is) ", detail):  # the signal's own value
        return units.get(signal, "")
    if isinstance(value, int | float) and not isinstance(value, bool):
        measured = check.get("measured") or {}
        if any(k.endswith("_ns") and v == value for k, v in measured.items()) or \
                f"{value:g} ns" in detail or f"{value} ns" in detail:
            return "ns"
        if any(k.endswith("_hz") and v == value for k, v in measured.items()):
            return "Hz"
        unit = units.get(signal, "")
        if unit and (f"{value:g} {unit}" in detail or f"{value} {unit}" in detail):  # "position 27.4 units"
            return unit
    return ""


def violation_text(check: Mapping[str, Any], violation: Mapping[str, Any], units: Mapping[str, str],
                   states: Mapping[int, str] | None = None) -> tuple[str, str]:
    """A violation's value and limit in words, with their unit (a state by its name).

    Examples
    --------
    >>> check = {"signal": "pmac.ect.time_zero_pos"}
    >>> violation_text(check, {"value": 500, "limit": "1500 ± 0.5",
    ...                        "detail": "value of pmac.ect.time_zero_pos is 500, expected 1500 ± 0.5"},
    ...                {"pmac.ect.time_zero_pos": "counts"})
    ('500 counts', '1500 ± 0.5 counts')
    """
    unit = violation_unit(check, violation, units)
    named = states if unit == units.get(str(check.get("signal") or ""), "") else None
    value, limit = violation.get("value", ""), violation.get("limit", "")
    limit_text = value_text(limit, unit, named)
    if isinstance(limit, str) and unit and unit != "ns" and re.search(r"\d$", limit.strip()):
        limit_text = f"{limit} {unit}"  # a rule written as text that ends in a number of the signal's unit
    return value_text(value, unit, named), limit_text


def violations_of(checks: Sequence[Mapping[str, Any]], resolution_s: Fraction,
                  units: Mapping[str, str] | None = None,
                  states: Mapping[str, Mapping[int, str]] | None = None) -> tuple[list[Marked], list[str]]:
    """The violations of ``result.json``'s checks as marks (at most :data:`MAX_VIOLATIONS` per check)."""
    marks: list[Marked] = []
    notes = []
    units = units or {}
    for number, check in enumerate(checks, 1):
        listed = [v for v in check.get("violations", []) if v.get("t_ns") is not None]
        named = (states or {}).get(str(check.get("signal") or ""))
        for v in listed[:MAX_VIOLATIONS]:
            value, limit = violation_text(check, v, units, named)
            marks.append(Marked(str(check["name"]), ticks_of_ns(v["t_ns"], resolution_s), value, limit,
                                humanize_ns(str(v.get("detail") or "")), number))
        total = int(check.get("n_violations", len(listed)))
        if total > min(len(listed), MAX_VIOLATIONS):
            notes.append(f"check {check['name']!r}: {min(len(listed), MAX_VIOLATIONS):,} of its {total:,} "
                         "violations are marked (result.json lists those it kept)")
    return marks, notes


def initial_window(end_t: int, marks: Sequence[Marked]) -> tuple[int, int]:
    """The time window the view opens on: around the first violation, else the whole run [ticks]."""
    end_t = max(end_t, 1)
    if not marks:
        return 0, end_t
    first = min(m.t for m in marks)
    half = max(end_t // 40, 1)
    start = min(max(first - half, 0), max(end_t - 2 * half, 0))
    return start, min(start + 2 * half, end_t)


def rows_of(trace: Trace, checks: Sequence[Mapping[str, Any]], *, folder: Path | None = None) -> tuple[list[Row], int]:
    """Every row of ``trace`` in reader order, its data prepared; long rows' finer levels written into
    ``folder/waveform/`` (none without a folder). Returns the rows and the number of side files."""
    named = named_signals(checks, list(trace.info))
    side = SideFiles(folder) if folder is not None else None
    rows = []
    for index, name in enumerate(reader_order(trace, named)):
        if trace.info[name].kind == "pulse":
            row = train_row(trace, name)
            if not row.exact and side is not None:
                side_levels.train_levels(row, trace, side=side, index=index)
        else:
            t, v = records(trace, name)
            row = value_row(trace, name, t=t, v=v)
            if not row.exact and side is not None:
                side_levels.value_levels(row, t, v, end_t=trace.end_t, side=side, index=index)
        row.checked = name in named
        if row.kind == "pulse" and row.rate_hz.size:
            order = row.left.argsort(kind="stable")
            row.left, row.right, row.rate_hz = row.left[order], row.right[order], row.rate_hz[order]
            row.low, row.high = min(0.0, float(row.rate_hz.min())), max(0.0, float(row.rate_hz.max()))
        rows.append(row)
    return rows, side.count if side is not None else 0


def _row_data(row: Row) -> dict[str, Any]:
    data: dict[str, Any] = {"name": row.name, "kind": row.kind, "unit": row.unit, "desc": humanize_ns(row.description),
                            "states": {str(k): v for k, v in row.states.items()} or None,
                            "low": _finite(row.low), "high": _finite(row.high, 1.0), "checked": row.checked,
                            "quiet": row.quiet, "constant": row.kind != "pulse" and row.distinct <= 1,
                            "value": row.value if math.isfinite(row.value) else None,
                            "first": max(row.first_t, 0), "pulses": row.pulses, "detail": row.detail}
    if row.kind == "pulse":
        data["unit"] = "pulses/s"
        data.update(left=b64(row.left), right=b64(row.right), rate=b64(row.rate_hz))
        if row.segments:
            data["seg"] = {k: _compact(a) for k, a in row.segments.items()}
    else:
        data.update(t=b64(row.t), v=_compact(row.v))
    return data


#: Height of a row's band [px] by kind (an int with named states, a constant or quiet row: less).
BAND_PX = {"bit": 26, "pulse": 42, "int": 40, "real": 54, "states": 30, "constant": 22}
QUIET_PX = 22
#: The figure's height above and below its bands (toolbar, time axes) [px].
MARGIN_PX = 70


def _band_px(row: Row) -> int:
    if row.quiet or (row.kind != "pulse" and row.distinct <= 1):
        return BAND_PX["constant"]
    return BAND_PX["states"] if row.kind == "int" and row.states else BAND_PX[row.kind]


def _compact(values: Any) -> str | dict[str, str]:
    """An array for the page: int32 in base64 (``{"i4": ...}``) when its values are such integers, else
    float64 in base64 (a string)."""
    a = np.asarray(values)
    if a.size and (a.dtype.kind in "iu" or (np.isfinite(a).all() and (a == np.round(a)).all())) and \
            np.abs(a).max() < 2**31:
        return {"i4": base64.b64encode(a.astype("<i4").tobytes()).decode("ascii")}
    return b64(a)


def _finite(value: float, default: float = 0.0) -> float:
    return value if math.isfinite(value) else default


def build(trace: Trace, checks: Sequence[Mapping[str, Any]], *, name: str = "run", folder: Path | None = None,
          pulse_cap: int = PULSE_CAP) -> Waveform:
    """The waveform of ``trace`` with the violations of ``checks`` (``result.json``'s)."""
    rows, n_side = rows_of(trace, checks, folder=folder)
    units = {r.name: r.unit for r in rows}
    states = {r.name: r.states for r in rows if r.states}
    marks, notes = violations_of(checks, trace.timebase.resolution_s, units, states)
    end_t = max(trace.end_t, 1)
    start, end = initial_window(end_t, marks)
    ns_per_tick = float(trace.timebase.resolution_s * 10**9)
    numbered = {}
    for number, c in enumerate(checks, 1):
        listed = [ticks_of_ns(v["t_ns"], trace.timebase.resolution_s) for v in c.get("violations", [])
                  if v.get("t_ns") is not None]
        rows_read = named_signals([c], list(trace.info))
        numbered[number] = {"number": number, "name": str(c.get("name")), "rows": rows_read,
                            "first": min(listed) if listed else None,
                            "marks": sum(m.number == number for m in marks)}
    shown = [r for r in rows if not r.quiet or r.checked]
    height = ((14 + 16 * sum(1 for c in numbered.values() if c["marks"])) if marks else 0) + sum(
        _band_px(r) for r in shown) + (QUIET_PX if len(shown) < len(rows) else 0)
    data = {"end": end_t, "buckets": BUCKETS, "height": height, "margin": MARGIN_PX, "bandPx": BAND_PX,
            "quietPx": QUIET_PX, "nsPerTick": ns_per_tick, "start": start, "stop": end, "cap": pulse_cap,
            "up": UP, "down": DOWN,
            "rows": [_row_data(r) for r in rows],
            "defaultRows": [r.name for r in rows if not r.quiet or r.checked],
            "quiet": [r.name for r in rows if r.quiet and not r.checked],
            "marks": [{"t": m.t, "check": m.number, "name": m.check, "value": m.value, "limit": m.limit,
                       "detail": m.detail} for m in sorted(marks, key=lambda m: (m.t, m.number))],
            "checks": list(numbered.values())}
    for r in rows:
        notes += [f"{r.name}: {n}" for n in r.notes]

    text = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return Waveform(text, rows, start, end, notes, n_side)


@cache
def figure_html() -> tuple[str, str]:
    """The waveform's Bokeh figure as ``(script, div)`` (``bokeh.embed.components``): the same for every
    page, made once per process; the page's script fills it from the page's data when it is ready."""
    from bokeh.document import Document
    from bokeh.embed import components
    from bokeh.models import (
        ColumnDataSource,
        CustomJS,
        CustomJSTickFormatter,
        FixedTicker,
        HoverTool,
        LinearAxis,
        Range1d,
    )
    from bokeh.plotting import figure

    x_range = Range1d(start=0, end=1, bounds=(0, 1), min_interval=10, name=TIME_RANGE)
    y_range = Range1d(start=100, end=0, name="lanes")
    plot: Any = figure(x_range=x_range, y_range=y_range, sizing_mode="stretch_both", name="waveform",
                       tools="xpan,xwheel_zoom,xbox_zoom,reset,save", toolbar_location="above",
                       min_border_left=10, min_border_right=16, output_backend="canvas")
    plot.xgrid.grid_line_alpha = 0.3
    plot.ygrid.visible = False
    bands = ColumnDataSource({"y0": [], "y1": [], "color": []}, name="bands")
    quads = ColumnDataSource({"left": [], "right": [], "bottom": [], "top": [], "color": [], "alpha": []},
                             name="quads")
    lines = ColumnDataSource({"xs": [], "ys": [], "color": []}, name="lines")
    texts = ColumnDataSource({"x": [], "y": [], "text": [], "color": []}, name="texts")
    spans = ColumnDataSource({"t": []}, name="violation_marks")
    points = ColumnDataSource({"t": [], "y": [], "check": [], "when": [], "value": [], "limit": [], "detail": []},
                              name="violation_points")
    plot.hstrip(y0="y0", y1="y1", source=bands, fill_color="color", line_color=None, level="underlay")
    plot.quad(left="left", right="right", bottom="bottom", top="top", source=quads, fill_color="color",
              fill_alpha="alpha", line_color="color", line_alpha="alpha", line_width=0.5, name="wave:blocks")
    plot.multi_line(xs="xs", ys="ys", source=lines, line_color="color", line_width=1.4, name="wave:lines")
    plot.text(x="x", y="y", text="text", source=texts, text_color="color", text_font_size="10px",
              text_baseline="middle", background_fill_color="white", background_fill_alpha=0.75,
              name="wave:labels")
    plot.vspan(x="t", source=spans, line_color=VIOLATION, line_dash="dashed", line_alpha=0.8,
               name="wave:violations")
    markers = plot.scatter("t", "y", source=points, marker="inverted_triangle", size=11, color=VIOLATION,
                           name="violations:markers")
    plot.add_tools(HoverTool(renderers=[markers], tooltips=[("check", "@check"), ("t", "@when"),
                                                             ("value", "@value"), ("limit", "@limit"),
                                                             ("detail", "@detail")]))
    ticker = FixedTicker(ticks=[], name="lane_ticks")
    yaxis = plot.left[0]
    yaxis.ticker = ticker
    yaxis.major_label_text_font_size = "11px"
    yaxis.major_tick_line_color = None
    yaxis.formatter = CustomJSTickFormatter(code="return cosimWave.laneName(tick);")
    formatter = CustomJSTickFormatter(args={"xr": x_range}, code="return cosimWave.timeText(tick, xr.end - xr.start);")
    plot.below[0].formatter = formatter
    top: Any = LinearAxis()
    top.formatter = formatter
    plot.add_layout(top, "above")
    models = {"fig": plot, "xr": x_range, "yr": y_range, "ticker": ticker, "bands": bands, "quads": quads,
              "lines": lines, "texts": texts, "spans": spans, "markPoints": points}
    changed = CustomJS(code="cosimWave.changed();")
    x_range.js_on_change("start", changed)
    x_range.js_on_change("end", changed)
    plot.js_on_event("mousemove", CustomJS(code="cosimWave.hover(cb_obj.x, cb_obj.y);"))
    document = Document()
    document.add_root(plot)
    document.js_on_event("document_ready", CustomJS(args=models, code="cosimWave.init({fig, xr, yr, ticker, bands, "
                                                                      "quads, lines, texts, spans, markPoints});"))
    script, div = components(plot)
    return script, div
