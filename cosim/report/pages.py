"""The HTML of the report's pages: the summary (``report.html``) and one page per run.

Plain HTML and CSS around the Bokeh waveform; every link is relative, so the folder opens from
disk and can be moved or zipped. The Bokeh library is loaded from ``report_files/`` next to
``report.html`` (one copy for every page), or inlined in each page.
"""

from __future__ import annotations

import html
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim.report.verdicts import VERDICTS, badge, meaning

#: Files of a results folder the page describes, in this order (other files are listed after them).
FILES = {
    "result.json": "verdict, parameters, checks with their violations, figures, notes",
    "trace.vcd": "every signal, for GTKWave and other waveform viewers",
    "trace.gtkw": "GTKWave view of trace.vcd (gtkwave trace.gtkw)",
    "trace_digital.vcd": "bits and pulse trains only, for sigrok-cli and PulseView",
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
                    f"<td>{html.escape(first)}</td><td class='num'>{float(r.get('simulated_s', 0)):g}</td>"
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


def page(entry: Entry, *, out: Path, bokeh: str, plot_script: str, plot_div: str, notes: Sequence[str],
         signals: Sequence[str], window: tuple[int, int] | None, ticks_per_ns: float = 1.0) -> str:
    """One run's page (``plot_script``/``plot_div``: the Bokeh waveform from ``bokeh.embed.components``)."""
    r = entry.result
    verdict = str(r.get("verdict"))
    back = html.escape(os.path.relpath(out / "report.html", entry.folder).replace(os.sep, "/"))
    text = entry.description.strip()
    first, _, rest = text.partition("\n")
    parts = [head(f"{entry.name}: {verdict}", bokeh + _HELPERS),
             f"<nav><a href='{back}'>all runs</a></nav>",
             f"<h1>{html.escape(entry.name)} {badge(verdict)}</h1><p><b>{html.escape(verdict)}</b>: "
             f"{html.escape(meaning(verdict))}</p>"]
    if first:
        parts.append(f"<p><b>{html.escape(first)}</b></p>")
    if rest.strip():
        parts.append(f"<pre class='doc'>{html.escape(rest.strip())}</pre>")
    parts += [_run_facts(r), _files(entry.folder), _checks(r), _figures(r), _notes(r)]
    parts.append("<h2 id='waveform'>Waveform</h2>")
    if window is None:
        parts.append("<p>No trace was written for this run.</p>")
    else:
        parts.append("<p><button onclick='cosimShow(null)'>whole run</button>"
                     + ("<button onclick='cosimFirst()'>first violation</button>" if _marked(r) else "")
                     + "Drag to pan, use the toolbar to zoom (box, wheel); pulse trains show their pulses "
                     "when few enough are in view, else their rate. Dashed red lines: check violations.</p>")
        if notes:
            parts.append("<p class='note'>Reduced to keep this page small:</p><ul class='note'>"
                         + "".join(f"<li>{html.escape(n)}</li>" for n in notes) + "</ul>")
        parts.append(f"<script type='application/json' id='cosim-signals'>{json.dumps(list(signals))}</script>")
        parts.append(f"<script>window.cosimWindow = {json.dumps(list(window))}; "
                     f"window.cosimTicksPerNs = {ticks_per_ns!r};</script>")
    parts += [plot_div, plot_script, "</main></body></html>"]
    return "".join(parts)


_HELPERS = """<script>
function cosimRange() { return Bokeh.documents[0].get_model_by_name('time'); }
function cosimShow(t) {
  const xr = cosimRange();
  if (t === null) { xr.setv({start: xr.bounds[0], end: xr.bounds[1]}); return; }
  const half = Math.max((xr.bounds[1] - xr.bounds[0]) / 40, 1);
  xr.setv({start: Math.max(t - half, xr.bounds[0]), end: Math.min(t + half, xr.bounds[1])});
}
function cosimShowNs(t_ns) { cosimShow(t_ns * window.cosimTicksPerNs); }
function cosimFirst() { const w = window.cosimWindow; cosimRange().setv({start: w[0], end: w[1]}); }
</script>"""


def _marked(r: Mapping[str, Any]) -> bool:
    return any(v.get("t_ns") is not None for c in r.get("checks", []) for v in c.get("violations", []))


def _run_facts(r: Mapping[str, Any]) -> str:
    params = "".join(f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(str(v))}</td></tr>"
                     for k, v in (r.get("parameters") or {}).items())
    facts = (f"<p>seed {r.get('seed')}, {float(r.get('simulated_s', 0)):g} s simulated in "
             f"{float(r.get('wall_time_s', 0)):.2f} s (real-time factor {r.get('real_time_factor')})</p>")
    blocks = [f"<h2>Parameters</h2><table id='parameters'><tr><th>parameter</th><th>value</th></tr>{params}</table>"
              if params else "<h2>Parameters</h2><p>none</p>", facts]
    if r.get("error"):
        blocks.append(f"<h2>Error</h2><pre class='doc'>{html.escape(str(r['error']))}</pre>")
    if r.get("terminated"):
        term = r["terminated"]
        log = "\n".join(term.get("log", [])[-10:])
        blocks.append(f"<h2>Terminated</h2><p>by {html.escape(str(term.get('plant')))} at t = {term.get('t_s')} s: "
                      f"{html.escape(str(term.get('reason')))}</p>" + (f"<pre class='doc'>{html.escape(log)}</pre>"
                                                                        if log else ""))
    if r.get("interrupted"):
        stop = r["interrupted"]
        blocks.append(f"<h2>Interrupted</h2><p>{html.escape(str(stop.get('signal')))} at t = {stop.get('t_s')} s</p>")
    return "".join(blocks)


def _files(folder: Path) -> str:
    present = sorted(p.name for p in folder.iterdir() if p.is_file() and p.name != PAGE
                     and not p.name.startswith(".")) if folder.is_dir() else []
    ordered = [n for n in FILES if n in present] + [n for n in present if n not in FILES]
    items = "".join(f"<li><a href='{html.escape(n)}'>{html.escape(n)}</a>"
                    f"{': ' + html.escape(FILES[n]) if n in FILES else ''}</li>" for n in ordered)
    return f"<h2>Files</h2><ul id='files'>{items}</ul>" if items else "<h2>Files</h2><p>none written</p>"


def _checks(r: Mapping[str, Any]) -> str:
    checks = r.get("checks", [])
    if not checks:
        return "<h2>Checks</h2><p>This run has no checks.</p>"
    rows = []
    for k, c in enumerate(checks, 1):
        shown = []
        for v in c.get("violations", [])[:5]:
            if v.get("t_ns") is None:
                continue
            t_ms = v["t_ns"] / 1e6
            detail = f" ({v['detail']})" if v.get("detail") else ""
            shown.append(f"<a href='#waveform' onclick='cosimShowNs({int(v['t_ns'])})'>t = {t_ms:.6f} ms</a>: "
                         f"{html.escape(str(v.get('value')))} vs "
                         f"limit {html.escape(str(v.get('limit')))}{html.escape(detail)}")
        more = int(c.get("n_violations", 0)) - len(shown)
        if more > 0 and shown:
            shown.append(f"... and {more:,} more in result.json")
        status = badge(str(c.get("verdict") or ("PASS" if c.get("passed") else "FAIL")))
        about = f"<br><span class=note>{html.escape(str(c['description']))}</span>" if c.get("description") else ""
        if c.get("hazard"):
            about += f"<br><span class=note>hazard it demonstrates: {html.escape(str(c['hazard']))}</span>"
        if c.get("nothing_checked"):
            about += f"<br><span class=note>examined nothing: {html.escape(str(c['nothing_checked']))}</span>"
        rows.append(f"<tr><td class='num'>{k}</td><td>{status}</td><td>{html.escape(str(c.get('name')))}{about}"
                    f"</td><td class='num'>{c.get('checked')}</td><td class='num'>{c.get('n_violations')}</td>"
                    f"<td>{'<br>'.join(shown)}</td></tr>")
    return ("<h2>Checks</h2><table id='checks'><tr><th>#</th><th></th><th>check</th><th>checked</th>"
            "<th>violations</th><th>first violations (click: show in the waveform)</th></tr>" + "".join(rows)
            + "</table>")


def _figures(r: Mapping[str, Any]) -> str:
    figures = r.get("figures") or {}
    if not figures:
        return ""
    rows = "".join(f"<tr><td>{html.escape(str(k))}</td><td class='num'>{_number(v.get('value'))}</td>"
                   f"<td>{html.escape(str(v.get('unit', '')))}</td></tr>" for k, v in figures.items())
    return f"<h2>Figures</h2><table id='figures'><tr><th>figure</th><th>value</th><th>unit</th></tr>{rows}</table>"


def _number(value: Any) -> str:
    return f"{value:.6g}" if isinstance(value, float) else html.escape(str(value))


def _notes(r: Mapping[str, Any]) -> str:
    notes = r.get("notes") or []
    if not notes:
        return ""
    items = "".join(f"<li>{html.escape(str(n))}</li>" for n in notes[:200])
    more = f"<p class='note'>... and {len(notes) - 200} more in result.json</p>" if len(notes) > 200 else ""
    return f"<h2>Notes</h2><ul id='notes'>{items}</ul>{more}"
