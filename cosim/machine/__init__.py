"""Machine files: one TOML file that describes one machine, run like a bundled scenario.

A machine file names the controller and its settings, the plants on its axes (a bundled model
with a preset, or a user's own FMU with a mapping of its variable names onto the couplings'
roles), the programs to run, the checks to apply and the end time::

    [machine]
    description = "3-axis PoKeys mill: a pocket job at 20 kHz"
    until = "2 s"

    [controller]
    family = "pokeys"
    [controller.axis.x]
    max_speed_hz = 20000

    [plant.stepper_x]
    model = "Stepper"
    preset = "nema17_17hs16_2004s1"
    stepper = { axis = "x" }

    [[move]]
    target = [8000, 0, 0]

    [[check]]
    type = "PulsesPerWindow"
    signal = "pokeys.x.step"
    max_count = 25
    window = "1 ms"

``cosim run MACHINE.toml [--set KEY=VALUE ...]`` runs it exactly like a bundled scenario (the
same result folder, report entry and exit codes); ``cosim check-machine MACHINE.toml`` builds it
without running. See ``docs/machines.md`` for every key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.machine.document import Table, apply_overrides, leaves, read_document
from cosim.scenario import Param, Run, ScenarioFile
from cosim.timebase import TimeBase

SUFFIX = ".toml"


@dataclass(frozen=True)
class MachineFile(ScenarioFile):
    """A machine file loaded for running: a scenario whose parameters are the file's keys."""

    document: dict[str, Any] = field(default_factory=dict, repr=False)

    def resolve(self, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The document with ``--set`` overrides applied (by dotted key or a unique trailing part)."""
        values = apply_overrides(self.document, dict(overrides or {}), file=self.path)
        _finite(values, self.path)
        return values

    def until_for(self, values: Mapping[str, Any]) -> str | int:
        """The end time the (overridden) document gives (checked: a time with a unit, naming the file)."""
        return _until(values, self.path)

    def resolution_for(self, values: Mapping[str, Any]) -> Fraction:
        """The resolution the (overridden) document gives (1 ns by default)."""
        return _resolution(values, self.path)


def load_machine(path: str | Path, *, program: str | Path | None = None) -> MachineFile:
    """Load a machine file (and check its ``[machine]`` table); the rest is checked when it is built.

    Parameters
    ----------
    path : path
        The ``.toml`` machine file.
    program : path, optional
        A program file that replaces the machine's ``[[program]]`` list (``cosim run prog.bas
        --machine MACHINE.toml``).
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigurationError(f"machine file {path} does not exist")
    document = read_document(path)
    notes: list[str] = []
    if program is not None:
        program = Path(program)
        if not program.is_file():
            raise ConfigurationError(f"program file {program} does not exist")
        document["program"] = [{"file": str(program.resolve())}]
        job = document.get("job")
        if isinstance(job, dict) and job.get("check") is False:  # said of the machine's own programs
            job["check"] = True
            notes.append(f"{path.name} says [job] check = false of its own programs; the job of {program.name} "
                         f"is checked (--set job.check=false to leave it unchecked)")
    _finite(document, path)
    machine = document.get("machine")
    if not isinstance(machine, dict):
        raise ConfigurationError(f"{path}: machine: the [machine] table is missing (it holds at least until = "
                                 "the end time, e.g. until = \"2 s\")")
    _resolution(document, path)
    _until(document, path)
    name = machine.get("name", path.stem if program is None else f"{path.stem}-{Path(program).stem}")
    if not isinstance(name, str) or not name:
        raise ConfigurationError.out_of_range("machine.name", name, "a non-empty string", where=str(path))
    description = machine.get("description", "")
    parameters = tuple(Param(key, value) for key, value in leaves(document)
                       if isinstance(value, bool | int | float | str))

    def build(run: Run) -> None:
        from cosim.machine.build import build_machine

        values = run.p.as_dict()
        job = values.get("job")
        if not (isinstance(job, dict) and job.get("check") is False):  # (not --set back to false)
            for note in notes:
                run.note(note)
        table = Table(values, file=path, timebase=run.sim.timebase)
        build_machine(run, table, base=path.resolve().parent)

    return MachineFile(name=name, path=path.resolve(), description=str(description), parameters=parameters,
                       until=_until(document, path), function=build, document=document)


def _until(document: Mapping[str, Any], path: Path) -> str:
    """``machine.until``: a time with a unit, > 0, a whole number of ticks of the machine's resolution."""
    until = document.get("machine", {}).get("until")
    if until is None:
        raise ConfigurationError(f"{path}: machine.until is missing (required: the end time, e.g. \"2 s\")")
    if isinstance(until, int | float) and not isinstance(until, bool):
        raise ConfigurationError.out_of_range("machine.until", until, f"a time with a unit: did you mean "
                                              f"\"{validate.shown(until)} s\"?", where=str(path))
    if not isinstance(until, str):
        raise ConfigurationError.out_of_range("machine.until", until, "a time with a unit, e.g. \"2 s\"",
                                              where=str(path))
    timebase = TimeBase(_resolution(document, path))
    try:
        ticks = timebase.ticks(until, name="machine.until")
    except ConfigurationError as exc:
        raise ConfigurationError(f"{path}: {exc}") from None
    if ticks <= 0:
        raise ConfigurationError.out_of_range("machine.until", until, "a time > 0, e.g. \"2 s\"", where=str(path))
    return until


def _resolution(document: Mapping[str, Any], path: Path) -> Fraction:
    text = document.get("machine", {}).get("resolution", "1 ns")
    try:
        ticks = TimeBase(Fraction(1, 10**12)).ticks(text, name="machine.resolution")
    except ConfigurationError as exc:
        raise ConfigurationError(f"{path}: {exc} (a resolution is a time in ps..s, e.g. \"10 ns\")") from None
    if ticks <= 0:
        raise ConfigurationError.out_of_range("machine.resolution", text, "> 0", where=str(path))
    return Fraction(ticks, 10**12)


def _finite(data: Any, path: Path, key: str = "") -> None:
    """Refuse ``nan`` and ``inf`` anywhere in a machine file: no key takes them (naming the file and key)."""
    if isinstance(data, float) and not math.isfinite(data):
        raise ConfigurationError.out_of_range(key, data, "a finite number", where=str(path))
    if isinstance(data, dict):
        for name, value in data.items():
            _finite(value, path, f"{key}.{name}" if key else str(name))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            _finite(value, path, f"{key}[{index}]")
