#!/usr/bin/env python3
"""Bootstrap and run cosim's two everyday jobs (standard library only).

Usage::

    python3 tasks.py main    # set up, build the FMUs, run every bundled scenario, write the report
    python3 tasks.py test    # set up, build the FMUs, lint, type-check and run the whole test suite

Both create ``.venv`` next to this file on first use (and refresh it when ``pyproject.toml``
changes), so they work on a fresh machine with only Python >= 3.11, gcc and cmake.
They are safe to run again: nothing is rebuilt that is up to date.
Extra arguments after the job name are passed on (to ``cosim main`` or to ``pytest``).
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
STAMP = VENV / ".bootstrap-stamp"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / ("python.exe" if os.name == "nt" else "python")


def _say(text: str) -> None:
    print(f"[tasks] {text}", flush=True)


def _run(*cmd: str | Path) -> None:
    result = subprocess.run([str(c) for c in cmd], cwd=ROOT)
    if result.returncode != 0:
        sys.exit(result.returncode)


def ensure_venv() -> None:
    """Create the virtual env and install cosim with its dev extras, once per pyproject change."""
    if sys.version_info < (3, 11):  # noqa: UP036 (this file runs before any venv exists, on any python3)
        sys.exit(f"cosim needs Python >= 3.11; this is {sys.version.split()[0]}")
    wanted = hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()
    if STAMP.exists() and STAMP.read_text().strip() == wanted and PY.exists():
        return
    if not PY.exists():
        _say(f"creating virtual environment in {VENV}")
        venv.EnvBuilder(with_pip=True).create(VENV)
    _say("installing cosim and its dependencies (first run only; takes a few minutes)")
    _run(PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip")
    _run(PY, "-m", "pip", "install", "--quiet", "-e", ".[dev]")
    STAMP.write_text(wanted + "\n")


def main_job(args: list[str]) -> None:
    ensure_venv()
    _run(BIN / "cosim", "main", *args)


def test_job(args: list[str]) -> None:
    ensure_venv()
    _say("building FMUs that are missing or older than their sources")
    _run(PY, "-m", "cosim.fmubuild")
    _say("ruff")
    _run(PY, "-m", "ruff", "check", "cosim", "tests", "bench", "tasks.py")
    _say("mypy")
    _run(PY, "-m", "mypy")
    _say("pytest")
    _run(PY, "-m", "pytest", *args)


def main() -> None:
    jobs = {"main": main_job, "test": test_job}
    if len(sys.argv) < 2 or sys.argv[1] not in jobs:
        print(__doc__)
        sys.exit(2)
    jobs[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
