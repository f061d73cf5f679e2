"""`cosim fmu-info` and `cosim run-fmu` on the bundled FMUs, and what is refused (Model Exchange, bad --set).

run-fmu is compared with fmpy's own simulate_fmu on the same grid: an independent importer (fmpy
steps FMI 3.0 FMUs without early return or event mode; cosim's master uses both).
"""

from __future__ import annotations

import json
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu

from cosim import fmudesc
from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.export import read_trace
from cosim.fmu import Fmu
from cosim.fmubuild import SOURCE_DIR, ensure_fmu, list_models

pytestmark = pytest.mark.fmu

#: Start values that make each bundled model's outputs move, its end time and grid [s].
RUNS: dict[str, tuple[dict[str, str], float, float]] = {
    "Laser": ({"enable": "true", "gate": "true", "pwm_on": "400"}, 0.01, 0.0005),
    "Stepper": ({"step_rate": "2000"}, 0.05, 0.001),
    "Servo": ({"u_cmd": "2.0"}, 0.02, 0.0005),
    "Conveyor": ({"speed_cmd": "0.5"}, 0.2, 0.005),
    "TypesTest": ({"speed": "2.0", "mode_in": "fast"}, 1.0, 0.05),
    "FeedthroughTest": ({"Float64_continuous_input": "1.5", "Int32_input": "3", "Boolean_input": "true"}, 0.5, 0.1),
}
MODELS = [(model, version) for model in sorted(RUNS) for version in (2, 3)]


def test_every_model_of_fmu_src_is_covered_here() -> None:
    assert sorted(RUNS) == list_models()


@pytest.mark.parametrize(("model", "version"), MODELS)
def test_fmu_info_lists_every_variable_with_its_unit(model: str, version: int,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    spec = fmudesc.load_spec(SOURCE_DIR / model)
    assert main(["fmu-info", str(ensure_fmu(model, version))]) == 0
    out = capsys.readouterr().out
    table = out[out.index("\n  name "):out.index("\ncouplings")]
    lines = {line.split()[0]: line.split() for line in table.splitlines() if line.strip()}
    assert out.startswith(f"{model}.fmu: {model} (FMI {version}.0)\n")
    for v in spec.for_fmi(version):
        row = lines[v.name]
        assert row[2] == v.causality, v.name
        if v.unit:
            assert v.unit in row[3:], v.name
    assert f"platforms: {'x86_64-linux' if version == 3 else 'linux64'}; sources included" in out


def test_fmu_info_says_which_couplings_an_fmu_serves(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fmu-info", "--json", str(ensure_fmu("Stepper", 3))]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["couplings"]["stepper"]["ready"] and info["couplings"]["switches"]["ready"]
    assert info["couplings"]["laser"]["missing"]["period_clocks"] == "pwm_period"
    assert main(["fmu-info", "--json", str(ensure_fmu("TypesTest", 3))]) == 0
    variables = {v["name"]: v for v in json.loads(capsys.readouterr().out)["variables"]}
    assert variables["matrix_out"]["dimensions"] == [2, 3] and variables["u16_in"]["min"] == 1
    assert variables["mode_in"]["items"] == {"off": 1, "slow": 2, "fast": 3}


@pytest.mark.parametrize(("model", "version"), MODELS)
def test_run_fmu_gives_the_outputs_of_fmpys_simulate_fmu(model: str, version: int, tmp_path: Path) -> None:
    sets, stop, step = RUNS[model]
    path = ensure_fmu(model, version)
    code = main(["run-fmu", str(path), "--until", f"{stop} s", "--step", f"{step} s", "--out", str(tmp_path),
                 *[arg for name, value in sets.items() for arg in ("--set", f"{name}={value}")]])
    assert code == 0
    assert json.loads((tmp_path / "result.json").read_text())["verdict"] == "UNCHECKED"  # no checks, exit 0
    trace = read_trace(tmp_path)
    starts = {name: 3 if value == "fast" else True if value == "true" else value for name, value in sets.items()}
    spec = fmudesc.load_spec(SOURCE_DIR / model)
    outputs = [v.name for v in spec.for_fmi(version) if v.causality == "output" and v.type not in ("String", "Binary")
               and not v.dimensions]
    reference = simulate_fmu(str(path), stop_time=stop, output_interval=step, start_values=starts, output=outputs)
    grid = np.rint(reference["time"] * 1e9).astype(np.int64)
    prefix = model.lower()
    for name in outputs:
        t, values = trace.edges(f"{prefix}.{name.lower()}")
        assert t.tolist() == grid.tolist(), name
        assert values.tolist() == pytest.approx(reference[name].astype(float).tolist(), rel=1e-9, abs=1e-12), name


def test_run_fmu_records_array_elements_and_ends_where_the_fmu_asks(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    path = ensure_fmu("TypesTest", 3)
    code = main(["run-fmu", str(path), "--set", "terminate_time=0.35", "--set", "vec_in=1, 2, 3.5", "--step",
                 "0.1 s", "--out", str(tmp_path)])
    assert code == 3  # TERMINATED: not a failure of the checks
    assert "TERMINATED by typestest (TypesTest.fmu) at t = 0.35 s" in capsys.readouterr().out
    trace = read_trace(tmp_path)
    assert trace.edges("typestest.vec_out.2")[1].tolist() == [7.0] * 5
    assert trace.edges("typestest.matrix_out.1.0")[0].tolist() == [0, 100_000_000, 200_000_000, 300_000_000,
                                                                   350_000_000]  # and the instant it stopped


@pytest.mark.parametrize(("sets", "message"), [
    (["speeed=1"], "TypesTest.fmu has no variable named 'speeed'; did you mean speed?"),
    (["position=1"], "position is an output; --set takes parameters and inputs"),
    (["u8_in=256"], "u8_in = 256 is not allowed (allowed: 0..255)"),
    (["flag_in=maybe"], "flag_in = 'maybe' is not allowed (allowed: true or false)"),
])
def test_run_fmu_refuses_bad_start_values(tmp_path: Path, sets: list[str], message: str,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    args = [arg for pair in sets for arg in ("--set", pair)]
    assert main(["run-fmu", str(ensure_fmu("TypesTest", 3)), *args, "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err


def model_exchange_fmu(folder: Path) -> Path:
    """An FMU with a Model Exchange interface only (model description alone: nothing gets that far)."""
    xml = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Bouncy" guid="{8c4e810f-3df3-4a00-8276-176fa3c9f000}"
  numberOfEventIndicators="0">
  <ModelExchange modelIdentifier="Bouncy"/>
  <ModelVariables>
    <ScalarVariable name="h" valueReference="0" causality="local" variability="continuous" initial="exact">
      <Real start="1"/>
    </ScalarVariable>
  </ModelVariables>
  <ModelStructure/>
</fmiModelDescription>
"""
    path = folder / "Bouncy.fmu"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("modelDescription.xml", xml)
    return path


def test_a_model_exchange_fmu_is_refused_with_how_to_export_one(tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    path = model_exchange_fmu(tmp_path)
    with pytest.raises(ConfigurationError, match=r"^Bouncy.fmu is a Model Exchange FMU: cosim needs a "
                                                 r"co-simulation FMU .* fmuType=\"cs\""):
        Fmu(path)
    assert main(["fmu-info", str(path)]) == 0
    assert "not usable as a cosim plant: co-simulation is required" in capsys.readouterr().out
    assert main(["run-fmu", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "Export it again with co-simulation enabled" in capsys.readouterr().err


@pytest.mark.parametrize("version", [2, 3])
def test_the_test_model_validates_and_rebuilds_from_its_own_sources(version: int, tmp_path: Path) -> None:
    path = ensure_fmu("TypesTest", version)
    assert validate_fmu(str(path)) == []
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(path) as zf:
        zf.extractall(unzipped)
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped), str(tmp_path / "build"))  # what another tool would do
    rebuilt = shutil.make_archive(str(tmp_path / "TypesTest"), "zip", unzipped)
    result = simulate_fmu(rebuilt, start_values={"speed": 2.0, "terminate_time": 0.35}, stop_time=1.0,
                          output_interval=0.05, output=["position", "event_stage"])
    reference = np.genfromtxt(SOURCE_DIR / "TypesTest" / "reference.csv", delimiter=",", names=True)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    assert result["position"].tolist() == pytest.approx(reference["position"].tolist(), abs=1e-12)
    assert result["event_stage"].tolist() == reference["event_stage"].tolist()


@pytest.mark.fmu
def test_an_fmi3_description_naming_a_missing_value_reference_says_which_and_where(tmp_path: Path) -> None:
    with zipfile.ZipFile(ensure_fmu("Laser", 3)) as good, zipfile.ZipFile(tmp_path / "bad.fmu", "w") as bad:
        for item in good.infolist():
            data = good.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                first_output = text.index("<Output ")
                vr_at = text.index('valueReference="', first_output)
                end = text.index('"', vr_at + len('valueReference="'))
                data = (text[:vr_at] + 'valueReference="4711' + text[end:]).encode()
                line = text[:first_output].count("\n") + 1
            bad.writestr(item, data)
    with pytest.raises(ConfigurationError) as info:  # a bad input file: exit status 2
        Fmu(tmp_path / "bad.fmu")
    assert f"value reference 4711 is named at line {line} but no variable has it" in str(info.value)
