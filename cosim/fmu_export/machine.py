"""A machine stepped from outside: the simulation inside an exported FMU, in integer ticks.

:class:`ExportedMachine` builds a machine document (as :mod:`cosim.machine` does for ``cosim run``),
then advances it on request: :meth:`~ExportedMachine.advance` runs every event up to and including
a target tick, or stops at the first later instant where an event-bearing output changes (FMI 3.0
early return). Its outputs are read at the instant reached, after all of its events (the value the
trace holds there) or just before them (:meth:`~ExportedMachine.values` with ``left=True``: what an
importer sees when it is told of an event, before event mode). Inputs set by the importer are
applied at the instant reached, after its events: like a ``[[stimulus]]`` there.

Outputs are watched where the trace records them (:class:`WatchedTrace`), so reading one costs
the same at the first and at the millionth step. Nothing here knows FMI: the float time of an
importer is mapped to ticks by :mod:`cosim.fmu_export.runtime`.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from simpy.core import StopSimulation
from simpy.events import Event

from cosim.errors import ConfigurationError
from cosim.fmu_export.spec import INT32, Port, read_spec, resolve_ports
from cosim.kernel import At, Simulation
from cosim.machine import MachineFile
from cosim.machine.build import build_machine
from cosim.machine.document import Table
from cosim.scenario import Run, Values
from cosim.signals import Signal
from cosim.timebase import TimeBase
from cosim.trace import Trace

#: Same-instant priority of the stop of an :meth:`ExportedMachine.advance`: after everything else.
STOP_PRIORITY = 1_000
#: Tables of a machine file an exported FMU does not build (checks and figures read a finished trace).
NOT_BUILT = ("export", "check", "figure")


class _Watch:
    """The latest value of a recorded signal, and its value just before the instant of its last change."""

    __slots__ = ("before", "t", "value")

    def __init__(self) -> None:
        self.value = 0.0
        self.before = 0.0
        self.t = -1

    def update(self, t: int, value: float) -> None:
        if t > self.t:
            self.before, self.t = self.value, t
        self.value = value

    def at(self, now: int, *, left: bool) -> float:
        return self.before if left and self.t == now else self.value


class _PulseWatch:
    """The signed pulse count of a pulse train at any instant from now on (segments may lie ahead)."""

    __slots__ = ("pending", "settled")

    def __init__(self) -> None:
        self.settled = 0
        self.pending: list[tuple[int, int, int, int]] = []  # (t0, duration, count, sign)

    def segment(self, t0: int, duration: int, count: int, direction: int) -> None:
        if count:
            self.pending.append((t0, duration, count, 1 if direction else -1))

    def position(self, t: int) -> int:
        """Pulses at or before tick ``t`` (pulse k of a segment at ``t0 + (k * duration) // count``).

        Segments whose last pulse is before ``t - 1`` are folded into the settled count, so asking
        for ``t - 1`` (a left limit) after ``t`` stays exact.
        """
        total, keep = self.settled, []
        for segment in self.pending:
            t0, duration, count, sign = segment
            if t < t0:
                keep.append(segment)
                continue
            # pulses k with (k * duration) // count <= t - t0, i.e. k * duration < (t - t0 + 1) * count
            total += sign * min(count, -(-(t - t0 + 1) * count // duration))
            if t0 + ((count - 1) * duration) // count < t - 1:
                self.settled += sign * count
            else:
                keep.append(segment)
        self.pending = keep
        return total


class WatchedTrace(Trace):
    """A :class:`~cosim.trace.Trace` that also keeps the latest value of a few signals as they are recorded.

    Parameters
    ----------
    timebase : TimeBase
    watched : iterable of str
        The signals to follow (the exported outputs).
    """

    def __init__(self, timebase: TimeBase, watched: Sequence[str]) -> None:
        super().__init__(timebase)
        self.watches: dict[str, _Watch] = {name: _Watch() for name in watched}
        self.pulse_watches: dict[str, _PulseWatch] = {name: _PulseWatch() for name in watched}
        #: Called with (name, t) when a watched signal records a value at or before now.
        self.on_change: Callable[[str, int], None] | None = None

    def takes_runs(self, name: str) -> bool:
        """An output is read, and its events found, at each instant: no runs recorded ahead of now."""
        return name not in self.watches

    def _changed(self, name: str, t: int, value: float) -> None:
        self.watches[name].update(t, value)
        if self.on_change is not None:
            self.on_change(name, t)

    def record(self, name: str, t: int, value: float) -> None:
        super().record(name, t, value)
        if name in self.watches:
            self._changed(name, t, value)

    def recorder(self, name: str) -> Callable[[int, float], None]:
        record = super().recorder(name)
        if name not in self.watches:
            return record

        def both(t: int, value: float) -> None:
            record(t, value)
            self._changed(name, t, value)

        return both

    def record_segment(self, name: str, t0: int, duration: int, count: int, direction: int, *,
                       width: int | None = None) -> None:
        super().record_segment(name, t0, duration, count, direction, width=width)
        if name in self.pulse_watches:
            self.pulse_watches[name].segment(t0, duration, count, direction)

    def segment_recorder(self, name: str) -> Callable[[int, int, int, int], None]:
        record = super().segment_recorder(name)
        if name not in self.pulse_watches:
            return record
        watch = self.pulse_watches[name]

        def both(t0: int, duration: int, count: int, direction: int) -> None:
            record(t0, duration, count, direction)
            watch.segment(t0, duration, count, direction)

        return both

    def record_pulse(self, name: str, t: int, direction: int) -> None:
        super().record_pulse(name, t, direction)
        if name in self.pulse_watches:
            self.pulse_watches[name].segment(t, 1, 1, direction)


def _comparator(port: Port) -> Callable[[float], float]:
    """The output's value from its source's value: the value itself, or a comparator's 1.0 / 0.0."""
    below, above = port.below, port.above
    if below is None and above is None:
        return lambda value: value
    return lambda value: float((below is None or value < below) and (above is None or value > above))


def machine_document(values: dict[str, Any], *, plants: str) -> dict[str, Any]:
    """The part of a machine document an FMU builds: no export, checks or figures (no plants when outside)."""
    document = {k: copy.deepcopy(v) for k, v in values.items() if k not in NOT_BUILT}
    if plants == "outside":
        document.pop("plant", None)
    return document


class ExportedMachine:
    """A machine built from its document and advanced on request (see the module docstring).

    Parameters
    ----------
    values : dict
        The machine document (``--set`` applied) with its ``[export]`` table.
    file : Path
        The machine file, for messages.
    base : Path
        The folder the document's relative paths (programs, FMUs) start from.
    seed : int
        Seed of the simulation's random generator.
    """

    def __init__(self, values: dict[str, Any], *, file: Path, base: Path, seed: int = 0) -> None:
        spec = read_spec(values, file=file)
        self.plants_inside = spec.plants == "inside"
        document = machine_document(values, plants=spec.plants)
        machine = MachineFile(name=file.stem, path=file, description="", parameters=(), until=0,
                              function=lambda run: None, document=document)
        timebase = TimeBase(machine.resolution_for(document))
        self.sim = sim = Simulation(timebase=timebase, seed=seed)
        watched = [str(t.data.get("signal")) for t in spec.outputs]
        self.trace = trace = WatchedTrace(timebase, watched)
        sim.trace = trace
        until = machine.until_for(document)
        self.until = sim.ticks(until, name="machine.until") if isinstance(until, str) else until
        self.step = Table({"step": spec.step}, file=file, path="export", timebase=timebase).time("step")
        if self.step <= 0:
            raise ConfigurationError.out_of_range("export.step", spec.step, "> 0", where=str(file))
        self.run = run = Run(sim=sim, p=Values(document), until=self.until)
        try:
            controller = build_machine(run, Table(document, file=file, timebase=timebase), base=base)
            stimulated = [str(s.get("signal")) for s in document.get("stimulus", []) if isinstance(s, dict)]
            self.outputs, self.inputs = resolve_ports(spec, trace=trace, inputs=controller.inputs(),
                                                      plants=run.plants, stimulated=stimulated)
        except BaseException:
            sim.close()
            raise
        self._input_signals: list[Signal] = [{s.name: s for s in controller.inputs()}[p.source] for p in self.inputs]
        self._readers = [self._reader(p) for p in self.outputs]
        self._events: dict[str, list[Callable[[float], float]]] = {}
        for port in self.outputs:
            if port.event:
                self._events.setdefault(port.source, []).append(_comparator(port))
        self._late: set[str] = set()
        self.warnings: list[str] = []
        self._t_start = 0
        self._stop_at = 0
        self._event_t: int | None = None
        self._early = False
        self._stops: set[int] = set()
        trace.on_change = self._on_change

    # -- reading outputs ------------------------------------------------------------------------------
    def _reader(self, port: Port) -> Callable[[bool], float]:
        sim, trace = self.sim, self.trace
        if port.kind == "pulse":
            pulses = trace.pulse_watches[port.source]
            return lambda left: float(pulses.position(sim.now - 1 if left else sim.now))
        if port.kind == "plant":
            plant_name, _, variable = port.source.partition(".")
            plant = next(p for p in self.run.plants if p.name == plant_name)
            return lambda left: float(plant.read(variable))
        watch = trace.watches[port.source]
        level = _comparator(port)
        return lambda left: level(watch.at(sim.now, left=left))

    def values(self, *, left: bool = False) -> list[float]:
        """Every output now: after the events of this instant, or just before them (``left``)."""
        out = [read(left) for read in self._readers]
        for port, value in zip(self.outputs, out, strict=True):
            if port.fmi_type == "Int32" and not INT32[0] <= value <= INT32[1]:
                raise ConfigurationError(f"output {port.name} = {value:.0f} does not fit an FMI Int32 "
                                         f"({INT32[0]}..{INT32[1]})")
        return out

    # -- inputs ---------------------------------------------------------------------------------------
    def apply_inputs(self, values: Sequence[float]) -> None:
        """Set the controller's inputs now (a signal records only a change)."""
        for signal, value in zip(self._input_signals, values, strict=True):
            if value != signal.value:
                signal.set(value)

    # -- advancing ------------------------------------------------------------------------------------
    @property
    def now(self) -> int:
        """The instant reached [ticks]."""
        return self.sim.now

    def advance(self, target: int, *, early_return: bool = False) -> bool:
        """Run every event up to and including tick ``target``; True if an event-bearing output changed there.

        With ``early_return`` the run stops at the first instant after now (at or before ``target``)
        where an event-bearing output changes, after all of that instant's events.
        """
        sim = self.sim
        if target < sim.now:
            raise ConfigurationError(f"cannot step back: target tick {target} is before now ({sim.now})")
        self._t_start, self._stop_at, self._event_t, self._early = sim.now, target, None, early_return
        self._schedule_stop(target)
        try:
            sim.env.run()
        finally:
            sim.trace.end_t = sim.now
        return self._event_t == sim.now

    def _schedule_stop(self, t: int) -> None:
        if t in self._stops:
            return
        self._stops.add(t)
        stop: Event = At(self.sim.env, t, STOP_PRIORITY)
        stop.callbacks.append(self._stop)

    def _stop(self, event: Event) -> None:
        now = self.sim.now
        self._stops.discard(now)
        if now == self._stop_at:
            raise StopSimulation(None)

    def _on_change(self, name: str, t: int) -> None:
        now = self.sim.now
        if t < now and name not in self._late:
            self._late.add(name)
            self.warnings.append(f"{name} was recorded at t = {t} ticks when the simulation was at {now}: "
                                 "the controller model records it after the fact, so the FMU reports it late")
        if name not in self._events or t != now or t <= self._t_start:
            return
        watch = self.trace.watches[name]
        if all(level(watch.before) == level(watch.value) for level in self._events[name]):
            return  # (a comparator that did not flip, or a value set back within the instant)
        if self._event_t is None or t < self._event_t:
            self._event_t = t
            if self._early and t < self._stop_at:
                self._stop_at = t
                self._schedule_stop(t)

    def close(self) -> None:
        """Free the plants (FMUs) inside."""
        self.sim.close()
