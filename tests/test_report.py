"""The report's site and waveform, without a browser: what each row draws, where violations go, links.

The traces are small and made by hand, so each expected number is written out: a 1 ms segment of
20 pulses is 20,000 pulses/s; a violation at 12,340 ns on a 10 ns time base is at tick 1,234.
"""

from __future__ import annotations

import base64
import json
import re
import subprocess
import sys
import zlib
from fractions import Fraction
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cosim.export import write_trace
from cosim.report import Entry, write_site
from cosim.report.levels import SideFiles, train_levels, value_levels
from cosim.report.rows import named_signals, reader_order, records, reduce_min_max, train_row, value_row
from cosim.report.text import humanize_ns, rst_html, state_names, time_text, value_text
from cosim.report.verdicts import VERDICTS, badge
from cosim.report.waveform import Marked, initial_window, violation_text, violation_unit, violations_of
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


def _page_data(page: Path) -> dict[str, Any]:
    text = page.read_text()
    found = re.search(r"<script type='application/json' id='cosim-wave'>(.*?)</script>", text, re.S)
    assert found is not None, f"{page} has no waveform data"
    return dict(json.loads(found[1]))


def _floats(b64: str) -> list[float]:
    return np.frombuffer(base64.b64decode(b64), dtype="<f8").tolist()


def _side(path: Path) -> dict[str, list[float]]:
    """A side file's arrays: ``cosimData("<name>", {array: {enc, first, n, z}})``, unpacked."""
    text = path.read_text()
    assert text.startswith(f'cosimData("{path.name}", ') and text.endswith(");\n")
    arrays = json.loads(text[text.index(", ") + 2:-3])
    out = {}
    for key, packed in arrays.items():
        raw = zlib.decompress(base64.b64decode(packed["z"]))
        if packed["enc"] == "f":
            out[key] = np.frombuffer(raw, "<f8").tolist()
        else:
            out[key] = (packed["first"] + np.r_[0, np.cumsum(np.frombuffer(raw, "<i4"))]).tolist()
    return out


def test_a_signal_recorded_once_is_a_labelled_line_from_its_record_to_the_end_of_the_run() -> None:
    row = value_row(_trace(), "dev.mode")
    assert row.t.tolist() == [250_000, 1_000_000]
    assert row.v.tolist() == [3.0, 3.0]
    assert row.distinct == 1 and not row.quiet  # it changed at 0.25 ms: not quiet, a constant line from there


def test_a_signal_never_recorded_or_held_from_the_start_is_quiet() -> None:
    never = value_row(_trace(), "dev.silent")
    assert (never.t.tolist(), never.v.tolist()) == ([0, 1_000_000], [0.0, 0.0])
    assert never.quiet and never.records == 0
    held_from_start = value_row(_trace(), "dev.x.dir")  # recorded once at t = 0
    assert held_from_start.quiet and held_from_start.value == 1.0
    assert not value_row(_trace(), "dev.x.pos").quiet


def test_rows_come_in_reader_order_the_checked_signals_first() -> None:
    trace = _trace()
    trace.declare("dev.level", "int", unit="slots")
    trace.declare("dev.under", "bit")
    named = named_signals([{"name": "no underrun", "signal": "dev.under", "passed": False,
                            "description": "dev.under never 1"}], list(trace.info))
    assert named == ["dev.under"]
    # then its device's group, then the axis x: pulse trains, bits, ints, reals as declared
    assert reader_order(trace, named) == ["dev.under", "dev.silent", "dev.mode", "dev.level",
                                          "dev.x.step", "dev.x.dir", "dev.x.pos"]


def test_a_check_names_the_signals_its_text_mentions_and_failed_checks_come_first() -> None:
    checks = [{"name": "fine", "signal": "a.x", "passed": True},
              {"name": "late", "signal": "b.y", "passed": False,
               "violations": [{"t_ns": 5, "value": 1, "limit": 0, "detail": "b.y rose before a.z"}]}]
    assert named_signals(checks, ["a.x", "a.z", "b.y"]) == ["b.y", "a.z", "a.x"]


def test_pulse_train_rate_per_segment_is_signed_by_direction_and_single_pulses_become_segments() -> None:
    trace = Trace()
    trace.declare("d.s", "pulse")
    trace.record_segment("d.s", 0, 1_000_000, 20, 1)        # 20 pulses in 1 ms forwards
    trace.record_segment("d.s", 1_000_000, 500_000, 5, 0)   # 5 in 0.5 ms backwards
    trace.record_pulse("d.s", 1_700_000, 1)
    trace.end_t = 2_000_000
    drawn = train_row(trace, "d.s")
    assert drawn.rate_hz[:2].tolist() == [20_000.0, -10_000.0]
    assert drawn.segments["t0"].tolist() == [0, 1_000_000, 1_700_000]
    assert drawn.segments["duration"].tolist() == [1_000_000, 500_000, 1]
    assert drawn.segments["count"].tolist() == [20, 5, 1]
    assert drawn.pulses == 26 and drawn.exact and not drawn.quiet


def test_a_pwm_output_cut_by_its_gate_is_drawn_at_its_carrier_rate_and_each_pulse_its_own_width() -> None:
    """20 kHz carrier (50 us), mark 20 us; the gate cuts the 4th pulse after 5 us: a segment of one
    pulse 5 us long, which is its high time, not a 200 kHz rate."""
    trace = Trace()
    trace.declare("d.pwm_out", "pulse", varying_width=True)
    trace.record_segment("d.pwm_out", 0, 150_000, 3, 1, width=20_000)
    trace.record_segment("d.pwm_out", 150_000, 5_000, 1, 1, width=5_000)
    trace.end_t = 200_000
    drawn = train_row(trace, "d.pwm_out", buckets=1)
    assert drawn.segments["width"].tolist() == [20_000, 5_000]
    assert drawn.rate_hz.tolist() == [4 / 200_000 * 1e9]  # 4 pulses in the 200 us slice: 20 kHz


def test_a_train_with_too_many_segments_keeps_its_rate_per_slice_and_says_so() -> None:
    trace = Trace()
    trace.declare("d.s", "pulse")
    trace.extend_segments("d.s", np.arange(0, 1000, 10), np.full(100, 10), np.full(100, 2), np.ones(100))
    trace.end_t = 1000
    drawn = train_row(trace, "d.s", embed_segments=50, buckets=10)
    assert not drawn.exact and not drawn.segments
    assert drawn.notes and "rate per slice" in drawn.notes[0]
    # 200 pulses over 10 slices of 100 ticks (1 ns): 20 pulses per 100 ns = 2e8 pulses/s
    assert drawn.rate_hz.tolist() == [2e8] * 10


def test_a_long_signal_keeps_each_slices_extremes_at_their_times() -> None:
    t = np.arange(1_000_000, dtype=np.int64)
    v = np.zeros(t.size)
    v[123_457], v[876_543] = 5.0, -7.0
    rt, rv = reduce_min_max(t, v, end_t=1_000_000, buckets=1000)
    assert rt.size <= 4000
    assert rt[rv == 5.0].tolist() == [123_457] and rt[rv == -7.0].tolist() == [876_543]


def test_a_long_signal_is_reduced_in_the_page_and_its_records_go_to_side_files(tmp_path: Path) -> None:
    trace = Trace(spill_rows=10_000)
    trace.declare("d.v", "real", unit="mm")
    trace.extend("d.v", np.arange(100_000) * 10, np.sin(np.arange(100_000) / 1000))
    trace.end_t = 1_000_000
    t, v = records(trace, "d.v")
    row = value_row(trace, "d.v", t=t, v=v, embed_points=5000, buckets=500)
    assert row.t.size <= 4 * 500 + 1 and row.records == 100_000 and not row.exact
    assert "100,000 records" in row.notes[0]
    assert row.t[-1] == 1_000_000
    side = SideFiles(tmp_path)
    value_levels(row, t, v, end_t=trace.end_t, side=side, index=3)
    raw = row.detail[-1]
    assert raw["w"] == 0 and len(raw["blocks"]) == 7  # 100,000 records in blocks of 16,384
    first, last = raw["blocks"][0], raw["blocks"][-1]
    assert (first[0], first[1]) == (0, 163_840) and last[1] == 1_000_000
    block = _side(tmp_path / first[2])
    assert block["t"] == (np.arange(16_384) * 10).tolist()  # the records, exact
    assert block["v"] == np.sin(np.arange(16_384) / 1000).tolist()
    assert _side(tmp_path / raw["blocks"][1][2])["t"][:2] == [163_840, 163_850]


def test_a_long_train_has_rate_levels_and_its_segments_in_side_files(tmp_path: Path) -> None:
    """60 s of 10 kHz in 1 ms segments of 10 pulses: 60,000 segments, more than a page holds."""
    trace = Trace()
    trace.declare("d.s", "pulse")
    n = 60_000
    trace.extend_segments("d.s", np.arange(n) * 1_000_000, np.full(n, 1_000_000), np.full(n, 10), np.ones(n))
    trace.end_t = n * 1_000_000
    row = train_row(trace, "d.s")
    assert not row.exact
    train_levels(row, trace, side=SideFiles(tmp_path), index=0)
    widths = [level["w"] for level in row.detail]
    assert widths[-1] == 0 and widths[:-1] == sorted(widths[:-1], reverse=True)
    assert round(float((row.rate_hz * (row.right - row.left)).sum()) / 1e9) == 600_000  # every pulse counted
    # 10 kHz: 585 or 586 pulses in a slice of 58.593792 ms (2**8 slices of 228,882 ns)
    assert set(np.round(row.rate_hz * 58_593_792 / 1e9).tolist()) == {585, 586}
    segments = row.detail[-1]["blocks"]
    assert len(segments) == 4 and segments[0][:2] == [0, 16_384 * 1_000_000 + 1]  # to its last segment's last fall


def test_violations_are_marked_at_their_tick_with_their_check_and_units() -> None:
    checks = [{"name": "late edge", "n_violations": 2, "signal": "d.b", "measured": {"worst_ns": 6},
               "violations": [{"t_ns": 12_340, "value": 5, "limit": 3, "detail": "x"},
                              {"t_ns": 50_000, "value": 6, "limit": 3}]},
              {"name": "fine", "n_violations": 0, "violations": []}]
    marks, notes = violations_of(checks, Fraction(1, 10**8))  # 10 ns ticks
    assert [(m.check, m.t) for m in marks] == [("late edge", 1234), ("late edge", 5000)]
    assert notes == []
    assert (marks[1].value, marks[1].limit) == ("6 ns", "3 ns")  # the check's figure says the value is in ns


def test_a_violation_is_in_the_unit_of_its_signal_or_of_the_duration_it_measured() -> None:
    underrun = {"name": "no buffer underrun", "signal": "pokeys.underrun",
                "measured": {"intervals": 1, "total_ns": 42000000, "longest_ns": 42000000, "max_value": 1}}
    long_one = {"t_ns": 319000000, "value": 42000000, "limit": "never > 0",
                "detail": "pokeys.underrun > 0 from 319000000 to 361000000 ns (highest 1)"}
    assert violation_unit(underrun, long_one, {}) == "ns"
    level = {"name": "level", "signal": "pokeys.buffer_level", "measured": {}}
    low = {"t_ns": 5, "value": 0, "limit": 1, "detail": "pokeys.buffer_level = 0 below 1"}
    assert violation_unit(level, low, {"pokeys.buffer_level": "slots"}) == "slots"
    assert violation_unit(level, {**low, "unit": "mm"}, {}) == "mm"  # a violation that says its unit


def test_each_check_says_the_unit_of_its_violations_and_the_report_uses_it() -> None:
    """The report used to guess the unit from the detail text: 0.3 J/mm of a laser read as "0.3 J", and a
    rate in pulses per second as a bare number. Each check now writes the unit of its value and limit."""
    from cosim.checks import Bound, EnergyPerLength, MaxPulseRate, PulsesPerWindow

    trace = Trace()
    trace.declare("laser.energy", "real", unit="J")
    trace.declare("head.x", "real", unit="mm")
    trace.declare("pokeys.x.step", "pulse")
    for t, energy, x in [(0, 0.0, 0.0), (1_000_000, 0.3, 1.0), (2_000_000, 0.6, 2.0)]:  # 0.3 J per mm
        trace.record("laser.energy", t, energy)
        trace.record("head.x", t, x)
    for k in range(30):  # 30 pulses 10 us apart in the first 1 ms: 100 kHz
        trace.record_pulse("pokeys.x.step", k * 10_000, 1)
    trace.end_t = 2_000_000
    units = {"laser.energy": "J", "head.x": "mm"}
    said = {}
    for check in (EnergyPerLength("laser.energy", ["head.x"], lower=0.36, upper=0.44),
                  Bound("head.x", upper=1.5), PulsesPerWindow("pokeys.x.step", 25, 1_000_000),
                  MaxPulseRate("pokeys.x.step", 25_000)):
        found = check.evaluate(trace).to_dict()
        violation = found["violations"][0]
        said[type(check).__name__] = (violation["unit"], *violation_text(found, violation, units))
    assert said == {"EnergyPerLength": ("J/mm", "0.3 J/mm", "0.36..0.44 J/mm"),
                    "Bound": ("mm", "2 mm", "1.5 mm"),
                    "PulsesPerWindow": ("pulses", "30 pulses", "25 pulses"),
                    "MaxPulseRate": ("Hz", "100,000 Hz", "25,000 Hz")}


def test_the_view_opens_around_the_first_violation_else_on_the_whole_run() -> None:
    assert initial_window(4_000_000, []) == (0, 4_000_000)
    start, end = initial_window(4_000_000, [Marked("a", 3_000_000), Marked("b", 1_000_000)])
    assert (start, end) == (900_000, 1_100_000)  # a twentieth of the run, centred on 1 ms
    assert initial_window(4_000_000, [Marked("a", 10)]) == (0, 200_000)  # clipped at the start
    assert initial_window(4_000_000, [Marked("a", 3_999_999)]) == (3_800_000, 4_000_000)


def test_states_are_named_from_the_signals_description() -> None:
    assert state_names("axis state x (AxisState codes)")[2] == "RUNNING"      # PoKeys axis states
    assert state_names("engine state (EngineState codes)")[100] == "STOP_LIMIT"
    assert state_names("method digit of the ECT entry: 9 frozen, 11 armed, 10 running") == \
        {9: "frozen", 11: "armed", 10: "running"}                           # PMAC time-base entry
    assert state_names("the controller's job: 0 idle, 1 running, 2 done (cosim.job.JobState)")[6] == "ABORTED"
    assert state_names("position counter x") == {}


def test_times_and_values_are_said_in_units() -> None:
    assert time_text(319_000_000) == "319 ms" and time_text(23_437_499) == "23.437499 ms"
    assert time_text(4_400_000_000) == "4.4 s" and time_text(12_500) == "12.5 us"
    assert humanize_ns("pokeys.underrun > 0 from 319000000 to 361000000 ns (highest 1)") == \
        "pokeys.underrun > 0 from 319 ms to 361 ms (highest 1)"
    assert humanize_ns("3 pulses in [1000000, 1020000) ns") == "3 pulses in [1 ms, 1.02 ms)"
    assert value_text(42_000_000, "ns") == "42 ms" and value_text(20, "slots") == "20 slots"


def test_descriptions_show_no_markup() -> None:
    text = rst_html("Runs ``pokeys.x.step`` (see :class:`cosim.trace.Trace`).\n\n* **one**\n* *two*\n\n"
                    "Example::\n\n    cosim run x\n")
    assert "``" not in text and ":class:" not in text and "**" not in text
    assert "<code>pokeys.x.step</code>" in text and "<li><b>one</b></li>" in text
    assert "<pre class='doc'>cosim run x</pre>" in text


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
              "not_modelled": [{"device": "dev", "name": "SERVO_GAIN", "value": "12", "where": "prog.bas:4"}],
              "figures": {"late": {"value": 1.5, "unit": "ms"}},
              "checks": [{"name": "late edge", "passed": False, "checked": 3, "n_violations": 1, "signal": "dev.mode",
                          "violations": [{"t_ns": 500_000, "value": 5, "limit": 3,
                                          "detail": "dev.mode = 5 above 3"}]}]}
    (run / "result.json").write_text(json.dumps(result))
    (run / "console.txt").write_text("      0.250000 ms  [dev.proc1]  hello <world>\n")
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


def test_a_page_shows_its_checks_in_units_its_console_and_what_was_set_but_not_modelled(tmp_path: Path) -> None:
    _, pages = _site(tmp_path)
    text = pages[0].read_text()
    assert "onclick='cosimWave.showNs(500000)'>500 us</a>: 5 vs limit 3 (dev.mode = 5 above 3)" in text
    assert "cosimWave.showCheck(1)" in text  # the link from the check to the rows it reads
    assert "onclick='cosimWave.showNs(250000)'>250 us</a></td><td><code>dev.proc1</code></td>" in text
    assert "hello &lt;world&gt;" in text
    assert "<td>dev</td><td><code>SERVO_GAIN</code></td><td>12</td><td>prog.bas:4</td>" in text


def test_a_pages_rows_put_the_checked_signal_first_and_fold_the_quiet_ones(tmp_path: Path) -> None:
    _, pages = _site(tmp_path)
    data = _page_data(pages[0])
    assert [r["name"] for r in data["rows"]][:1] == ["dev.mode"]  # the check reads it
    assert data["quiet"] == ["dev.silent", "dev.x.dir"]  # never recorded, held from the start
    assert data["defaultRows"] == ["dev.mode", "dev.x.step", "dev.x.pos"]
    assert data["marks"] == [{"t": 500_000, "check": 1, "name": "late edge", "value": "5", "limit": "3",
                              "detail": "dev.mode = 5 above 3"}]
    pos = next(r for r in data["rows"] if r["name"] == "dev.x.pos")
    assert pos["unit"] == "mm" and _floats(pos["t"])[-1] == 1_000_000  # held to the end of the run


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


def test_the_main_job_says_the_cpu_and_wall_time_of_what_it_measured() -> None:
    from cosim.mainjob import Stopwatch

    assert re.fullmatch(r"\d+\.\d s CPU, \d+\.\d s wall", Stopwatch().stop())
