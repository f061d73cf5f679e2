"""A PASS means the job ran: every machine whose controller reports its job is checked to the job's end.

    [controller] ──> controller.job (cosim.job.Job) ──> <device>.job  0 idle, 1 running, 2 done, 3..6 stopped
                                                            │
    machine builder: JobCompleted(<device>.job) + job_s ────┘  ([job] check = false / hazard = ... / stop = ...)

A fake family (``fake``) whose job is scripted by its ``[controller]`` table stands in for the controller
families; the Trio and PoKeys controllers of main get their job from tests/job_doubles.py.

    fake job   0 |‾ 1 running ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|_ 2 done (or 4 limit, ...) ____|   until 3 s
               0 s                                 2.084 s                        3 s
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import Any

import pytest
from job_doubles import drive_jobs

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.job import Job, JobState
from cosim.machine import build, load_machine
from cosim.machine.check import check_machine
from cosim.machine.document import Table
from cosim.machine.families import families
from cosim.runner import run_scenario
from cosim.scenario import Run
from cosim.timebase import Priority

ENDINGS = {"done": None, "error": JobState.ERROR, "limit": JobState.LIMIT, "emergency": JobState.EMERGENCY,
           "aborted": JobState.ABORTED}


class FakeController:
    """A controller whose job starts at 0 and ends at ``[controller] at`` the way ``ends`` says."""

    def __init__(self, run: Run, table: Table) -> None:
        self.sim = run.sim
        self.ends = table.text("ends", "done", choices=(*ENDINGS, "never", "running"))
        self.at = table.time("at", None) or 0
        self.reports = table.flag("reports_job", True)
        if self.reports:
            self.job = Job(run.sim, "fake")

    def script(self) -> None:
        if not self.reports or self.ends == "never":
            return
        job = self.job
        self.sim.call_at(0, Priority.HOST, lambda: job.begin("program"))
        if self.ends == "running":
            return
        state = ENDINGS[self.ends]
        if state is None:
            self.sim.call_at(self.at, Priority.HOST, lambda: job.finish("program"))
        else:
            self.sim.call_at(self.at, Priority.HOST, lambda: job.stop(state, "x hit its positive limit switch"))


class FakeFamily:
    name = "fake"
    tables: tuple[str, ...] = ()

    def controller(self, run: Run, table: Table, *, base: Path) -> FakeController:
        return FakeController(run, table)

    def port(self, controller: Any, kind: str, table: Table) -> Any:
        raise ConfigurationError("the fake controller has no ports")

    def start(self, run: Run, controller: FakeController, programs: list[Table], document: Table, *,
              base: Path) -> None:
        controller.script()


@pytest.fixture
def fake(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Any:
    """``fake(controller_lines, extra)``: a machine file of the fake family, until 3 s."""
    real = families()
    monkeypatch.setattr(build, "families", lambda: {**real, "fake": FakeFamily()})

    def machine(controller: str = "", extra: str = "") -> Path:
        path = tmp_path / "fake.toml"
        path.write_text(f'[machine]\nuntil = "3 s"\n\n[controller]\nfamily = "fake"\n{controller}\n{extra}')
        return path

    return machine


def test_a_job_that_completes_passes_and_job_s_is_the_instant_it_ended(fake: Any) -> None:
    result = run_scenario(load_machine(fake('ends = "done"\nat = "2.084 s"')))
    assert result.verdict == "PASS", result.table()
    assert [c["name"] for c in result.checks] == ["the fake job completed"]
    assert result.figures["job_s"] == {"value": 2.084, "unit": "s"}  # not 3 s, the run's end
    assert result.checks[0]["measured"] == {"state": 2, "end_ns": 2_084_000_000}


@pytest.mark.parametrize(("controller", "t_ns", "detail"), [
    ('ends = "limit"\nat = "1.5 s"', 1_500_000_000,
     "the job stopped at a limit (LIMIT) at 1.5 s: x hit its positive limit switch"),
    ('ends = "emergency"\nat = "1 s"', 1_000_000_000,
     "the job stopped by an emergency stop (EMERGENCY) at 1 s: x hit its positive limit switch"),
    ('ends = "never"', 3_000_000_000, "the job never started (IDLE)"),
    ('ends = "running"', 3_000_000_000, "the job was still running when the run ended (RUNNING)"),
])
def test_a_job_that_did_not_complete_fails_with_how_it_ended(fake: Any, tmp_path: Path, controller: str,
                                                             t_ns: int, detail: str,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(fake(controller)), "--out", str(tmp_path / "o")]) == 1
    out = capsys.readouterr().out
    assert "scenario fake: FAIL" in out and detail in out
    result = run_scenario(load_machine(fake(controller)))
    (violation,) = result.checks[0]["violations"]
    assert (violation["t_ns"], violation["limit"], violation["detail"]) == (t_ns, 2, detail)
    stopped = "at" in controller
    assert (result.figures["job_s"]["value"] == t_ns / 1e9) if stopped else math.isnan(result.figures["job_s"]["value"])


def test_job_check_false_turns_the_check_off_and_says_so(fake: Any) -> None:
    result = run_scenario(load_machine(fake('ends = "running"', "[job]\ncheck = false\n")))
    assert result.checks == [] and result.verdict == "UNCHECKED"
    assert "job.check = false: whether the job completed is not checked" in result.notes


def test_a_stop_the_machine_demonstrates_is_a_hazard_shown(fake: Any) -> None:
    hazard = '[job]\nhazard = "x runs into its positive limit switch"\nstop = "limit"\n'
    shown = run_scenario(load_machine(fake('ends = "limit"\nat = "1.5 s"', hazard)))
    assert shown.verdict == "HAZARD SHOWN", shown.table()
    assert shown.hazards == [{"check": "the fake job completed", "shows": "x runs into its positive limit switch",
                              "shown": True}]
    other_stop = run_scenario(load_machine(fake('ends = "error"\nat = "1.5 s"', hazard)))
    assert other_stop.verdict == "FAIL"  # stopped, but not by the limit the machine demonstrates
    completed = run_scenario(load_machine(fake('ends = "done"\nat = "1.5 s"', hazard)))
    assert completed.verdict == "FAIL" and completed.shown == 0
    any_stop = run_scenario(load_machine(fake('ends = "error"\nat = "1.5 s"', hazard.replace('stop = "limit"\n', ""))))
    assert any_stop.verdict == "HAZARD SHOWN"


@pytest.mark.parametrize(("extra", "message"), [
    ("[job]\nchek = false\n", r"fake.toml: job.chek is not a key here; did you mean check\?"),
    ('[job]\nstop = "limit"\n', r"fake.toml: job.stop = 'limit': a stop is a hazard the machine shows"),
    ('[job]\nhazard = "x"\nstop = "crash"\n', r"job.stop: value = 'crash' is not allowed \(allowed: error, limit, "
                                              r"emergency, aborted\)"),
    ('[job]\ncheck = false\nhazard = "x"\n', r"job: check = false checks nothing"),
])
def test_bad_job_tables_are_refused(fake: Any, extra: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(fake("", extra)))


def test_a_controller_that_does_not_report_its_job_gets_no_job_check(fake: Any) -> None:
    result = run_scenario(load_machine(fake("reports_job = false")))
    assert result.checks == [] and "job_s" not in result.figures
    with pytest.raises(ConfigurationError, match=r"does not report its job .* a job hazard cannot be shown"):
        check_machine(load_machine(fake("reports_job = false", '[job]\nhazard = "x"\n')))


# -- real controllers, their job driven by the doubles --------------------------------------------------------

TRIO = """
[machine]
until = "3 s"

[controller]
family = "trio"

[[program]]
file = "wait.bas"
"""


def test_a_trio_job_s_is_when_its_processes_stopped_not_the_runs_end(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """The program waits 2084 ms and ends: job_s = 2.084 s in a 3 s run (it used to be 3 s, the run's end)."""
    drive_jobs(monkeypatch)
    (tmp_path / "wait.bas").write_text("WA(2084)\nPRINT \"done\"\n")
    (tmp_path / "m.toml").write_text(TRIO)
    result = run_scenario(load_machine(tmp_path / "m.toml"))
    assert result.verdict == "PASS", result.table()
    assert result.figures["job_s"]["value"] == 2.084
    table = result.table().splitlines()  # the PRINT line, with its time, in the terminal table too
    assert table[table.index("  console (1 line, all in console.txt):") + 1].startswith("    2.084 s  [trio.")
    (tmp_path / "wait.bas").write_text("WA(4000)\n")  # still waiting when the run ends
    late = run_scenario(load_machine(tmp_path / "m.toml"))
    assert late.verdict == "FAIL" and math.isnan(late.figures["job_s"]["value"])


@pytest.mark.fmu
def test_the_trio_machine_with_pwm_control_1_forgotten_warns_that_its_laser_never_fired(
        tmp_path: Path) -> None:
    """TN20-81 without PWM_CONTROL(1): the PWM output never runs, energy_J = 0 J: the notes say so."""
    from cosim.controllers.trio.basic import EXAMPLES as TRIO_EXAMPLES

    text = (TRIO_EXAMPLES / "tn20_81.bas").read_text()
    (tmp_path / "tn20_81.bas").write_text(text)
    shutil.copy(TRIO_EXAMPLES / "tn20_81.bas", tmp_path / "tn20_81.bas")
    machine = tmp_path / "m.toml"
    machine.write_text('[machine]\nuntil = "900 ms"\n\n[controller]\nfamily = "trio"\n\n[[program]]\n'
                       'file = "tn20_81.bas"\n\n[plant.laser]\nmodel = "Laser"\npreset = "laser_co2_40w"\n'
                       'laser = { axis = 3 }\n\n[[figure]]\nname = "energy_J"\noutput = "laser.energy"\n'
                       'unit = "J"\n')
    healthy = run_scenario(load_machine(machine))
    assert healthy.figures["energy_J"]["value"] > 0 and not any("never fired" in n for n in healthy.notes)
    (tmp_path / "tn20_81.bas").write_text(text.replace("PWM_CONTROL(1)\n", ""))
    forgotten = run_scenario(load_machine(machine))
    assert forgotten.figures["energy_J"]["value"] == 0
    assert ("warning: the laser of plant laser never fired: trio.wdog, trio.axis3.gate and trio.axis3.pwm_mark were "
            "never on together (no PWM output reached it)") in forgotten.notes
    assert "note warning: the laser of plant laser never fired" in forgotten.table()


GCODE = """
[machine]
until = "12 s"

[controller]
family = "pokeys"
[controller.axis.x]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
limit_pos_enabled = true
[controller.axis.y]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
[controller.axis.z]
steps_per_unit = 400
max_velocity = 20
max_accel = 500

[[program]]
file = "job.nc"

[plant.stepper_x]
model = "Stepper"
preset = "nema17_17hs16_2004s1"
parameters = { screw_lead = 0.008, limit_pos_position = 0.3, limit_neg_position = -0.01 }
stepper = { axis = "x" }

[travel]
x = [0, 300]                # mm: the axis is 300 mm long
"""


@pytest.fixture
def x400(tmp_path: Path) -> Path:
    (tmp_path / "job.nc").write_text("G21 G90\nG1 X400 F3000\nM2\n")
    path = tmp_path / "mill.toml"
    path.write_text(GCODE)
    return path


@pytest.mark.fmu
def test_g1_x400_on_a_300_mm_axis_fails_its_travel(x400: Path, tmp_path: Path) -> None:
    """From the job's first slot at 8 ms: 50 ms of acceleration at 1000 mm/s^2 (1.25 mm), then 50 mm/s: x is past
    300 mm from 8 ms + 50 ms + 298.75 mm / 50 mm/s = 6.033 s and goes on to 400 mm. It used to PASS, exit 0."""
    assert main(["run", str(x400), "--out", str(tmp_path / "o")]) == 1
    result = run_scenario(load_machine(x400))
    travel = next(c for c in result.checks if c["name"] == "axis x within its travel 0..300 mm")
    assert travel["outcome"] == "FAIL" and travel["n_violations"] == 1
    (violation,) = travel["violations"]
    assert (violation["t_ns"], violation["value"], violation["limit"]) == (6_033_000_000, 400, 300)
    assert travel["measured"] == {"min": 0, "max": 400}


@pytest.mark.fmu
def test_g1_x400_with_the_limit_switch_coupled_fails_with_the_limit_stop(x400: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The switch at 300 mm trips at about 6.03 s; the engine stops (state 100): the job did not complete."""
    drive_jobs(monkeypatch)
    x400.write_text(GCODE.replace('stepper = { axis = "x" }', 'stepper = { axis = "x" }\nswitches = { axis = "x" }'))
    result = run_scenario(load_machine(x400))
    assert result.verdict == "FAIL", result.table()
    job = next(c for c in result.checks if c["name"] == "the pokeys job completed")
    (violation,) = job["violations"]
    assert violation["value"] == 4 and violation["detail"].startswith("the job stopped at a limit (LIMIT) at 6.03")
    assert 6.02 < result.figures["job_s"]["value"] < 6.04  # when it stopped
