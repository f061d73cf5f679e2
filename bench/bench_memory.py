"""Peak memory of long PoKeys jobs per simulated minute, with and without the VCD export.

Each job is the bundled ``pokeys_job`` scenario (3 axes near 25 kHz, planned out-and-back moves,
steppers off: what grows with a long run is the trace, the checks and the exports, not the
plants), run in a fresh process the way ``cosim run`` runs it: simulate, check every pulse, write
the results folder (Parquet tables, and with VCD ``trace.vcd``, ``trace_digital.vcd`` and
``trace.gtkw``). Printed per job and export:

* the resident set size (RSS) at every simulated minute, sampled inside the run (does memory
  grow with simulated time?);
* the peak RSS of the whole process (run, checks, export: ``ru_maxrss``) and that peak per
  simulated minute;
* process CPU time (user + system) beside wall time, and the size of what was written.

Jobs: ``60s`` (4 moves of 360,000 x pulses, 61 s), ``10min`` (15 moves of 960,000, 601 s) and
``1h`` (86 moves of 1,000,000, 3,606 s; about 10 GB of VCD, minutes of run time). Run::

    .venv/bin/python bench/bench_memory.py [--jobs 60s,10min] [--no-vcd-only] [--keep DIR]
    .venv/bin/python bench/bench_memory.py --jobs 1h
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Generator
from pathlib import Path
from typing import Any

#: name: (scenario parameters, until)
JOBS: dict[str, tuple[dict[str, str], str]] = {
    "60s": ({"moves": "4", "distance": "360000"}, "61 s"),
    "10min": ({"moves": "15", "distance": "960000"}, "601 s"),
    "1h": ({"moves": "86", "distance": "1000000"}, "3606 s"),
}
MIB = 1 << 20


def rss_mib() -> float:
    """This process's resident set size now [MiB] (Linux)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * resource.getpagesize() / MIB


def child(job: str, vcd: bool, out: Path) -> dict[str, Any]:
    """Run one job in this process and measure it (called in a fresh process by :func:`measure`)."""
    from cosim.kernel import Simulation
    from cosim.runner import run_scenario
    from cosim.scenario import Run, load
    from cosim.timebase import Priority

    parameters, until = JOBS[job]
    scenario = load("pokeys_job")
    minutes: list[tuple[int, float, int]] = []

    def sample(sim: Simulation) -> Generator[Any, Any, None]:
        minute = sim.ticks("60 s")
        k = 1
        while True:
            yield sim.at(k * minute, Priority.SAMPLE)
            minutes.append((k, round(rss_mib(), 1), sim.trace.memory_rows()))
            k += 1

    def with_sampling(run: Run) -> None:
        scenario.function(run)
        run.sim.process(sample(run.sim))

    wall, cpu = time.perf_counter(), time.process_time()
    result = run_scenario(dataclasses.replace(scenario, function=with_sampling),
                          overrides={**parameters, "steppers": "false"}, until=until, out=out,
                          formats=("vcd", "parquet") if vcd else ("parquet",))
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return {"job": job, "vcd": vcd, "verdict": result.verdict, "simulated_s": result.simulated_s,
            "peak_mib": round(usage.ru_maxrss / 1024, 1), "cpu_s": round(time.process_time() - cpu, 2),
            "wall_s": round(time.perf_counter() - wall, 2), "minutes": minutes,
            "written_mib": round(sum(p.stat().st_size for p in out.iterdir() if p.is_file()) / MIB, 1)}


def measure(job: str, vcd: bool, out: Path) -> dict[str, Any]:
    """Run ``job`` in a fresh process; its measurements."""
    done = subprocess.run([sys.executable, __file__, "--child", job, "vcd" if vcd else "no-vcd", str(out)],
                          capture_output=True, text=True, check=True)
    return dict(json.loads(done.stdout.splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", default="60s,10min", help="comma-separated: " + ", ".join(JOBS))
    parser.add_argument("--no-vcd-only", action="store_true", help="skip the runs with VCD")
    parser.add_argument("--keep", type=Path, help="keep the results folders here (default: deleted)")
    parser.add_argument("--child", nargs=3, metavar=("JOB", "VCD", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        job, vcd, out = args.child
        print(json.dumps(child(job, vcd == "vcd", Path(out))))
        return
    base = args.keep or Path(tempfile.mkdtemp(prefix="cosim-bench-memory-"))
    print(f"{'job':>6} {'VCD':>4} {'verdict':>7} {'peak RSS':>10} {'per sim. min':>12} {'CPU':>8} {'wall':>8} "
          f"{'written':>10}  RSS at each simulated minute [MiB]")
    try:
        for job in args.jobs.split(","):
            for vcd in (False,) if args.no_vcd_only else (False, True):
                out = base / f"{job}-{'vcd' if vcd else 'no-vcd'}"
                r = measure(job, vcd, out)
                per_minute = r["peak_mib"] / (r["simulated_s"] / 60)
                curve = " ".join(f"{rss:.0f}" for _, rss, _ in r["minutes"][:12])
                more = " ..." if len(r["minutes"]) > 12 else ""
                print(f"{job:>6} {'yes' if vcd else 'no':>4} {r['verdict']:>7} {r['peak_mib']:>6.0f} MiB "
                      f"{per_minute:>8.1f} MiB {r['cpu_s']:>6.1f} s {r['wall_s']:>6.1f} s "
                      f"{r['written_mib']:>6.0f} MiB  {curve}{more}", flush=True)
    finally:
        if args.keep is None:
            shutil.rmtree(base, ignore_errors=True)


if __name__ == "__main__":
    main()
