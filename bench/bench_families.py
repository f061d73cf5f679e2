"""Every family's acceptance figure of issue 29 in one table, from the benches that exist in this tree.

Runs each bench as its own process, one after the other (``--repeat`` runs of its parts, min /
median / max), and collects the lines ``FIGURE {json}`` they print (:func:`clock.figure_line`):
family, figure, min / median / max, goal, met. A bench that prints no such line is read by the
older summary it prints (``... (min / median / max): a / b / c x``, the marginal real-time factors
of ``bench_trio.py`` and ``bench_pmac.py``), else listed with its last output line. A bench that is
missing is listed as missing; one that fails is listed as failed, with its last error line: the
table is printed in any case. ``met`` compares the median with the goal; ``worst`` the worst run.

Run::

    .venv/bin/python bench/bench_families.py [--repeat 3] [--only NAME ...] [--list]

Benches (in this order): startup (and startup with python-control lazy, for the PMAC figure),
kernel, pokeys, trio, pmac, master.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from clock import FIGURE_PREFIX, machine_load

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


@dataclass(frozen=True)
class Bench:
    """One bench script and how the summary runs it."""

    name: str
    script: str
    family: str  # the family a figure is filed under when the bench prints no FIGURE line
    args: tuple[str, ...] = ()
    goal: float | None = None  # for the older summaries: the goal (higher is better)


BENCHES = (
    Bench("startup", "bench_startup.py", "start-up"),
    Bench("startup-lazy-control", "bench_startup.py", "start-up", ("--only", "pmac", "--lazy-control")),
    Bench("kernel", "bench_kernel.py", "kernel"),
    Bench("pokeys", "bench_pokeys.py", "pokeys", ("--no-naive",), goal=50),
    Bench("trio", "bench_trio.py", "trio", goal=50),
    Bench("pmac", "bench_pmac.py", "pmac", goal=25),
    Bench("master", "bench_master.py", "master"),
)
#: ``label ... (min / median / max): a / b / c x`` (the marginal real-time factors bench_trio.py prints).
_SPREAD = re.compile(r"^\s*(?P<label>.*?)\(min / median / max\):\s*(?P<a>[\d.]+) / (?P<b>[\d.]+) / (?P<c>[\d.]+)x")


@dataclass
class Row:
    family: str
    figure: str
    values: str = ""
    goal: str = ""
    met: str = ""
    worst: str = ""


def run(bench: Bench, repeat: int) -> tuple[list[Row], float]:
    """Run one bench; its rows (figures, or why there are none) and its wall time [s]."""
    path = HERE / bench.script
    if not path.is_file():
        return [Row(bench.family, f"{bench.script}: not in this tree", met="missing")], 0.0
    started = time.perf_counter()
    done = subprocess.run([sys.executable, str(path), "--repeat", str(repeat), *bench.args], cwd=ROOT,
                          capture_output=True, text=True)
    wall = time.perf_counter() - started
    lines = done.stdout.splitlines()
    rows = [_figure_row(json.loads(line.removeprefix(FIGURE_PREFIX)), bench)
            for line in lines if line.startswith(FIGURE_PREFIX)]
    if not rows and done.returncode == 0:
        rows = _older_rows(lines, bench)
    if done.returncode != 0:
        error = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        rows.append(Row(bench.family, f"{bench.script} failed (status {done.returncode}): {error[:90]}", met="failed"))
    return rows, wall


def _figure_row(figure: dict[str, object], bench: Bench) -> Row:
    low, mid, high = (float(figure[k]) for k in ("min", "median", "max"))  # type: ignore[arg-type]
    sense = ">=" if figure.get("higher_is_better", True) else "<="
    label = str(figure["figure"]) + (" (python-control lazy)" if "--lazy-control" in bench.args
                                     and "lazy" not in str(figure["figure"]) else "")
    return Row(str(figure["family"]), label, f"{low:.3g} / {mid:.3g} / {high:.3g}", f"{sense} {figure['goal']}",
               "yes" if figure.get("met") else "NO", "yes" if figure.get("met_by_worst") else "no")


def _older_rows(lines: list[str], bench: Bench) -> list[Row]:
    """Figures of a bench that prints no FIGURE line: its ``(min / median / max): a / b / c x`` lines."""
    rows, heading = [], ""
    for line in lines:
        match = _SPREAD.match(line)
        if match is None:
            if line and not line.startswith((" ", "machine", "load")):
                heading = line.rstrip(":")
            continue
        values = sorted(float(match[k]) for k in "abc")
        label = " ".join(p for p in (heading, match["label"].strip()) if p)
        met = worst = ""
        if bench.goal is not None:
            met, worst = ("yes" if values[1] >= bench.goal else "NO"), ("yes" if values[0] >= bench.goal else "no")
        rows.append(Row(bench.family, label[:70], " / ".join(f"{v:.3g}" for v in values),
                        f">= {bench.goal}" if bench.goal is not None else "", met, worst))
    if not rows:
        last = next((line for line in reversed(lines) if line.strip()), "(no output)")
        rows.append(Row(bench.family, f"{bench.script}: no FIGURE line; last line: {last.strip()[:70]}"))
    return rows


def table(rows: list[Row]) -> str:
    header = Row("family", "figure", "min / median / max", "goal", "met", "worst")
    widths = [max(len(getattr(r, f)) for r in [header, *rows]) for f in ("family", "figure", "values", "goal", "met")]
    out = []
    for k, r in enumerate([header, *rows]):
        out.append("  ".join(v.ljust(w) for v, w in zip((r.family, r.figure, r.values, r.goal, r.met),
                                                          widths, strict=True)) + "  " + r.worst)
        if k == 0:
            out.append("  ".join("-" * w for w in widths) + "  -----")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each bench's parts (default 3)")
    parser.add_argument("--only", nargs="+", choices=[b.name for b in BENCHES], help="these benches only")
    parser.add_argument("--list", action="store_true", help="list the benches and whether they are in this tree")
    args = parser.parse_args(argv)
    chosen = [b for b in BENCHES if args.only is None or b.name in args.only]
    if args.list:
        for b in chosen:
            print(f"{b.name:22s} {b.script:18s} {' '.join(b.args):28s} "
                  f"{'present' if (HERE / b.script).is_file() else 'missing'}")
        return
    print(f"machine: {machine_load()} (before)")
    rows: list[Row] = []
    for bench in chosen:
        found, wall = run(bench, args.repeat)
        rows += found
        print(f"  {bench.name}: {len(found)} row(s), {wall:.0f} s", flush=True)
    print(f"machine: {machine_load()} (after)")
    print(f"\nissue 29 acceptance figures, process CPU time, {args.repeat} runs each (min / median / max); "
          "met: the median meets the goal, worst: the worst run does")
    print(table(rows))


if __name__ == "__main__":
    main()
