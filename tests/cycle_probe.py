"""Test helper: probe a PMAC model once per servo cycle."""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any, TypeVar

from cosim.controllers.pmac.units import ServoClock
from cosim.kernel import Simulation
from cosim.timebase import Priority

T = TypeVar("T")


def record_each_cycle(sim: Simulation, clock: ServoClock, probe: Callable[[int, int], T], *,
                      cycles: int) -> list[T]:
    """Call ``probe(k, t_ns)`` after servo cycle ``k`` (priority SAMPLE) for ``k < cycles``.

    Returns the list the results are appended to (filled as the simulation runs).
    """
    results: list[T] = []

    def sample() -> Generator[Any, Any, None]:
        for k in range(clock.first_cycle_at_or_after(sim.now), cycles):
            t = clock.t(k)
            yield sim.at(t, Priority.SAMPLE)
            results.append(probe(k, t))

    sim.process(sample())
    return results
