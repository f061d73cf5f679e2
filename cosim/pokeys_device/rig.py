"""The virtual PoKeys assembled: simulation, engine model, plants, device, pacer; checks when it stops.

:func:`VirtualPoKeys.create` wires everything the server needs::

    Simulation ── PulseEngine (cosim.controllers.pokeys) ── plants wired by ``wire(sim, engine)``
                      │
                 PulseEngineAdapter ── Device (protocol) ── DeviceServer (UDP/TCP, :mod:`.server`)
                      │
                 RealtimePacer (one slot per wall-clock ms)

The engine is built for the identity's model (``EngineConfig.for_model``: 3 axes and 25 pulses
per slot on a 56E or 57E, 8 axes and 125 on a 57CNC). Underruns and refused fills are the
engine's own records (:attr:`PulseEngine.underruns`, :attr:`PulseEngine.refusals`).

When the server stops, :meth:`VirtualPoKeys.finish` runs the PoKeys checks over every recorded pulse
(at most the model's pulses per slot, pulses at least the matching spacing apart, direction set up
before each pulse) and that no fill was refused, writes the trace exports and a ``device.json``
summary (lag report, packet counters, underruns, refusals).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from cosim.checks import CheckResult, DirectionSetup, MinPulseSpacing, PulsesPerWindow, ValueAt
from cosim.controllers.pokeys import EngineConfig, PulseEngine
from cosim.errors import ConfigurationError
from cosim.export import write_trace
from cosim.kernel import Simulation
from cosim.pokeys_device.adapter import PulseEngineAdapter
from cosim.pokeys_device.device import Device
from cosim.pokeys_device.identity import DeviceIdentity
from cosim.pokeys_device.realtime import LagReport, RealtimePacer

Wiring = Callable[[Simulation, PulseEngine], None]
"""``wire(sim, engine)``: couples plants (steppers, switch doubles) to the engine's signals."""


@dataclass
class VirtualPoKeys:
    """Everything behind the sockets. Build it with :meth:`create`."""

    sim: Simulation
    engine: PulseEngine
    adapter: PulseEngineAdapter
    device: Device
    pacer: RealtimePacer
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
            The engine's power-on configuration (the host may change it over the protocol);
            default ``EngineConfig.for_model(identity.model)``. Its model must be the identity's.
        seed : int
            Seed of ``sim.rng`` (for plants that draw random numbers).
        wire : callable, optional
            ``wire(sim, engine)`` couples plants to the engine's step, direction and switch signals.
        rt_priority : int, optional
            SCHED_FIFO priority for the pacing threads (see :class:`RealtimePacer`).
        """
        identity = identity or DeviceIdentity.preset("57E")
        config = config or EngineConfig.for_model(identity.model)
        if config.model != identity.model:
            raise ConfigurationError.out_of_range("engine model", config.model,
                                                  f"{identity.model} (the identity's model)")
        sim = Simulation(seed=seed)
        engine = PulseEngine(sim, config)
        if wire is not None:
            wire(sim, engine)
        adapter = PulseEngineAdapter(engine)
        device = Device(identity, adapter)
        pacer = RealtimePacer(sim, rt_priority=rt_priority)
        return cls(sim, engine, adapter, device, pacer)

    def checks(self) -> list[CheckResult]:
        """The PoKeys checks over every recorded pulse (an axis without pulses passes), and no refused fill."""
        trace, engine = self.sim.trace, self.engine
        cfg, device = engine.config, engine.device
        limit, spacing_us = device.max_pulses_per_slot, device.min_spacing_ns // 1000
        spacing = self.sim.ticks(device.min_spacing_ns, "ns")
        results = []
        for a, axis in enumerate(engine.axis_names):
            step, direction = f"{engine.name}.{axis}.step", f"{engine.name}.{axis}.dir"
            positive_level = 1 if cfg.axes[a].invert_direction else 0
            results += [
                PulsesPerWindow(step, limit, engine.slot_ticks, allow_empty=True,
                                name=f"{axis}: at most {limit} pulses per 1 ms slot").evaluate(trace),
                MinPulseSpacing(step, spacing, allow_empty=True,
                                name=f"{axis}: pulses at least {spacing_us} us apart").evaluate(trace),
                DirectionSetup(step, direction, engine.dir_setup_ticks, positive_level=positive_level,
                               allow_empty=True, name=f"{axis}: direction set up before each pulse").evaluate(trace),
            ]
        results.append(ValueAt(engine.refused_fills.name, None, 0,
                               name=f"no fill refused (an entry a PoKeys{device.name} cannot emit)").evaluate(trace))
        return results

    def summary(self) -> dict[str, Any]:
        """Lag report, packet counters, underruns, positions and pulses per axis, check verdicts."""
        lag: LagReport = self.pacer.report()
        return {
            "identity": asdict(self.device.identity),
            "simulated_ns": self._ns(self.sim.now),
            "lag": {**asdict(lag), "kept_up": lag.kept_up},
            "packets": dict(self.device.log.counts),
            "underruns": [{"t_start_ns": self._ns(u.t_start), "length_ns": self._ns(u.length), "slots": u.slots}
                          for u in self.engine.underruns],
            "refusals": [{"t_ns": self._ns(r.t), "slot": r.slot, "axis": self.engine.axis_names[r.axis],
                          "count": r.count, "limit": r.limit, "reason": r.reason} for r in self.engine.refusals],
            "positions": list(self.engine.status().positions),
            "pulses": [train.position for train in self.engine.steps],
            "checks": [r.summary() for r in self.results],
            "passed": all(r.passed for r in self.results),
            "verdict": self.verdict(),
        }

    def verdict(self) -> str:
        """``FAIL`` (a check failed), ``UNCHECKED`` (no axis emitted a pulse: the pulse checks examined
        nothing, e.g. no client drove the device) or ``PASS``."""
        if not all(r.passed for r in self.results):
            return "FAIL"
        pulse_checks = [r for r in self.results if r.signal.endswith(".step")]
        return "UNCHECKED" if all(r.checked == 0 for r in pulse_checks) else "PASS"

    def _ns(self, ticks: int) -> int:
        """``ticks`` in nanoseconds (the device's simulation runs at 1 ns, or any whole-ns resolution)."""
        return int(ticks * self.sim.timebase.resolution_s * 10**9)

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
