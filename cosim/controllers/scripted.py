"""A scripted source: sets signals at given instants (the simplest controller)."""

from __future__ import annotations

from collections.abc import Generator, Iterable, Mapping
from typing import Any

from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.signals import Signal
from cosim.timebase import Priority


def play(sim: Simulation, schedule: Iterable[tuple[int, Mapping[Signal, float]]], *,
         priority: int = Priority.HOST) -> None:
    """Start a process that applies ``schedule`` (``(t, {signal: value})`` in time order).

    Parameters
    ----------
    sim : Simulation
    schedule : iterable of (int, mapping)
        Times [ticks] (non-decreasing) and the signal values to set at each.
    priority : int
        Same-instant priority of the changes (HOST by default).
    """
    steps = list(schedule)
    times = [t for t, _ in steps]
    if times != sorted(times):
        raise ConfigurationError(f"schedule times must not decrease; got {times[:10]}")

    def run() -> Generator[Any, Any, None]:
        for t, values in steps:
            yield sim.at(t, priority)
            for signal, value in values.items():
                signal.set(value)

    sim.process(run())
