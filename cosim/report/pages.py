"""The HTML of the report's pages: the summary (``report.html``) and one page per run.

Plain HTML and CSS around the Bokeh waveform; every link is relative, so the folder opens from
disk and can be moved or zipped. The Bokeh library is loaded from ``report_files/`` next to
``report.html`` (one copy for every page), or inlined in each page.
"""

from __future__ import annotations

import html
import json
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim.report.text import humanize_ns, number_text, rst_html, rst_inline, time_text, value_text
from cosim.report.verdicts import VERDICTS, badge, meaning
from cosim.report.waveform import MARGIN_PX, violation_text

#: Files of a results folder the page describes, in this order (other files are listed after them).
FILES = {
    "result.json": "verdict, parameters, checks with their violations, figures, notes",
    "trace.vcd": "every signal, for GTKWave and other waveform viewers",
    "trace.gtkw": "GTKWave view of trace.vcd (gtkwave trace.gtkw)",
    "trace_digital.vcd": "bits and pulse trains only, for sigrok-cli and PulseView",
    "console.txt": "the run's console: time, source and text of each line",
    "trace.vcd.gz": "every signal, compressed (GTKWave opens it as it is; gunzip for other viewers)",
    "trace_digital.vcd.gz": "bits and pulse trains only, compressed (gunzip for sigrok-cli and PulseView)",
    "trace_meta.json": "resolution, end of the run, each signal's kind, unit and description",
    "edges.parquet": "table: changes of bit and int signals",
    "values.parquet": "table: changes and samples of real signals",
    "segments.parquet": "table: pulse-train segments (t0, duration, count, dir)",
    "pulses.parquet": "table: pulses recorded one by one",
    "trace_wide.csv": "one column per signal, time in seconds, for spreadsheets",
}
PAGE = "index.html"

STYLE = """
body{font-family:system-ui,sans-serif;margin:1.5em 2em;color:#222}
main{max-width:78em}table{border-collapse:collapse;font-size:90%;margin:0.5em 0}
td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}th{background:#f3f3f3}
.verdict{color:#fff;padding:1px 7px;border-radius:4px;font-weight:bold;font-size:90%;white-space:nowrap}
.ok{color:#2a9d3f;font-weight:bold}.bad{color:#d62728;font-weight:bold}
pre.doc{background:#f7f7f7;padding:0.6em;overflow-x:auto;font-size:85%}
.note{color:#555;font-size:90%}button{margin-right:0.5em}
td.num{text-align:right;font-variant-numeric:tabular-nums}
p.lead{font-size:110%}details.doc{margin:0.5em 0}details.doc h3{font-size:100%}
code{font-size:92%;background:#f3f3f3;padding:0 2px}tr.checked td{background:#fff6e0}
pre.line{margin:0;white-space:pre-wrap;font-size:92%}
.readout{font:12px ui-monospace,monospace;background:#f7f7f7;border:1px solid #ddd;padding:3px 6px;
  position:sticky;top:0;z-index:5;min-height:1.3em}
p.tools button{margin:0 0.4em 0.3em 0}#cosim-violation{margin-left:0.6em;color:#b01c1c}
"""


@dataclass(frozen=True)
class Entry:
    """One run of the report.

    Parameters
    ----------
    name : str
        Scenario or machine name.
    folder : path
        Its results folder (``result.json``, the trace, the exports); the page is written there.
    result : dict
        The content of ``result.json``.
    description : str
        What the scenario is (its docstring, or the machine file's description); the first line is
        the summary's.
    """

    name: str
    folder: Path
    result: Mapping[str, Any]
    description: str = ""


def head(title: str, scripts: str = "") -> str:
    return (f"<!doctype html><html lang='en'><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            f"<style>{STYLE}</style>{scripts}</head><body><main>")


def summary(entries: Sequence[Entry], out: Path) -> str:
    """The summary page: totals, the verdict legend, one row per run with a link to its page."""
    counts: dict[str, int] = {}
    for e in entries:
        counts[str(e.result.get("verdict"))] = counts.get(str(e.result.get("verdict")), 0) + 1
    total = ", ".join(f"{n} {badge(v)}" for v, n in counts.items())
    rows = []
    for e in entries:
        r = e.result
        s = r.get("summary", {})
        link = html.escape(os.path.relpath(e.folder / PAGE, out).replace(os.sep, "/"))
        first = e.description.strip().splitlines()[0] if e.description.strip() else ""
        rows.append(f"<tr><td><a href='{link}'>{html.escape(e.name)}</a></td><td>{badge(str(r.get('verdict')))}</td>"
                    f"<td class='num'>{s.get('passed', 0)}</td><td class='num'>{s.get('failed', 0)}</td>"
                    f"<td class='num'>{s.get('unchecked', 0)}</td>"
                    f"<td class='num'>{_hazards(s)}</td>"
                    f"<td>{rst_inline(first)}</td><td class='num'>{float(r.get('simulated_s', 0)):g}</td>"
                    f"<td class='num'>{float(r.get('wall_time_s', 0)):.2f}</td></tr>")
    legend = "".join(f"<li>{badge(v)} {html.escape(m)}</li>" for v, (_, m) in VERDICTS.items())
    return (head("cosim report") + f"<h1>cosim report</h1><p>{len(entries)} runs: {total or 'none'}.</p>"
            "<table id='runs'><tr><th>scenario</th><th>verdict</th><th>checks passed</th><th>checks failed</th>"
            "<th>checks that examined nothing</th><th>hazards shown</th>"
            "<th>description</th><th>simulated [s]</th><th>wall [s]</th></tr>" + "".join(rows) + "</table>"
            f"<h2>Verdicts</h2><ul>{legend}</ul>"
            "<p class='note'>Each run's page has its description, parameters, checks with their violations, "
            "figures, the waveform of every signal and links to its trace files.</p></main></body></html>")


def _hazards(summary: Mapping[str, Any]) -> str:
    """``shown/declared`` hazards of a run, empty when it declares none."""
    declared = int(summary.get("hazards", 0) or 0)
    return f"{int(summary.get('hazards_shown', 0) or 0)}/{declared}" if declared else ""


def page(entry: Entry, *, out: Path, scripts: str, plot_script: str, plot_divs: Sequence[str], notes: Sequence[str],
         wave_data: str | None, rows: Sequence[Any] = ()) -> str:
    """One run's page (``plot_script``/``plot_divs``: the Bokeh waveform and XY paths from ``bokeh.embed.components``;
    ``wave_data``: the waveform's data, None when the run wrote no trace)."""
    r = entry.result
    units = {row.name: row.unit for row in rows}
    verdict = str(r.get("verdict"))
    back = html.escape(os.path.relpath(out / "report.html", entry.folder).replace(os.sep, "/"))
    text = entry.description.strip()
    first, _, rest = text.partition("\n")
    parts = [head(f"{entry.name}: {verdict}", scripts),
             f"<nav><a href='{back}'>all runs</a> · <a href='#checks'>checks</a> · <a href='#waveform'>waveform</a>"
             " · <a href='#console'>console</a> · <a href='#run'>run</a> · <a href='#files'>files</a></nav>",
             f"<h1>{html.escape(entry.name)} {badge(verdict)}</h1><p><b>{html.escape(verdict)}</b>: "
             f"{html.escape(meaning(verdict))}</p>"]
    if first:
        parts.append(f"<p class='lead'>{rst_inline(first)}</p>")
    if rest.strip():
        parts.append(f"<details class='doc'><summary>whole description</summary>{rst_html(rest.strip())}</details>")
    states = {row.name: row.states for row in rows if row.states}
    parts += [_problems(r), _checks(r, wave_data is not None, units, states), _figures(r)]
    parts.append("<h2 id='waveform'>Waveform</h2>")
    if wave_data is None:
        parts.append("<p>No trace was written for this run.</p>")
    else:
        marked = _marked(r)
        parts.append("<p class='tools'><button onclick='cosimWave.whole()'>whole run</button>"
                     + ("<button onclick='cosimWave.violation(\"first\")'>first violation</button>"
                        "<button onclick='cosimWave.violation(\"previous\")'>previous violation</button>"
                        "<button onclick='cosimWave.violation(\"next\")'>next violation</button>" if marked else "")
                     + "<button onclick='cosimWave.setRows(null)'>all rows</button>"
                     "<span id='cosim-violation' class='note'></span></p>"
                     "<p class='note'>Drag to pan, box or wheel to zoom (toolbar); the view is in the address "
                     "(copy it to share). Shaded rows: signals a check reads. Pulse trains show their pulses when "
                     "few enough are in view, else their rate (pulses/s; blue forwards, orange backwards). Dashed "
                     "red lines: check violations.</p>"
                     "<div id='cosim-readout' class='readout'>point at a row to read its value</div>")
        parts.append(f"<script type='application/json' id='cosim-wave'>{wave_data}</script>")
        height = json.loads(wave_data)["height"] + MARGIN_PX if wave_data else 400
        parts.append(f"<div id='cosim-plot' style='height:{height}px'>{plot_divs[0] if plot_divs else ''}</div>")
        if notes:
            parts.append("<p class='note'>Held in the page in reduced form:</p><ul class='note'>"
                         + "".join(f"<li>{html.escape(n)}</li>" for n in notes) + "</ul>")
        parts.append(_rows_table(rows))
        if len(plot_divs) > 1:
            parts.append("<h3>XY paths</h3>" + "".join(plot_divs[1:]))
    parts += [_console(entry.folder), _not_modelled(r), _notes(r), _run_facts(r), _files(entry.folder)]
    parts += [plot_script, "</main></body></html>"]
    return "".join(parts)


def _marked(r: Mapping[str, Any]) -> bool:
    return any(v.get("t_ns") is not None for c in r.get("checks", []) for v in c.get("violations", []))


def _rows_table(rows: Sequence[Any]) -> str:
    """Every signal of the run with its kind, unit and description; a box to show or hide its row."""
    if not rows:
        return ""
    lines = []
    for row in rows:
        what = ("no pulses in the whole run" if row.kind == "pulse" else
                "never recorded" if row.records == 0 else "holds " + value_text(row.value, row.unit, row.states)
                ) if row.quiet else (f"{row.pulses:,} pulses" if row.kind == "pulse" else f"{row.records:,} records")
        states = ", ".join(f"{k} {v}" for k, v in row.states.items())
        lines.append(f"<tr{' class=checked' if row.checked else ''}><td><input type='checkbox' class='cosim-row' "
                     f"value='{html.escape(row.name)}' onchange='cosimWave.toggle(this)'></td>"
                     f"<td><code>{html.escape(row.name)}</code></td><td>{row.kind}</td><td>{html.escape(row.unit)}</td>"
                     f"<td>{html.escape(what)}</td><td>{rst_inline(humanize_ns(row.description))}"
                     f"{'<br><span class=note>states: ' + html.escape(states) + '</span>' if states else ''}</td></tr>")
    quiet = sum(1 for r in rows if r.quiet and not r.checked)
    return (f"<details id='rows'><summary>rows: {len(rows)} signals ({quiet} quiet, folded into one line); "
            "tick to show or hide</summary><table><tr><th></th><th>signal</th><th>kind</th><th>unit</th>"
            "<th>in this run</th><th>description</th></tr>" + "".join(lines) + "</table></details>")


def _problems(r: Mapping[str, Any]) -> str:
    blocks = []
    if r.get("error"):
        blocks.append(f"<h2>Error</h2><pre class='doc'>{html.escape(str(r['error']))}</pre>")
    if r.get("terminated"):
        term = r["terminated"]
        log = "\n".join(term.get("log", [])[-10:])
        blocks.append(f"<h2>Terminated</h2><p>by {html.escape(str(term.get('plant')))} at "
                      f"{html.escape(_seconds(term.get('t_s')))}: {html.escape(str(term.get('reason')))}</p>"
                      + (f"<pre class='doc'>{html.escape(log)}</pre>" if log else ""))
    if r.get("interrupted"):
        stop = r["interrupted"]
        blocks.append(f"<h2>Interrupted</h2><p>{html.escape(str(stop.get('signal')))} at "
                      f"{html.escape(_seconds(stop.get('t_s')))}</p>")
    return "".join(blocks)


def _seconds(t_s: Any) -> str:
    return time_text(float(t_s) * 1e9) if isinstance(t_s, int | float) else f"t = {t_s} s"


def _run_facts(r: Mapping[str, Any]) -> str:
    params = "".join(f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(str(v))}</td></tr>"
                     for k, v in (r.get("parameters") or {}).items())
    facts = (f"<p>seed {r.get('seed')}, {html.escape(time_text(float(r.get('simulated_s', 0)) * 1e9))} simulated in "
             f"{float(r.get('wall_time_s', 0)):.2f} s of wall time (real-time factor {r.get('real_time_factor')})</p>")
    table = (f"<table id='parameters'><tr><th>parameter</th><th>value</th></tr>{params}</table>" if params
             else "<p>no parameters</p>")
    return f"<h2 id='run'>Parameters and run</h2>{table}{facts}"


def _files(folder: Path) -> str:
    present = sorted(p.name for p in folder.iterdir() if p.is_file() and p.name != PAGE
                     and not p.name.startswith(".")) if folder.is_dir() else []
    ordered = [n for n in FILES if n in present] + [n for n in present if n not in FILES]
    items = "".join(f"<li><a href='{html.escape(n)}'>{html.escape(n)}</a>"
                    f"{': ' + html.escape(FILES[n]) if n in FILES else ''}</li>" for n in ordered)
    return (f"<h2 id='files'>Files</h2><ul id='files-list'>{items}</ul>" if items
            else "<h2 id='files'>Files</h2><p>none written</p>")


def _checks(r: Mapping[str, Any], drawn: bool, units: Mapping[str, str],
            states: Mapping[str, Mapping[int, str]]) -> str:
    checks = r.get("checks", [])
    if not checks:
        return "<h2 id='checks'>Checks</h2><p>This run has no checks.</p>"
    rows = []
    for k, c in enumerate(checks, 1):
        shown = []
        signal = str(c.get("signal") or "")
        for v in c.get("violations", [])[:5]:
            if v.get("t_ns") is None:
                continue
            value, limit = violation_text(c, v, units, states.get(signal))
            detail = f" ({humanize_ns(str(v['detail']))})" if v.get("detail") else ""
            when = time_text(int(v["t_ns"]))
            link = (f"<a href='#waveform' onclick='cosimWave.showNs({int(v['t_ns'])})'>{when}</a>" if drawn
                    else when)
            shown.append(f"{link}: {html.escape(value)} vs limit {html.escape(limit)}{html.escape(detail)}")
        more = int(c.get("n_violations", 0)) - len(shown)
        if more > 0 and shown:
            shown.append(f"... and {more:,} more ({c.get('n_violations'):,} in all; result.json lists the first)")
        status = badge(str(c.get("verdict") or ("PASS" if c.get("passed") else "FAIL")))
        about = (f"<br><span class=note>{rst_inline(humanize_ns(str(c['description'])))}</span>"
                 if c.get("description") else "")
        if c.get("hazard"):
            about += f"<br><span class=note>hazard it demonstrates: {rst_inline(str(c['hazard']))}</span>"
        if c.get("nothing_checked"):
            about += f"<br><span class=note>examined nothing: {html.escape(str(c['nothing_checked']))}</span>"
        reads = (f"<br><a class='rows' href='#waveform' onclick='cosimWave.showCheck({k})'>show the rows it reads"
                 f"{' (' + html.escape(signal) + ')' if signal else ''}</a>" if drawn else "")
        rows.append(f"<tr id='check-{k}'><td class='num'>{k}</td><td>{status}</td><td>"
                    f"{html.escape(str(c.get('name')))}{about}{reads}"
                    f"</td><td class='num'>{_count(c.get('checked'))}</td>"
                    f"<td class='num'>{_count(c.get('n_violations'))}</td>"
                    f"<td>{'<br>'.join(shown)}</td></tr>")
    return ("<h2 id='checks'>Checks</h2><table id='checks-table'><tr><th>#</th><th></th><th>check</th><th>checked</th>"
            "<th>violations</th><th>first violations (click: show in the waveform)</th></tr>" + "".join(rows)
            + "</table>")


def _count(value: Any) -> str:
    return f"{value:,}" if isinstance(value, int) else html.escape(str(value))


def _figures(r: Mapping[str, Any]) -> str:
    figures = r.get("figures") or {}
    if not figures:
        return ""
    rows = "".join(f"<tr><td>{html.escape(str(k))}</td><td class='num'>{_number(v.get('value'))}</td>"
                   f"<td>{html.escape(str(v.get('unit', '')))}</td></tr>" for k, v in figures.items())
    return f"<h2>Figures</h2><table id='figures'><tr><th>figure</th><th>value</th><th>unit</th></tr>{rows}</table>"


def _number(value: Any) -> str:
    if value is None:
        return "could not be evaluated"
    return number_text(value) if isinstance(value, int | float) else html.escape(str(value))


def _notes(r: Mapping[str, Any]) -> str:
    notes = r.get("notes") or []
    if not notes:
        return ""
    items = "".join(f"<li>{rst_inline(humanize_ns(str(n)))}</li>" for n in notes[:200])
    more = f"<p class='note'>... and {len(notes) - 200} more in result.json</p>" if len(notes) > 200 else ""
    return f"<h2>Notes</h2><ul id='notes'>{items}</ul>{more}"


def _not_modelled(r: Mapping[str, Any]) -> str:
    """The settings the run accepted and stored but that do not act ("set, not modelled")."""
    found = r.get("not_modelled") or []
    if not found:
        return ""
    rows = "".join(f"<tr><td>{html.escape(str(n.get('device', '')))}</td>"
                   f"<td><code>{html.escape(str(n.get('name', '')))}</code></td>"
                   f"<td>{html.escape(str(n.get('value', '')))}</td><td>{html.escape(str(n.get('where') or ''))}</td>"
                   "</tr>" for n in found[:500])
    more = f"<p class='note'>... and {len(found) - 500} more in result.json</p>" if len(found) > 500 else ""
    return ("<h2 id='not-modelled'>Set, not modelled</h2><p class='note'>Accepted and stored, but the model does not "
            "act on them:</p><table id='not-modelled-table'><tr><th>device</th><th>setting</th><th>value</th>"
            f"<th>where</th></tr>{rows}</table>{more}")


#: Console lines shown in a page (the rest are in console.txt).
CONSOLE_LINES = 500
_CONSOLE = re.compile(r"^\s*(-?[\d.]+) ms  \[([^\]]*)\]  (.*)$")


def _console(folder: Path) -> str:
    """The run's console (``console.txt``: ``<t> ms  [<source>]  <text>``), each time a link into the waveform."""
    path = folder / "console.txt"
    if not path.is_file():
        return ""
    rows, total = [], 0
    with path.open(encoding="utf-8", errors="replace") as lines:
        for line in lines:
            total += 1
            if total > CONSOLE_LINES:
                continue
            found = _CONSOLE.match(line.rstrip("\n"))
            if found is None:
                rows.append(f"<tr><td></td><td></td><td>{html.escape(line.rstrip())}</td></tr>")
                continue
            t_ns = round(float(found[1]) * 1e6)
            rows.append(f"<tr><td class='num'><a href='#waveform' onclick='cosimWave.showNs({t_ns})'>"
                        f"{html.escape(time_text(t_ns))}</a></td><td><code>{html.escape(found[2])}</code></td>"
                        f"<td><pre class='line'>{html.escape(found[3])}</pre></td></tr>")
    if not total:
        return "<h2 id='console'>Console</h2><p class='note'>Nothing was written to the console.</p>"
    more = (f"<p class='note'>... and {total - CONSOLE_LINES:,} more lines in "
            "<a href='console.txt'>console.txt</a></p>" if total > CONSOLE_LINES else "")
    return (f"<h2 id='console'>Console</h2><p class='note'>{total:,} lines (PRINT, SEND, messages, why a job stopped); "
            "click a time to show it in the waveform.</p><table id='console-table'><tr><th>t</th><th>source</th>"
            f"<th>text</th></tr>{''.join(rows)}</table>{more}")
