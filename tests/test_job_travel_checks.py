"""JobCompleted and Travel on traces built by hand: what they examine, when they fail, what they report.

    fake.job   0 |‾ 1 ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|_ 2 (done) / 4 (limit, reason on the console) ___    end 3 s
    position   0 ___/‾‾‾ 120 ‾‾‾ 150 ‾‾\\___ -5 ___/‾‾ 0      travel -1..130: two excursions
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from cosim.checks import JobCompleted, Travel
from cosim.errors import ConfigurationError
from cosim.job import Job, JobState
from cosim.kernel import Simulation
from cosim.runner import run_scenario
from cosim.scenario import load
from cosim.trace import Trace

S = 1_000_000_000


def job_trace(*changes: tuple[int, int], end: int = 3 * S) -> Trace:
    trace = Trace()
    trace.declare("fake.job", "int")
    trace.record("fake.job", 0, 0)
    for t, state in changes:
        trace.record("fake.job", t, state)
    trace.end_t = end
    return trace


def test_a_job_done_passes_and_says_when_it_ended() -> None:
    result = JobCompleted("fake.job").evaluate(job_trace((0, 1), (2 * S, 2)))
    assert result.outcome == "PASS" and result.checked == 1 and dict(result.measured) == {"state": 2, "end_ns": 2 * S}


def test_a_stop_fails_with_the_reason_the_job_wrote_on_the_console() -> None:
    trace = job_trace((0, 1), (S, 3))
    trace.write_line(S // 2, "fake.proc1", "a PRINT line is not a reason")
    trace.write_line(S, "fake.job", "ERROR: prog.bas line 4: division by zero")
    (violation,) = JobCompleted("fake.job").evaluate(trace).violations
    assert (violation.t_ns, violation.value, violation.limit) == (S, 3, 2)
    assert violation.detail == "the job stopped on an error (ERROR) at 1 s: prog.bas line 4: division by zero"


def test_the_expected_end_may_be_a_stop() -> None:
    trace = job_trace((0, 1), (S, 4))
    assert JobCompleted("fake.job", ends="limit").evaluate(trace).outcome == "PASS"
    assert JobCompleted("fake.job", ends="limit").evaluate(job_trace((0, 1), (S, 2))).outcome == "FAIL"
    with pytest.raises(ConfigurationError, match=r"ends = 'crash' is not allowed \(allowed: done, error, limit"):
        JobCompleted("fake.job", ends="crash")


def test_a_trace_without_the_job_signal_is_examined_nothing_never_a_pass() -> None:
    result = JobCompleted("fake.job").evaluate(Trace())
    assert result.outcome == "UNCHECKED" and "does not report its job" in result.nothing_checked


def test_a_job_that_began_again_after_it_was_done_is_judged_by_its_last_state() -> None:
    assert JobCompleted("fake.job").evaluate(job_trace((0, 1), (S, 2), (2 * S, 1))).outcome == "FAIL"


def position_trace(kind: str = "int") -> Trace:
    trace = Trace()
    trace.declare("dev.x.position", kind)
    for t, v in [(0, 0), (1 * S, 120), (2 * S, 150), (3 * S, 140), (4 * S, 100), (5 * S, -5), (6 * S, 0)]:
        trace.record("dev.x.position", t, v)
    trace.end_t = 7 * S
    return trace


def test_each_excursion_is_one_violation_with_its_farthest_position() -> None:
    result = Travel("dev.x.position", -1, 130).evaluate(position_trace())
    assert [(v.t_ns, v.value, v.limit) for v in result.violations] == [(2 * S, 150, 130), (5 * S, -5, -1)]
    assert result.checked == 7 and dict(result.measured) == {"min": -5, "max": 150}


def test_the_scale_turns_the_signal_unit_into_the_travel_unit() -> None:
    """10 counts per mm: 150 counts = 15 mm, past a 0..12 mm travel."""
    (violation,) = Travel("dev.x.position", 0, 12, scale=10, unit="mm").evaluate(position_trace()).violations[:1]
    assert (violation.value, violation.limit) == (15, 12)
    assert violation.detail == "dev.x.position went past 12 mm, to 15 mm"


def test_a_pulse_train_is_read_as_its_signed_count_across_chunks() -> None:
    trace = Trace(chunk_pulses=3)  # 12 pulses in chunks of 3
    trace.declare("dev.x.step", "pulse")
    trace.record_segment("dev.x.step", 0, 1000, 5, 1)      # up to 5
    trace.record_segment("dev.x.step", 1000, 1000, 7, 0)   # down to -2
    result = Travel("dev.x.step", -1, 4).evaluate(trace)
    assert [(v.t_ns, v.value, v.limit) for v in result.violations] == [(800, 5, 4), (1000 + 6 * 1000 // 7, -2, -1)]
    assert result.checked == 12


def test_a_travel_without_positions_is_examined_nothing() -> None:
    trace = Trace()
    trace.declare("dev.x.position", "int")
    assert Travel("dev.x.position", 0, 1).evaluate(trace).outcome == "UNCHECKED"
    with pytest.raises(ConfigurationError, match=r"low = 2 is not allowed \(allowed: <= high \(1\)\)"):
        Travel("dev.x.position", 2, 1)


SCRIPT = '''"""A controller that reports its job, declared with run.job."""
from cosim.job import Job
from cosim.timebase import Priority

UNTIL = "3 s"


class Controller:
    def __init__(self, sim):
        self.job = Job(sim, "fake")


def scenario(run):
    controller = Controller(run.sim)
    run.sim.call_at(0, Priority.HOST, lambda: controller.job.begin("program"))
    run.sim.call_at(run.sim.ticks("1.25 s"), Priority.HOST, lambda: controller.job.finish("program"))
    run.job(controller)
'''


def test_a_scenario_declares_the_job_check_and_job_s_with_run_job(tmp_path: Path) -> None:
    script = tmp_path / "job.py"
    script.write_text(SCRIPT)
    result = run_scenario(load(script))
    assert result.verdict == "PASS" and result.figures["job_s"] == {"value": 1.25, "unit": "s"}
    script.write_text(SCRIPT.replace("lambda: controller.job.finish(\"program\")", "lambda: None"))
    cut = run_scenario(load(script))
    assert cut.verdict == "FAIL" and math.isnan(cut.figures["job_s"]["value"])
    assert cut.checks[0]["violations"][0]["detail"] == "the job was still running when the run ended (RUNNING)"


def test_run_job_on_a_controller_without_a_job_declares_nothing() -> None:
    from cosim.scenario import Run, Values

    with Simulation() as sim:
        run = Run(sim=sim, p=Values({}), until=1)
        assert run.job(object()) is False and run.checks == [] and run.figures == {}
        job_holder = type("C", (), {})()
        job_holder.job = Job(sim, "fake")  # type: ignore[attr-defined]
        with pytest.raises(ConfigurationError, match=r"ends = 'limit'\) is a hazard the scenario shows"):
            run.job(job_holder, ends="limit")
    assert JobState.DONE == 2
