"""Sweeps: runs seeded from (sweep seed, index) only, same table with 1 or 2 workers, errors as rows."""

from __future__ import annotations

import json
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import pandas as pd
import pytest

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.sweep import parse_grid, parse_random, plan, sweep

FLAKY = '''"""Fails for x = 2."""
from cosim.scenario import Param
PARAMETERS = (Param("x", 1, "", (0, 5), "the value"), Param("y", 0.5, "", (0.0, 1.0), "a level"))
UNTIL = "1 us"


def scenario(run):
    if run.p.x == 2:
        raise RuntimeError("x must not be 2")
    run.figure("twice_y", 2 * run.p.y)
'''


@pytest.fixture
def script(tmp_path: Path) -> str:
    path = tmp_path / "flaky.py"
    path.write_text(FLAKY)
    return str(path)


def test_plan_is_a_function_of_seed_and_index(script: str) -> None:
    runs = plan(script, grid={"x": [0, 1, 2]}, random={"y": None}, samples=4, seed=9)
    again = plan(script, grid={"x": [0, 1, 2]}, random={"y": None}, samples=4, seed=9)
    assert runs == again
    assert [r.index for r in runs] == list(range(12))
    assert [r.overrides["x"] for r in runs] == ["0"] * 4 + ["1"] * 4 + ["2"] * 4
    assert len({r.seed for r in runs}) == 12
    assert all(0.0 <= float(r.overrides["y"]) <= 1.0 for r in runs)
    assert plan(script, random={"y": None}, samples=4, seed=10)[0] != runs[0]


def test_random_integers_stay_in_range_and_bad_names_are_refused(script: str) -> None:
    runs = plan(script, random={"x": ("3", "5")}, samples=50)
    assert {int(r.overrides["x"]) for r in runs} == {3, 4, 5}
    with pytest.raises(ConfigurationError, match="the scenario has no parameter 'z'"):
        plan(script, grid={"z": [1]})
    with pytest.raises(ConfigurationError, match=r"parameter x = 9 is not allowed \(allowed: 0\.\.5\)"):
        plan(script, random={"x": ("0", "9")})


def test_a_broken_run_is_a_row_with_its_error(script: str) -> None:
    table = sweep(script, plan(script, grid={"x": [1, 2, 3]}), workers=0, progress=False)
    assert table["verdict"].tolist() == ["UNCHECKED", "ERROR", "UNCHECKED"]  # FLAKY declares no checks
    assert "x must not be 2" in table.loc[1, "error"]
    assert table["fig.twice_y"].tolist()[::2] == [1.0, 1.0]


def test_command_line_parsers() -> None:
    assert parse_grid(["pwm_on=1,2, 3"]) == {"pwm_on": ["1", "2", "3"]}
    assert parse_random(["a", "b=1:2"]) == {"a": None, "b": ("1", "2")}
    with pytest.raises(ConfigurationError, match="expected NAME=v1,v2"):
        parse_grid(["pwm_on"])


@pytest.mark.fmu
def test_same_table_with_one_and_two_workers(tmp_path: Path) -> None:
    runs = plan("laser_pwm", grid={"pwm_period": [200, 1000]}, random={"pwm_on": ("0", "1000")}, samples=3, seed=4)
    one = sweep("laser_pwm", runs, workers=1, progress=False)
    two = sweep("laser_pwm", runs, workers=2, progress=False, out=tmp_path)
    pd.testing.assert_frame_equal(one, two)
    assert len(one) == 6 and set(one["verdict"]) == {"PASS"}
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "sweep.parquet"), two)


TIMED = '''"""A gate of gate_ms, checked against a limit; fails with a reason for x = 3."""
from types import SimpleNamespace

from cosim.scenario import Param
PARAMETERS = (Param("gate_ms", 1.0, "ms", (0.001, 10.0), "gate time"), Param("x", 1, "", (0, 5), "a count"),
              Param("level", 0.5, "V", (0.0, 1.0), "a level"))
UNTIL = "1 us"


class AtMost:
    def __init__(self, value, limit):
        self.value, self.limit = value, limit

    def evaluate(self, trace):
        ok = self.value <= self.limit
        return SimpleNamespace(to_dict=lambda: {
            "name": f"x at most {self.limit} (a deliberately long check name)", "passed": ok, "checked": 1,
            "n_violations": int(not ok), "violations": [], "measured": {"max": self.value}})


def scenario(run):
    run.figure("gate_ticks", run.sim.ticks(run.p.gate_ms, "ms"), "ns")
    run.check(AtMost(run.p.x, 2))
    if run.p.x == 4:
        raise RuntimeError("x = 4 breaks the run")
'''


@pytest.fixture
def timed(tmp_path: Path) -> str:
    path = tmp_path / "timed.py"
    path.write_text(TIMED)
    return str(path)


def test_times_are_drawn_in_whole_ticks_and_integers_in_whole_numbers(timed: str) -> None:
    runs = plan(timed, random={"gate_ms": ("0.5", "3"), "x": None}, samples=40)
    gates = [Fraction(Decimal(r.overrides["gate_ms"])) for r in runs]
    assert all((g * 10**6).denominator == 1 for g in gates)  # 1 ns = 1e-6 ms
    assert all(Fraction(1, 2) <= g <= 3 for g in gates) and len(set(gates)) == 40
    assert {r.overrides["x"] for r in runs} <= {"0", "1", "2", "3", "4", "5"}
    level = plan(timed, random={"level": None}, samples=3)  # not a time: uniform, as it prints
    assert all(0.0 <= float(r.overrides["level"]) <= 1.0 for r in level)


def test_a_declared_step_gives_values_on_that_step(timed: str) -> None:
    runs = plan(timed, random={"gate_ms": ("0.5", "1.5", "0.25"), "x": ("1", "5", "2")}, samples=60)
    assert {r.overrides["gate_ms"] for r in runs} == {"0.5", "0.75", "1", "1.25", "1.5"}
    assert {r.overrides["x"] for r in runs} == {"1", "3", "5"}
    with pytest.raises(ConfigurationError, match=r"must be whole numbers of the time resolution \(1 ns\)"):
        plan(timed, random={"gate_ms": ("0.5", "1.5", "0.0000001")})
    with pytest.raises(ConfigurationError, match=r"step of x = 0.5 is not allowed \(allowed: > 0, whole\)"):
        plan(timed, random={"x": ("1", "5", "0.5")})
    assert parse_random(["gate_ms=0.5:1.5:0.25"]) == {"gate_ms": ("0.5", "1.5", "0.25")}
    with pytest.raises(ConfigurationError, match="NAME=LOW:HIGH:STEP"):
        parse_random(["gate_ms=0.5:1:2:3"])


def test_short_columns_a_legend_and_the_files_next_to_the_table(timed: str, tmp_path: Path) -> None:
    runs = plan(timed, grid={"x": [1, 3, 4]}, random={"gate_ms": ("1", "2")}, samples=1)
    table = sweep(timed, runs, workers=0, progress=False, out=tmp_path / "out")
    assert table.attrs["legend"] == {"c1": "x at most 2 (a deliberately long check name)"}
    assert table.attrs["swept"] == ["gate_ms", "x"]
    assert table["verdict"].tolist() == ["PASS", "FAIL", "ERROR"]
    assert table["c1.passed"].tolist()[:2] == [True, False]
    assert table["c1.max"].tolist()[:2] == [1, 3]
    assert table["failed"].tolist() == ["", "c1", ""]
    assert table["fig.gate_ticks"].tolist()[:2] == [int(Decimal(r.overrides["gate_ms"]) * 10**6) for r in runs[:2]]
    meta = json.loads((tmp_path / "out" / "sweep.json").read_text())
    assert meta["legend"] == table.attrs["legend"] and meta["verdicts"] == {"ERROR": 1, "FAIL": 1, "PASS": 1}
    assert meta["units"] == {"gate_ticks": "ns"}
    page = (tmp_path / "out" / "sweep.html").read_text()
    assert "gate_ticks vs gate_ms" in page and "gate_ticks vs x" in page
    assert "<script src=" not in page.replace("<script src=\"data:", "")  # Bokeh inlined: opens offline
    assert "x = 4 breaks the run" in page and "x at most 2 (a deliberately long check name)" in page


def test_the_command_line_says_why_runs_failed(timed: str, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    status = main(["sweep", timed, "--grid", "x=0,3,4,3,4,3,4,3", "--workers", "0", "--out", str(tmp_path)])
    assert status == 1  # a run broke
    out, err = capsys.readouterr()
    assert "8 runs in" in out and "3 ERROR, 4 FAIL, 1 PASS" in out
    lines = [line.strip() for line in out.splitlines()]
    assert "run 1 (x=3): FAIL  c1 x at most 2 (a deliberately long check name) (1 violation)" in lines
    assert "run 2 (x=4): ERROR  " + f"{timed}:25: RuntimeError: x = 4 breaks the run" in lines
    assert sum(line.startswith("run ") for line in lines) == 5
    assert "... and 2 more (column 'verdict', 'error' and 'failed' of the table)" in lines
    assert "c1 = x at most 2 (a deliberately long check name)" in lines
    # not a terminal: progress is plain lines, no carriage returns
    assert "\r" not in err and "sweep timed: 8/8 runs (3 ERROR, 4 FAIL, 1 PASS)" in err


@pytest.mark.fmu
def test_a_float_millisecond_parameter_sweeps_without_errors(tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    status = main(["sweep", "laser_pwm", "--random", "gate_ms=0.5:3", "--samples", "6", "--workers", "0",
                   "--out", str(tmp_path), "--no-report"])
    out = capsys.readouterr().out
    table = pd.read_parquet(tmp_path / "sweep.parquet")
    assert status == 0, out
    assert len(table) == 6 and set(table["verdict"]) == {"PASS"}
    assert len(set(table["p.gate_ms"])) == 6
    assert "6 runs in" in out and "6 PASS" in out


def test_hazard_runs_have_their_verdicts_per_check_and_only_a_missed_hazard_is_a_reason(tmp_path: Path) -> None:
    from cosim.sweep_report import reasons

    path = tmp_path / "hazard.py"
    path.write_text(TIMED.replace("run.check(AtMost(run.p.x, 2))", "run.hazard(AtMost(run.p.x, 2), shows='x > 2')"))
    table = sweep(str(path), plan(str(path), grid={"x": [1, 3]}), workers=0, progress=False)
    assert table["verdict"].tolist() == table["c1.verdict"].tolist() == ["HAZARD MISSED", "HAZARD SHOWN"]
    assert table["failed"].tolist() == ["c1", ""]
    assert reasons(table) == ["run 0 (x=1): HAZARD MISSED  c1 x at most 2 (a deliberately long check name) "
                              "(HAZARD MISSED: 0 violations)"]


MACHINE = """
[machine]
until = "40 ms"  # 100 steps at 5 kHz take 20 ms and the job must finish

[controller]
family = "pokeys"
[controller.axis.x]
max_speed_hz = 10000
accel = 10000000

[[move]]
target = [100, 0, 0]

[[check]]
type = "PulsesPerWindow"
signal = "pokeys.x.step"
max_count = 25
window = "1 ms"
"""


def test_a_machine_file_sweep_has_a_column_per_swept_key(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The swept key was missing from the table (whole tables as p.controller, ...) and the runs read 'run 0 ()'."""
    machine = tmp_path / "m.toml"
    machine.write_text(MACHINE)
    runs = plan(str(machine), grid={"controller.axis.x.max_speed_hz": ["5000", "10000"],
                                    "check[0].max_count": ["6", "25"]})
    table = sweep(str(machine), runs, workers=0, progress=False)
    assert table["p.controller.axis.x.max_speed_hz"].tolist() == [5000, 5000, 10000, 10000]
    assert table["p.check[0].max_count"].tolist() == [6, 25, 6, 25]
    assert table["verdict"].tolist() == ["PASS", "PASS", "FAIL", "PASS"]  # 5 or 10 pulses a 1 ms slot vs 6
    assert "p.controller" not in table.columns
    assert main(["sweep", str(machine), "--grid", "check[0].max_count=5", "--workers", "0", "--no-report",
                 "--out", str(tmp_path / "o")]) == 0  # a FAIL is a result of the sweep, not a broken run
    assert "run 0 (check[0].max_count=5): FAIL" in capsys.readouterr().out


def test_a_machine_key_out_of_its_range_is_refused_before_the_first_run(tmp_path: Path) -> None:
    """A PoKeys 56E steps at most 25 kHz: a sweep with 90 kHz in its grid is refused, naming the run, key and range."""
    machine = tmp_path / "m.toml"
    machine.write_text(MACHINE)
    with pytest.raises(ConfigurationError, match=r"sweep run 1 \(controller.axis.x.max_speed_hz=90000\).*"
                                                 r"max_speed_hz = 90000 is not allowed \(allowed: > 0..25000"):
        plan(str(machine), grid={"controller.axis.x.max_speed_hz": ["12000", "90000"]})
