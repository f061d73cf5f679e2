"""Bad input is found before anything runs, named by file and key (or line), and exits 2 without a traceback.

    machine file ──load──> [machine] until, NaN anywhere, duplicate keys
                 ──build─> every key (did you mean), every signal a check or figure names, every time's unit
    script ──compile──> its encoding ──run──> a figure that is not a number, a custom check that raises:
                                              reported at the user's line
    sweep ──plan──> every grid and random value against its declared range, and --out, before the first run
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.machine import load_machine
from cosim.machine.check import check_machine
from cosim.runner import run_scenario
from cosim.scenario import load

MACHINE = """
[machine]
until = "900 ms"

[controller]
family = "trio"

[[program]]
file = "tn20_81.bas"

[plant.laser]
model = "Laser"
preset = "laser_co2_40w"
laser = { axis = 3 }

[[check]]
type = "PulsesPerWindow"
signal = "trio.axis3.step"
max_count = 25
window = "1 ms"

[[figure]]
name = "energy_J"
output = "laser.energy"
unit = "J"
"""


@pytest.fixture
def machine(tmp_path: Path) -> Path:
    from cosim.controllers.trio.basic import EXAMPLES as TRIO_EXAMPLES

    shutil.copy(TRIO_EXAMPLES / "tn20_81.bas", tmp_path / "tn20_81.bas")
    path = tmp_path / "m.toml"
    path.write_text(MACHINE)
    return path


@pytest.mark.fmu
@pytest.mark.parametrize(("old", "new", "message"), [
    # a check on a misspelt signal used to pass check-machine and end as an ERROR after the whole run
    ('signal = "trio.axis3.step"', 'signal = "trio.axis3.stp"',
     r"m.toml: check\[0\].signal: no signal named 'trio.axis3.stp' in this machine; did you mean trio.axis3.step"),
    # max_cnt used to be reported as "max_count is missing"
    ("max_count = 25", "max_cnt = 25",
     r"m.toml: check\[0\].max_cnt is not a key here; did you mean max_count\? \(the keys of a PulsesPerWindow check"),
    ('window = "1 ms"', "window = 1000000",
     r"m.toml: check\[0\].window: time = 1000000 is not allowed \(allowed: a time with a unit, e.g. \"40 us\"; did "
     r"you mean \"1000000 ms\"\?\)"),
    ('window = "1 ms"', 'window = "1 msec"',
     r"m.toml: check\[0\].window: unit of time = 'msec' is not allowed \(allowed: s, ms, us"),
    # until = 5 used to be 5 ns: check-machine said OK and the run exited 4
    ('until = "900 ms"', "until = 5", r"m.toml: machine.until = 5 is not allowed \(allowed: a time with a unit: did "
                                      r"you mean \"5 s\"\?\)"),
    ('until = "900 ms"', 'until = "5 sec"',
     r"m.toml: unit of machine.until = 'sec' is not allowed \(allowed: s, ms, us"),
    ('until = "900 ms"', 'until = "900 ms"\nuntil = "1 s"',
     r"m.toml:4: machine.until is given twice \(a key may appear once in a TOML file; the second is on line 4: "
     r"until = \"1 s\"\)"),
    ('preset = "laser_co2_40w"', 'preset = "laser_co2_40w"\npreset = "x"', r"m.toml:14: plant.laser.preset is given "
                                                                        r"twice"),
    ("[plant.laser]", "[plant.laser]\nparameters = { tau_rise = nan }",
     r"m.toml: plant.laser.parameters.tau_rise = nan is not allowed \(allowed: a finite number\)"),
    ("[plant.laser]", "[plant.laser]\nparameters = { tau_rise = -1.0 }",
     r"(?s)m.toml: plant.laser.parameters: the FMU refused a start value: .*tau_rise = -1 s is not allowed"),
    ('output = "laser.energy"', 'signal = "laser.energy"',
     r"m.toml: figure\[0\].signal: laser.energy is an output of plant laser that is not recorded: record it with "
     r"record = \{ variables = \[\"energy\"\], period = \"1 ms\" \} in \[plant.laser\]"),
    ('name = "energy_J"', 'nme = "energy_J"', r"m.toml: figure\[0\].nme is not a key here; did you mean name\?"),
])
def test_check_machine_finds_it_before_anything_runs(machine: Path, old: str, new: str, message: str,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    machine.write_text(MACHINE.replace(old, new, 1))
    assert main(["check-machine", str(machine)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(machine))


@pytest.mark.fmu
def test_a_signal_another_axis_has_may_still_be_declared_during_the_run(machine: Path) -> None:
    """trio.axis1.step exists once a program sets ATYPE on axis 1: a check on it is not refused before the run."""
    machine.write_text(MACHINE.replace('signal = "trio.axis3.step"', 'signal = "trio.axis1.step"'))
    assert "OK: a trio machine" in check_machine(load_machine(machine))


POKEYS = """
[machine]
until = "100 ms"

[controller]
family = "pokeys"

[[move]]
target = [2000, 0, 0]

[[check]]
type = "PulsesPerWindow"
signal = "pokeys.x.step"
max_count = 25
window = "1 ms"
"""


@pytest.mark.parametrize(("old", "new", "message"), [
    # a PoKeys machine declares all its axes when it is built: an unknown one is not "another axis, later"
    ('signal = "pokeys.x.step"', 'signal = "pokeys.q.step"',
     r"t.toml: check\[0\].signal: no signal named 'pokeys.q.step' in this machine; did you mean"),
    # a signal given as a list used to pass check-machine and break the check after the run (TypeError)
    ('signal = "pokeys.x.step"', 'signal = ["pokeys.x.step"]',
     r"t.toml: check\[0\].signal: a signal name is text, not \['pokeys.x.step'\]"),
    ('type = "PulsesPerWindow"\nsignal = "pokeys.x.step"\nmax_count = 25\nwindow = "1 ms"',
     'type = "EnergyPerLength"\nsignal = "pokeys.x.position"\npositions = "pokeys.x.position"\nlower = 0\nupper = 1',
     r"t.toml: check\[0\]: EnergyPerLength\(pokeys.x.position\): positions = 'pokeys.x.position' is not allowed "
     r"\(allowed: a list of position signals"),
    # a signal of the wrong kind for its check or figure used to be found after the whole run (ERROR, exit 1;
    # a figure's said "no signal named 'pokeys.x.step' ...; did you mean pokeys.x.step")
    ('type = "PulsesPerWindow"\nsignal = "pokeys.x.step"\nmax_count = 25\nwindow = "1 ms"',
     'type = "Bound"\nsignal = "pokeys.x.step"\nupper = 1',
     r"t.toml: check\[0\]: Bound\(pokeys.x.step\): signal pokeys.x.step is a pulse signal; this check needs a bit "
     r"or int or real signal"),
    ('type = "PulsesPerWindow"\nsignal = "pokeys.x.step"', 'type = "PulsesPerWindow"\nsignal = "pokeys.x.position"',
     r"t.toml: check\[0\]: PulsesPerWindow\(pokeys.x.position\): signal pokeys.x.position is a int signal; this "
     r"check needs a pulse signal"),
    ("[[check]]", '[[figure]]\nname = "peak"\nsignal = "pokeys.x.step"\nreduce = "max"\n\n[[check]]',
     r"t.toml: figure\[0\].reduce: reduce = 'max' reads a value; pokeys.x.step is a pulse train \(use reduce = "
     r"\"pulses\""),
    ("[[check]]", '[[figure]]\nname = "net"\nsignal = "pokeys.x.position"\nreduce = "pulses"\n\n[[check]]',
     r"t.toml: figure\[0\].reduce: reduce = 'pulses' counts the pulses of a pulse train; pokeys.x.position is a "
     r"int signal"),
])
def test_check_machine_finds_a_signal_no_run_can_have(tmp_path: Path, old: str, new: str, message: str,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    machine = tmp_path / "t.toml"
    machine.write_text(POKEYS.replace(old, new, 1))
    assert main(["check-machine", str(machine)]) == 2
    assert "Traceback" not in capsys.readouterr().err
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(machine))


@pytest.mark.fmu
def test_until_given_by_set_is_checked_like_the_file(machine: Path, tmp_path: Path,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", str(machine), "--set", "until=5", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert 'machine.until = 5 is not allowed (allowed: a time with a unit: did you mean "5 s"?)' in err
    assert not (tmp_path / "o").exists()
    assert main(["run", "laser_pwm", "--until", "5", "--out", str(tmp_path / "o")]) == 2
    assert 'until = \'5\' is not allowed (allowed: a time with a unit: did you mean "5 s"?)' in capsys.readouterr().err


def test_a_script_that_is_not_utf8_is_refused_with_its_file_and_line(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    script = tmp_path / "latin1.py"
    script.write_bytes('"""Caf\xe9 scenario."""\n\ndef scenario(run):\n    pass\n'.encode("latin-1"))
    assert main(["run", str(script), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"{script}:1: not UTF-8 text: 'utf-8' codec can't decode byte 0xe9" in err and "Traceback" not in err
    script.write_bytes(b"# -*- coding: latin-1 -*-\n" + script.read_bytes())  # declared: Python reads it
    assert load(script).description == "Caf\xe9 scenario."


def test_a_nan_for_a_float_parameter_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "laser_pwm", "--set", "gate_ms=nan", "--out", str(tmp_path / "o")]) == 2
    assert "parameter gate_ms = 'nan' is not a number" in capsys.readouterr().err


def test_an_output_folder_under_a_file_is_refused_before_the_run(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "afile").write_text("")
    assert main(["run", "laser_pwm", "--out", str(tmp_path / "afile" / "out")]) == 2
    assert f"{tmp_path / 'afile'} is a file, not a folder" in capsys.readouterr().err
    assert main(["sweep", "laser_pwm", "--grid", "pwm_on=1,2", "--workers", "0",
                 "--out", str(tmp_path / "afile" / "sweep")]) == 2
    assert f"{tmp_path / 'afile'} is a file, not a folder" in capsys.readouterr().err


def test_a_sweep_checks_every_value_before_the_first_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--grid pwm_on=1,70000 used to run both, then report pwm_on=nan and store NaN in sweep.parquet."""
    out = tmp_path / "sweep"
    assert main(["sweep", "laser_pwm", "--grid", "pwm_on=1,70000", "--workers", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "sweep run 1 (pwm_on=70000): parameter pwm_on = 70000 is not allowed (allowed: 0..65535 clocks)" in err
    assert not out.exists()  # nothing ran, nothing written


SCRIPT = '''"""Figures and checks that break."""
from cosim.checks.result import CheckResult
from cosim.scenario import Run

UNTIL = "1 ms"


class Broken:
    name = "my rule"

    def evaluate(self, trace):
        limit = 0
        return CheckResult("my rule", True, 1 // limit, 0)


def scenario(run: Run) -> None:
    run.check(Broken())
    run.figure("label", lambda: "abc")
'''


def test_a_figure_that_is_not_a_number_and_a_check_that_raises_name_the_users_lines(tmp_path: Path) -> None:
    script = tmp_path / "broken.py"
    script.write_text(SCRIPT)
    result = run_scenario(load(script))
    assert result.verdict == "ERROR"
    assert result.checks[0]["error"] == f"{script}:13: check my rule: ZeroDivisionError: integer division or modulo " \
                                        "by zero"  # the line that raised, not the run.check line (17)
    assert result.figures["label"]["error"] == f"{script}:18: figure label: TypeError: the value 'abc' is a str, " \
                                               "not a number"
