"""Real-time factor of the Trio runs (issue 29): trio_example with the Laser FMU and the engraver machine.

Each run is timed in process CPU time, ``--repeat`` times (min / median / max). Start-up (imports,
building the machine, loading the FMUs, the checks and writing nothing) is cancelled by the
long-minus-short method: the marginal real-time factor is

    (simulated s of the long run - simulated s of the short run) / (CPU s long - CPU s short)

* **trio_example**: the TN20-81 program with the Laser FMU sampled every 1 ms, 2 passes vs 20
  passes (4.4 s vs 43.9 s of machine time);
* **engraver**: ``examples/trio_engraver/engraver.toml`` (two Stepper FMUs, the Laser FMU sampled
  every 100 us, two BASIC processes), run to 0.5 s vs to its end at 4 s;
* **line**: ``examples/trio_line/line.toml`` (the marking line: DATUM homing of a Stepper FMU lift,
  CONNECT to the conveyor, REGIST, the Laser FMU sampled every 1 ms, three processes), run to 0.5 s
  vs to its end at 5 s.

Both runs of a pair are measured in the same process, one after the other, the short one first;
the first pair is preceded by one untimed short run so that imports and FMU builds are not timed.
``--profile NAME`` prints the top functions of one long run by own time instead. Run::

    .venv/bin/python bench/bench_trio.py [--repeat 3] [--only trio_example|engraver|line] [--profile NAME]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from clock import machine_load, measure, spread

from cosim.catalog import load
from cosim.runner import Result, run_scenario

ROOT = Path(__file__).resolve().parent.parent
ENGRAVER = ROOT / "examples" / "trio_engraver" / "engraver.toml"
LINE = ROOT / "examples" / "trio_line" / "line.toml"


@dataclass(frozen=True)
class Pair:
    """A short and a long run of the same machine."""

    name: str
    short: Callable[[], Result]
    long: Callable[[], Result]


def _checked(result: Result) -> Result:
    if result.error is not None or result.verdict != "PASS":
        raise SystemExit(f"{result.scenario}: {result.verdict} {result.error or ''}\n{result.table()}")
    return result


PAIRS = {
    "trio_example": Pair(
        "trio_example (Laser FMU, 2 vs 20 passes)",
        lambda: _checked(run_scenario(load("trio_example"), overrides={"passes": "2"})),
        lambda: _checked(run_scenario(load("trio_example"), overrides={"passes": "20"}))),
    "engraver": Pair(
        "engraver (2 Stepper FMUs + Laser FMU, to 0.5 s vs to 4 s)",
        lambda: run_scenario(load(ENGRAVER), until="500 ms"),
        lambda: _checked(run_scenario(load(ENGRAVER)))),
    "line": Pair(
        "line (Stepper FMU lift + Laser FMU, to 0.5 s vs to 5 s)",
        lambda: run_scenario(load(LINE), until="500 ms"),
        lambda: _checked(run_scenario(load(LINE)))),
}


def marginal(pair: Pair, repeat: int) -> None:
    pair.short()  # warm-up: imports, FMU builds, lark grammars
    rates, short_cpu, long_cpu = [], [], []
    for _ in range(repeat):
        with measure() as lap_short:
            short = pair.short()
        with measure() as lap_long:
            long = pair.long()
        simulated = float(long.simulated_s) - float(short.simulated_s)
        rates.append(simulated / (lap_long.cpu_s - lap_short.cpu_s))
        short_cpu.append(lap_short.cpu_s)
        long_cpu.append(lap_long.cpu_s)
    print(f"{pair.name}:")
    print(f"  short run  {float(short.simulated_s):7.3f} s simulated, CPU {spread(short_cpu)} s")
    print(f"  long run   {float(long.simulated_s):7.3f} s simulated, CPU {spread(long_cpu)} s")
    print(f"  marginal real-time factor (min / median / max): {spread(rates, '{:.1f}')}x "
          f"(median {statistics.median(rates):.1f}x)")


def profile(pair: Pair, top: int) -> None:
    pair.short()
    profiler = cProfile.Profile()
    profiler.enable()
    pair.long()
    profiler.disable()
    stats = pstats.Stats(profiler)
    stats.sort_stats("tottime").print_stats(top)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--only", choices=sorted(PAIRS))
    parser.add_argument("--profile", choices=sorted(PAIRS))
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args()
    if args.profile:
        profile(PAIRS[args.profile], args.top)
        return
    print(machine_load())
    for key, pair in PAIRS.items():
        if args.only in (None, key):
            marginal(pair, args.repeat)
    print(machine_load())


if __name__ == "__main__":
    main()
