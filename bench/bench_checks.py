"""Process CPU and wall time of the pulse-train checks over a trace of 5,000,000 pulses.

The trace holds ``SEGMENTS`` one-millisecond slots of ``PULSES_PER_SEGMENT`` evenly spread
pulses (1 MHz), reversing direction every ``REVERSE_EVERY`` slots: the direction output changes
at the start of the slot and that slot's pulses start ``DIR_LEAD_NS`` later. Each check is timed on its
own, including the pulse materialisation it does (:meth:`Trace.pulses`); that materialisation
is also timed alone. The best of ``--repeat`` runs is shown (CPU time, and the wall time of the
same run). Run::

    .venv/bin/python bench/bench_checks.py [--segments N] [--repeat R]
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from functools import partial

import numpy as np
from clock import Lap, machine_load, measure

from cosim.checks import Check, DirectionSetup, MaxPulseRate, MinPulseSpacing, PulsesPerWindow
from cosim.trace import Trace

SLOT_NS = 1_000_000
PULSES_PER_SEGMENT = 1000
REVERSE_EVERY = 100
DIR_LEAD_NS = 5_000


def build_trace(segments: int) -> Trace:
    """A step train and its direction output, recorded segment by segment."""
    trace = Trace()
    trace.declare("bench.x.step", "pulse")
    trace.declare("bench.x.dir", "bit")
    direction = (np.arange(segments) // REVERSE_EVERY + 1) % 2  # 1, then 0 after 100 slots, ...
    trace.record("bench.x.dir", 0, 1)
    for k in range(segments):
        t0 = k * SLOT_NS  # t0 + k*period, never summed
        if k and direction[k] != direction[k - 1]:
            trace.record("bench.x.dir", t0, int(direction[k]))
            trace.record_segment("bench.x.step", t0 + DIR_LEAD_NS, SLOT_NS - DIR_LEAD_NS, PULSES_PER_SEGMENT,
                                 int(direction[k]))
        else:
            trace.record_segment("bench.x.step", t0, SLOT_NS, PULSES_PER_SEGMENT, int(direction[k]))
    trace.end_t = segments * SLOT_NS
    return trace


def best_of(repeat: int, action: Callable[[], object]) -> Lap:
    """The run of ``action()`` with the least CPU time of ``repeat`` runs."""
    laps = []
    for _ in range(repeat):
        with measure() as lap:
            action()
        laps.append(lap)
    return min(laps, key=lambda lap: lap.cpu_s)


def show(label: str, lap: Lap, n: int) -> None:
    print(f"  {label:42s} cpu {lap.cpu_s:7.3f} s  {n / lap.cpu_s / 1e6:7.1f} M pulses/s   wall {lap.wall_s:7.3f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=5000, help="1 ms slots of 1000 pulses (default 5000)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per check; the best is shown (default 3)")
    args = parser.parse_args()

    trace = build_trace(args.segments)
    n = args.segments * PULSES_PER_SEGMENT
    checks: list[Check] = [
        MinPulseSpacing("bench.x.step", 900),
        MaxPulseRate("bench.x.step", 1_100_000),
        MaxPulseRate("bench.x.step", 1_100_000, window=SLOT_NS),
        PulsesPerWindow("bench.x.step", PULSES_PER_SEGMENT, SLOT_NS),
        DirectionSetup("bench.x.step", "bench.x.dir", 2_000),
    ]
    print(f"machine: {machine_load()}")
    print(f"{n:,} pulses in {args.segments} segments; best of {args.repeat} runs (least CPU time)")
    def materialise() -> None:
        trace.drop_pulse_cache()  # Trace.pulses keeps its arrays: time the work, not the cache
        trace.pulses("bench.x.step")

    def evaluate(check: Check) -> None:
        trace.drop_pulse_cache()
        check.evaluate(trace)

    show("Trace.pulses (materialise only)", best_of(args.repeat, materialise), n)
    for check in checks:
        result = check.evaluate(trace)
        if not result.passed or result.checked != n:
            raise SystemExit(f"bench trace should pass every check: {result.summary()}")
        label = check.label + (" window" if isinstance(check, MaxPulseRate) and check.window else "")
        show(label, best_of(args.repeat, partial(evaluate, check)), n)


if __name__ == "__main__":
    main()
