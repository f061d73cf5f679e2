"""A Turbo PMAC project as users keep it loads and runs (issue 27): ``examples/pmac_project``.

    web mark 2 (54.7 ms)  ____|‾|____   CS 1: frozen at 30 ms, armed by PLC 1, cut starts at the mark
    watchdog (PLC 2)      ^0   ^50.6   ^101.0 ms  (CS 2 timer 1: 113 servo cycles = 50.0 ms, counted down)
    PLC 3                               ^ CMD"&2 B2 R" after the third tick, once the web's entry runs
    CS 2 (kinematics)                   |--- (10,0) (10,10) (0,10) half circle (0,0) back to (10,0) --->
    pmac.job              1 from 30 ms ........................................................ 2 (DONE)
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cosim.machine import load_machine
from cosim.runner import Result, run_scenario

pytestmark = pytest.mark.fmu

PROJECT = Path(__file__).resolve().parent.parent / "examples" / "pmac_project" / "project.toml"


@pytest.fixture(scope="module")
def project(tmp_path_factory: pytest.TempPathFactory) -> tuple[Result, Path]:
    """One run of the project for every test here (its results folder too)."""
    out = tmp_path_factory.mktemp("project") / "out"
    return run_scenario(load_machine(PROJECT), out=out), out


def test_the_project_runs_its_two_coordinate_systems_and_three_plcs(project: tuple[Result, Path]) -> None:
    result, out = project
    assert result.verdict == "PASS", result.table()
    figures = {name: f["value"] for name, f in result.figures.items()}
    assert figures["triggered_starts"] == 1 and figures["stale_starts"] == 0
    assert figures["job_state"] == 2  # DONE: both motion programs reached their ends
    console = (out / "console.txt").read_text().splitlines()
    ticks = [line for line in console if "[pmac.plc2]  WATCHDOG TICK" in line]
    assert [line.split()[0] for line in ticks[:3]] == ["0.000000", "50.600000", "101.000000"]
    assert any("[pmac.plc3]  TABLE STARTED" in line and line.split()[0] == "101.000000" for line in console)


def test_the_report_lists_what_was_set_but_not_modelled(project: tuple[Result, Path]) -> None:
    result, out = project
    listed = {(item["name"], str(item["value"])) for item in result.not_modelled}
    assert ("I130", "2000") in listed and ("I430", "2000") in listed  # Ixx30 of motors 1 and 4 (I130,4,100=2000)
    assert ("I7043", "3") in listed
    assert not any(name == "I5" for name, _value in listed)  # I5=3 acts: PLC 0 and the background PLCs run
    assert ("M162->", "D:$00008B") in listed  # an M-variable on a register the model does not have
    where = {item["name"]: item["where"] for item in result.not_modelled}
    assert where["I130"].startswith("setup.pmc:") and where["I7043"].startswith("setup.pmc:")
    saved = json.loads((out / "result.json").read_text())
    assert len(saved["not_modelled"]) == len(result.not_modelled) > 100
