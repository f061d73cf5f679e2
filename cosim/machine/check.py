"""``cosim check-machine`` and ``cosim params``: build a machine at t = 0 without simulating, and say what it holds."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from cosim.kernel import Simulation
from cosim.machine import MachineFile
from cosim.machine.document import KeySpec, Table
from cosim.scenario import Run, Values
from cosim.timebase import TimeBase


@contextmanager
def built(machine: MachineFile, *, overrides: Mapping[str, Any] | None = None) -> Iterator[tuple[Run, Table]]:
    """The machine built at t = 0 (every key, program, FMU, coupling and signal checked), and its document."""
    values = machine.resolve(overrides)
    with Simulation(timebase=TimeBase(machine.resolution_for(values))) as sim:
        until = machine.until_for(values)
        end = sim.ticks(until, name="machine.until") if isinstance(until, str) else until
        run = Run(sim=sim, p=Values(values), until=end)
        document = Table(values, file=machine.path, timebase=sim.timebase)
        from cosim.machine.build import build_machine

        build_machine(run, document, base=machine.path.parent)
        yield run, document


def check_machine(machine: MachineFile, *, overrides: Mapping[str, Any] | None = None) -> str:
    """Build ``machine`` (every key, program, FMU and coupling checked); a summary line, or ConfigurationError."""
    with built(machine, overrides=overrides) as (run, document):
        until = machine.until_for(document.data)
        family = document.data["controller"]["family"]
        return (f"{machine.path}: OK: a {family} machine with {len(run.plants)} plant(s), {len(run.checks)} "
                f"check(s), {len(run.figures)} figure(s), {len(run.sim.trace.names())} signals; runs until {until}")


def machine_keys(machine: MachineFile, *, overrides: Mapping[str, Any] | None = None) -> list[KeySpec]:
    """Every key the machine's builder read, with its value (or default), unit and allowed values."""
    from cosim.machine.params import describe, loader_keys

    with built(machine, overrides=overrides) as (run, document):
        specs = loader_keys(document) + document.specs()
        return describe(document.data, specs, plants={plant.name: plant for plant in run.plants})
