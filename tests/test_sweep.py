"""Sweeps: runs seeded from (sweep seed, index) only, same table with 1 or 2 workers, errors as rows."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

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
    assert table["verdict"].tolist() == ["PASS", "ERROR", "PASS"]
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
