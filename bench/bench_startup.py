"""Start-up cost of a run (issue 29): a machine file run for 1 ms, in a fresh interpreter, in process CPU time.

What a user pays before the first simulated instant matters (every example run is mostly start-up):
importing cosim and what the run needs, reading and building the machine, loading its FMUs, the
1 ms run itself, its checks and writing the results folder (``result.json``, ``trace.vcd``, the
Parquet tables). Each case runs in a new interpreter, ``--repeat`` times (min / median / max), after
one untimed run that builds missing FMUs and fills the per-user caches (the built grammars, Python's
bytecode): the figure is what every later run costs. Python caches the bytecode of the modules
as it does for an installed cosim (in a folder of the temporary directory, ``PYTHONPYCACHEPREFIX``,
so that the checkout is not written to), also where the environment says ``PYTHONDONTWRITEBYTECODE``;
``--no-bytecode-cache`` measures a start that compiles every module from source. The CPU time is
the child's user + system time (``resource.getrusage(RUSAGE_CHILDREN)``), which other work on a
shared machine disturbs little.

Two ways in, for each example machine:

* **cli**: ``cosim run MACHINE.toml --until "1 ms" --out TMP`` (the ``cosim`` script's own entry point);
* **runner**: ``cosim.runner.run_scenario(cosim.catalog.load(MACHINE.toml), until="1 ms", out=TMP)``
  called from a fresh ``python -c``.

Goals (issue 29): a Trio or PoKeys machine <= 0.5 s, a PMAC one <= 1.0 s. ``--lazy-control`` makes
``import control`` (python-control) lazy in the child, as if the PMAC servo modules imported it only
where a loop is designed: the module is loaded on first use, so a run that designs a loop still gets it
(``--imports`` then shows scipy and matplotlib).
Run::

    .venv/bin/python bench/bench_startup.py [--repeat 3] [--only trio|pokeys|pmac] [--lazy-control]
                                            [--way cli|runner] [--imports] [--no-bytecode-cache]

``--imports`` lists, per case, the packages (cosim by module) whose imports took longest (``-X importtime``, wall).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from clock import figure_line, machine_load, spread

ROOT = Path(__file__).resolve().parent.parent
#: Seconds of CPU a start-up may cost, by family.
GOAL_S = {"trio": 0.5, "pokeys": 0.5, "pmac": 1.0}
CASES = (
    ("trio", "examples/trio_engraver/engraver.toml"),
    ("trio", "examples/trio_tn20_81_fmu/tn20_81.toml"),
    ("pokeys", "examples/pokeys_router/router.toml"),
    ("pokeys", "examples/pokeys_mill/mill.toml"),
    ("pmac", "examples/pmac_flying_shear/shear.toml"),
    ("pmac", "examples/pmac_external_time_base/line.toml"),
)
#: Verdicts a 1 ms run may end with (most checks have not seen anything yet): anything but a crash.
ACCEPTED_STATUS = (0, 1, 3, 4)

#: Makes ``import control`` lazy: a stand-in module that imports python-control on its first attribute use.
#: (importlib's LazyLoader does not do for this: ``import control`` itself reads ``__spec__`` and loads it.)
LAZY_CONTROL = """
import importlib, sys, types
class _LazyControl(types.ModuleType):
    def __getattr__(self, name):
        sys.modules.pop("control", None)
        real = importlib.import_module("control")
        self.__dict__.update(real.__dict__)
        return getattr(real, name)
sys.modules["control"] = _LazyControl("control")
"""
CLI = "import sys\nfrom cosim.cli import main\nsys.argv[0] = 'cosim'\nsys.exit(main(sys.argv[1:]))\n"
RUNNER = """import sys
from cosim.catalog import load
from cosim.runner import run_scenario
result = run_scenario(load(sys.argv[1]), until="1 ms", out=sys.argv[2])
sys.exit(0 if result.error is None else 1)
"""


@dataclass(frozen=True)
class Case:
    """One timed start-up: a family's machine file entered one way."""

    family: str
    machine: str
    way: str  # cli or runner

    def argv(self, out: str, *, lazy_control: bool, importtime: bool = False) -> list[str]:
        prelude = LAZY_CONTROL if lazy_control else ""
        flags = ["-X", "importtime"] if importtime else []
        if self.way == "cli":
            code = prelude + CLI
            return [sys.executable, *flags, "-c", code, "run", self.machine, "--until", "1 ms", "--out", out]
        return [sys.executable, *flags, "-c", prelude + RUNNER, self.machine, out]


def children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_once(case: Case, *, lazy_control: bool) -> float:
    """CPU seconds of one fresh interpreter running ``case``."""
    with tempfile.TemporaryDirectory(prefix="cosim-startup-") as folder:
        before = children_cpu_s()
        done = subprocess.run(case.argv(str(Path(folder) / "out"), lazy_control=lazy_control), cwd=ROOT,
                              capture_output=True, text=True, env=_env())
        spent = children_cpu_s() - before
    if done.returncode not in ACCEPTED_STATUS or "Traceback" in done.stderr:
        raise SystemExit(f"{case.machine} ({case.way}) failed with status {done.returncode}:\n{done.stderr}")
    return spent


def heaviest_imports(case: Case, *, lazy_control: bool, top: int = 10) -> list[tuple[str, float]]:
    """The packages ``case`` imported, by their modules' own import time summed [s] (``-X importtime``)."""
    with tempfile.TemporaryDirectory(prefix="cosim-startup-") as folder:
        done = subprocess.run(case.argv(str(Path(folder) / "out"), lazy_control=lazy_control, importtime=True),
                              cwd=ROOT, capture_output=True, text=True, env=_env())
    package: dict[str, float] = {}
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        own, _cumulative, name = line.removeprefix("import time:").split("|")
        parts = name.strip().split(".")
        key = ".".join(parts[:3]) if parts[0] == "cosim" else parts[0]
        package[key] = package.get(key, 0.0) + int(own) * 1e-6
    return sorted(package.items(), key=lambda kv: -kv[1])[:top]


#: Set by --no-bytecode-cache: every start compiles cosim's modules from source.
BYTECODE = {"cache": True}


def _env() -> dict[str, str]:
    """The child's environment: this checkout first on the path; bytecode cached as an installed cosim has it."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    if BYTECODE["cache"]:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(Path(tempfile.gettempdir()) / f"cosim-bench-pycache-{os.getuid()}")
    else:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def measure_case(case: Case, *, repeat: int, lazy_control: bool) -> list[float]:
    """Warm up once (FMU builds, caches), then ``repeat`` timed runs [CPU s]."""
    run_once(case, lazy_control=lazy_control)
    return [run_once(case, lazy_control=lazy_control) for _ in range(repeat)]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per case (default 3: min/median/max)")
    parser.add_argument("--only", choices=sorted(GOAL_S), help="one family only")
    parser.add_argument("--way", choices=("cli", "runner"), help="one way in only (default both)")
    parser.add_argument("--lazy-control", action="store_true",
                        help="make `import control` lazy in the child (python-control loaded on first use)")
    parser.add_argument("--imports", action="store_true", help="also list the heaviest imports of each case")
    parser.add_argument("--no-bytecode-cache", action="store_true",
                        help="compile every module from source at each start (PYTHONDONTWRITEBYTECODE)")
    args = parser.parse_args(argv)
    BYTECODE["cache"] = not args.no_bytecode_cache
    print(f"machine: {machine_load()}")
    print(f"start-up of a machine file run for 1 ms, fresh interpreter, process CPU s, {args.repeat} runs "
          f"(min / median / max){'; python-control lazy' if args.lazy_control else ''}")
    worst: dict[str, list[float]] = {}
    for family, machine in CASES:
        if args.only not in (None, family):
            continue
        for way in ("cli", "runner"):
            if args.way not in (None, way):
                continue
            case = Case(family, machine, way)
            laps = measure_case(case, repeat=args.repeat, lazy_control=args.lazy_control)
            met = "yes" if max(laps) <= GOAL_S[family] else ("median" if sorted(laps)[len(laps) // 2]
                                                              <= GOAL_S[family] else "NO")
            print(f"  {family:7s} {way:7s} {machine:45s} {spread(laps)} s   goal <= {GOAL_S[family]} s: {met}")
            if args.imports:
                for name, seconds in heaviest_imports(case, lazy_control=args.lazy_control):
                    print(f"        import {name:28s} {seconds:6.3f} s (wall, -X importtime)")
            if family not in worst or sorted(laps)[len(laps) // 2] > sorted(worst[family])[len(laps) // 2]:
                worst[family] = laps
    for family, laps in worst.items():
        note = " (python-control lazy)" if args.lazy_control else ""
        print(figure_line(family, f"start-up, 1 ms machine-file run{note} [CPU s]", laps,
                          goal=GOAL_S[family], higher_is_better=False))
    print(f"machine: {machine_load()}")


if __name__ == "__main__":
    main()
