"""Verdicts and exit statuses: each verdict from a tiny script, exactly, through `cosim run`; `--until` honoured
or refused.

    dev.gate  0 ____|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾   on at 100 ns, until the end (1 us)
    dev.step  (declared, never a pulse: a check on it examines nothing)

The first that applies: INTERRUPTED, ERROR, FAIL, HAZARD MISSED, UNCHECKED (a check examined nothing), HAZARD SHOWN,
TERMINATED, UNCHECKED (no checks, or none examined anything), PASS.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.runner import run_scenario
from cosim.scenario import load

SCRIPT = '''"""Verdict case."""
from cosim.checks import Bound, MinPulseSpacing, ValueAt
from cosim.errors import PlantTerminated
from cosim.scenario import Run
from cosim.signals import Signal

UNTIL = "1 us"
ON = Bound("dev.gate", lower=0, upper=1, name="gate within 0..1")  # holds
OFF = Bound("dev.gate", lower=0, upper=0, name="gate never on")  # broken at 100 ns
NONE = MinPulseSpacing("dev.step", 10, name="no step pulses")  # examines nothing
NONE_OK = MinPulseSpacing("dev.step", 10, allow_empty=True, name="no step pulses, fine")
AFTER_END = ValueAt("dev.gate", 5000, expected=0, name="gate off at 5 us")  # 5 us: after the run's end
NAN = ValueAt("dev.level", None, expected=0, name="level 0 at the end")  # the level is NaN: no value


def scenario(run: Run) -> None:
    gate = Signal(run.sim, "dev.gate")
    run.sim.trace.declare("dev.step", "pulse")
    run.sim.trace.declare("dev.level", "real")
    run.sim.trace.record("dev.level", 0, float("nan"))

    def switch_on():
        yield run.sim.at(100)
        gate.set(1)

    run.sim.process(switch_on())
'''

#: (case, lines added to the scenario function, verdict, exit status)
CASES = [
    ("pass", ["run.check(ON)"], "PASS", 0),
    ("pass with an empty check that may be empty", ["run.check(ON)", "run.check(NONE_OK)"], "PASS", 0),
    ("fail", ["run.check(ON)", "run.check(OFF)"], "FAIL", 1),
    ("a failed check outranks a shown hazard", ["run.hazard(OFF, shows='h')", "run.check(OFF)"], "FAIL", 1),
    ("error", ["run.check(ON)", "raise RuntimeError('broken')"], "ERROR", 1),
    ("hazard shown", ["run.hazard(OFF, shows='the gate opens')", "run.check(ON)"], "HAZARD SHOWN", 0),
    ("hazard shown, an ordinary check examined nothing", ["run.hazard(OFF, shows='h')", "run.check(NONE)"],
     "UNCHECKED", 4),  # the shown hazard does not vouch for a check that saw nothing
    ("hazard shown, an ordinary check that may be empty", ["run.hazard(OFF, shows='h')", "run.check(NONE_OK)"],
     "HAZARD SHOWN", 0),
    ("hazard missed: its check passed", ["run.hazard(ON, shows='h')"], "HAZARD MISSED", 1),
    ("hazard missed: one of two", ["run.hazard(OFF, shows='h')", "run.hazard(ON, shows='h')"], "HAZARD MISSED", 1),
    ("hazard missed: its check examined nothing", ["run.hazard(NONE, shows='h')"], "HAZARD MISSED", 1),
    ("hazard missed: its instant was not simulated", ["run.hazard(AFTER_END, shows='h')"], "HAZARD MISSED", 1),
    ("hazard missed: its value is not a number", ["run.hazard(NAN, shows='h')"], "HAZARD MISSED", 1),
    ("unchecked: no checks", [], "UNCHECKED", 4),
    ("unchecked: every check examined nothing", ["run.check(NONE_OK)"], "UNCHECKED", 4),
    ("unchecked: a check examined nothing", ["run.check(ON)", "run.check(NONE)"], "UNCHECKED", 4),
    ("terminated", ["run.check(ON)", "run.run_until(500)",
                    "raise PlantTerminated('p ended', 'p', 'p.fmu', 500, 'asked to stop')"], "TERMINATED", 3),
    ("interrupted", ["run.check(OFF)", "raise KeyboardInterrupt('SIGINT')"], "INTERRUPTED", 130),
]


def _script(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "case.py"
    path.write_text(SCRIPT + "".join(f"    {line}\n" for line in lines))
    return path


@pytest.mark.parametrize(("lines", "verdict", "status"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_each_verdict_and_its_exit_status(tmp_path: Path, lines: list[str], verdict: str, status: int) -> None:
    assert main(["run", str(_script(tmp_path, lines)), "--out", str(tmp_path / "out")]) == status
    assert json.loads((tmp_path / "out" / "result.json").read_text())["verdict"] == verdict


def test_allow_unchecked_exits_0_and_keeps_the_verdict(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    script = _script(tmp_path, ["run.check(NONE)"])
    assert main(["run", str(script), "--out", str(tmp_path / "out"), "--allow-unchecked"]) == 0
    out = capsys.readouterr().out
    assert "scenario case: UNCHECKED  (0/1 checks passed, 1 examined nothing, " in out
    assert "  UNCHECKED  no step pulses  [0 checked, 0 violations]" in out
    assert "          examined nothing: signal dev.step had no data: nothing was checked" in out


def test_result_json_lists_the_hazards_and_each_check_says_what_came_of_it(tmp_path: Path) -> None:
    script = _script(tmp_path, ["run.hazard(OFF, shows='the gate opens')", "run.hazard(NONE, shows='pulses')",
                                "run.check(ON)"])
    result = run_scenario(load(script), out=tmp_path / "out")
    data = json.loads((tmp_path / "out" / "result.json").read_text())
    assert data["verdict"] == result.verdict == "HAZARD MISSED"
    assert data["hazards"] == [{"check": "gate never on", "shows": "the gate opens", "shown": True},
                               {"check": "no step pulses", "shows": "pulses", "shown": False}]
    assert [(c["name"], c["outcome"], c["verdict"], c["hazard"]) for c in data["checks"]] == [
        ("gate never on", "FAIL", "HAZARD SHOWN", "the gate opens"),
        ("no step pulses", "UNCHECKED", "HAZARD MISSED", "pulses"),
        ("gate within 0..1", "PASS", "PASS", None)]
    assert data["summary"] == {"checks": 3, "passed": 1, "failed": 0, "unchecked": 0, "hazards": 2,
                               "hazards_shown": 1}
    assert data["checks"][0]["violations"][0]["t_ns"] == 100  # the hazard shown where the gate opened


def test_a_hazard_must_say_what_it_shows(tmp_path: Path) -> None:
    result = run_scenario(load(_script(tmp_path, ["run.hazard(OFF, shows=' ')"])))
    assert result.verdict == "ERROR" and result.error_kind == "configuration"
    assert "run.hazard(shows=''): say in one line what the hazard is" in str(result.error)


# -- --until ----------------------------------------------------------------------------------------------------

def test_until_shorter_than_the_phases_is_refused_naming_scenario_value_and_minimum(
        tmp_path: Path) -> None:
    """pokeys_jog_limit jogs to 500 ms before it stops the jog: 100 ms would silently run to 500 ms."""
    assert main(["run", "pokeys_jog_limit", "--until", "100 ms", "--out", str(tmp_path / "out")]) == 2
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    assert result["verdict"] == "ERROR" and result["simulated_s"] == 0
    assert result["error"].endswith("scenario pokeys_jog_limit: until = 0.1 s is not allowed (allowed: at least "
                                    "0.5 s: the scenario runs in phases to that time)")


@pytest.mark.parametrize(("until", "allowed"), [("5", 'a time with a unit: did you mean "5 s"?'),
                                               ("nan", "a finite time > 0 with a unit, e.g. '20 ms'"),
                                               ("inf", "a finite time > 0 with a unit, e.g. '20 ms'")])
def test_until_without_a_unit_or_not_finite_is_refused_with_what_is_allowed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], until: str, allowed: str) -> None:
    assert main(["run", "laser_pwm", "--until", until, "--out", str(tmp_path / "out")]) == 2
    assert f"until = '{until}' is not allowed (allowed: {allowed})" in capsys.readouterr().err


def test_until_stops_a_scenario_that_ends_on_its_own_and_says_the_job_was_cut_short() -> None:
    """trio_example runs its passes to the end (4.4 s by default); --until 50 ms stops it at 50 ms."""
    result = run_scenario(load("trio_example"), overrides={"laser": "false"}, until="50 ms")
    assert result.simulated_s == 0.05 and result.until == 50_000_000
    assert result.notes == ["the run ended at 0.05 s (until) before the passes ended: checks of the whole job do "
                            "not hold for the part simulated"]
    assert result.verdict == "FAIL" and "job_s" not in result.figures  # whole-job checks fail, they do not pass
    failed = [c["name"] for c in result.checks if not c["passed"]]
    assert failed == ["gate edges at the exact step counts, forward (GT) and reverse (LT)", "the axis is back at 0"]


def test_the_main_job_fails_on_any_run_not_as_declared_and_shows_hazards_in_its_table() -> None:
    from cosim.mainjob import exit_status, summary_table
    from cosim.runner import Result

    def result(name: str, *checks: tuple[bool, int, str | None]) -> Result:
        return Result(name, {}, 0, 1000, checks=[
            {"name": f"c{k}", "passed": ok, "checked": 1, "n_violations": n, "violations": [], "measured": {},
             "hazard": shows} for k, (ok, n, shows) in enumerate(checks)])

    passed, shown = result("a", (True, 0, None)), result("b", (False, 2, "h"), (True, 0, None))
    missed, failed, unchecked = result("c", (True, 0, "h")), result("d", (False, 1, None)), result("e")
    assert [r.verdict for r in (passed, shown, missed, failed, unchecked)] == [
        "PASS", "HAZARD SHOWN", "HAZARD MISSED", "FAIL", "UNCHECKED"]
    assert exit_status([passed, shown]) == 0
    assert [exit_status([passed, shown, bad]) for bad in (missed, failed, unchecked)] == [1, 1, 1]
    lines = summary_table([passed, shown, unchecked]).splitlines()[2:]
    assert [line.split()[:3] for line in lines] == [["a", "PASS", "1/1"], ["b", "HAZARD", "SHOWN"],
                                                    ["e", "UNCHECKED", "0/0"]]
    assert " 1/1h 1/1 " in lines[1]
