"""`cosim run-fmu` on what third-party FMUs bring: legacy descriptions, a start time, an event mode they
refuse, a terminate request at the last instant, names with capitals; and files that are not FMUs.

    TypesTest, speed 1 m/s, stage_time = terminate_time = 0.3 s, --until 0.3 s, --step 0.1 s:

    event_stage  1 ______________________|‾ 2      the FMU asks to end the run at 0.3 s, in the step
    position     0      0.1     0.2     0.3 m      that reaches it: the last sample is its last value
                 0      0.1     0.2     0.3 s
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Callable
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.export import read_trace
from cosim.fmubuild import ensure_fmu
from cosim.fmuvars import trace_names

pytestmark = pytest.mark.fmu


def patched(fmu: Path, target: Path, edit: Callable[[str], str]) -> Path:
    """A copy of ``fmu`` whose modelDescription.xml is ``edit``ed (the binaries are the same)."""
    with zipfile.ZipFile(fmu) as good, zipfile.ZipFile(target, "w") as copy:
        for item in good.infolist():
            data = good.read(item)
            if item.filename == "modelDescription.xml":
                data = edit(data.decode()).encode()
            copy.writestr(item, data)
    return target


def legacy(tmp_path: Path) -> Path:
    """FeedthroughTest (FMI 2.0) as older exporters write it: an Integer output of continuous variability
    and a parameter declared constant, which fmpy's validator refuses and which run all the same."""
    def edit(text: str) -> str:
        output = 'name="Int32_output" valueReference="7" description="Int32_input" causality="output" '
        text = text.replace(output + 'variability="discrete"', output + 'variability="continuous"')
        return text.replace('causality="parameter" variability="fixed"', 'causality="parameter" variability="constant"')

    return patched(ensure_fmu("FeedthroughTest", 2), tmp_path / "Legacy.fmu", edit)


def test_a_legacy_description_is_refused_saying_why_and_runs_with_no_validate(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fmu = legacy(tmp_path)
    assert main(["run-fmu", str(fmu), "--out", str(tmp_path / "refused")]) == 2
    err = capsys.readouterr().err
    assert "Legacy.fmu: cannot read modelDescription.xml" in err
    assert "--no-validate runs it anyway" in err
    table = tmp_path / "inputs.csv"
    table.write_text("time,Int32_input\n0,4\n0.5,5\n")
    out = tmp_path / "out"
    assert main(["run-fmu", str(fmu), "--no-validate", "--input", str(table), "--until", "1 s", "--step", "0.25 s",
                 "--out", str(out)]) == 0
    captured = capsys.readouterr()
    warning = next(n for n in json.loads((out / "result.json").read_text())["notes"] if n.startswith("WARNING"))
    assert "Legacy.fmu runs without validation (--no-validate): fmpy's validator finds" in warning
    assert 'The variable "Int32_output"' in warning and 'must have variability != "continuous"' in warning
    assert "Legacy.fmu runs without validation" in captured.err  # said on the console too
    t, values = read_trace(out).edges("legacy.int32_output")
    assert t.tolist() == [0, 250_000_000, 500_000_000, 750_000_000, 1_000_000_000]
    assert values.tolist() == [4, 4, 5, 5, 5]
    assert main(["fmu-info", str(fmu)]) == 0  # described all the same, with the findings
    assert "fmpy's validator finds" in capsys.readouterr().out


@pytest.mark.parametrize("fmi_version", [2, 3])
@pytest.mark.parametrize("in_event_mode", [False, True])
def test_the_terminate_sample_is_the_fmus_last_value(fmi_version: int, in_event_mode: bool, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code = main(["run-fmu", str(ensure_fmu("TypesTest", fmi_version)), "--set", "speed=1", "--set",
                 "stage_time=0.3", "--set", "terminate_time=0.3", "--set", f"terminate_in_event_mode={in_event_mode}",
                 "--until", "0.3 s", "--step", "0.1 s", "--out", str(out)])
    trace = read_trace(out)
    t, stage = trace.edges("typestest.event_stage")
    assert t.tolist() == [0, 100_000_000, 200_000_000, 300_000_000]
    assert stage.tolist() == [1, 1, 1, 2]  # the stage the FMU has at 0.3 s, where it stopped or the run ended
    assert trace.edges("typestest.position")[1].tolist() == pytest.approx([0, 0.1, 0.2, 0.3], abs=1e-12)
    # FMI 2.0 asks to terminate in the step that reaches 0.3 s; FMI 3.0 returns early there for the stage
    # event, and would ask in the next step, which the run (ending at 0.3 s) does not take
    assert code == (3 if fmi_version == 2 else 0)


def test_a_start_time_and_the_default_experiments_start_are_honoured(tmp_path: Path) -> None:
    """TypesTest integrates speed from its start: 2 m/s from 0.5 s is 0, 0.5, 1.0 m at 0.5, 0.75, 1.0 s."""
    out = tmp_path / "given"
    assert main(["run-fmu", str(ensure_fmu("TypesTest", 3)), "--set", "speed=2", "--start", "0.5 s", "--until",
                 "1 s", "--step", "0.25 s", "--out", str(out)]) == 0
    t, position = read_trace(out).edges("typestest.position")
    assert t.tolist() == [500_000_000, 750_000_000, 1_000_000_000]
    assert position.tolist() == pytest.approx([0.0, 0.5, 1.0], abs=1e-12)
    late = '<DefaultExperiment startTime="0.5"'
    declared = patched(ensure_fmu("TypesTest", 2), tmp_path / "Late.fmu",
                       lambda text: text.replace('<DefaultExperiment startTime="0"', late))
    out = tmp_path / "declared"
    assert main(["run-fmu", str(declared), "--set", "speed=2", "--until", "1 s", "--step", "0.25 s", "--out",
                 str(out)]) == 0
    t, position = read_trace(out).edges("late.position")
    assert t.tolist() == [500_000_000, 750_000_000, 1_000_000_000]
    assert position.tolist() == pytest.approx([0.0, 0.5, 1.0], abs=1e-12)


def test_an_fmu_that_refuses_its_declared_event_mode_runs_without_and_the_run_says_so(tmp_path: Path) -> None:
    out = tmp_path / "out"
    table = tmp_path / "inputs.csv"
    table.write_text("time,Int32_input\n0,1\n0.1,2\n")
    assert main(["run-fmu", str(ensure_fmu("FeedthroughTest", 3)), "--set", "refuse_event_mode=true", "--input",
                 str(table), "--until", "0.2 s", "--step", "0.1 s", "--out", str(out)]) == 0
    notes = json.loads((out / "result.json").read_text())["notes"]
    assert any("declares event mode (hasEventMode) but refused it" in note and "fmi3UpdateDiscreteStates" in note
               and "it runs without event mode" in note for note in notes), notes
    assert read_trace(out).edges("feedthroughtest.int32_output")[1].tolist() == [1, 2, 2]


def test_names_with_capitals_get_one_signal_each_and_keep_their_names_beside_the_trace(tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert main(["run-fmu", str(ensure_fmu("FeedthroughTest", 3)), "--until", "0.1 s", "--out", str(out)]) == 0
    meta = json.loads((out / "trace_meta.json").read_text())["meta"]["fmu_variables"]
    assert meta["feedthroughtest.float64_continuous_output"] == "Float64_continuous_output"
    header = (out / "outputs.csv").read_text().splitlines()[0]
    assert header == "time,Float64_continuous_output,Float64_discrete_output,Int32_output,Boolean_output"


def test_trace_names_never_merge_two_variables_and_do_not_depend_on_the_selection() -> None:
    order = ["time", "Speed", "speed", "der(x)", "der_x_", "a.B[1]", "speed_v2"]
    names = trace_names(order[1:], "m", order=order)  # Speed: speed is taken, then speed_v2 (a variable's own)
    assert names == {"Speed": "m.speed_v2_v2", "speed": "m.speed", "der(x)": "m.der_x__v4", "der_x_": "m.der_x_",
                     "a.B[1]": "m.a.b_1_", "speed_v2": "m.speed_v2"}
    assert len(set(names.values())) == len(names)
    assert trace_names(["der(x)", "Speed"], "m", order=order) == {"der(x)": "m.der_x_", "Speed": "m.speed"}
    assert trace_names(["Float64_continuous_output"], "feedthrough") == {
        "Float64_continuous_output": "feedthrough.float64_continuous_output"}


def non_fmus(folder: Path) -> dict[str, tuple[Path, str]]:
    """Files that are not FMUs, and what the refusal says of each."""
    text = folder / "notes.fmu"
    text.write_text("these are my notes, not an FMU\n")
    empty_zip = folder / "empty.fmu"
    with zipfile.ZipFile(empty_zip, "w") as archive:
        archive.writestr("readme.txt", "no model description here")
    machine = folder / "machine.toml"
    machine.write_text("[machine]\nuntil = \"1 ms\"\n")
    return {"text": (text, "notes.fmu is not an FMU: not a zip archive"),
            "zip": (empty_zip, "empty.fmu is not an FMU: the zip archive has no modelDescription.xml"),
            "toml": (machine, "machine.toml is not an FMU: a machine file (run it with `cosim run`)")}


@pytest.mark.parametrize("command", ["run-fmu", "fmu-info"])
@pytest.mark.parametrize("kind", ["text", "zip", "toml"])
def test_a_file_that_is_not_an_fmu_exits_2_saying_what_it_is(command: str, kind: str, tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    path, message = non_fmus(tmp_path)[kind]
    extra = ["--out", str(tmp_path / "out")] if command == "run-fmu" else []
    assert main([command, str(path), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_a_plant_fmu_that_is_a_text_file_names_the_machine_file_and_key(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    non_fmus(tmp_path)
    machine = tmp_path / "laser.toml"
    machine.write_text('[machine]\nuntil = "1 ms"\n\n[controller]\nfamily = "pokeys"\n\n[plant.laser]\n'
                       'fmu = "notes.fmu"\n')
    assert main(["check-machine", str(machine)]) == 2
    err = capsys.readouterr().err
    assert f"{machine}: plant.laser.fmu:" in err and "notes.fmu is not an FMU: not a zip archive" in err


def test_export_to_a_path_under_a_file_is_refused_before_anything_runs(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "afile").write_text("a file, not a folder\n")
    machine = Path(__file__).resolve().parents[1] / "examples" / "trio_tn20_81_fmu" / "tn20_81.toml"
    assert main(["export-fmu", str(machine), "-o", str(tmp_path / "afile" / "out.fmu")]) == 2
    err = capsys.readouterr().err
    assert f"-o {tmp_path / 'afile' / 'out.fmu'}: {tmp_path / 'afile'} is a file, not a folder" in err
    assert "Traceback" not in err
