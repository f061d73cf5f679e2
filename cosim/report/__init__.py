"""The report of a set of runs: a small static site that opens from disk, offline, with no server.

``<out>/report.html``
    The summary: one row per run with its verdict (each verdict its own colour and wording, see
    :mod:`cosim.report.verdicts`), checks passed and failed, the first line of its description and a
    link to its page.
``<out>/<run>/index.html``
    One page per run, next to the run's files (:mod:`cosim.report.pages`): its verdict, description,
    checks with their violations in units (each a link that shows it in the waveform), figures, the
    waveform, the run's console, the settings set but not modelled, notes, parameters and files.
    The waveform (:mod:`cosim.report.waveform`) is one figure for every signal, in the order a reader
    needs (:mod:`cosim.report.rows`), drawn by the page's script from data prepared once, the view
    kept in the page's address; the XY path of a gated axis (:mod:`cosim.report.xy`) below it.
``<out>/<run>/waveform/``
    A long run's finer levels, loaded when the view zooms in (:mod:`cosim.report.levels`).
``<out>/report_files/``
    The plotting library (``bokeh-<version>.min.js``) and the waveform's script, once for every page
    (``inline=True`` puts them in each page instead, about 1.3 MB a page, for a page that travels
    alone).

Every link is relative. What a page embeds is bounded; a page says what it holds reduced.
"""

from __future__ import annotations

import ast
import hashlib
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
    scripts = None if inline else _shared_scripts(out)
    for entry in entries:
        write_page(entry, out=out, scripts=scripts)
    path = out / "report.html"
    path.write_text(summary(entries, out), encoding="utf-8")
    return path


def _shared_scripts(out: Path) -> dict[str, Path]:
    """The plotting library and the waveform's script, once in ``out/report_files/`` for every page."""
    import bokeh
    from bokeh.util.paths import bokehjs_path

    library = out / ASSETS / f"bokeh-{bokeh.__version__}.min.js"
    if not library.exists():
        library.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(bokehjs_path() / "js" / "bokeh.min.js", library)
    code = _our_script()
    ours = out / ASSETS / f"cosim-waveform-{hashlib.sha256(code.encode()).hexdigest()[:10]}.js"
    if not ours.exists():
        ours.write_text(code, encoding="utf-8")
    return {"bokeh": library, "cosim": ours}


def _our_script() -> str:
    from cosim.report.pulses_js import PULSES_JS
    from cosim.report.waveform import JS

    return PULSES_JS + "\n" + JS


def _script_tags(scripts: dict[str, Path] | None, folder: Path) -> str:
    if scripts is None:
        from bokeh.resources import Resources

        return Resources(mode="inline", components=["bokeh"]).render_js() + f"<script>{_our_script()}</script>"
    return "".join(f"<script src='{os.path.relpath(p, folder).replace(os.sep, '/')}'></script>"
                   for p in scripts.values())


def write_page(entry: Entry, *, out: Path, scripts: dict[str, Path] | None = None) -> Path:
    """Write one run's page into its folder (and a long run's side files into its ``waveform/``);
    ``scripts``: the shared library and waveform script (None: inlined in the page)."""
    from cosim.export import META, read_trace
    from cosim.report.levels import SIDE
    from cosim.report.waveform import build, figure_html
    from cosim.report.xy import xy_paths

    entry.folder.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(entry.folder / SIDE, ignore_errors=True)  # an older report's side files
    plot_script, divs, data = "", [], None
    notes: list[str] = []
    rows: list[Any] = []
    if (entry.folder / META).is_file():
        trace = read_trace(entry.folder)
        try:
            wave = build(trace, entry.result.get("checks", []), name=entry.name, folder=entry.folder)
            paths = xy_paths(trace)
        finally:
            trace.discard_spill()
        script, div = figure_html()
        texts = [script, div]
        if paths:  # the XY paths of gated axes: a document of their own
            from bokeh.embed import components

            more, found = components(paths)
            texts += [more, *found]
        script, div, *rest = stable_ids(texts, entry.name)
        plot_script = script + (rest[0] if rest else "")
        divs = [div, *rest[1:]]
        notes, rows, data = wave.notes, wave.rows, wave.data
    text = page(entry, out=out, scripts=_script_tags(scripts, entry.folder), plot_script=plot_script,
                plot_divs=divs, notes=notes, wave_data=data, rows=rows)
    path = entry.folder / PAGE
    path.write_text(text, encoding="utf-8")
    return path
