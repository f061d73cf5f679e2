"""``cosim check-machine``: build a machine at t = 0 without simulating, and say what it holds."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from cosim.kernel import Simulation
from cosim.machine import MachineFile
from cosim.scenario import Run, Values
from cosim.timebase import TimeBase


def check_machine(machine: MachineFile, *, overrides: Mapping[str, Any] | None = None) -> str:
    """Build ``machine`` (every key, program, FMU and coupling checked); a summary line, or ConfigurationError."""
    values = machine.resolve(overrides)
    with Simulation(timebase=TimeBase(machine.resolution_for(values))) as sim:
        until = machine.until_for(values)
        end = sim.ticks(until, name="machine.until") if isinstance(until, str) else until
        run = Run(sim=sim, p=Values(values), until=end)
        machine.function(run)
        family = values["controller"]["family"]
        return (f"{machine.path}: OK: a {family} machine with {len(run.plants)} plant(s), {len(run.checks)} "
                f"check(s), {len(run.figures)} figure(s), {len(sim.trace.names())} signals; runs until {until}")
