"""The PMAC example machines run from their text through the machine file, as ``cosim run`` does.

    examples/pmac_flying_shear/shear.toml        the Turbo manual's triggered move, with the dummy read
    examples/pmac_flying_shear/shear_stale.toml  without it, on a lightly loaded controller: the hazard
    examples/pmac_external_time_base/line.toml   the PMAC User Manual's SF 2048 at 64 counts/ms = 100 %

Web: 200,000 counts/m at 1.28 m/s = 256 counts/ms; marks at 0.0200071 m + k * 0.05 m, i.e. at 4001.42,
14001.42, ... counts; the program freezes the entry at the first servo cycle after 30 ms.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.machine import load_machine
from cosim.runner import run_scenario

pytestmark = pytest.mark.fmu

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SHEAR = EXAMPLES / "pmac_flying_shear"


def test_the_manual_triggered_move_starts_at_the_captured_mark_position(tmp_path: Path) -> None:
    result = run_scenario(load_machine(SHEAR / "shear.toml"), out=tmp_path / "out")
    assert result.verdict == "PASS", result.table()
    figures = {name: f["value"] for name, f in result.figures.items()}
    assert figures["triggered_starts"] == 1 and figures["stale_starts"] == 0
    assert 0 <= 14001.42 - figures["time_zero_counts"] < 1 / 256  # truncated to 1/256 count
    assert figures["motor1_final_cmd"] == 0  # the cut and the return both ran


def test_without_the_dummy_read_a_light_load_starts_from_the_stale_capture(capsys: pytest.CaptureFixture[str],
                                                                          tmp_path: Path) -> None:
    assert main(["run", str(SHEAR / "shear_stale.toml"), "--out", str(tmp_path / "o")]) == 0  # HAZARD SHOWN: 0
    out = capsys.readouterr().out
    assert "scenario pmac_flying_shear_stale: HAZARD SHOWN  (2/2 hazards shown, " in out
    assert "HAZARD SHOWN  time zero = the web's position at mark 2 (1/256 count)  [1 checked, 1 violations]" in out
    assert "HAZARD SHOWN  no triggered start from a stale capture  [" in out
    assert "hazard: no dummy read after the freeze: time zero is the stale capture of mark 1 (4001.42 counts)" in out
    assert "at t=120000000 ns: value 4001.41796875 vs limit 14001.4" in out  # mark 1 (1/256 count), not mark 2
    assert "figure stale_starts = 1" in out
    result = json.loads((tmp_path / "o" / "result.json").read_text())
    assert result["verdict"] == "HAZARD SHOWN" and [h["shown"] for h in result["hazards"]] == [True, True]
    healthy = {t["name"] for t in tomllib.loads((SHEAR / "shear.toml").read_text())["check"]}
    assert {h["check"] for h in result["hazards"]} <= healthy  # shear.toml's own rules, which pass there


@pytest.mark.parametrize("machine", ["shear.toml", "shear_stale.toml"])
def test_the_examples_check_without_running(machine: str) -> None:
    from cosim.machine.check import check_machine

    assert "OK: a pmac machine with 2 plant(s)" in check_machine(load_machine(SHEAR / machine))


def test_the_user_manual_external_time_base_is_100_percent_at_64_counts_per_ms(tmp_path: Path) -> None:
    result = run_scenario(load_machine(EXAMPLES / "pmac_external_time_base" / "line.toml"))
    assert result.verdict == "PASS", result.table()
    assert abs(result.figures["final_percent"]["value"] - 100) <= 100 * 2 * 2048 / 3_713_707
