"""A portable exported FMU runs away from the environment that exported it.

    cosim export-fmu tn20_81.toml ──> tn20_81.fmu   (resources/cosim/wheels: cosim, numpy, simpy, lark, ...)
        copied into an empty folder; then, in a mount namespace, every folder this interpreter imports
        from outside the base CPython (the exporting venv, the source checkout) is hidden under an empty
        tmpfs, so nothing of them can be reached:
        ├──> ecos (a C importer, no Python in it): the FMU finds the base CPython's libpython, installs
        │    its wheels into a fresh per-user cache and runs
        └──> fmpy in a fresh venv of the base CPython (fmpy and what it needs, no cosim)

    TN20-81: the laser gate switches at steps 1761 on, 1841 off, 3121 on, 3521 off (16 steps per mm):
    in fmpy with early return at exactly those counts; in ecos on its 1 ms grid, equal to cosim run.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import numpy as np
import pytest

import cosim
from cosim.export import read_trace
from cosim.fmu_export.package import export_fmu
from cosim.fmu_export.wheels import wheels_for
from cosim.fmubuild import MODELS_DIR
from cosim.machine import load_machine
from cosim.runner import run_scenario

pytestmark = [pytest.mark.fmu, pytest.mark.slow]

ROOT = Path(__file__).resolve().parent.parent
TN20_81 = ROOT / "examples" / "trio_tn20_81_fmu" / "tn20_81.toml"
C_IMPORTER = Path(sys.prefix) / "c-importer"
NS = 1_000_000_000
#: What fmpy needs to run a co-simulation FMU (installed without their other requirements).
FMPY = ("FMPy", "numpy", "lxml", "attrs", "lark", "msgpack", "Jinja2", "MarkupSafe")
HIDE = """set -e
IFS=:
for place in $1; do
  if [ -d "$place" ]; then mount -t tmpfs cosim-hidden "$place"; else mount --bind /dev/null "$place"; fi
done
unset IFS
shift
exec "$@"
"""
FMPY_RUN = """
import json, sys
try:
    import cosim
    sys.exit("cosim is importable in the fresh environment: " + cosim.__file__)
except ImportError:
    pass
from fmpy import simulate_fmu
log = []
result = simulate_fmu(sys.argv[1], stop_time=0.9, output_interval=1e-3, early_return_allowed=True,
                      use_event_mode=True, debug_logging=True, logger=lambda *args: log.append(args[-1].decode()))
import cosim
print(json.dumps({"time": result["time"].tolist(), "gate": result["laser_gate"].astype(int).tolist(),
                  "steps": result["x_steps"].astype(int).tolist(), "cosim": cosim.__file__, "log": log}))
"""


def _hidden_folders() -> list[str]:
    """Every folder this interpreter imports from that is not the base CPython's, outermost only."""
    base = Path(sys.base_prefix).resolve()
    folders = {Path(sys.prefix).resolve(), Path(cosim.__file__).resolve().parent.parent}
    folders |= {Path(p).resolve() for p in sys.path if p and Path(p).is_dir()}
    folders = {f for f in folders if not f.is_relative_to(base) and f != Path("/")}
    return sorted(str(f) for f in folders if not any(f != g and f.is_relative_to(g) for g in folders))


def _can_hide() -> str:
    if shutil.which("unshare") is None:
        return "unshare is not installed"
    done = subprocess.run(["unshare", "--mount", "--propagation", "private", "true"], capture_output=True)
    return "" if done.returncode == 0 else f"cannot make a mount namespace here (root needed): {done.stderr!r}"


def _away(command: list[str], *, folder: Path, hidden: list[str], env: dict[str, str]) -> subprocess.CompletedProcess:
    script = folder / "hide.sh"
    script.write_text(HIDE)
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    return subprocess.run(["unshare", "--mount", "--propagation", "private", "sh", str(script), ":".join(hidden),
                           *command], cwd=folder, env={**clean, **env}, capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def away(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    reason = _can_hide()
    if reason:
        pytest.skip(reason)
    work = tmp_path_factory.mktemp("portable")
    run = run_scenario(load_machine(TN20_81), out=work / "run", formats=("csv",))
    assert run.verdict == "PASS", run.table()
    exported = export_fmu(TN20_81, work / "export" / "tn20_81.fmu")
    again = export_fmu(TN20_81, work / "again" / "tn20_81.fmu")
    assert again.path.read_bytes() == exported.path.read_bytes()  # deterministic, wheels and all
    assert "cosim_workbench" in " ".join(exported.wheels) and any(w.startswith("numpy-") for w in exported.wheels)
    folder = work / "elsewhere"
    folder.mkdir()
    fmu = folder / "tn20_81.fmu"
    shutil.copyfile(exported.path, fmu)  # the FMU alone, in an empty folder
    fresh = work / "fresh"
    venv.EnvBuilder(with_pip=True).create(fresh)
    wheels = wheels_for(FMPY, MODELS_DIR / "export" / "wheels")
    subprocess.run([str(fresh / "bin" / "python"), "-m", "pip", "install", "--quiet", "--no-index", "--no-deps",
                    *map(str, wheels)], check=True, env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    return {"work": work, "fmu": fmu, "fresh": fresh, "trace": read_trace(work / "run"), "hidden": _hidden_folders()}


def test_the_fmu_runs_in_fmpy_from_a_fresh_environment_without_cosim(away: dict[str, object]) -> None:
    work, fmu, fresh = Path(str(away["work"])), Path(str(away["fmu"])), Path(str(away["fresh"]))
    script = work / "fmpy_run.py"
    script.write_text(FMPY_RUN)
    cache = work / "cache_fmpy"
    done = _away([str(fresh / "bin" / "python"), str(script), str(fmu)], folder=fmu.parent,
                 hidden=list(away["hidden"]), env={"COSIM_FMU_CACHE": str(cache)})  # type: ignore[call-overload]
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    result = json.loads(done.stdout.splitlines()[-1])
    assert result["cosim"].startswith(str(cache)), result["cosim"]  # cosim came from the FMU's own wheels
    assert any("cosim and its packages from " + str(cache) in line for line in result["log"]), result["log"]
    ticks = np.round(np.array(result["time"]) * NS).astype(np.int64)
    gate, steps = np.array(result["gate"]), np.array(result["steps"])
    edges = np.nonzero(np.diff(gate))[0] + 1  # the row after each change: the edge's own instant
    assert [int(steps[i]) for i in edges] == [1761, 1841, 3121, 3521]
    trace = away["trace"]
    t, _ = trace.edges("trio.axis3.gate")  # type: ignore[attr-defined]
    assert ticks[edges].tolist() == t[1:].tolist()  # at the ticks of cosim run


def test_the_fmu_runs_in_a_c_importer_with_the_exporting_environment_hidden(away: dict[str, object]) -> None:
    work, fmu = Path(str(away["work"])), Path(str(away["fmu"]))
    importer = _importer(work)
    folder = work / "ecos"
    folder.mkdir(exist_ok=True)
    done = _away([str(importer / "Scripts" / "ecos"), "simulate", "--path", str(fmu), "--stopTime", "0.9",
                  "--stepSize", "0.001", "--noParallel"], folder=folder, hidden=list(away["hidden"]),  # type: ignore[call-overload]
                 env={"COSIM_FMU_CACHE": str(work / "cache_ecos"), "LD_LIBRARY_PATH": str(importer / "lib"),
                      "TMPDIR": str(folder)})
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    table = folder / "tn20_81.csv"
    assert table.is_file(), done.stdout[-3000:] + done.stderr[-3000:]
    rows = np.genfromtxt(table, delimiter=",", names=True, deletechars="")
    columns = {name.split("::")[-1].split("[")[0]: rows[name] for name in rows.dtype.names}
    grid = np.round(columns["time"] * NS).astype(np.int64)
    trace = away["trace"]
    assert np.array_equal(columns["x_steps"], trace.positions_at("trio.axis3.step", grid))  # type: ignore[attr-defined]
    assert np.array_equal(columns["laser_gate"], trace.values_at("trio.axis3.gate", grid))  # type: ignore[attr-defined]
    opened = np.nonzero(np.diff(columns["laser_gate"]))[0] + 1
    assert len(opened) == 4  # on, off, on, off
    assert (Path(str(work / "cache_ecos")) / "").is_dir()  # installed on first instantiation


def _system_libpythons() -> list[str]:
    """The shared libpython of this minor version that the dynamic loader finds (ldconfig's cache)."""
    soname = f"libpython{sys.version_info.major}.{sys.version_info.minor}.so.1.0"
    done = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True)
    found = {line.split("=>")[-1].strip() for line in done.stdout.splitlines() if soname in line and "=>" in line}
    return sorted(str(Path(p).resolve()) for p in found if Path(p).exists())


def _importer(work: Path) -> Path:
    if not (C_IMPORTER / "Scripts" / "ecos").is_file():
        pytest.skip(f"the C importer is not installed ({C_IMPORTER}): `python3 tasks.py test` installs it")
    importer = work / "c-importer"
    if not importer.exists():
        shutil.copytree(C_IMPORTER, importer, symlinks=True)  # it lives in the venv, which is hidden
    return importer


def test_on_another_cpython_of_the_same_minor_version_too(away: dict[str, object], tmp_path: Path) -> None:
    """The exporting CPython hidden as well: the FMU finds the system's own (Debian's python3.X here)."""
    others = [p for p in _system_libpythons() if not Path(p).is_relative_to(Path(sys.base_prefix).resolve())]
    if not others:
        pytest.skip("no second CPython of this minor version with a shared libpython on this computer")
    work, fmu = Path(str(away["work"])), Path(str(away["fmu"]))
    importer = _importer(work)
    hidden = [*list(away["hidden"]), str(Path(sys.base_prefix).resolve())]  # type: ignore[call-overload]
    done = _away([str(importer / "Scripts" / "ecos"), "simulate", "--path", str(fmu), "--stopTime", "0.9",
                  "--stepSize", "0.001", "--noParallel"], folder=tmp_path, hidden=hidden,
                 env={"COSIM_FMU_CACHE": str(tmp_path / "cache"), "LD_LIBRARY_PATH": str(importer / "lib"),
                      "TMPDIR": str(tmp_path), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0 and (tmp_path / "tn20_81.csv").is_file(), done.stdout[-3000:] + done.stderr[-3000:]
    rows = np.genfromtxt(tmp_path / "tn20_81.csv", delimiter=",", names=True, deletechars="")
    gate = rows[next(n for n in rows.dtype.names if "laser_gate" in n)]
    assert len(np.nonzero(np.diff(gate))[0]) == 4


def test_a_missing_python_is_said_exactly_in_the_fmu_log(away: dict[str, object], tmp_path: Path) -> None:
    """No CPython of the FMU's version to be found: the log says what was looked at and what to install."""
    work, fmu = Path(str(away["work"])), Path(str(away["fmu"]))
    importer = _importer(work)
    hidden = [*list(away["hidden"]), str(Path(sys.base_prefix).resolve()), *_system_libpythons()]  # type: ignore[call-overload]
    done = _away([str(importer / "Scripts" / "ecos"), "simulate", "--path", str(fmu), "--stopTime", "0.01",
                  "--stepSize", "0.001", "--noParallel", "-l", "debug"], folder=tmp_path, hidden=hidden,
                 env={"COSIM_FMU_CACHE": str(tmp_path / "cache"), "LD_LIBRARY_PATH": str(importer / "lib"),
                      "TMPDIR": str(tmp_path), "PATH": "/usr/bin:/bin"})
    output = done.stdout + done.stderr
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    assert f"the Python runtime this FMU needs is missing: no CPython {version} with a shared libpython was found" \
        in output, output[-3000:]
    assert "(recorded at export: not on this computer)" in output
    assert f"libpython{version}.so.1.0 (not on the library search path)" in output
    assert f"set COSIM_FMU_LIBPYTHON to its libpython{version}.so.1.0" in output


def test_the_stage_sample_in_the_docs_is_what_the_script_prints() -> None:
    """docs/export.md shows docs/samples/stage_in_fmpy.txt, made by the command below: it must be what the
    script prints now (``python examples/trio_tn20_81_fmu/stage_in_fmpy.py > docs/samples/stage_in_fmpy.txt``)."""
    script = ROOT / "examples" / "trio_tn20_81_fmu" / "stage_in_fmpy.py"
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    shown = (ROOT / "docs" / "samples" / "stage_in_fmpy.txt").read_text()
    assert done.stdout == shown
    assert shown.splitlines()[0].startswith("t = 470.125100 ms  gate on ")  # the tick of cosim run's first edge
    assert '--8<-- "docs/samples/stage_in_fmpy.txt"' in (ROOT / "docs" / "export.md").read_text()
