"""The run's console, its notes and the job signal: what every controller family writes to."""

from __future__ import annotations

import doctest
import json

import pytest

from cosim import job as job_module
from cosim import notes as notes_module
from cosim import trace as trace_module
from cosim.job import Job, JobState
from cosim.kernel import Simulation
from cosim.notes import Notes
from cosim.runner import run_scenario
from cosim.scenario import ScenarioFile


def test_console_lines_keep_their_instant_and_order_also_past_the_memory_limit(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(trace_module, "CONSOLE_LINES", 4)
    sim = Simulation()
    sim.trace.spool_dir = tmp_path
    for k in range(10):
        sim.trace.write_line(k * 1_000, "trio.proc1", f"line {k}\twith a tab")
    lines = list(sim.trace.console())
    assert [c.t for c in lines] == [k * 1_000 for k in range(10)]
    assert lines[9].text == "line 9\twith a tab"        # the one still in memory keeps its tab
    assert lines[0].text == "line 0 with a tab"         # a spilled line's tab became a space
    assert sim.trace.console_count == 10


def test_a_line_break_in_a_console_line_becomes_a_space() -> None:
    sim = Simulation()
    sim.trace.write_line(5, "gcode", "first\nsecond")
    assert [c.text for c in sim.trace.console()] == ["first second"]


def test_a_setting_set_twice_is_listed_once_with_its_last_value() -> None:
    notes = Notes()
    for k in range(15):
        notes.not_modelled("pmac", f"I{130 + k}", k, where=f"setup.pmc:{k + 1}")
    notes.not_modelled("pmac", "I130", 99, where="setup.pmc:40")
    items = notes.unmodelled()
    assert len(items) == 15
    assert (items[-1].name, items[-1].value, items[-1].where) == ("I130", 99, "setup.pmc:40")
    (summary,) = notes.texts()
    assert summary.startswith("pmac: set, not modelled (15): I131 = 1, ")
    assert summary.endswith("and 3 more (result.json: not_modelled)")


def test_a_keyed_note_is_replaced_in_its_place() -> None:
    notes = Notes()
    notes.add("first")
    notes.add("2 lines skipped", key="skipped")
    notes.add("last")
    notes.add("3 lines skipped", key="skipped")
    assert notes.texts() == ["first", "3 lines skipped", "last"]


def test_a_job_is_done_when_its_last_part_ends() -> None:
    """
    part a  ──█████████────────────
    part b  ────────███████████────
    job     0 1 . . . . . . . . 2       (done at 3000)
    """
    sim = Simulation()
    job = Job(sim, "trio")

    def parts(sim: Simulation):
        job.begin("a")
        yield sim.at(1_000)
        job.begin("b")
        yield sim.at(2_000)
        job.finish("a")
        yield sim.at(3_000)
        job.finish("b")

    sim.process(parts(sim))
    sim.run(until=5_000)
    t, v = sim.trace.edges("trio.job")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (0, 1), (3_000, 2)]
    assert job.end_t == 3_000


def test_a_stopped_job_keeps_its_first_reason_and_says_it_on_the_console() -> None:
    sim = Simulation()
    job = Job(sim, "pokeys")
    job.begin("pocket.nc")
    job.stop(JobState.LIMIT, "x limit+ switch at 300.0 mm")
    job.stop(JobState.EMERGENCY, "a later stop")
    job.begin("pocket.nc")   # nothing restarts a stopped job by itself
    assert job.state == JobState.LIMIT
    assert [(c.source, c.text) for c in sim.trace.console()] == [
        ("pokeys.job", "LIMIT: x limit+ switch at 300.0 mm")]
    with pytest.raises(ValueError, match="ERROR, LIMIT, EMERGENCY or ABORTED"):
        job.stop(JobState.DONE, "no")


def test_the_runner_writes_the_console_and_the_settings_not_modelled(tmp_path) -> None:
    def scenario(run) -> None:
        run.sim.trace.write_line(0, "trio.proc1", "hello")
        run.sim.notes.not_modelled("trio", "P_GAIN(axis 0)", 1.5, where="a.bas:3")

    result = run_scenario(ScenarioFile("console_demo", tmp_path / "demo.py", "", (), 1_000, scenario),
                          out=tmp_path / "out")
    assert (tmp_path / "out" / "console.txt").read_text() == "      0.000000 ms  [trio.proc1]  hello\n"
    stored = json.loads((tmp_path / "out" / "result.json").read_text())
    assert stored["console_lines"] == 1
    assert stored["not_modelled"] == [{"device": "trio", "name": "P_GAIN(axis 0)", "value": 1.5,
                                       "where": "a.bas:3"}]
    assert "trio: set, not modelled (1): P_GAIN(axis 0) = 1.5" in result.notes


@pytest.mark.parametrize("module", [job_module, notes_module], ids=lambda m: m.__name__)
def test_docstring_examples(module: object) -> None:
    failures, tried = doctest.testmod(module)  # type: ignore[arg-type]
    assert failures == 0 and tried > 0
