#!/usr/bin/env python3
"""Bootstrap and run cosim's everyday jobs (standard library only).

Usage::

    python3 tasks.py main       # set up, build the FMUs, run every bundled scenario, write the report
    python3 tasks.py test       # set up, build the FMUs, lint, type-check, build the docs, run the test suite
                                #   (installs the Debian packages the tests use where missing: sigrok-cli, chromium)
    python3 tasks.py notebooks  # set up with JupyterLab, register the kernel, open the notebooks
                                #   (--execute: run them all into results/notebooks/ instead)
    python3 tasks.py docs       # build the documentation site into site/ (--serve: live preview)

Each creates ``.venv`` next to this file on first use (and refreshes it when ``pyproject.toml``
changes), so they work on a fresh machine with only Python >= 3.11, gcc and cmake.
They are safe to run again: nothing is rebuilt that is up to date.
Extra arguments after the job name are passed on (to ``cosim main``, to ``pytest``, to ``mkdocs``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".bootstrap-stamp"
NOTEBOOK_STAMP = VENV / ".notebooks-stamp"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / ("python.exe" if os.name == "nt" else "python")
KERNEL = "cosim"
#: Debian packages the test suite uses, by the command each provides (tests that need one skip without it).
TEST_PACKAGES = {"sigrok-cli": "sigrok-cli", "chromium": "chromium", "vcd2fst": "gtkwave", "rs274": "linuxcnc-uspace"}


def _say(text: str) -> None:
    print(f"[tasks] {text}", flush=True)


def _run(*cmd: str | Path) -> None:
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")  # mkdocs-material's banner about its successor
    result = subprocess.run([str(c) for c in cmd], cwd=ROOT, env=env)
    if result.returncode != 0:
        sys.exit(result.returncode)


def _pyproject_hash() -> str:
    return hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()


def ensure_venv(extras: str = "dev,docs") -> None:
    """Create the virtual env and install cosim with its dev and docs extras, once per pyproject change."""
    if sys.version_info < (3, 11):  # noqa: UP036 (this file runs before any venv exists, on any python3)
        sys.exit(f"cosim needs Python >= 3.11; this is {sys.version.split()[0]}")
    wanted = _pyproject_hash()
    if STAMP.exists() and STAMP.read_text().strip() == wanted and PY.exists():
        return
    if not PY.exists():
        _say(f"creating virtual environment in {VENV}")
        venv.EnvBuilder(with_pip=True).create(VENV)
    _say("installing cosim and its dependencies (first run only; takes a few minutes)")
    _run(PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip")
    # The distribution was called `cosim` before it became `cosim-workbench`: drop an old install's
    # metadata and script so that the two do not both claim the `cosim` command.
    _run(PY, "-m", "pip", "uninstall", "--quiet", "--yes", "cosim")
    _run(PY, "-m", "pip", "install", "--quiet", "-e", f".[{extras}]")
    STAMP.write_text(wanted + "\n")


#: The C importer the tests run exported machine FMUs in (a program without Python): the ecos co-simulation
#: engine's command line (ecospy wheel) and the TBB runtime it links (tbb wheel), both from PyPI, kept
#: apart from the project's packages in .venv/c-importer (ecos in Scripts/, libtbb in lib/).
C_IMPORTER = VENV / "c-importer"
C_IMPORTER_PACKAGES = ("ecospy==0.7.2", "tbb==2023.2.0")


def ensure_c_importer() -> None:
    """Install the C importer once (a second run finds it and does nothing)."""
    ecos = C_IMPORTER / "Scripts" / "ecos"
    stamp = C_IMPORTER / ".stamp"
    wanted = " ".join(C_IMPORTER_PACKAGES)
    if ecos.exists() and stamp.exists() and stamp.read_text().strip() == wanted:
        return
    _say(f"installing the C importer for the FMU export tests ({wanted}) into {C_IMPORTER}")
    _run(PY, "-m", "pip", "install", "--quiet", "--no-deps", "--prefix", C_IMPORTER, *C_IMPORTER_PACKAGES)
    ecos.chmod(0o755)
    stamp.write_text(wanted + "\n")


def main_job(args: list[str]) -> None:
    ensure_venv()
    _run(BIN / "cosim", "main", *args)


def ensure_debian_packages(packages: dict[str, str]) -> None:
    """Install the Debian packages whose command is missing, quietly, where apt-get can (as root).

    Elsewhere (no apt-get, not root, no network) say so and go on: the tests that need them skip.
    """
    missing = sorted({package for command, package in packages.items() if shutil.which(command) is None})
    if not missing:
        return
    if shutil.which("apt-get") is None or not hasattr(os, "geteuid") or os.geteuid() != 0:
        _say(f"not installing {', '.join(missing)} (needs apt-get as root): the tests that use them skip")
        return
    _say(f"installing {', '.join(missing)} (Debian packages the tests use)")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    installed = subprocess.run(["apt-get", "install", "-y", "-q", "--no-install-recommends", *missing], **quiet)
    if installed.returncode != 0:  # an old or missing package list: refresh it once and try again
        subprocess.run(["apt-get", "update", "-q"], **quiet)
        installed = subprocess.run(["apt-get", "install", "-y", "-q", "--no-install-recommends", *missing], **quiet)
    if installed.returncode != 0:
        _say(f"could not install {', '.join(missing)}: the tests that use them skip")


def test_job(args: list[str]) -> None:
    ensure_venv()
    ensure_debian_packages(TEST_PACKAGES)
    _say("building FMUs that are missing or older than their sources")
    _run(PY, "-m", "cosim.fmubuild", "--quiet")
    ensure_c_importer()
    _say("ruff")
    _run(PY, "-m", "ruff", "check", "cosim", "tests", "bench", "docs", "tasks.py")
    _say("mypy")
    _run(PY, "-m", "mypy")
    _say("docs (mkdocs build --strict)")
    with tempfile.TemporaryDirectory(prefix="cosim-site-") as site:
        _run(PY, "-m", "mkdocs", "build", "--strict", "--site-dir", site)
    _say("pytest")
    _run(PY, "-m", "pytest", *args)


def docs_job(args: list[str]) -> None:
    ensure_venv()
    if "--serve" in args:
        _run(PY, "-m", "mkdocs", "serve", "--strict", *[a for a in args if a != "--serve"])
        return
    _run(PY, "-m", "mkdocs", "build", "--strict", *args)
    _say(f"site built: open {ROOT / 'site' / 'index.html'}")


def notebooks_job(args: list[str]) -> None:
    """JupyterLab in the venv (the `notebooks` extra), the venv's kernel registered, then open or execute."""
    ensure_venv()
    wanted = _pyproject_hash()
    if not (NOTEBOOK_STAMP.exists() and NOTEBOOK_STAMP.read_text().strip() == wanted):
        _say("installing JupyterLab into .venv (the `notebooks` extra; first run only)")
        _run(PY, "-m", "pip", "install", "--quiet", "-e", ".[dev,docs,notebooks]")
        NOTEBOOK_STAMP.write_text(wanted + "\n")
    _say(f"registering the kernel {KERNEL!r} (\"Python (cosim)\", {PY}) for this user")
    _run(PY, "-m", "ipykernel", "install", "--user", "--name", KERNEL, "--display-name", "Python (cosim)")
    notebooks = sorted((ROOT / "notebooks").glob("*.ipynb"))
    if "--execute" in args:
        out = ROOT / "results" / "notebooks"
        _say(f"executing {len(notebooks)} notebooks into {out}")
        _run(BIN / "jupyter", "nbconvert", "--to", "notebook", "--execute",
             f"--ExecutePreprocessor.kernel_name={KERNEL}", "--ExecutePreprocessor.timeout=600",
             "--output-dir", out, *notebooks)
        return
    _say("opening JupyterLab (Ctrl-C to stop)")
    as_root = ["--allow-root"] if hasattr(os, "geteuid") and os.geteuid() == 0 else []  # containers, CI
    _run(BIN / "jupyter", "lab", ROOT / "notebooks", *as_root, *args)


def main() -> None:
    jobs = {"main": main_job, "test": test_job, "notebooks": notebooks_job, "docs": docs_job}
    if len(sys.argv) < 2 or sys.argv[1] not in jobs:
        print(__doc__)
        sys.exit(2)
    jobs[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
