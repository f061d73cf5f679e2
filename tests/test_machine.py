"""Machine files: one TOML file per machine, run like a bundled scenario, every bad key refused before the run.

    mill.toml ──load──> MachineFile ──run_scenario──> result.json, trace, report entry (like a scenario)
                 └─ --set KEY=VALUE by dotted key or unique last part
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.machine import load_machine
from cosim.machine.check import check_machine
from cosim.runner import run_scenario

pytestmark = pytest.mark.fmu

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
MILL = EXAMPLES / "pokeys_mill" / "mill.toml"

TRIO = """
[machine]
description = "the TN20-81 program on a EURO205X"
until = "900 ms"

[controller]
family = "trio"

[job]
check = false  # tn20_81.bas repeats its two passes until stopped: the job never ends

[[program]]
file = "tn20_81.bas"

[plant.laser]
model = "Laser"
preset = "laser_co2_40w"
laser = { axis = 3 }

[[check]]
type = "EdgeAtPosition"
signal = "trio.axis3.gate"
position_signal = "trio.axis3.step"
expected = [[1761, 1], [1841, 0], [3121, 1], [3521, 0]]
tol_counts = 0

[[figure]]
name = "energy_J"
output = "laser.energy"
unit = "J"
"""


@pytest.fixture
def trio_machine(tmp_path: Path) -> Path:
    from cosim.controllers.trio.basic import EXAMPLES as TRIO_EXAMPLES

    shutil.copy(TRIO_EXAMPLES / "tn20_81.bas", tmp_path / "tn20_81.bas")
    path = tmp_path / "engraver.toml"
    path.write_text(TRIO)
    return path


def test_the_pokeys_mill_example_runs_like_a_scenario_and_passes(tmp_path: Path) -> None:
    result = run_scenario(load_machine(MILL), out=tmp_path / "out")
    assert result.verdict == "PASS" and len(result.checks) == 10, result.table()  # 9 + the job completed
    assert result.figures["pulses"]["value"] == 33_600  # 2 x 2 mm plunge + 4 x 20 mm sides at 400 pulses/mm
    assert (tmp_path / "out" / "result.json").is_file() and (tmp_path / "out" / "trace.vcd").is_file()


def test_set_by_unique_last_key_part_changes_the_job_time(tmp_path: Path) -> None:
    """x limited to 12 kHz: the two 8000-pulse x sides take longer, so the job ends later."""
    fast = run_scenario(load_machine(MILL))
    slow = run_scenario(load_machine(MILL), overrides={"x.max_speed_hz": "12000", "until": '"3 s"'})
    assert slow.parameters["controller"]["axis"]["x"]["max_speed_hz"] == 12_000
    assert slow.figures["job_done_ms"]["value"] > fast.figures["job_done_ms"]["value"] + 100


def test_a_trio_program_runs_from_its_text_with_a_laser_coupled_by_the_machine_file(trio_machine: Path) -> None:
    result = run_scenario(load_machine(trio_machine))
    assert result.verdict == "PASS", result.table()
    assert result.figures["energy_J"]["value"] > 0


def test_a_program_given_on_the_command_line_replaces_the_machine_programs(trio_machine: Path,
                                                                          tmp_path: Path) -> None:
    program = tmp_path / "other.bas"
    program.write_text((trio_machine.parent / "tn20_81.bas").read_text())
    # the machine's [job] check = false is said of its own programs: the job of other.bas is checked
    assert main(["run", str(program), "--machine", str(trio_machine), "--out", str(tmp_path / "o")]) == 1
    result = json.loads((tmp_path / "o" / "result.json").read_text())
    assert result["checks"][0]["name"] == "the trio job completed" and result["checks"][0]["outcome"] == "FAIL"
    assert ("engraver.toml says [job] check = false of its own programs; the job of other.bas is checked "
            "(--set job.check=false to leave it unchecked)") in result["notes"]
    assert main(["run", str(program), "--machine", str(trio_machine), "--set", "job.check=false",
                 "--out", str(tmp_path / "o2")]) == 0  # it repeats for ever, as the user says
    assert main(["run", str(program), "--out", str(tmp_path / "o")]) == 2  # a program needs its machine


def test_check_machine_builds_without_running(trio_machine: Path) -> None:
    line = check_machine(load_machine(trio_machine))
    assert "OK: a trio machine with 1 plant(s), 1 check(s), 5 figure(s)" in line  # 4 of the family, 1 declared


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace('preset = "laser_co2_40w"', 'preset = "laser_co2_40w"\npresett = 1'),
     r"engraver.toml: plant.laser.presett is not a key of plant.laser; did you mean preset\?"),
    (lambda t: t.replace('family = "trio"', 'family = "trrio"'),
     r"engraver.toml: controller.family: value = 'trrio' is not allowed \(allowed: pmac, pokeys, trio\)"),
    (lambda t: t.replace('model = "Laser"', 'fmu = "missing.fmu"'),
     r"engraver.toml: plant.laser.fmu: FMU file .*missing.fmu does not exist"),
    (lambda t: t.replace('model = "Laser"', 'fmu = "tn20_81.bas"'),  # a file that is there, but not an FMU
     r"engraver.toml: plant.laser.fmu: .*tn20_81.bas is not an FMU: fmu = takes an .fmu file"),
    (lambda t: t.replace("laser = { axis = 3 }", 'laser = { axis = 3, variables = { mark_clocks = "pwm_onn" } }'),
     r"plant.laser.laser: laser coupling of laser: role 'mark_clocks' is mapped to 'pwm_onn', which laser does "
     r"not have; did you mean pwm_on"),
    (lambda t: t.replace("laser = { axis = 3 }", "laser = { axis = 1 }"),
     r"plant.laser.laser.axis: PWM axis = 1 is not allowed \(allowed: 2, 3"),
    (lambda t: t.replace('type = "EdgeAtPosition"', 'type = "EdgeAtPositon"'),
     r"check\[0\].type: value = 'EdgeAtPositon' is not allowed \(allowed: Bound, DirectionSetup, Duration"),
    (lambda t: t.replace("tol_counts = 0\n", ""), r"check\[0\].tol_counts is missing \(required by EdgeAtPosition\)"),
    (lambda t: t.replace('until = "900 ms"', ""), r"engraver.toml: machine.until is missing"),
    (lambda t: t.replace('file = "tn20_81.bas"', 'file = "nothere.bas"'), r"program\[0\].file: .*nothere.bas"),
    (lambda t: t.replace("[controller]", "[controller\n"), r"engraver.toml:6: not a valid TOML machine file: .*line 6"),
    (lambda t: t + '\n[[stimulus]]\nsignal = "trio.in.99"\nat = ["0 ms"]\nvalues = [1]\n',
     r"stimulus\[0\].signal = 'trio.in.99' is not allowed"),
])
def test_bad_machine_files_are_refused_with_file_key_and_allowed_values(trio_machine: Path, edit: object,
                                                                        message: str) -> None:
    trio_machine.write_text(edit(TRIO))  # type: ignore[operator]
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(trio_machine))


def test_bad_input_through_the_cli_exits_2_and_runs_nothing(trio_machine: Path, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    trio_machine.write_text(TRIO.replace("laser = { axis = 3 }", 'laser = { axis = 3, variables = { gate = "g" } }'))
    assert main(["check-machine", str(trio_machine)]) == 2
    assert "role 'gate' is mapped to 'g'" in capsys.readouterr().err
    assert main(["run", str(trio_machine), "--out", str(tmp_path / "o")]) == 2
    assert main(["run", str(MILL), "--set", "max_speed_hz=1", "--out", str(tmp_path / "o")]) == 2
    assert "is ambiguous: it could be controller.axis.x.max_speed_hz" in capsys.readouterr().err


def test_set_writes_a_new_key_by_its_whole_dotted_path(trio_machine: Path) -> None:
    machine = load_machine(trio_machine)
    values = machine.resolve({"controller.axis.3.SPEED": "500", "machine.until": "2 s"})
    assert values["controller"]["axis"] == {"3": {"SPEED": 500}} and values["machine"]["until"] == "2 s"
    with pytest.raises(ConfigurationError, match=r"--set SPED: the machine file has no key 'SPED'"):
        machine.resolve({"SPED": "500"})


def test_set_reaches_a_key_of_an_array_of_tables_by_the_name_params_shows(trio_machine: Path) -> None:
    """`cosim params` lists check[0].tol_counts ("set any with --set"): --set used to refuse it (no key)."""
    machine = load_machine(trio_machine)
    assert "check[0].tol_counts" in [p.name for p in machine.parameters]  # what params and sweeps offer
    assert machine.resolve({"check[0].tol_counts": "2"})["check"][0]["tol_counts"] == 2
    assert machine.resolve({"tol_counts": "3"})["check"][0]["tol_counts"] == 3  # a unique last part, as elsewhere
    named = machine.resolve({"check[0].name": '"gate edges"'})  # a new key of a table that is there
    assert named["check"][0]["name"] == "gate edges"
    assert machine.document["check"][0]["tol_counts"] == 0  # the file's own document is not changed
    with pytest.raises(ConfigurationError, match=r"--set check\[3\].tol_counts: the machine file has no key"):
        machine.resolve({"check[3].tol_counts": "1"})
    # a last part found in a table and in an array of tables means the table's, as before arrays were reachable
    trio_machine.write_text(TRIO + '\n[[check]]\ntype = "IntervalsAbove"\nsignal = "trio.wdog"\nlimit = 0\n'
                                   'until = "1 ms"\n')
    assert load_machine(trio_machine).resolve({"until": '"2 s"'})["machine"]["until"] == "2 s"


@pytest.mark.parametrize("example", ["trio_tn20_81_fmu/tn20_81.toml", "pokeys_mill/mill.toml"])
def test_a_trio_or_pokeys_machine_does_not_import_the_pmac_servo_design(example: str) -> None:
    """python-control (and with it scipy and matplotlib) was imported by every machine build: seconds of
    start-up, and 60 MB of wheels in every exported FMU (docs/export.md: 'numpy is the largest')."""
    import subprocess
    import sys

    code = ("import sys\nfrom cosim.machine import load_machine\nfrom cosim.machine.check import check_machine\n"
            f"check_machine(load_machine({str(EXAMPLES / example)!r}))\n"
            "print(sorted(m for m in ('control', 'scipy', 'matplotlib') if m in sys.modules))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
