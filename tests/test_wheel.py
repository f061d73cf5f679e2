"""A normal install works outside the clone: build the wheel, pip-install it into a fresh venv, run a scenario.

This is the slowest test of the suite (about 25 s with pip's cache warm, as it is after
``tasks.py`` has set up ``.venv``; the first time on a new machine pip downloads the dependencies
again only if they are not cached). It is marked ``slow``: ``pytest -m "not slow"`` leaves it out
while developing; ``tasks.py test`` and CI run it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

import cosim
from cosim.scenario import bundled

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


def _run(*cmd: str | Path, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    done = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, f"{' '.join(map(str, cmd))} failed ({done.returncode}):\n{done.stdout}\n{done.stderr}"
    return done


def _files(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if "__pycache__" not in p.parts}


def test_the_wheel_installs_into_a_fresh_venv_and_runs_laser_pwm(tmp_path: Path) -> None:
    assert not tmp_path.is_relative_to(ROOT)
    # 1. the wheel, built the way any user builds it (isolated build with the declared backend)
    _run(sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--wheel-dir", tmp_path / "dist", ROOT,
         cwd=tmp_path)
    (wheel,) = (tmp_path / "dist").glob("cosim_workbench-*.whl")
    assert wheel.name == f"cosim_workbench-{cosim.__version__}-py3-none-any.whl"
    names = set(zipfile.ZipFile(wheel).namelist())
    for carried in ("cosim/_data/fmu_src/Laser/model.c", "cosim/_data/fmu_src/Laser/model.toml",
                    "cosim/_data/fmu_src/common/fmi3_cs.c", "cosim/_data/presets/laser_co2_40w.toml",
                    "cosim/scenarios/laser_pwm.py", "cosim/controllers/trio/examples/tn20_81.bas", "cosim/py.typed"):
        assert carried in names
    assert not [n for n in names if n.endswith((".fmu", ".so", ".pyc")) or n.startswith("tests/")]

    # 2. a fresh venv (no pip of its own: this process's pip installs into it) and a plain `pip install`
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(env_dir)
    python = env_dir / "bin" / "python"
    _run(sys.executable, "-m", "pip", "--python", python, "install", "--quiet", wheel, cwd=tmp_path)
    site = Path(_run(python, "-c", "import cosim, pathlib; print(pathlib.Path(cosim.__file__).parent)",
                     cwd=tmp_path).stdout.strip())
    assert site.is_relative_to(env_dir)
    installed_before = _files(site)

    # 3. the bundled scenario, outside the clone, with the FMU built on first use into the per-user cache
    work = tmp_path / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("COSIM_FMU_SRC", "COSIM_MODELS", "PYTHONPATH", "VIRTUAL_ENV")}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    cosim_cmd = env_dir / "bin" / "cosim"
    assert _run(cosim_cmd, "--version", cwd=work, env=env).stdout == f"cosim {cosim.__version__}\n"
    done = _run(cosim_cmd, "run", "laser_pwm", "--out", "out", cwd=work, env=env)
    assert "scenario laser_pwm: PASS  (3/3 checks passed" in done.stdout
    cache = tmp_path / "cache" / "cosim" / cosim.__version__ / "models"
    assert f"cosim: building Laser (FMI 3.0) into {cache / 'fmi3' / 'Laser.fmu'}" in done.stderr
    assert (work / "out" / "result.json").is_file()
    assert _files(site) == installed_before  # nothing written into the package folder

    # 4. the FMU commands say what they did
    built = _run(cosim_cmd, "build-fmus", "Laser", cwd=work, env=env).stdout.splitlines()
    assert built[0].split()[:4] == ["built", "Laser", "FMI", "2.0"]
    assert built[1].split() == ["up", "to", "date", "Laser", "FMI", "3.0", str(cache / "fmi3" / "Laser.fmu")]
    assert built[2].startswith(f"1 built, 1 up to date in {cache} (sources: {site / '_data' / 'fmu_src'})")
    listed = _run(python, "-m", "cosim", "list", cwd=work, env=env).stdout.splitlines()
    assert [line.split()[0] for line in listed][:len(bundled())] == bundled()
    assert any(line.split()[0].endswith("pokeys_mill/mill.toml") for line in listed)  # the example machines
