"""The report in a real browser: headless Chromium (the Debian package) driven by Playwright.

A few quick runs (PoKeys, Trio, PMAC with a violation, a machine file) are reported into one site;
each page must load without a console error or warning and draw every signal of its run (a row,
or a name in the quiet line), the signals a check reads first; its first draw is measured in the
browser; the view round-trips through the URL; next / previous violation step through the marks.
The pulse rule the page runs in JavaScript is compared with :func:`cosim.pulses.materialize_pulses`,
and the switch between rate and pulses is checked on a real train.

First draw: the page marks ``cosim-first-draw`` in the browser's performance timeline once the
figure has painted its rows. Its wall time (from navigation start) is printed, not asserted: on a
machine loaded with other work it measures the queue. What is asserted is the CPU time of the
page's main thread up to that mark (Chrome's ``ThreadTime`` metric): the drawing work itself,
which a loaded machine does not inflate.

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
READY = "window.cosimWave && window.cosimWave.drawn === true"
#: Most CPU time of a page's main thread from its creation to its first draw [s] (see the module's docstring).
FIRST_DRAW_CPU_S = 1.0


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


def _new_page(browser: Any) -> tuple[Any, list[str]]:
    """A page, and the errors and warnings it will write to its console."""
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    messages: list[str] = []
    page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: messages.append(f"page error: {e}"))
    return page, messages


def _open(browser: Any, path: Path, fragment: str = "") -> tuple[Any, list[str]]:
    page, messages = _new_page(browser)
    page.goto(path.resolve().as_uri() + fragment)
    page.wait_for_function(READY)
    return page, messages


def _pages(site: Path) -> list[Path]:
    return sorted(site.glob("*/index.html"))


def _redrawn(page: Any, action: str) -> None:
    """Run ``action`` in the page and wait until the rows are drawn again."""
    before = page.evaluate("cosimWave.draws")
    page.evaluate(action)
    page.wait_for_function(f"cosimWave.draws > {before}")


def test_every_page_loads_cleanly_draws_every_signal_and_first_draws_quickly(site: Path, browser: Any) -> None:
    first = browser.new_page()
    first.goto((site / "report.html").resolve().as_uri())
    links = first.eval_on_selector_all("#runs a", "links => links.map(a => a.getAttribute('href'))")
    first.close()
    assert sorted(links) == sorted(str(p.relative_to(site)) for p in _pages(site)) and len(links) == 4
    timings = {}
    for path in _pages(site):
        page, messages = _new_page(browser)
        cdp = page.context.new_cdp_session(page)
        cdp.send("Performance.enable")
        before = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
        page.goto(path.resolve().as_uri())
        page.wait_for_function(READY)
        after = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
        wall_ms = page.evaluate("performance.getEntriesByName('cosim-first-draw')[0].startTime")
        cpu_s = after["ThreadTime"] - before["ThreadTime"]
        timings[path.parent.name] = (round(wall_ms), round(cpu_s * 1000))
        signals = list(json.loads((path.parent / "trace_meta.json").read_text())["signals"])
        lanes = page.evaluate("cosimWave.lanes()")
        drawn = {lane["name"] for lane in lanes if lane["h"] > 0}
        quiet = [n for lane in lanes if lane["name"] == "quiet" for n in lane["names"]]
        assert sorted(drawn.union(quiet) - {"violations", "quiet"}) == sorted(signals), path.parent.name
        size = page.evaluate("(() => { const v = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name("
                             "'waveform')); return [v.bbox.width, v.bbox.height]; })()")
        assert size[0] > 1000 and size[1] >= sum(lane["h"] for lane in lanes), path.parent.name
        page.close()
        assert messages == [], f"{path.parent.name}: {messages}"
        assert cpu_s <= FIRST_DRAW_CPU_S, f"{path.parent.name}: {cpu_s:.2f} s of CPU to its first draw"
    print("first draw [ms of wall time since navigation, ms of main-thread CPU]:", timings)


def test_the_signals_a_check_reads_come_first(site: Path, browser: Any) -> None:
    """pokeys_stall: the hazard is the buffer draining (pokeys.buffer_level) into an underrun
    (pokeys.underrun, the signal its check reads): both come before the axes, no switch in between."""
    page, messages = _open(browser, site / "pokeys_stall" / "index.html")
    names = [lane["name"] for lane in page.evaluate("cosimWave.lanes()")]
    quiet = next(lane["names"] for lane in page.evaluate("cosimWave.lanes()") if lane["name"] == "quiet")
    page.close()
    assert names[:2] == ["violations", "pokeys.underrun"]
    assert names.index("pokeys.buffer_level") < names.index("pokeys.x.step") < names.index("pokeys.x.position")
    assert "pokeys.x.limit_pos" in quiet and "pokeys.x.limit_pos" not in names  # a switch never tripped
    assert messages == []


def test_the_view_round_trips_through_the_url(site: Path, browser: Any) -> None:
    path = site / "pokeys_stall" / "index.html"
    page, messages = _open(browser, path, "#t=300,340&rows=pokeys.underrun,pokeys.buffer_level")
    state = page.evaluate("cosimWave.viewState()")
    assert (state["start"], state["end"]) == (300_000_000, 340_000_000)  # 1 ns ticks
    assert state["rows"] == ["pokeys.underrun", "pokeys.buffer_level"]  # in reader order
    _redrawn(page, "Bokeh.documents[0].get_model_by_name('time').setv({start: 310500000, end: 312000000})")
    page.wait_for_function("location.hash.startsWith('#t=310.5,312&')")
    shared = page.evaluate("location.href")
    page.close()
    again = browser.new_page(viewport={"width": 1400, "height": 900})
    again.goto(shared)
    again.wait_for_function(READY)
    state = again.evaluate("cosimWave.viewState()")
    again.close()
    assert (state["start"], state["end"], state["rows"]) == (310_500_000, 312_000_000,
                                                             ["pokeys.underrun", "pokeys.buffer_level"])
    assert messages == []


def test_next_and_previous_violation_step_through_the_marks(site: Path, browser: Any) -> None:
    """pmac_stale_capture: one violation of each check, at 23.437499 ms and at 40 ms."""
    folder = site / "pmac_stale_capture"
    result = json.loads((folder / "result.json").read_text())
    times = sorted(v["t_ns"] for c in result["checks"] for v in c["violations"])  # 1 ns ticks
    assert times == [23_437_499, 40_000_000], "precondition: the two violations of this run"
    page, messages = _open(browser, folder / "index.html")

    def centre() -> float:  # the middle of the view, or the run's end (40 ms) when the view reaches it
        state = page.evaluate("cosimWave.viewState()")
        return state["end"] if state["end"] == 40_000_000 else (state["start"] + state["end"]) / 2

    page.evaluate("cosimWave.violation('first')")
    assert centre() == times[0]
    page.evaluate("cosimWave.violation('next')")
    assert centre() == times[1]
    page.evaluate("cosimWave.violation('next')")
    assert centre() == times[1]  # the last one stays
    page.evaluate("cosimWave.violation('previous')")
    assert centre() == times[0]
    said = page.inner_text("#cosim-violation")
    page.close()
    assert said.startswith("violation 1 of 2: check ") and " at 23.437499 ms: " in said
    assert messages == []


def test_the_view_opens_on_the_first_violation_marked_on_every_row(site: Path, browser: Any) -> None:
    folder = site / "pmac_stale_capture"
    result = json.loads((folder / "result.json").read_text())
    times_ns = [v["t_ns"] for c in result["checks"] for v in c["violations"]]
    assert times_ns, "precondition: this run has violations"
    first = min(times_ns)  # 1 ns ticks
    end_t = json.loads((folder / "trace_meta.json").read_text())["end_t"]
    page, _ = _open(browser, folder / "index.html")
    start, end, marked = page.evaluate("""(() => {
        const doc = Bokeh.documents[0];
        const xr = doc.get_model_by_name('time');
        const spans = doc.get_model_by_name('violation_marks');
        return [xr.start, xr.end, Array.from(spans.data.t)];
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
    state = "cosimWave.lanes().find((l) => l.name === 'pokeys.x.step')"
    _redrawn(page, "cosimWave.whole()")  # the whole run (the page opens on the stall's first violation)
    assert page.evaluate(state)["showing"] == "rate"  # about 20,000 pulses: the rate
    _redrawn(page, "Bokeh.documents[0].get_model_by_name('time').setv({start: 100000000, end: 100400000})")
    lane = page.evaluate(state)
    inside = t[(t + width > 100_000_000) & (t <= 100_400_000)]  # high at some instant in view
    assert lane["showing"] == "pulses" and inside.size > 0
    assert lane["pulses"] == inside.tolist()
    _redrawn(page, "cosimWave.whole()")
    assert page.evaluate(state)["showing"] == "rate"
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
