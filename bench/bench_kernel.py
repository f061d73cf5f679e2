"""Cost per event of the kernel (issue 29): ``Simulation.after`` / ``at`` / ``call_at`` against bare SimPy.

Each part runs ``--events`` events in one process, ``--repeat`` times (min / median / max), in
process CPU time per event [us]:

* **bare SimPy**: a process that yields ``env.timeout(1)`` (the reference);
* **after**: a process that yields ``sim.after(1, Priority.SLOT)`` (a controller's slot loop);
* **at**: a process that yields ``sim.at(now + 1, Priority.SLOT)``;
* **call_at**: a callback that schedules the next one with ``sim.call_at(now + 1, Priority.SLOT, cb)``
  (no process), against bare SimPy's ``env.timeout(1)`` with the same callback appended;
* **after, 8 processes**: eight processes at different periods (a queue that holds several events).

Goal (issue 29): each within 1.3x of its bare SimPy reference. Run::

    .venv/bin/python bench/bench_kernel.py [--events 200000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
from collections.abc import Callable, Generator
from typing import Any

import simpy
from clock import figure_line, machine_load, measure, spread

from cosim.kernel import Simulation
from cosim.timebase import Priority

GOAL_RATIO = 1.3


def bare_timeout(events: int) -> None:
    env = simpy.Environment()

    def loop() -> Generator[Any, Any, None]:
        for _ in range(events):
            yield env.timeout(1)

    env.process(loop())
    env.run()


def bare_callbacks(events: int) -> None:
    env = simpy.Environment()

    def fire(_event: Any) -> None:
        now = env.now
        if now < events:
            env.timeout(1).callbacks.append(fire)

    env.timeout(1).callbacks.append(fire)
    env.run()


def bare_many(events: int) -> None:
    env = simpy.Environment()

    def loop(period: int, count: int) -> Generator[Any, Any, None]:
        for _ in range(count):
            yield env.timeout(period)

    for k in range(8):
        env.process(loop(k + 1, events // 8))
    env.run()


def after(events: int) -> None:
    sim = Simulation()

    def loop() -> Generator[Any, Any, None]:
        for _ in range(events):
            yield sim.after(1, Priority.SLOT)

    sim.process(loop())
    sim.run(until=events + 1)


def at(events: int) -> None:
    sim = Simulation()

    def loop() -> Generator[Any, Any, None]:
        for k in range(1, events + 1):
            yield sim.at(k, Priority.SLOT)

    sim.process(loop())
    sim.run(until=events + 1)


def call_at(events: int) -> None:
    sim = Simulation()

    def fire() -> None:
        now = sim.now
        if now < events:
            sim.call_at(now + 1, Priority.SLOT, fire)

    sim.call_at(1, Priority.SLOT, fire)
    sim.run(until=events + 1)


def after_many(events: int) -> None:
    sim = Simulation()

    def loop(period: int, count: int) -> Generator[Any, Any, None]:
        for _ in range(count):
            yield sim.after(period, Priority.SLOT)

    for k in range(8):
        sim.process(loop(k + 1, events // 8))
    sim.run(until=8 * (events // 8) + 1)


#: (name, cosim part, its bare SimPy reference)
PARTS: tuple[tuple[str, Callable[[int], None], Callable[[int], None]], ...] = (
    ("after", after, bare_timeout),
    ("at", at, bare_timeout),
    ("call_at", call_at, bare_callbacks),
    ("after, 8 processes", after_many, bare_many),
)


def per_event_us(part: Callable[[int], None], events: int) -> float:
    with measure() as lap:
        part(events)
    return lap.cpu_s / events * 1e6


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--events", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each part (default 3: min/median/max)")
    args = parser.parse_args(argv)
    print(f"machine: {machine_load()}")
    print(f"{args.events} events per run, {args.repeat} runs, process CPU us per event (min / median / max); "
          "each run of a part follows a run of its reference (the ratio is taken pair by pair)")
    ratios_all: dict[str, list[float]] = {}
    for name, part, reference in PARTS:
        part(1000), reference(1000)  # warm up
        pairs = [(per_event_us(reference, args.events), per_event_us(part, args.events)) for _ in range(args.repeat)]
        ratios = [mine / bare for bare, mine in pairs]
        ratios_all[name] = ratios
        met = "yes" if statistics.median(ratios) <= GOAL_RATIO else "NO"
        print(f"  {name:20s} cosim {spread([m for _, m in pairs])} us, bare SimPy ({reference.__name__}) "
              f"{spread([b for b, _ in pairs])} us: {spread(ratios, '{:.2f}')}x (goal <= {GOAL_RATIO}x: {met})")
    worst = max(ratios_all.values(), key=statistics.median)
    print(figure_line("kernel", "cost per event / bare SimPy event, worst part [x]", worst,
                      goal=GOAL_RATIO, higher_is_better=False))
    print(f"machine: {machine_load()}")


if __name__ == "__main__":
    main()
