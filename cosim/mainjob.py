"""The main job: build what is missing, run every bundled scenario and example machine, summarise, report.

Each scenario and each example machine (``examples/**/*.toml``) writes its results into
``<out>/<name>/``; the job prints one summary table and writes ``<out>/summary.json`` and the
static HTML report ``<out>/report.html``.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from cosim.catalog import examples, load
from cosim.outdir import OutputFolder
from cosim.runner import Result, run_scenario, to_json
from cosim.scenario import bundled

#: Verdicts the main job counts as expected (the others make it exit 1).
GOOD = ("PASS", "HAZARD SHOWN", "TERMINATED")


def summary_table(results: list[Result]) -> str:
    """One line per scenario: verdict, checks, key figures, wall time, real-time factor.

    The checks column is ``passed/checks`` of the ordinary checks, preceded by ``shown/hazards``
    and ``h`` for a scenario that declares hazards (``1/1h 2/2``).
    """
    head = f"{'scenario':<28} {'verdict':<13} {'checks':>9} {'wall s':>7} {'RTF':>8}  key figures"
    lines = [head, "-" * len(head)]
    for r in results:
        figures = ", ".join(f"{k}={v['value']:.4g}{(' ' + v['unit']) if v['unit'] else ''}"
                            for k, v in list(r.figures.items())[:3])
        checks = " ".join(([f"{r.shown}/{len(r.hazard_checks)}h"] if r.hazard_checks else [])
                          + ([f"{r.passed}/{len(r.ordinary)}"] if r.ordinary or not r.checks else []))
        lines.append(f"{r.scenario:<28} {r.verdict:<13} {checks:>9} {r.wall_time_s:>7.2f} "
                     f"{r.real_time_factor:>8.1f}  {figures}")
        if r.error:
            lines.append(f"    error: {r.error.splitlines()[0]}")
    return "\n".join(lines)


def main_job(out: Path) -> int:
    """Run every bundled scenario and example machine into ``out``; returns the exit status.

    0 when every run is PASS, HAZARD SHOWN or TERMINATED, 1 when any is FAIL, ERROR, HAZARD MISSED
    or UNCHECKED, 130 when Ctrl-C (or SIGTERM) stopped the job:
    the scenario that was running keeps what it simulated (INTERRUPTED), the rest are not run, and
    the summary and report cover what ran. ``out`` is replaced as a whole when the job ends.
    """
    from cosim import fmubuild

    for model in fmubuild.list_models():
        for version in (2, 3):
            fmubuild.ensure_fmu(model, version)
    staged = OutputFolder(out)
    runs = Stopwatch()
    results = []
    scenarios = []
    names: list[str | Path] = [*bundled(), *examples()]
    for name in names:
        scenario = load(name)
        scenarios.append(scenario)
        print(f"running {scenario.name} ...", flush=True)
        results.append(run_scenario(scenario, out=staged.staging / scenario.name, progress=True))
        if results[-1].verdict == "INTERRUPTED":
            print(f"interrupted: {len(names) - len(results)} scenario(s) not run", flush=True)
            break
    ran = runs.stop()
    print()
    print(summary_table(results))
    (staged.staging / "summary.json").write_text(to_json([r.to_dict() for r in results]))
    report = Stopwatch()
    from cosim.report import write_report

    write_report(results, staged.staging, scenarios=scenarios)
    written = report.stop()
    staged.commit()
    print(f"report: {out / 'report.html'}")
    print(f"time: {len(results)} runs {ran}; report {written}")
    bad = [f"{r.scenario} ({r.verdict})" for r in results if r.verdict not in GOOD]
    tail = f"; not as expected: {', '.join(bad)}" if bad else ""
    shown = sum(r.verdict == "HAZARD SHOWN" for r in results)
    print(f"\n{len(results) - len(bad)}/{len(results)} scenarios as expected ({shown} of them HAZARD SHOWN){tail}")
    return exit_status(results)


class Stopwatch:
    """CPU time (this process and its children: FMU builds, subprocesses) and wall time since it was made."""

    def __init__(self) -> None:
        self.cpu, self.wall = _cpu_s(), time.perf_counter()

    def stop(self) -> str:
        """What it measured, as ``12.3 s CPU, 45.6 s wall``."""
        return f"{_cpu_s() - self.cpu:.1f} s CPU, {time.perf_counter() - self.wall:.1f} s wall"


def _cpu_s() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def exit_status(results: list[Result]) -> int:
    """130 when the last run was interrupted, 1 when any run is not PASS, HAZARD SHOWN or TERMINATED, else 0."""
    if results and results[-1].verdict == "INTERRUPTED":
        return 130
    return 1 if any(r.verdict not in GOOD for r in results) else 0
