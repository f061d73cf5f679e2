"""The report of a set of runs: a small static site that opens from disk, offline, with no server.

``<out>/report.html``
    The summary: one row per run with its verdict (each verdict its own colour and wording, see
    :mod:`cosim.report.verdicts`), checks passed and failed, the first line of its description and a
    link to its page.
``<out>/<run>/index.html``
    One page per run, next to the run's files: its description, parameters, checks with their
    violations (each a link that shows it in the waveform), figures, notes, links to ``result.json``,
    the VCDs, the GTKWave view and the tables, then the waveform (:mod:`cosim.report.waveform`):
    every signal of the trace on one linked time axis, pulse trains from their segments,
    violations marked, opening on the first violation; and the XY path of a gated axis
    (:mod:`cosim.report.xy`).
``<out>/report_files/bokeh-<version>.min.js``
    The plotting library, once for every page (``inline=True`` puts it in each page instead, about
    1.3 MB a page, for a page that travels alone).

Every link is relative. What a page embeds is bounded (see :mod:`cosim.report.rows`); a page says
what it reduced.
"""

from __future__ import annotations

import ast
import os
import shutil
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Protocol

from cosim.report.ids import stable_ids
from cosim.report.pages import PAGE, Entry, page, summary

__all__ = ["PAGE", "Entry", "describe", "write_page", "write_report", "write_site"]

ASSETS = "report_files"


class _Described(Protocol):
    @property
    def name(self) -> str: ...

    @property
    def path(self) -> Path: ...

    @property
    def description(self) -> str: ...


def describe(scenario: _Described) -> str:
    """The whole description of a scenario (its module docstring) or of a machine file (its description)."""
    if scenario.path.suffix == ".py" and scenario.path.is_file():
        try:
            doc = ast.get_docstring(ast.parse(scenario.path.read_text(), str(scenario.path)))
        except SyntaxError:
            doc = None
        if doc:
            return doc
    return scenario.description


def write_report(results: Iterable[Any], out: Path, *, scenarios: Sequence[_Described] = (),
                 inline: bool = False) -> Path:
    """Write the report of ``results`` (:class:`cosim.runner.Result`, each with its folder ``out``) into ``out``.

    Parameters
    ----------
    results : iterable of Result
        The runs, in the order of the summary.
    out : path
        The folder of ``report.html`` (the runs' folders are usually inside it).
    scenarios : sequence of ScenarioFile
        The scenarios that were run, for their descriptions (matched by name).
    inline : bool
        Put the plotting library in every page instead of once in ``report_files/``.

    Returns
    -------
    Path
        ``out/report.html``.
    """
    described = {s.name: describe(s) for s in scenarios}
    entries = [Entry(r.scenario, Path(r.out) if r.out is not None else Path(out) / r.scenario, r.to_dict(),
                     described.get(r.scenario, "")) for r in results]
    return write_site(entries, Path(out), inline=inline)


def write_site(entries: Sequence[Entry], out: Path, *, inline: bool = False) -> Path:
    """Write the summary ``out/report.html`` and each entry's page; returns the summary's path."""
    out.mkdir(parents=True, exist_ok=True)
    library = None if inline else _copy_library(out)
    for entry in entries:
        write_page(entry, out=out, library=library)
    path = out / "report.html"
    path.write_text(summary(entries, out), encoding="utf-8")
    return path


def _copy_library(out: Path) -> Path:
    import bokeh
    from bokeh.util.paths import bokehjs_path

    target = out / ASSETS / f"bokeh-{bokeh.__version__}.min.js"
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(bokehjs_path() / "js" / "bokeh.min.js", target)
    return target


def write_page(entry: Entry, *, out: Path, library: Path | None = None) -> Path:
    """Write one run's page into its folder; ``library``: the shared ``bokeh.min.js`` (None: inlined)."""
    from bokeh.document import Document
    from bokeh.embed import components
    from bokeh.layouts import column, row
    from bokeh.resources import Resources

    from cosim.export import META, read_trace
    from cosim.report.pulses_js import PULSES_JS
    from cosim.report.waveform import build, violations_of
    from cosim.report.xy import xy_paths

    entry.folder.mkdir(parents=True, exist_ok=True)
    if library is None:
        scripts = Resources(mode="inline", components=["bokeh"]).render_js()
    else:
        scripts = f"<script src='{os.path.relpath(library, entry.folder).replace(os.sep, '/')}'></script>"
    scripts += f"<script>{PULSES_JS}</script>"  # window.cosimPulses: the rule the waveform uses, for a reader
    script = div = ""
    notes: list[str] = []
    signals: list[str] = []
    window = None
    ticks_per_ns = 1.0
    if (entry.folder / META).is_file():
        trace = read_trace(entry.folder)
        try:
            marks, notes = violations_of(entry.result.get("checks", []), trace.timebase.resolution_s)
            wave = build(trace, marks)
            paths = xy_paths(trace)
        finally:
            trace.discard_spill()
        root = column(wave.layout, row(*paths), sizing_mode="stretch_width") if paths else wave.layout
        document = Document()
        document.add_root(root)
        if wave.on_ready is not None:
            document.js_on_event("document_ready", wave.on_ready)
        script, div = stable_ids(components(root), entry.name)
        notes += wave.notes
        signals, window = wave.signals, (wave.start, wave.end)
        ticks_per_ns = float(1 / (trace.timebase.resolution_s * 10**9))
    text = page(entry, out=out, bokeh=scripts, plot_script=script, plot_div=div, notes=notes, signals=signals,
                window=window, ticks_per_ns=ticks_per_ns)
    path = entry.folder / PAGE
    path.write_text(text, encoding="utf-8")
    return path
