"""The picture of a sweep: each figure against each swept parameter, runs coloured by verdict.

:func:`write_report` writes one standalone HTML file (Bokeh, its JavaScript inlined, so it opens
offline and can be mailed): a header with the verdict counts, the legend of the short column names
and the reasons of the first runs that did not pass, then a grid of scatter plots, one row per
figure (``fig.*`` columns; the number of failed checks when the scenario declares no figure), one
column per swept parameter, one colour per verdict (:data:`VERDICT_COLOURS`: PASS green, FAIL red,
HAZARD SHOWN orange, HAZARD MISSED purple, UNCHECKED grey-blue, ...); ERROR runs have no figures and
are counted in the header. Hovering a point shows the run's index, verdict and parameter values.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

VERDICT_COLOURS = {"PASS": "#2a9d3f", "FAIL": "#d62728", "ERROR": "#7f7f7f", "HAZARD SHOWN": "#ff7f0e",
                   "HAZARD MISSED": "#9467bd", "UNCHECKED": "#6b8fb3", "TERMINATED": "#8c564b",
                   "INTERRUPTED": "#bcbd22"}
#: Verdicts of runs that came out as the scenario declares (the others are listed with their reasons).
EXPECTED = ("PASS", "HAZARD SHOWN")


def write_report(table: Any, path: Path, *, scenario: str) -> Path:
    """Write the sweep report of ``table`` (from :func:`cosim.sweep.sweep`) to ``path``; returns ``path``.

    Parameters
    ----------
    table : pandas.DataFrame
        The sweep table with its ``attrs`` (``swept``, ``legend``, ``units``).
    path : path
        The HTML file to write.
    scenario : str
        Scenario name, for the title.
    """
    from bokeh.embed import file_html
    from bokeh.layouts import column, gridplot
    from bokeh.models.widgets.markups import Div
    from bokeh.resources import INLINE

    from cosim.report.ids import stable_ids

    swept = [p for p in table.attrs.get("swept", []) if f"p.{p}" in table.columns]
    figures = [c for c in table.columns if c.startswith("fig.")] or (
        ["checks_failed"] if "checks_failed" in table.columns else [])
    units = table.attrs.get("units", {})
    plots = [_scatter(table, x, y, unit=units.get(y.removeprefix("fig."), ""))
             for y in figures for x in (swept or [None])]
    header = Div(text=_header(table, scenario=scenario, swept=swept), sizing_mode="stretch_width")
    parts: list[Any] = [header]
    if plots:
        parts.append(gridplot(plots, ncols=max(1, len(swept)), width=380, height=300, toolbar_location="right"))
    else:
        parts.append(Div(text="<p>No run produced a figure to plot.</p>"))
    text = file_html(column(*parts), resources=INLINE, title=f"sweep {scenario}")
    path.write_text(stable_ids([text], f"sweep/{scenario}")[0], encoding="utf-8")
    return path


def _scatter(table: Any, parameter: str | None, y: str, *, unit: str) -> Any:
    """One plot: ``y`` against ``p.<parameter>`` (or the run index), one glyph set per verdict."""
    from bokeh.models import ColumnDataSource, HoverTool
    from bokeh.plotting import figure

    x_column = f"p.{parameter}" if parameter else "index"
    values = table[x_column]
    categorical = values.dtype == object or values.dtype == bool
    x_label = parameter or "run"
    kwargs: dict[str, Any] = {"x_range": sorted({str(v) for v in values})} if categorical else {}
    plot = figure(title=f"{y.removeprefix('fig.')} vs {x_label}", x_axis_label=x_label,
                  y_axis_label=f"{y.removeprefix('fig.')}" + (f" [{unit}]" if unit else ""),
                  tools="pan,box_zoom,wheel_zoom,reset,save", **kwargs)
    for verdict, colour in VERDICT_COLOURS.items():
        rows = table[(table["verdict"] == verdict) & table[y].notna()]
        if not len(rows):
            continue
        source = ColumnDataSource({
            "x": [str(v) for v in rows[x_column]] if categorical else rows[x_column].astype(float).tolist(),
            "y": rows[y].astype(float).tolist(),
            "run": rows["index"].astype(int).tolist(),
            "verdict": [verdict] * len(rows),
            "failed": rows["failed"].astype(str).tolist() if "failed" in rows else [""] * len(rows),
        })
        plot.scatter("x", "y", source=source, size=8, color=colour, alpha=0.8, legend_label=verdict)
    plot.add_tools(HoverTool(tooltips=[("run", "@run"), ("verdict", "@verdict"), ("failed checks", "@failed"),
                                       (x_label, "@x"), (y, "@y")]))
    if plot.legend:
        plot.legend.location = "top_left"
        plot.legend.click_policy = "hide"
    return plot


def _header(table: Any, *, scenario: str, swept: list[str]) -> str:
    counts = ", ".join(f'<span style="color:{VERDICT_COLOURS.get(v, "black")}">{n} {v}</span>'
                       for v, n in verdict_counts(table).items())
    legend = table.attrs.get("legend", {})
    items = "".join(f"<li><code>{html.escape(k)}</code>: {html.escape(v)}</li>" for k, v in legend.items())
    why = "".join(f"<li><code>{html.escape(line)}</code></li>" for line in reasons(table, limit=20))
    errors = int((table["verdict"] == "ERROR").sum()) if len(table) else 0
    return (f"<h1>Sweep of {html.escape(scenario)}</h1>"
            f"<p>{len(table)} runs: {counts or 'none'}. Swept: "
            f"{', '.join(f'<code>{html.escape(p)}</code>' for p in swept) or 'nothing (repeated runs)'}."
            + (f" {errors} ERROR run(s) produced no figures and are not plotted." if errors else "") + "</p>"
            + (f"<p>Check columns:</p><ul>{items}</ul>" if items else "")
            + (f"<p>Runs that did not pass:</p><ul>{why}</ul>" if why else ""))


def verdict_counts(table: Any) -> dict[str, int]:
    """Runs per verdict, e.g. ``{"FAIL": 1, "PASS": 5}``."""
    return {str(k): int(v) for k, v in sorted(table["verdict"].value_counts().items())} if len(table) else {}


def reasons(table: Any, *, limit: int = 5) -> list[str]:
    """Why runs did not come out as declared (not PASS or HAZARD SHOWN): one line for each of the first ``limit``
    such runs, then a count of the rest."""
    legend = table.attrs.get("legend", {})
    swept = table.attrs.get("swept", [])
    bad = table[~table["verdict"].isin(EXPECTED)] if len(table) else table
    lines = []
    for _, row in bad.head(limit).iterrows():
        values = ", ".join(f"{p}={row[f'p.{p}']}" for p in swept if f"p.{p}" in row)
        if row["verdict"] == "ERROR":
            why = str(row["error"]).splitlines()[0] if row["error"] else "no error message"
        else:
            why = "; ".join(f"{key} {legend.get(key, '')} ({_why(row, key)})"
                            for key in str(row["failed"]).split(", ") if key) or _nothing(row["verdict"])
        lines.append(f"run {int(row['index'])} ({values}): {row['verdict']}  {why}")
    if len(bad) > limit:
        lines.append(f"... and {len(bad) - limit} more (column 'verdict', 'error' and 'failed' of the table)")
    return lines


def _why(row: Any, key: str) -> str:
    """What came of one check of a run: its violations, or its verdict when it examined nothing or was missed."""
    verdict = row.get(f"{key}.verdict", "FAIL")
    if verdict == "FAIL":
        return _violations(row[f"{key}.n_violations"])
    return f"{verdict}: {_violations(row[f'{key}.n_violations'])}"


def _nothing(verdict: str) -> str:
    """The reason of a run without a failed check."""
    if verdict == "UNCHECKED":
        return "no check examined anything"
    return "a plant ended the run early" if verdict == "TERMINATED" else "a check failed"


def _violations(count: Any) -> str:
    n = int(count)
    return f"{n} violation{'s' if n != 1 else ''}"
