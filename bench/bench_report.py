"""CPU time of writing the report of stored results (the main job's, by default), min/median/max of 3.

The runs are not repeated: the report is written again over a results folder that ``cosim main``
wrote once (each run's ``result.json``, ``trace_meta.json`` and tables), each time in a fresh
process, the way the main job writes it after its runs (the scenarios' modules already imported).
Printed: the process CPU time (user + system) of ``write_site`` per repetition, its min/median/max,
the number of pages and rows, and the pages' sizes. Run::

    .venv/bin/cosim main --out /tmp/results        # once (minutes)
    .venv/bin/python bench/bench_report.py /tmp/results [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any


def entries(results: Path) -> list[Any]:
    """The report's entries of a results folder, in the order of its ``summary.json``."""
    from cosim.catalog import load
    from cosim.report import Entry, describe

    order = [r["scenario"] for r in json.loads((results / "summary.json").read_text())]
    found = []
    for name in order:
        folder = results / name
        result = json.loads((folder / "result.json").read_text())
        try:
            description = describe(load(_source(name)))
        except Exception:  # a run whose scenario is gone still gets its page
            description = ""
        found.append(Entry(name, folder, result, description))
    return found


def _source(name: str) -> str | Path:
    from cosim.catalog import examples

    machine = next((p for p in examples() if p.stem == name), None)
    return machine if machine is not None else name


def child(results: Path) -> dict[str, Any]:
    """Write the report once in this process; its CPU and wall time."""
    import cosim.runner  # noqa: F401  (imported by the main job before its report)

    found = entries(results)
    from cosim.report import write_site

    cpu, wall = time.process_time(), time.perf_counter()
    write_site(found, results)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    pages = [e.folder / "index.html" for e in found]
    return {"cpu_s": cpu, "wall_s": wall, "pages": len(pages), "sizes": [p.stat().st_size for p in pages]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path, help="a folder written by `cosim main --out`")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(args.results)))
        return
    runs = []
    for k in range(args.repeat):
        done = subprocess.run([sys.executable, __file__, str(args.results), "--child"], capture_output=True,
                              text=True, check=True)
        runs.append(json.loads(done.stdout.splitlines()[-1]))
        print(f"run {k + 1}: {runs[-1]['cpu_s']:.2f} s CPU, {runs[-1]['wall_s']:.2f} s wall", flush=True)
    cpu = [r["cpu_s"] for r in runs]
    sizes = sorted(runs[-1]["sizes"])
    print(f"report of {runs[-1]['pages']} pages: CPU min {min(cpu):.2f} s, median {statistics.median(cpu):.2f} s, "
          f"max {max(cpu):.2f} s")
    print(f"pages: {sizes[0] / 1e3:.0f} kB to {sizes[-1] / 1e6:.2f} MB, median {statistics.median(sizes) / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
