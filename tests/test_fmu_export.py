"""A machine as an FMU: exported, run in fmpy and in a C importer, and compared with ``cosim run``.

    machine.toml ──cosim run──────────────> trace (the reference)
         └──────cosim export-fmu──> .fmu ──> fmpy (FMI 3.0 early return + event mode; FMI 2.0)
                                         └──> ecos (a C++ importer, no Python in the process)

    outputs at each communication point t < until == the trace at t; each gate / direction edge
    comes back at its own tick (an early return), first with the value before it, then after it.

The C importer is the ``ecos`` command line of the ecospy wheel, installed by ``tasks.py test``
into ``.venv/c-importer``; without it those tests are skipped (with how to install it).
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from cosim.cli import main
from cosim.errors import ConfigurationError
from cosim.export import read_trace
from cosim.fmu_export.package import export_fmu
from cosim.fmu_export.spec import default_name
from cosim.machine import load_machine
from cosim.runner import run_scenario
from cosim.trace import Trace

pytestmark = pytest.mark.fmu

ROOT = Path(__file__).resolve().parent.parent
TN20_81 = ROOT / "examples" / "trio_tn20_81_fmu" / "tn20_81.toml"
MILL = ROOT / "examples" / "pokeys_mill" / "mill.toml"
ECOS = Path(sys.prefix) / "c-importer" / "Scripts" / "ecos"
needs_ecos = pytest.mark.skipif(not ECOS.is_file(), reason=f"the C importer is not installed ({ECOS}): "
                                "`python3 tasks.py test` installs it")
NS = 1_000_000_000  # ticks per second (both machines run at the default 1 ns resolution)


# -- the machines, run by cosim and exported ---------------------------------------------------------
@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fmu_export")


@pytest.fixture(scope="module")
def trio_trace(work: Path) -> Trace:
    result = run_scenario(load_machine(TN20_81), out=work / "trio_run", formats=("csv",))
    assert result.verdict == "PASS", result.table()
    return read_trace(work / "trio_run")


@pytest.fixture(scope="module")
def mill_trace(work: Path) -> Trace:
    result = run_scenario(load_machine(MILL), out=work / "mill_run", formats=("csv",))
    assert result.verdict == "PASS", result.table()
    return read_trace(work / "mill_run")


# These FMUs are linked (they use this environment): quick to write. The portable ones, which carry cosim
# and its packages, are tested away from this environment in test_fmu_portable.py.
@pytest.fixture(scope="module")
def trio_fmu(work: Path) -> Path:
    return export_fmu(TN20_81, work / "tn20_81.fmu", portable=False).path


@pytest.fixture(scope="module")
def mill_fmu(work: Path) -> Path:
    return export_fmu(MILL, work / "mill.fmu", portable=False).path


def _at_grid(result: Any, until: int) -> tuple[np.ndarray, np.ndarray]:
    """(ticks, row indices) of the last row at each instant before ``until`` (after any event there)."""
    ticks = np.round(result["time"] * NS).astype(np.int64)
    last = np.r_[ticks[1:] != ticks[:-1], True] & (ticks < until)
    return ticks[last], np.nonzero(last)[0]


def _ecos(fmu: Path, folder: Path, *, stop_s: float, step_s: float, debug: bool = False) -> tuple[dict[str, Any], str]:
    """Run ``fmu`` in the C importer; its CSV columns by variable name, and what it printed."""
    folder.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "LD_LIBRARY_PATH": str(ECOS.parent.parent / "lib"), "TMPDIR": str(folder)}
    done = subprocess.run([str(ECOS), "simulate", "--path", str(fmu), "--stopTime", repr(stop_s), "--stepSize",
                           repr(step_s), "--noParallel", *(["-l", "debug"] if debug else [])],
                          cwd=folder, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr  # the importer did not crash
    columns: dict[str, Any] = {}
    table = folder / f"{fmu.stem}.csv"
    if table.is_file():
        with open(table) as f:
            rows = list(csv.reader(f, skipinitialspace=True))
        for i, header in enumerate(rows[0]):
            name = header.split("::")[-1].split("[")[0]
            columns[name] = np.array([float(row[i]) for row in rows[1:]])
    return columns, done.stdout + done.stderr


# -- the Trio TN20-81 machine (its controller alone; the stage is the importer's) ------------------------
def test_exported_fmus_pass_fmpys_validator_and_the_fmi_schema(work: Path, trio_fmu: Path, mill_fmu: Path) -> None:
    """fmpy's validator reads the model description against the FMI 3.0 (2.0) schema and checks its rules."""
    fmi2 = export_fmu(TN20_81, work / "tn20_81_fmi2.fmu", fmi_version=2, portable=False).path
    for fmu in (trio_fmu, mill_fmu, fmi2):
        assert validate_fmu(str(fmu)) == [], fmu
    names = zipfile.ZipFile(trio_fmu).namelist()
    assert {"modelDescription.xml", "binaries/x86_64-linux/tn20_81.so", "resources/cosim/runtime.txt",
            "resources/cosim/machine.json", "resources/cosim/machine/programs/0_tn20_81.bas"} <= set(names)


def test_trio_in_fmpy_returns_early_at_each_gate_edge_at_the_tick_of_cosim_run(
        trio_fmu: Path, trio_trace: Trace) -> None:
    result = simulate_fmu(str(trio_fmu), stop_time=0.9, output_interval=1e-3, early_return_allowed=True,
                          use_event_mode=True)
    ticks = np.round(result["time"] * NS).astype(np.int64)
    gate = result["laser_gate"].astype(int)
    edges = [(int(ticks[i + 1]), int(gate[i + 1])) for i in np.nonzero(np.diff(gate))[0]]
    t, v = trio_trace.edges("trio.axis3.gate")
    assert edges == [(int(a), int(b)) for a, b in zip(t[1:], v[1:], strict=True)]
    # each edge twice at one instant: the row before the event (early return), the row after (event mode)
    for tick, _ in edges:
        assert list(ticks).count(tick) == 2
    # TN20-81: the gate switches at steps 1761 on, 1841 off, 3121 on, 3521 off
    steps = {tick: int(result["x_steps"][np.nonzero(ticks == tick)[0][-1]]) for tick, _ in edges}
    assert [steps[tick] for tick, _ in edges] == [1761, 1841, 3121, 3521]
    grid, rows = _at_grid(result, 900_000_000)
    assert set(range(0, 900_000_000, 1_000_000)) <= set(grid.tolist())  # every communication point, and the edges
    assert np.array_equal(result["x_steps"][rows], trio_trace.positions_at("trio.axis3.step", grid))
    for name, signal in (("x_dir", "trio.axis3.dir"), ("laser_gate", "trio.axis3.gate"),
                         ("pwm_on_clocks", "trio.axis3.pwm_mark"), ("gate_fifo", "trio.axis3.fifo_level"),
                         ("drive_enable", "trio.wdog")):
        assert np.array_equal(result[name][rows].astype(float), trio_trace.values_at(signal, grid)), name


@needs_ecos
def test_trio_in_the_c_importer_equals_cosim_run(work: Path, trio_fmu: Path, trio_trace: Trace) -> None:
    """A C++ program without Python: the FMU loads the recorded libpython and environment by itself."""
    columns, _ = _ecos(trio_fmu, work / "ecos_trio", stop_s=0.9, step_s=1e-3)
    grid = np.round(columns["time"] * NS).astype(np.int64)
    assert len(grid) >= 899 and grid[1] == 1_000_000
    assert np.array_equal(columns["x_steps"], trio_trace.positions_at("trio.axis3.step", grid))
    for name, signal in (("x_dir", "trio.axis3.dir"), ("laser_gate", "trio.axis3.gate"),
                         ("pwm_on_clocks", "trio.axis3.pwm_mark"), ("gate_fifo", "trio.axis3.fifo_level")):
        assert np.array_equal(columns[name], trio_trace.values_at(signal, grid)), name
    assert columns["laser_gate"].sum() > 0  # the gate is open for a while


def test_the_stage_example_marks_at_the_gate_edges_instants(trio_fmu: Path, trio_trace: Trace) -> None:
    """docs/export.md's worked example: the TN20-81 FMU drives a stage model in fmpy."""
    sys.path.insert(0, str(TN20_81.parent))
    try:
        from stage_in_fmpy import engrave  # type: ignore[import-not-found]
    finally:
        sys.path.remove(str(TN20_81.parent))
    marks = engrave(trio_fmu)
    t, _ = trio_trace.edges("trio.axis3.gate")
    assert [round(m.t_s * NS) for m in marks] == t[1:].tolist()
    assert [m.gate for m in marks] == [True, False, True, False]
    assert [m.commanded_mm for m in marks] == [1761 / 16, 1841 / 16, 3121 / 16, 3521 / 16]
    assert all(0 < m.commanded_mm - m.stage_mm < 5 for m in marks)  # the stage lags the command while moving


# -- the PoKeys mill (its steppers inside) -----------------------------------------------------------------
@needs_ecos
def test_mill_in_fmpy_and_in_the_c_importer_equals_cosim_run(work: Path, mill_fmu: Path, mill_trace: Trace) -> None:
    result = simulate_fmu(str(mill_fmu), stop_time=2.5, output_interval=1e-3, early_return_allowed=True,
                          use_event_mode=True)
    columns, _ = _ecos(mill_fmu, work / "ecos_mill", stop_s=2.5, step_s=1e-3)
    grid, rows = _at_grid(result, 2_500_000_000)
    ecos_grid = np.round(columns["time"] * NS).astype(np.int64)
    for host_grid, values in ((grid, {k: result[k][rows] for k in result.dtype.names}), (ecos_grid, columns)):
        for axis in "xyz":
            assert np.array_equal(values[f"{axis}_steps"], mill_trace.positions_at(f"pokeys.{axis}.step", host_grid))
            assert np.array_equal(values[f"{axis}_dir"].astype(float),
                                  mill_trace.values_at(f"pokeys.{axis}.dir", host_grid))
        assert np.array_equal(values["buffer_level"].astype(float),
                              mill_trace.values_at("pokeys.buffer_level", host_grid))
        assert np.array_equal(values["engine_state"].astype(float), mill_trace.values_at("pokeys.state", host_grid))
        assert np.array_equal(values["buffer_empty"].astype(bool),
                              mill_trace.values_at("pokeys.buffer_level", host_grid) < 1)
    assert max(result["x_steps"]) == 8000  # the 20 mm side at 400 pulses per mm
    assert abs(result["x_carriage"][-1]) < 1e-9  # the plant inside: the carriage is back at 0 m
    # the direction edges come back at their own ticks
    ticks = np.round(result["time"] * NS).astype(np.int64)
    x_dir = result["x_dir"].astype(int)
    t, _ = mill_trace.edges("pokeys.x.dir")
    assert [int(ticks[i + 1]) for i in np.nonzero(np.diff(x_dir))[0]] == t[1:].tolist()
    # events (two rows at one instant) exactly where an event-bearing output changes: a direction, the engine
    # state, or the buffer_empty comparator flipping (not at every change of the buffer level)
    expected: set[int] = set()
    for signal in ("pokeys.x.dir", "pokeys.y.dir", "pokeys.z.dir", "pokeys.state"):
        expected |= set(mill_trace.edges(signal)[0][1:].tolist())
    level_t, level = mill_trace.edges("pokeys.buffer_level")
    flips = np.nonzero(np.diff((level < 1).astype(int)))[0] + 1
    expected |= set(level_t[flips].tolist())
    events = set(ticks[1:][ticks[1:] == ticks[:-1]].tolist())
    assert events == {t for t in expected if 0 < t < 2_500_000_000} and len(events) < 20


def test_an_estop_from_the_importer_stops_the_engine_as_a_stimulus_does(tmp_path: Path, mill_fmu: Path) -> None:
    """The importer sets the E-stop input at 1 s; cosim run of the same mill with a [[stimulus]] there agrees."""
    estop = np.array([(0.0, False), (1.0, True)], dtype=[("time", np.float64), ("estop", np.bool_)])
    result = simulate_fmu(str(mill_fmu), stop_time=1.2, output_interval=1e-3, input=estop,
                          early_return_allowed=True, use_event_mode=True)
    text = MILL.read_text().replace('inputs = [{ signal = "pokeys.emergency", name = "estop" }]', "")
    text += '\n[[stimulus]]\nsignal = "pokeys.emergency"\nat = ["1 s"]\nvalues = [1]\n'
    machine = tmp_path / "mill_estop.toml"
    machine.write_text(text)
    run = run_scenario(load_machine(machine), until="1.2 s", out=tmp_path / "run", formats=("csv",))
    assert run.error is None, run.error
    trace = read_trace(tmp_path / "run")
    grid, rows = _at_grid(result, 1_200_000_000)
    assert np.array_equal(result["engine_state"][rows].astype(float), trace.values_at("pokeys.state", grid))
    assert np.array_equal(result["x_steps"][rows], trace.positions_at("pokeys.x.step", grid))
    assert result["engine_state"][-1] == 101  # EngineState.STOP_EMERGENCY: stopped by the emergency input


def test_fmi2_export_runs_in_fmpy_like_fmi3_at_its_communication_points(work: Path, trio_trace: Trace) -> None:
    fmu = export_fmu(TN20_81, work / "tn20_81_fmi2_run.fmu", fmi_version=2, portable=False).path
    result = simulate_fmu(str(fmu), stop_time=0.9, output_interval=1e-3)
    grid, rows = _at_grid(result, 900_000_000)
    assert len(grid) == 900  # no early return in FMI 2.0: the communication points only
    assert np.array_equal(result["x_steps"][rows], trio_trace.positions_at("trio.axis3.step", grid))
    assert np.array_equal(result["laser_gate"][rows].astype(float), trio_trace.values_at("trio.axis3.gate", grid))


def test_an_export_is_deterministic_and_the_cli_says_what_it_wrote(tmp_path: Path, trio_fmu: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["export-fmu", str(TN20_81), "-o", str(tmp_path / "again.fmu"), "--linked"]) == 0
    assert (tmp_path / "again.fmu").read_bytes() == trio_fmu.read_bytes()
    out = capsys.readouterr().out
    assert "laser_gate" in out and "(event)" in out and "libpython" in out


# -- bad input ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("export", "message"), [
    ('outputs = ["trio.axis3.gatee"]',
     "export.outputs[0].signal: 'trio.axis3.gatee' is not a signal of this machine; did you mean trio.axis3.gate,"),
    ('outputs = [{ signal = "trio.axis3.step", event = true }]',
     "export.outputs[0].event = True is not allowed (allowed: false for a step output"),
    ('outputs = ["trio.axis3.gate"]\ninputs = ["trio.axis3.gate"]',
     "export.inputs[0].signal: 'trio.axis3.gate' is not an input of this controller"),
    ('outptus = ["trio.axis3.gate"]', "export.outptus is not a key of export; did you mean outputs?"),
    ('outputs = [{ signal = "trio.axis3.gate", name = "a b" }]', "export.outputs[0].name = 'a b' is not allowed"),
    ('outputs = ["trio.axis3.gate", { signal = "trio.axis3.dir", name = "trio.axis3.gate" }]',
     "two variables are named 'trio.axis3.gate'"),
])
def test_a_bad_export_table_is_refused_with_the_file_the_key_and_what_is_allowed(
        tmp_path: Path, export: str, message: str) -> None:
    text = TN20_81.read_text()
    start = text.index("[export]")
    end = text.index("[[check]]")
    shutil.copy(TN20_81.parent / "tn20_81.bas", tmp_path / "tn20_81.bas")
    machine = tmp_path / "bad.toml"
    machine.write_text(text[:start] + "[export]\n" + export + "\n\n" + text[end:])
    with pytest.raises(ConfigurationError) as info:
        export_fmu(machine, tmp_path / "bad.fmu")
    assert str(info.value).startswith(str(machine)) and message in str(info.value)
    assert not (tmp_path / "bad.fmu").exists()
    assert main(["export-fmu", str(machine), "-o", str(tmp_path / "bad.fmu")]) == 2


def test_a_numbered_input_gets_an_fmi_name_without_a_digit_after_the_dot() -> None:
    assert default_name("trio.in.8") == "trio.in_8"
    assert default_name("pokeys.x.limit_pos") == "pokeys.x.limit_pos"
    assert default_name("trio.axis3.gate") == "trio.axis3.gate"


def test_a_machine_without_an_export_table_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigurationError, match=r"has no \[export\] table"):
        export_fmu(_without_export(tmp_path), tmp_path / "x.fmu")


def _without_export(tmp_path: Path) -> Path:
    text = TN20_81.read_text()
    shutil.copy(TN20_81.parent / "tn20_81.bas", tmp_path / "tn20_81.bas")
    machine = tmp_path / "plain.toml"
    machine.write_text(text[:text.index("[export]")] + text[text.index("[[check]]"):])
    return machine


def _with_runtime(fmu: Path, target: Path, **changes: str) -> Path:
    """A copy of ``fmu`` whose resources/cosim/runtime.txt has some keys changed."""
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w") as out:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "resources/cosim/runtime.txt":
                lines = [f"{line.split('=')[0]}={changes.get(line.split('=')[0], line.partition('=')[2])}"
                         if "=" in line else line for line in data.decode().splitlines()]
                data = ("\n".join(lines) + "\n").encode()
            out.writestr(item, data)
    return target


def test_a_missing_python_environment_fails_instantiation_in_fmpy_with_a_clear_log(
        tmp_path: Path, trio_fmu: Path) -> None:
    broken = _with_runtime(trio_fmu, tmp_path / "broken.fmu", path="/nonexistent/venv/site-packages")
    log: list[tuple[Any, ...]] = []
    with pytest.raises(Exception, match="instantiate"):
        simulate_fmu(str(broken), stop_time=0.01, logger=lambda *args: log.append(args))
    messages = [args[-1].decode() for args in log]
    assert any("the Python environment this FMU needs is missing: /nonexistent/venv/site-packages does not exist"
               in m for m in messages), messages


@needs_ecos
def test_a_python_that_moved_is_found_again_on_the_path(tmp_path: Path, trio_fmu: Path) -> None:
    """The libpython recorded at export is gone: the FMU looks for python3.X on the PATH and the system's
    libpython3.X (what it says when none is found: test_fmu_portable.py) and runs."""
    moved = _with_runtime(trio_fmu, tmp_path / "moved.fmu", libpython="/nonexistent/libpython3.11.so.1.0")
    columns, output = _ecos(moved, tmp_path / "ecos", stop_s=0.01, step_s=1e-3)
    assert len(columns.get("x_steps", [])) >= 10, output


def test_a_pmac_machine_carries_its_setup_files(tmp_path: Path) -> None:
    """controller.setup names PMAC files read at power-up: they were left out of the FMU, so the export of
    the flying shear failed ('setup.pmc does not exist' in the FMU's resources)."""
    shear = ROOT / "examples" / "pmac_flying_shear"
    for name in ("shear.toml", "setup.pmc", "shear.pmc", "arm.pmc"):
        shutil.copy(shear / name, tmp_path / name)
    machine = tmp_path / "shear.toml"
    machine.write_text(machine.read_text() + '\n[export]\noutputs = ["pmac.motor1.cmd_pos"]\n')
    fmu = export_fmu(machine, tmp_path / "shear.fmu", portable=False).path  # runs it from its resources first
    with zipfile.ZipFile(fmu) as archive:
        carried = [name for name in archive.namelist() if name.endswith(".pmc")]
        assert archive.read("resources/cosim/machine/setup/0_setup.pmc") == (shear / "setup.pmc").read_bytes()
    assert sorted(carried) == ["resources/cosim/machine/programs/0_shear.pmc",
                               "resources/cosim/machine/programs/1_arm.pmc",
                               "resources/cosim/machine/setup/0_setup.pmc"]
