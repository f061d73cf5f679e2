"""The command line's basics: --version, python -m cosim, shell completion, a list that imports nothing heavy,
FMU commands that say what they did, and progress output that suits pipes."""

from __future__ import annotations

import io
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import cosim
from cosim import fmubuild
from cosim.catalog import examples
from cosim.cli import COMMANDS, main
from cosim.kernel import Simulation
from cosim.runner import _close_progress_bar, _progress_bar
from cosim.scenario import bundled, description, load


def _cosim(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "cosim", *args], capture_output=True, text=True, cwd=cwd,
                          check=False)


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out == f"cosim {cosim.__version__}\n"


def test_python_m_cosim_lists_every_bundled_scenario_with_its_description(tmp_path: Path) -> None:
    done = _cosim("list", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert [line.split()[0] for line in lines] == bundled() + [str(p) for p in examples()]
    laser = next(line for line in lines if line.startswith("laser_pwm "))
    assert laser.split(None, 1)[1] == ("Laser PWM: a 40 W CO2 laser gated on twice by a scripted modulation "
                                       "source; energy checked in closed form.")


def test_list_reads_descriptions_without_importing_scenarios_or_fmpy() -> None:
    code = ("import sys, io, contextlib\n"
            "from cosim.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    main(['list'])\n"
            "heavy = sorted(m for m in sys.modules if m.split('.')[0] in ('fmpy', 'numpy', 'pandas', 'simpy')"
            " or m.startswith(('cosim_scenario_', 'cosim.kernel', 'cosim.master', 'cosim.controllers')))\n"
            "print(heavy)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_description_is_the_first_docstring_line_without_running_the_file(tmp_path: Path) -> None:
    script = tmp_path / "boom.py"
    script.write_text('"""Blinks a gate.\n\nMore text."""\nraise SystemExit("never run")\n')
    assert description(script) == "Blinks a gate."
    (tmp_path / "broken.py").write_text('"""Broken."""\ndef (:\n')
    assert description(tmp_path / "broken.py") == ""
    assert description("laser_pwm") == load("laser_pwm").description


def test_every_command_is_in_the_table_and_has_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    for command in COMMANDS:
        assert command.name in text


@pytest.mark.parametrize("shell", ["bash", "zsh", "tcsh"])
def test_completion_scripts_are_generated(shell: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["completion", shell]) == 0
    script = capsys.readouterr().out
    assert "build-fmus" in script and "sweep" in script and "laser_pwm" in script


@pytest.mark.skipif(shutil.which("bash") is None, reason="needs bash")
def test_bash_completes_commands_options_and_scenario_names(tmp_path: Path) -> None:
    script = tmp_path / "cosim.bash"
    done = _cosim("completion", "bash")
    script.write_text(done.stdout)
    (tmp_path / "mine.py").write_text("")

    def complete(*words: str) -> list[str]:
        line = " ".join(["cosim", *words])
        probe = (f"source {script}\nCOMP_WORDS=(cosim {' '.join(words)})\nCOMP_CWORD={len(words)}\n"
                 f"COMP_LINE='{line}'\nCOMP_POINT={len(line)}\n_shtab_cosim\nprintf '%s\\n' \"${{COMPREPLY[@]}}\"\n")
        result = subprocess.run(["bash", "-c", probe], capture_output=True, text=True, cwd=tmp_path, check=True)
        return sorted(result.stdout.split())

    assert complete("li") == ["list"]
    assert complete("sweep", "laser_p") == ["laser_pwm"]
    assert "mine.py" in complete("run", "mi")
    assert complete("sweep", "laser_pwm", "--wor") == ["--workers"]


def test_build_fmus_says_what_it_did(capsys: pytest.CaptureFixture[str]) -> None:
    fmubuild.ensure_fmu("Laser", 2)
    fmubuild.ensure_fmu("Laser", 3)
    assert main(["build-fmus", "Laser"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["up", "to", "date", "Laser", "FMI", "2.0", str(fmubuild.fmu_path("Laser", 2))]
    assert out[1].split()[-1] == str(fmubuild.fmu_path("Laser", 3))
    assert out[2] == f"0 built, 2 up to date in {fmubuild.MODELS_DIR} (sources: {fmubuild.SOURCE_DIR})"


def test_fmu_commands_refuse_a_missing_source_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(fmubuild, "SOURCE_DIR", tmp_path / "nothing")
    assert main(["build-fmus"]) == 2
    assert f"no plant sources in {tmp_path / 'nothing'}" in capsys.readouterr().err
    assert main(["check-fmus"]) == 2
    assert "nothing to check" in capsys.readouterr().err
    assert main(["build-fmus", "Lasr"]) == 2
    assert "no plant model named 'Lasr'" in capsys.readouterr().err


def test_installed_cosim_builds_into_a_per_user_cache(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    if sys.platform != "linux":
        pytest.skip("the XDG cache variable is how Linux names the per-user cache")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert fmubuild._cache_dir() == tmp_path / "cosim" / cosim.__version__ / "models"
    monkeypatch.setattr(fmubuild, "CHECKOUT", None)
    assert fmubuild.data_dir("models/presets", "presets") == fmubuild.PACKAGE_DIR / "_data" / "presets"


def test_platform_folder_is_fmpys() -> None:
    import platform

    if sys.platform != "linux" or platform.machine() != "x86_64":
        pytest.skip("the literal names below are those of x86-64 Linux")
    assert (fmubuild.platform_folder(2), fmubuild.platform_folder(3)) == ("linux64", "x86_64-linux")


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_no_progress_bar_when_stderr_is_not_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    with Simulation() as sim:
        assert _progress_bar(sim, sim.ticks("1 ms")) is None  # a pipe, a log, CI: no bar at all


def test_the_progress_bar_waits_two_seconds_and_ends_with_its_line(monkeypatch: pytest.MonkeyPatch) -> None:
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    with Simulation() as sim:
        end = sim.ticks("10 ms")
        bar = _progress_bar(sim, end)
        assert bar is not None and sim.env.on_progress is not None
        sim.env.on_progress(sim.ticks("1 ms"))
        assert terminal.getvalue() == ""  # a short run draws nothing
        bar.start_t -= 3.0  # as if three seconds of wall time had passed
        bar.last_print_t -= 3.0
        sim.env.on_progress(sim.ticks("5 ms"))
        assert "5.0/10.0 ms" in terminal.getvalue()
        sim.run(until=end)
        _close_progress_bar(bar, sim)
    shown = terminal.getvalue()
    assert shown.endswith("\n") and "100%" in shown.split("\r")[-1] and "10.0/10.0 ms" in shown.split("\r")[-1]


def test_run_says_which_files_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "laser_pwm", "--out", str(tmp_path / "out")]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == (f"results in {tmp_path / 'out'}/ (console.txt, edges.parquet, pulses.parquet, result.json, "
                    "segments.parquet, trace.gtkw, trace.vcd, trace_digital.vcd, trace_meta.json, values.parquet)")
    assert main(["run", "laser_pwm", "--out", str(tmp_path / "csv"), "--no-vcd", "--format", "csv"]) == 0
    assert ("(console.txt, edges.csv, pulses.csv, result.json, segments.csv, trace_meta.json, trace_wide.csv, "
            "values.csv)") in capsys.readouterr().out


EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.fmu
def test_params_of_a_machine_file_give_units_allowed_values_and_defaults(tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    """It used to say "any str" / "any int" for every key."""
    assert main(["params", str(EXAMPLES / "pokeys_mill" / "mill.toml")]) == 0
    rows = {line.split()[0]: " ".join(line.split()[1:]) for line in capsys.readouterr().out.splitlines()[4:]}
    assert rows["machine.until"] == '"2.5 s" time a time with a unit, e.g. "2 s"'
    assert rows["controller.model"] == '"56E" 56E, 56U, 57E, 57CNC'
    assert rows["controller.axis.x.max_speed_hz"] == "20000 Hz > 0, at most the model's rate (25 kHz on a 56E)"
    assert rows["host.prefill"] == "64 1..128"
    assert rows["check[0].window"] == '"1 ms" time a time with a unit'
    assert rows["job.check"] == "(true) true, false"  # a default: the file does not give it
    assert main(["params", str(EXAMPLES / "trio_engraver" / "engraver.toml")]) == 0
    rows = {line.split()[0]: " ".join(line.split()[1:]) for line in capsys.readouterr().out.splitlines()[4:]}
    assert rows["controller.servo_period_us"] == "1000 us 250, 500, 1000, 2000 (SERVO_PERIOD)"
    assert rows["plant.laser.record.period"] == '"100 us" time a time with a unit, e.g. "40 us"'
    assert rows["plant.stage_x.stepper.axis"] == "3 >= 0"
    (tmp_path / "p.bas").write_text("WA(10)\n")
    (tmp_path / "m.toml").write_text('[machine]\nuntil = "1 s"\n[controller]\nfamily = "trio"\n[controller.axis.3]\n'
                                     'UNITS = 16\n[[program]]\nfile = "p.bas"\n[plant.laser]\nmodel = "Laser"\n'
                                     'parameters = { tau_rise = 5e-5 }\nlaser = { axis = 3 }\n')
    assert main(["params", str(tmp_path / "m.toml")]) == 0
    rows = {line.split()[0]: " ".join(line.split()[1:]) for line in capsys.readouterr().out.splitlines()[4:]}
    assert rows["controller.axis.3.UNITS"] == "16 counts/unit > 0 (default 1): step pulses per user unit"
    assert rows["plant.laser.parameters.tau_rise"] == "5e-05 s any finite number (FMU parameter)"  # its unit, its range


def test_params_of_a_scenario_name_the_kind_of_an_unbounded_parameter(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["params", "trio_example"]) == 0
    assert "laser    True     \n" not in capsys.readouterr().out
    from cosim.scenario import Param

    assert [Param("n", 1).allowed(), Param("x", 0.5).allowed(), Param("s", "a").allowed(),
            Param("f", True).allowed()] == ["any integer", "any number", "any text", "true, false"]


@pytest.mark.parametrize(("program", "kind"), [("job.bas", "Trio BASIC"), ("shear.pmc", "PMAC"), ("a.pmac", "PMAC"),
                                               ("pocket.nc", "G-code (PoKeys)"), ("p.ngc", "G-code (PoKeys)"),
                                               ("p.gcode", "G-code (PoKeys)")])
def test_run_help_names_every_kind_of_program_file(program: str, kind: str, capsys: pytest.CaptureFixture[str]) -> None:
    """`cosim run --help` used to name only .bas programs."""
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    shown = " ".join(capsys.readouterr().out.split())
    assert all(s in shown for s in (".py", ".toml", ".bas", ".pmc, .pmac", ".nc, .ngc, .gcode"))
    assert main(["run", program]) == 2
    assert f"{program} is a {kind} program: name the machine it runs on with --machine" in capsys.readouterr().err
