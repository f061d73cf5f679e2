"""The report's site and waveform, without a browser: what each row draws, where violations go, links.

The traces are small and made by hand, so each expected number is written out: a 1 ms segment of
20 pulses is 20,000 pulses/s; a violation at 12,340 ns on a 10 ns time base is at tick 1,234.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from fractions import Fraction
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cosim.export import write_trace
from cosim.report import Entry, write_site
from cosim.report.rows import held, reduce_min_max, train
from cosim.report.verdicts import VERDICTS, badge
from cosim.report.waveform import Marked, build, initial_window, violations_of
from cosim.timebase import TimeBase
from cosim.trace import Trace


def _trace(end_t: int = 1_000_000) -> Trace:
    trace = Trace()
    trace.declare("dev.x.step", "pulse", pulse_width=100)
    trace.declare("dev.x.dir", "bit")
    trace.declare("dev.mode", "int")
    trace.declare("dev.x.pos", "real", unit="mm")
    trace.declare("dev.silent", "bit")
    trace.record_segment("dev.x.step", 0, 1_000_000, 20, 1)
    trace.record("dev.x.dir", 0, 1)
    trace.record("dev.mode", 250_000, 3)  # one value, first recorded at 0.25 ms
    for t in range(0, end_t, 100_000):
        trace.record("dev.x.pos", t, t / 1e5)
    trace.end_t = end_t
    return trace


def _model(layout: Any, name: str) -> Any:
    found = layout.select_one({"name": name})
    assert found is not None, f"no model named {name}"
    return found


def test_a_signal_recorded_once_is_a_line_from_its_record_to_the_end_of_the_run() -> None:
    line = held(_trace(), "dev.mode")
    assert line.t.tolist() == [250_000, 1_000_000]
    assert line.value.tolist() == [3.0, 3.0]


def test_a_signal_never_recorded_is_a_line_at_zero_and_says_so() -> None:
    line = held(_trace(), "dev.silent")
    assert (line.t.tolist(), line.value.tolist()) == ([0, 1_000_000], [0.0, 0.0])
    assert "never recorded" in line.note


def test_every_signal_has_its_row_and_glyph_in_the_layout() -> None:
    wave = build(_trace(), [])
    assert wave.signals == ["dev.x.step", "dev.x.dir", "dev.silent", "dev.x.pos", "dev.mode"]  # digital first
    for name in ("dev.x.dir", "dev.silent", "dev.mode", "dev.x.pos"):
        data = _model(wave.layout, f"wave:{name}:line").data_source.data
        assert data["t"][-1] == 1_000_000  # every line reaches the end of the run
    assert _model(wave.layout, "wave:dev.x.step:rate").data_source.data["rate"].tolist() == [20_000.0]


def test_pulse_train_rate_per_segment_is_signed_by_direction_and_single_pulses_become_segments() -> None:
    trace = Trace()
    trace.declare("d.s", "pulse")
    trace.record_segment("d.s", 0, 1_000_000, 20, 1)        # 20 pulses in 1 ms forwards
    trace.record_segment("d.s", 1_000_000, 500_000, 5, 0)   # 5 in 0.5 ms backwards
    trace.record_pulse("d.s", 1_700_000, 1)
    trace.end_t = 2_000_000
    drawn = train(trace, "d.s")
    assert drawn.rate_hz[:2].tolist() == [20_000.0, -10_000.0]
    assert drawn.t0.tolist() == [0, 1_000_000, 1_700_000]
    assert (drawn.duration.tolist(), drawn.count.tolist()) == ([1_000_000, 500_000, 1], [20, 5, 1])
    assert drawn.pulses == 26 and drawn.expandable


def test_a_pwm_output_cut_by_its_gate_is_drawn_at_its_carrier_rate_and_each_pulse_its_own_width() -> None:
    """20 kHz carrier (50 us), mark 20 us; the gate cuts the 4th pulse after 5 us: a segment of one
    pulse 5 us long, which is its high time, not a 200 kHz rate."""
    trace = Trace()
    trace.declare("d.pwm_out", "pulse", varying_width=True)
    trace.record_segment("d.pwm_out", 0, 150_000, 3, 1, width=20_000)
    trace.record_segment("d.pwm_out", 150_000, 5_000, 1, 1, width=5_000)
    trace.end_t = 200_000
    drawn = train(trace, "d.pwm_out", buckets=1)
    assert drawn.width.tolist() == [20_000, 5_000]
    assert drawn.rate_hz.tolist() == [4 / 200_000 * 1e9]  # 4 pulses in the 200 us slice: 20 kHz


def test_a_train_with_too_many_segments_is_drawn_as_a_rate_and_says_so() -> None:
    trace = Trace()
    trace.declare("d.s", "pulse")
    trace.extend_segments("d.s", np.arange(0, 1000, 10), np.full(100, 10), np.full(100, 2), np.ones(100))
    trace.end_t = 1000
    drawn = train(trace, "d.s", max_segments=50, buckets=10)
    assert not drawn.expandable and drawn.t0.size == 0
    assert drawn.notes and "rate" in drawn.notes[0]
    # 200 pulses over 10 slices of 100 ticks (1 ns): 20 pulses per 100 ns = 2e8 pulses/s
    assert drawn.rate_hz.tolist() == [2e8] * 10


def test_a_long_signal_keeps_each_slices_extremes_at_their_times() -> None:
    t = np.arange(1_000_000, dtype=np.int64)
    v = np.zeros(t.size)
    v[123_457], v[876_543] = 5.0, -7.0
    rt, rv = reduce_min_max(t, v, end_t=1_000_000, buckets=1000)
    assert rt.size <= 4000
    assert rt[rv == 5.0].tolist() == [123_457] and rt[rv == -7.0].tolist() == [876_543]


def test_held_reduces_a_long_signal_and_says_so() -> None:
    trace = Trace(spill_rows=10_000)
    trace.declare("d.v", "real")
    trace.extend("d.v", np.arange(100_000), np.sin(np.arange(100_000) / 1000))
    trace.end_t = 100_000
    line = held(trace, "d.v", max_points=5000, buckets=500)
    assert line.t.size <= 4 * 500 + 1 and line.records == 100_000
    assert "100,000 records" in line.note
    assert line.t[-1] == 100_000


def test_violations_are_marked_at_their_tick_with_their_check() -> None:
    checks = [{"name": "late edge", "n_violations": 2, "violations": [
        {"t_ns": 12_340, "value": 5, "limit": 3, "detail": "x"}, {"t_ns": 50_000, "value": 6, "limit": 3}]},
        {"name": "fine", "n_violations": 0, "violations": []}]
    marks, notes = violations_of(checks, Fraction(1, 10**8))  # 10 ns ticks
    assert [(m.check, m.t) for m in marks] == [("late edge", 1234), ("late edge", 5000)]
    assert notes == []
    trace = Trace(TimeBase(Fraction(1, 10**8)))
    trace.declare("d.b", "bit")
    trace.end_t = 100_000
    wave = build(trace, marks)
    assert _model(wave.layout, "wave:d.b:violations").data_source.data["t"] == [1234, 5000]
    assert _model(wave.layout, "violations:markers").data_source.data["check"] == ["late edge", "late edge"]


def test_the_view_opens_around_the_first_violation_else_on_the_whole_run() -> None:
    assert initial_window(4_000_000, []) == (0, 4_000_000)
    start, end = initial_window(4_000_000, [Marked("a", 3_000_000), Marked("b", 1_000_000)])
    assert (start, end) == (900_000, 1_100_000)  # a twentieth of the run, centred on 1 ms
    assert initial_window(4_000_000, [Marked("a", 10)]) == (0, 200_000)  # clipped at the start
    assert initial_window(4_000_000, [Marked("a", 3_999_999)]) == (3_800_000, 4_000_000)


def test_each_verdict_has_its_own_colour_and_wording() -> None:
    names = ["PASS", "FAIL", "ERROR", "HAZARD SHOWN", "HAZARD MISSED", "UNCHECKED", "TERMINATED", "INTERRUPTED"]
    assert sorted(VERDICTS) == sorted(names)
    assert len({colour for colour, _ in VERDICTS.values()}) == len(names)
    assert len({text for _, text in VERDICTS.values()}) == len(names)
    assert ">SOMETHING NEW<" in badge("SOMETHING NEW")  # a verdict the report does not know is still shown


class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        wanted = {"a": "href", "script": "src"}.get(tag)
        self.links += [v for k, v in attrs if k == wanted and v]


def _site(tmp_path: Path) -> tuple[Path, list[Path]]:
    out = tmp_path / "results"
    run = out / "demo"
    write_trace(_trace(), run)
    result = {"scenario": "demo", "verdict": "HAZARD SHOWN", "parameters": {"speed": 3}, "seed": 0,
              "summary": {"checks": 1, "passed": 0, "failed": 1}, "notes": ["a note"],
              "figures": {"late": {"value": 1.5, "unit": "ms"}},
              "checks": [{"name": "late edge", "passed": False, "checked": 3, "n_violations": 1,
                          "violations": [{"t_ns": 500_000, "value": 5, "limit": 3}]}]}
    (run / "result.json").write_text(json.dumps(result))
    other = out / "empty"
    other.mkdir(parents=True)
    entries = [Entry("demo", run, result, "Demo: one line.\n\nMore text."),
               Entry("empty", other, {"scenario": "empty", "verdict": "ERROR", "error": "it broke", "checks": []})]
    return write_site(entries, out), [run / "index.html", other / "index.html"]


def test_site_pages_link_only_to_files_that_exist(tmp_path: Path) -> None:
    summary, pages = _site(tmp_path)
    for page in [summary, *pages]:
        parser = _Links()
        parser.feed(page.read_text())
        local = [link for link in parser.links if not link.startswith("#")]
        assert local, page
        for link in local:
            assert not re.match(r"^[a-z]+:", link), f"{page.name}: {link} is not relative"
            assert (page.parent / link).is_file(), f"{page}: {link} does not exist"
    text = pages[0].read_text()
    for name in ("trace.vcd", "trace.gtkw", "trace_digital.vcd", "result.json", "edges.parquet"):
        assert f"href='{name}'" in text
    assert "HAZARD SHOWN" in summary.read_text() and "Demo: one line." in summary.read_text()
    assert "More text." in text and "it broke" in pages[1].read_text()


def test_site_inline_puts_the_library_in_each_page(tmp_path: Path) -> None:
    out = tmp_path / "results"
    write_trace(_trace(), out / "demo")
    write_site([Entry("demo", out / "demo", {"verdict": "PASS", "checks": []})], out, inline=True)
    text = (out / "demo" / "index.html").read_text()
    assert "<script src=" not in text and len(text) > 1_000_000 and not (out / "report_files").exists()


@pytest.mark.parametrize("verdict", list(VERDICTS))
def test_summary_shows_each_verdict_as_written(tmp_path: Path, verdict: str) -> None:
    out = tmp_path / "r"
    (out / "a").mkdir(parents=True)
    write_site([Entry("a", out / "a", {"verdict": verdict, "checks": []})], out)
    assert f'data-verdict="{verdict}"' in (out / "report.html").read_text()


def test_summary_counts_hazards_shown_and_checks_that_examined_nothing(tmp_path: Path) -> None:
    out = tmp_path / "r"
    summary = {"checks": 2, "passed": 1, "failed": 0, "unchecked": 1, "hazards": 2, "hazards_shown": 1}
    (out / "a").mkdir(parents=True)
    write_site([Entry("a", out / "a", {"verdict": "HAZARD MISSED", "checks": [], "summary": summary})], out)
    row = (out / "report.html").read_text().split("<td><a href='a/index.html'>a</a></td>")[1].split("</tr>")[0]
    assert "<td class='num'>1</td><td class='num'>0</td><td class='num'>1</td><td class='num'>1/2</td>" in row


def test_a_page_describes_a_scenario_with_its_whole_docstring_and_a_machine_with_its_description() -> None:
    from cosim.catalog import examples, load
    from cosim.report import describe

    text = describe(load("laser_pwm"))
    assert text.startswith("Laser PWM: a 40 W CO2 laser gated on twice") and "gate_ms" in text
    mill = load(next(p for p in examples() if p.name == "mill.toml"))
    assert describe(mill) == mill.description != ""


PAGE_SCRIPT = """
import json, sys
from pathlib import Path
from cosim.export import write_trace
from cosim.report import Entry, write_site
from cosim.trace import Trace

out = Path(sys.argv[1])
trace = Trace()
trace.declare("dev.x.step", "pulse", pulse_width=100)
trace.declare("dev.x.dir", "bit")
trace.record_segment("dev.x.step", 0, 1_000_000, 20, 1)
trace.record("dev.x.dir", 0, 1)
trace.end_t = 2_000_000
write_trace(trace, out / "demo", formats=("parquet",))
result = {"scenario": "demo", "verdict": "PASS", "checks": []}
(out / "demo" / "result.json").write_text(json.dumps(result))
write_site([Entry("demo", out / "demo", result, "Demo.")], out)
"""


def test_the_same_run_gives_the_same_page_byte_for_byte(tmp_path: Path) -> None:
    """Bokeh names its document and root element with random uuids; the page must not change from run to run."""
    pages = []
    for k in range(2):
        subprocess.run([sys.executable, "-c", PAGE_SCRIPT, str(tmp_path / str(k))], check=True)
        pages.append((tmp_path / str(k) / "demo" / "index.html").read_bytes())
    assert pages[0] == pages[1]
    assert b"docs_json" in pages[0]  # a Bokeh page indeed
