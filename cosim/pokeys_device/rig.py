"""The virtual PoKeys assembled: simulation, engine model, plants, device, pacer; checks when it stops.

:func:`VirtualPoKeys.create` wires everything the server needs::

    Simulation ── PulseEngine (cosim.controllers.pokeys) ── plants wired by ``wire(sim, engine)``
                      │
                 PulseEngineAdapter ── Device (protocol) ── DeviceServer (UDP/TCP, :mod:`.server`)
                      │
                 RealtimePacer (one slot per wall-clock ms) + UnderrunWatch

When the server stops, :meth:`VirtualPoKeys.finish` runs the PoKeys checks over every recorded pulse
(at most 25 per slot, pulses at least 40 us apart, direction set up before each pulse), writes the
trace exports and a ``device.json`` summary (lag report, packet counters, underruns).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Generator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from cosim.checks import CheckResult, DirectionSetup, MinPulseSpacing, PulsesPerWindow
from cosim.controllers.pokeys import AXES, MAX_PULSES_PER_SLOT, SLOT_NS, EngineConfig, EngineState, PulseEngine
from cosim.export import write_trace
from cosim.kernel import At, Simulation
from cosim.pokeys_device.adapter import PulseEngineAdapter
from cosim.pokeys_device.device import Device
from cosim.pokeys_device.identity import DeviceIdentity
from cosim.pokeys_device.realtime import LagReport, RealtimePacer
from cosim.timebase import Priority

Wiring = Callable[[Simulation, PulseEngine], None]
"""``wire(sim, engine)``: couples plants (steppers, switch doubles) to the engine's signals."""


@dataclass(frozen=True)
class Underrun:
    """Slots of buffer mode that found the buffer empty, between two slots that had data.

    Attributes
    ----------
    t_start_ns : int
        Start of the first empty slot.
    slots : int
        Empty slots in a row.
    """

    t_start_ns: int
    slots: int


class UnderrunWatch:
    """Finds buffer underruns as the host sees them: an empty buffer in buffer mode that data ends.

    Just before every slot start (priority SLOT - 1) it looks at the buffer level the engine is
    about to pop from. Empty slots in buffer mode after data start a stretch; the stretch is an
    underrun if data comes again while still in buffer mode. A stretch that lasts until the state
    changes or the run ends is the end of a job, not an underrun. Confirmed underruns are recorded
    as ``pokeys_device.underrun`` (1 during the empty slots).
    """

    def __init__(self, sim: Simulation, engine: PulseEngine) -> None:
        self.sim = sim
        self.engine = engine
        self.underruns: list[Underrun] = []
        self._armed = False
        self._stretch: tuple[int, int] | None = None
        self._name = "pokeys_device.underrun"
        sim.trace.declare(self._name, "bit", description="1 during slots that found the buffer empty mid-job")
        sim.trace.record(self._name, sim.now, 0)
        sim.process(self.watch_slots())

    def watch_slots(self) -> Generator[Any, Any, None]:
        """SimPy process: one look per slot start, before the engine's."""
        t0, env = self.engine.t0_ns, self.sim.env
        k = 0
        while True:
            t = t0 + k * SLOT_NS
            yield At(env, t, Priority.SLOT - 1)
            self.look(t)
            k += 1

    def look(self, t: int) -> None:
        """The buffer level the slot starting at ``t`` will pop from."""
        if self.engine.state != EngineState.BUFFER:
            self._armed, self._stretch = False, None
            return
        if self.engine.buffer.level:
            if self._stretch is not None:
                start, slots = self._stretch
                self.underruns.append(Underrun(start, slots))
                self.sim.trace.record(self._name, start, 1)
                self.sim.trace.record(self._name, t, 0)
            self._armed, self._stretch = True, None
        elif self._armed:
            start, slots = self._stretch or (t, 0)
            self._stretch = (start, slots + 1)


@dataclass
class VirtualPoKeys:
    """Everything behind the sockets. Build it with :meth:`create`."""

    sim: Simulation
    engine: PulseEngine
    adapter: PulseEngineAdapter
    device: Device
    pacer: RealtimePacer
    watch: UnderrunWatch
    results: list[CheckResult] = field(default_factory=list)

    @classmethod
    def create(cls, identity: DeviceIdentity | None = None, *, config: EngineConfig | None = None, seed: int = 0,
               wire: Wiring | None = None, rt_priority: int | None = None) -> VirtualPoKeys:
        """A fresh simulation with the engine model, plants from ``wire``, the device and its pacer.

        Parameters
        ----------
        identity : DeviceIdentity, optional
            Default: the PoKeys57E preset (pulse engine v2).
        config : EngineConfig, optional
            The engine's power-on configuration (the host may change it over the protocol).
        seed : int
            Seed of ``sim.rng`` (for plants that draw random numbers).
        wire : callable, optional
            ``wire(sim, engine)`` couples plants to the engine's step, direction and switch signals.
        rt_priority : int, optional
            SCHED_FIFO priority for the pacing threads (see :class:`RealtimePacer`).
        """
        sim = Simulation(seed=seed)
        engine = PulseEngine(sim, config or EngineConfig())
        if wire is not None:
            wire(sim, engine)
        adapter = PulseEngineAdapter(engine)
        device = Device(identity or DeviceIdentity.preset("57E"), adapter)
        pacer = RealtimePacer(sim, rt_priority=rt_priority)
        return cls(sim, engine, adapter, device, pacer, UnderrunWatch(sim, engine))

    def checks(self) -> list[CheckResult]:
        """The PoKeys checks over every recorded pulse (an axis without pulses passes)."""
        trace, cfg = self.sim.trace, self.engine.config
        results = []
        for a, axis in enumerate(AXES):
            step, direction = f"{self.engine.name}.{axis}.step", f"{self.engine.name}.{axis}.dir"
            positive_level = 1 if cfg.axes[a].invert_direction else 0
            results += [
                PulsesPerWindow(step, MAX_PULSES_PER_SLOT, SLOT_NS, allow_empty=True,
                                name=f"{axis}: at most {MAX_PULSES_PER_SLOT} pulses per 1 ms slot").evaluate(trace),
                MinPulseSpacing(step, SLOT_NS // MAX_PULSES_PER_SLOT, allow_empty=True,
                                name=f"{axis}: pulses at least 40 us apart").evaluate(trace),
                DirectionSetup(step, direction, cfg.dir_setup_ns, positive_level=positive_level, allow_empty=True,
                               name=f"{axis}: direction set up before each pulse").evaluate(trace),
            ]
        return results

    def summary(self) -> dict[str, Any]:
        """Lag report, packet counters, underruns, positions and pulses per axis, check verdicts."""
        lag: LagReport = self.pacer.report()
        return {
            "identity": asdict(self.device.identity),
            "simulated_ns": self.sim.now,
            "lag": {**asdict(lag), "kept_up": lag.kept_up},
            "packets": dict(self.device.log.counts),
            "underruns": [asdict(u) for u in self.watch.underruns],
            "positions": list(self.engine.status().positions),
            "pulses": [train.position for train in self.engine.steps],
            "checks": [r.summary() for r in self.results],
            "passed": all(r.passed for r in self.results),
        }

    def finish(self, out: str | Path | None = None, *, formats: tuple[str, ...] = ("vcd", "parquet")) -> dict[str, Any]:
        """After the server stopped: run the checks, write the trace and ``device.json`` into ``out``."""
        self.sim.trace.end_t = self.sim.now
        self.sim.trace.meta["pokeys_device"] = {"model": self.device.identity.model,
                                                "serial": self.device.identity.serial}
        self.results = self.checks()
        summary = self.summary()
        if out is not None:
            folder = write_trace(self.sim.trace, out, formats=formats)
            (folder / "device.json").write_text(json.dumps(summary, indent=1))
        return summary
