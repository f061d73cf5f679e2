"""The report in a real browser: headless Chromium (the Debian package) driven by Playwright.

A few quick runs (PoKeys, Trio, PMAC with a violation, a machine file) are reported into one site;
each page must load without a console error or warning, and every signal of each run's trace must
have its row drawn (a Bokeh view with a size). The pulse rule the page runs in JavaScript is
compared with :func:`cosim.pulses.materialize_pulses`, the view's switch between rate and pulses is
checked on a real train, and a screenshot of one page is kept in the test's output folder.

``tasks.py test`` installs ``chromium`` with apt-get where it is missing; only where it could not
(no root, no apt-get) do these tests skip.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cosim.catalog import examples, load
from cosim.export import read_trace
from cosim.pulses import materialize_pulses
from cosim.report import write_report
from cosim.runner import run_scenario

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = [pytest.mark.fmu, pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (tasks.py test installs the Debian package `chromium` "
                             "with apt-get where it runs as root; here it could not)")]
#: name, overrides: PoKeys pulses, Trio with the laser, PMAC whose fix makes both hazard checks fail
#: (violations to mark), and a machine file.
RUNS = [("pokeys_stall", {}), ("trio_raster_starved", {}), ("pmac_stale_capture", {})]
READY = "window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle"


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("report")
    machine = next(p for p in examples() if p.name == "mill.toml")
    scenarios, results = [], []
    for name, overrides in [*RUNS, (machine, {})]:
        scenario = load(name)
        scenarios.append(scenario)
        results.append(run_scenario(scenario, overrides=overrides, out=out / scenario.name))
    write_report(results, out, scenarios=scenarios)
    return out


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, headless=True)
        yield chromium
        chromium.close()


def _open(browser: Any, path: Path) -> tuple[Any, list[str]]:
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    messages: list[str] = []
    page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: messages.append(f"page error: {e}"))
    page.goto(path.resolve().as_uri())
    return page, messages


def _pages(site: Path) -> list[Path]:
    return sorted(site.glob("*/index.html"))


def test_every_page_loads_cleanly_and_draws_every_signal(site: Path, browser: Any) -> None:
    summary, messages = _open(browser, site / "report.html")
    links = summary.eval_on_selector_all("#runs a", "links => links.map(a => a.getAttribute('href'))")
    summary.close()
    assert messages == []
    assert sorted(links) == sorted(str(p.relative_to(site)) for p in _pages(site)) and len(links) == 4
    for path in _pages(site):
        page, messages = _open(browser, path)
        page.wait_for_function(READY)
        signals = list(json.loads((path.parent / "trace_meta.json").read_text())["signals"])
        assert signals, path
        sizes = page.evaluate("""(names) => names.map((n) => {
            const doc = Bokeh.documents[0];
            const row = doc.get_model_by_name('wave:' + n);
            const glyph = doc.get_model_by_name('wave:' + n + ':line') || doc.get_model_by_name('wave:' + n + ':rate');
            const view = row ? Bokeh.index.find_one(row) : null;
            return [n, glyph !== null, view ? view.bbox.width : 0, view ? view.bbox.height : 0];
        })""", signals)
        for name, has_glyph, width, height in sizes:
            assert has_glyph and width > 0 and height > 0, f"{path.parent.name}: {name} is not drawn"
        if path.parent.name == "pokeys_stall":
            shot = path.parents[1] / "pokeys_stall.png"
            page.screenshot(path=str(shot), full_page=True)
            print(f"screenshot: {shot}")
        page.close()
        assert messages == [], f"{path.parent.name}: {messages}"


def test_the_view_opens_on_the_first_violation_marked_on_every_row(site: Path, browser: Any) -> None:
    folder = site / "pmac_stale_capture"
    result = json.loads((folder / "result.json").read_text())
    times_ns = [v["t_ns"] for c in result["checks"] for v in c["violations"]]
    assert times_ns, "precondition: this run has violations"
    first = min(times_ns)  # 1 ns ticks
    end_t = json.loads((folder / "trace_meta.json").read_text())["end_t"]
    page, _ = _open(browser, folder / "index.html")
    page.wait_for_function(READY)
    start, end, marked = page.evaluate("""(() => {
        const doc = Bokeh.documents[0];
        const xr = doc.get_model_by_name('time');
        const spans = doc.get_model_by_name('wave:pmac.ect.method:violations');
        return [xr.start, xr.end, Array.from(spans.data_source.data.t)];
    })()""")
    page.close()
    assert start <= first <= end and end - start == end_t // 20
    assert sorted(marked) == sorted(times_ns)


def test_a_pulse_train_shows_its_pulses_when_zoomed_in_and_its_rate_when_zoomed_out(site: Path,
                                                                                     browser: Any) -> None:
    folder = site / "pokeys_stall"
    trace = read_trace(folder)
    t, _ = trace.pulses("pokeys.x.step")
    width = trace.info["pokeys.x.step"].pulse_width
    page, messages = _open(browser, folder / "index.html")
    page.wait_for_function(READY)
    state = """(() => {
        const doc = Bokeh.documents[0];
        const pulses = doc.get_model_by_name('wave:pokeys.x.step:pulses');
        const rate = doc.get_model_by_name('wave:pokeys.x.step:rate');
        return [pulses.visible, rate.visible, Array.from(pulses.data_source.data.left)];
    })()"""
    page.evaluate("cosimShow(null)")  # the whole run (the page opens on the stall's first violation)
    assert page.evaluate(state)[:2] == [False, True]  # about 20,000 pulses: the rate
    page.evaluate("Bokeh.documents[0].get_model_by_name('time').setv({start: 100000000, end: 100400000})")
    shown, rate_shown, left = page.evaluate(state)
    inside = t[(t + width > 100_000_000) & (t <= 100_400_000)]  # high at some instant in view
    assert shown and not rate_shown and inside.size > 0
    assert left == inside.tolist()
    page.evaluate("cosimShow(null)")
    assert page.evaluate(state)[:2] == [False, True]
    page.close()
    assert messages == []


def test_the_pages_pulse_rule_is_cosims(site: Path, browser: Any) -> None:
    rng = np.random.default_rng(17)
    n = 40
    duration = rng.integers(1, 2_000_000, n)
    count = np.minimum(rng.integers(1, 400, n), duration)
    t0 = 4_000_000_000 + np.cumsum(np.r_[0, duration[:-1] + rng.integers(0, 1000, n - 1)])  # long runs: big ticks
    width = rng.integers(1, 50, n)  # a PWM output's mark differs from segment to segment
    segments = {"t0": t0.tolist(), "duration": duration.tolist(), "count": count.tolist(), "dir": [1] * n,
                "width": width.tolist()}
    every = materialize_pulses(t0, duration, count)
    every_width = np.repeat(width, count)
    page, _ = _open(browser, _pages(site)[0])
    page.wait_for_function(READY)
    windows = [(float(t0[0] - 5), float(t0[-1] + duration[-1] + 5))]
    windows += [tuple(sorted(rng.uniform(t0[0], t0[-1] + duration[-1], 2).tolist())) for _ in range(30)]
    wide = int(np.flatnonzero(every_width >= 3)[0])
    windows.append((float(every[wide] + 1), float(every[wide] + 2)))  # inside one pulse: it is drawn, not a gap
    for start, end in windows:
        found = page.evaluate("([s, a, b]) => cosimPulses(s, a, b, 1e9)", [segments, start, end])
        inside = (every + every_width > np.ceil(start)) & (every <= np.floor(end))  # high at some instant in view
        assert found["t"] == every[inside].tolist(), (start, end)
        assert found["width"] == every_width[inside].tolist(), (start, end)
    over = page.evaluate("([s, a, b]) => cosimPulses(s, a, b, 10)", [segments, windows[0][0], windows[0][1]])
    page.close()
    assert over is None  # more than the cap: the caller draws the rate
