"""The waveform of one run as a Bokeh layout: a timing diagram on one time axis, violations marked.

Rows, top to bottom, all on one linked time range (:data:`TIME_RANGE`, in ticks) over the whole run:

1. ``violations``: one line per check that failed, a marker at each violation (hover: check,
   time, value, limit), present only when a check has a violation;
2. the digital signals, stacked: pulse trains then bits, grouped by device and axis
   (:func:`cosim.report.rows.signal_order`);
3. the analog signals: integers then reals.

Each signal's row is a figure named ``wave:<signal>`` (the dotted trace name), its main glyph
``wave:<signal>:line`` (a value held to the run's end), or ``wave:<signal>:rate`` and
``wave:<signal>:pulses`` for a pulse train: zoomed out a train shows its rate (pulses/s, negative
for direction 0) per segment; when the visible window holds at most :data:`PULSE_CAP` pulses the
browser expands the segments into pulses (each its segment's width high, see
:mod:`cosim.report.pulses_js`). Every violation is a dashed red line on every row.

The view opens on the first violation (a window of a twentieth of the run around it), else on the
whole run.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from cosim.report.pulses_js import SWITCH_JS
from cosim.report.rows import Held, Train, held, signal_order, ticks_of_ns, train
from cosim.trace import Trace

TIME_RANGE = "time"
#: Most pulses drawn one by one in a train's row; more visible pulses are shown as the rate.
PULSE_CAP = 4000
#: Violations of one check drawn (the rest are counted in the page).
MAX_VIOLATIONS = 500
UP, DOWN = "#1f77b4", "#ff7f0e"
VIOLATION = "#d62728"
_HEIGHT = {"bit": 56, "pulse": 80, "int": 100, "real": 110}
_LEFT = 70  # px left of every plot area, so that the rows line up


@dataclass(frozen=True)
class Marked:
    """A violation to mark: the check's name, its time [ticks], what it found, the check's number (1 = first)."""

    check: str
    t: int
    value: str = ""
    limit: str = ""
    detail: str = ""
    number: int = 0


@dataclass
class Waveform:
    """The Bokeh layout of a run with what the page says about it."""

    layout: Any
    signals: list[str]
    start: int
    end: int
    notes: list[str] = field(default_factory=list)
    #: The callback to run when the page is ready (draws the pulses in view), if there are pulse trains.
    on_ready: Any = None


def violations_of(checks: Sequence[Mapping[str, Any]], resolution_s: Fraction) -> tuple[list[Marked], list[str]]:
    """The violations of ``result.json``'s checks as marks (at most :data:`MAX_VIOLATIONS` per check)."""
    marks: list[Marked] = []
    notes = []
    for number, check in enumerate(checks, 1):
        listed = [v for v in check.get("violations", []) if v.get("t_ns") is not None]
        for v in listed[:MAX_VIOLATIONS]:
            marks.append(Marked(str(check["name"]), ticks_of_ns(v["t_ns"], resolution_s), str(v.get("value", "")),
                                str(v.get("limit", "")), str(v.get("detail") or ""), number))
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


def build(trace: Trace, marks: Sequence[Marked], *, pulse_cap: int = PULSE_CAP) -> Waveform:
    """The waveform layout of ``trace`` with ``marks``."""
    from bokeh.layouts import gridplot
    from bokeh.models import ColumnDataSource, CustomJS, Range1d

    end_t = max(trace.end_t, 1)
    start, end = initial_window(end_t, marks)
    x_range = Range1d(start=start, end=end, bounds=(0, end_t), min_interval=10, name=TIME_RANGE)
    ms_per_tick = float(trace.timebase.resolution_s) * 1e3
    marks_source = ColumnDataSource(_marks_data(marks, ms_per_tick), name="violation_marks")
    figures: list[Any] = []
    notes: list[str] = []
    trains: list[dict[str, Any]] = []
    if marks:
        figures.append(_violation_row(marks, marks_source, x_range))
    names = signal_order(trace)
    for name in names:
        info = trace.info[name]
        plot = _row(name, info.kind, f"{name}  ({info.kind}{', ' + info.unit if info.unit else ''})"
                    f"{': ' + info.description if info.description else ''}", x_range)
        if info.kind == "pulse":
            drawn = train(trace, name)
            trains.append(_pulse_row(plot, name, drawn))
            notes += [f"{name}: {n}" for n in drawn.notes]
        else:
            line = held(trace, name)
            _value_row(plot, name, line, kind=info.kind)
            if line.note:
                notes.append(f"{name}: {line.note}")
        plot.vspan(x="t", source=marks_source, line_color=VIOLATION, line_dash="dashed", line_alpha=0.8,
                   name=f"wave:{name}:violations")
        figures.append(plot)
    _axes(figures, ms_per_tick)
    switch = None
    if trains:
        switch = CustomJS(args={"xr": x_range, "trains": trains, "cap": pulse_cap, "up": UP, "down": DOWN},
                          code=SWITCH_JS)
        x_range.js_on_change("start", switch)
        x_range.js_on_change("end", switch)
    layout = gridplot([[f] for f in figures], merge_tools=True, toolbar_location="right",
                      sizing_mode="stretch_width")
    return Waveform(layout, names, start, end, notes, switch if trains else None)


def _marks_data(marks: Sequence[Marked], ms_per_tick: float) -> dict[str, Any]:
    checks = list(dict.fromkeys(m.check for m in marks))
    return {"t": [m.t for m in marks], "t_ms": [m.t * ms_per_tick for m in marks],
            "row": [checks.index(m.check) for m in marks], "check": [m.check for m in marks],
            "value": [m.value for m in marks], "limit": [m.limit for m in marks],
            "detail": [m.detail for m in marks]}


def _row(name: str, kind: str, title: str, x_range: Any) -> Any:
    from bokeh.plotting import figure

    plot: Any = figure(x_range=x_range, height=_HEIGHT[kind], sizing_mode="stretch_width", name=f"wave:{name}",
                  tools="xpan,xwheel_zoom,xbox_zoom,reset,save", min_border_left=_LEFT, min_border_right=10,
                  min_border_top=4, min_border_bottom=4, title=title)
    title_style: Any = plot.title
    title_style.text_font_size = "11px"
    title_style.text_font_style = "normal"
    # the axes and grids by position, not plot.yaxis / plot.xgrid: those search the whole model graph
    plot.left[0].major_label_text_font_size = "10px"
    for grid in plot.center:
        grid.grid_line_alpha = 0.35
    return plot


def _value_row(plot: Any, name: str, line: Held, *, kind: str) -> None:
    from bokeh.models import ColumnDataSource, FixedTicker, Range1d

    source = ColumnDataSource({"t": line.t.astype(np.float64), "v": line.value.astype(np.float64)},
                              name=f"wave:{name}:data")
    colour = "#2a9d3f" if kind == "bit" else "#333333"
    plot.step("t", "v", source=source, mode="after", line_width=1.4, color=colour, name=f"wave:{name}:line")
    finite = line.value[np.isfinite(line.value)]
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    if kind == "bit":
        low, high = min(low, 0.0), max(high, 1.0)
        plot.left[0].ticker = FixedTicker(ticks=[0, 1])
    pad = (high - low) * 0.1 or max(abs(high) * 0.1, 0.5)
    plot.y_range = Range1d(start=low - pad, end=high + pad)


def _pulse_row(plot: Any, name: str, drawn: Train) -> dict[str, Any]:
    from bokeh.models import BasicTicker, ColumnDataSource, HoverTool, Range1d

    rates = ColumnDataSource({"left": drawn.left.astype(np.float64), "right": drawn.right.astype(np.float64),
                              "rate": drawn.rate_hz.astype(np.float64)}, name=f"wave:{name}:rates")
    segments = ColumnDataSource({"t0": drawn.t0.astype(np.float64), "duration": drawn.duration.astype(np.float64),
                                 "count": drawn.count.astype(np.float64), "dir": drawn.direction.astype(np.float64),
                                 "width": np.maximum(drawn.width, 1).astype(np.float64)},
                                name=f"wave:{name}:segments")
    pulses = ColumnDataSource({"left": [], "right": [], "colour": []}, name=f"wave:{name}:pulse_data")
    rate = plot.quad(left="left", right="right", bottom=0, top="rate", source=rates, fill_color=UP,
                     fill_alpha=0.45, line_color=UP, line_width=0.5, name=f"wave:{name}:rate")
    shown = plot.quad(left="left", right="right", bottom=0, top=1, source=pulses, fill_color="colour",
                      line_color="colour", visible=False, name=f"wave:{name}:pulses")
    plot.add_tools(HoverTool(renderers=[rate], tooltips=[("rate [pulses/s]", "@rate{0,0.0}")]))
    low = min(0.0, float(drawn.rate_hz.min())) if drawn.rate_hz.size else 0.0
    high = max(1.0, float(drawn.rate_hz.max())) if drawn.rate_hz.size else 1.0
    pad = (high - low) * 0.08
    plot.y_range = Range1d(start=low - pad, end=high + pad)
    title_style: Any = plot.title
    axis = plot.left[0]
    axis.axis_label = "pulses/s"
    axis.axis_label_text_font_size = "9px"
    axis.ticker = BasicTicker(desired_num_ticks=3)
    if not drawn.pulses:
        title_style.text += "  (no pulses in this run)"
    return {"axis": axis, "segments": segments, "pulses": pulses, "rate_renderer": rate,
            "pulse_renderer": shown,
            "y": plot.y_range, "rate_low": low - pad, "rate_high": high + pad,
            "expandable": drawn.expandable}


def _violation_row(marks: Sequence[Marked], source: Any, x_range: Any) -> Any:
    from bokeh.models import FixedTicker, HoverTool, Range1d

    checks = list(dict.fromkeys(m.check for m in marks))
    numbers = {m.check: m.number for m in marks}
    plot = _row("violations", "int", "check violations (numbered as in the table of checks; hover for value and limit)",
                x_range)
    plot.name = "violations"
    plot.height = 40 + 22 * len(checks)
    plot.y_range = Range1d(start=len(checks) - 0.5, end=-0.5)
    axis = plot.left[0]
    axis.ticker = FixedTicker(ticks=list(range(len(checks))))
    axis.major_label_overrides = {k: f"check {numbers[c]}" if numbers[c] else _short(c) for k, c in enumerate(checks)}
    markers = plot.scatter("t", "row", source=source, marker="inverted_triangle", size=11, color=VIOLATION,
                           name="violations:markers")
    first = {m.check: m for m in sorted(marks, key=lambda m: m.t, reverse=True)}  # each check's first
    plot.text(x=[m.t for m in first.values()], y=[checks.index(c) for c in first],
              text=list(first),
              x_offset=8, y_offset=6, text_font_size="10px", text_color=VIOLATION, name="violations:labels")
    plot.add_tools(HoverTool(renderers=[markers], tooltips=[("check", "@check"), ("t [ms]", "@t_ms{0.000000}"),
                                                             ("value", "@value"), ("limit", "@limit"),
                                                             ("detail", "@detail")]))
    return plot


def _short(text: str, size: int = 16) -> str:
    return text if len(text) <= size else text[:size - 1] + "…"


def _axes(figures: list[Any], ms_per_tick: float) -> None:
    """One time axis in ms above the first row and below the last; none between."""
    from bokeh.models import CustomJSTickFormatter, LinearAxis

    formatter = CustomJSTickFormatter(args={"scale": ms_per_tick},
                                      code="return Number((tick * scale).toPrecision(12)).toString();")
    for k, plot in enumerate(figures):
        axis = plot.below[0]
        axis.formatter = formatter
        axis.visible = k == len(figures) - 1
        if k == len(figures) - 1:
            axis.axis_label = "t [ms]"
            plot.height += 40
    if figures:
        top: Any = LinearAxis(axis_label="t [ms]")
        top.formatter = formatter
        figures[0].add_layout(top, "above")
        figures[0].height += 40
