"""The bundled laser scenario from the command line: results on disk, --set, range errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import vcdvcd

from cosim.cli import main

pytestmark = pytest.mark.fmu


def run(tmp_path: Path, *args: str) -> tuple[int, dict]:
    out = tmp_path / "out"
    status = main(["run", "laser_pwm", "--out", str(out), *args])
    result = json.loads((out / "result.json").read_text()) if (out / "result.json").exists() else {}
    return status, result


def test_runs_and_writes_json_vcd_and_tables(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, result = run(tmp_path)
    assert status == 0
    assert result["verdict"] == "PASS" and result["summary"] == {"checks": 3, "passed": 3, "failed": 0, "unchecked": 0,
                                                             "hazards": 0, "hazards_shown": 0}
    assert "PASS  energy equals the closed form (1e-9 relative)" in capsys.readouterr().out
    assert {p.name for p in (tmp_path / "out").iterdir()} >= {"result.json", "trace.vcd", "trace_digital.vcd",
                                                              "trace.gtkw", "edges.parquet", "values.parquet"}
    vcd = vcdvcd.VCDVCD(str(tmp_path / "out" / "trace.vcd"))
    gate = next(s for s in vcd.signals if s.endswith("gate"))
    assert [t for t, v in vcd[gate].tv if v == "1"] == [100_000, 3_100_000]  # ns: 0.1 ms and 0.1 + 2 + 1 ms


def test_set_changes_the_result(tmp_path: Path) -> None:
    _, default = run(tmp_path)
    status, half = run(tmp_path, "--set", "pwm_on=200", "--set", "fmi_version=2")
    assert status == 0
    assert half["parameters"]["pwm_on"] == 200
    assert half["figures"]["energy_J"]["value"] == pytest.approx(default["figures"]["energy_J"]["value"] / 2,
                                                                 rel=0.01)


def test_out_of_range_parameter_exits_2_naming_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _ = run(tmp_path, "--set", "pwm_on=70000")
    assert status == 2
    assert "parameter pwm_on = 70000 is not allowed (allowed: 0..65535 clocks)" in capsys.readouterr().err


def test_unknown_fmu_variable_in_a_script_names_file_and_line(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    script = tmp_path / "badvar.py"
    script.write_text('"""Bad variable."""\nfrom cosim.signals import Signal\nPARAMETERS = ()\nUNTIL = "1 ms"\n\n\n'
                      'def scenario(run):\n    laser = run.plant("Laser", name="laser")\n'
                      '    laser.drive("gat", Signal(run.sim, "ctl.gate"))\n')
    assert main(["run", str(script), "--out", str(tmp_path / "out")]) == 2
    assert f"{script}:9: laser (Laser.fmu) has no variable named 'gat'; did you mean gate?" in capsys.readouterr().out
