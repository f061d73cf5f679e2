"""Real-time factor of the PoKeys pulse engine on a 60 s 3-axis job at up to 25 kHz, beside a naive model.

The same job runs in one process: through :class:`PulseEngine` (one pulse-train segment per slot
and axis) alone, through it with three Stepper FMUs (NEMA 17 preset with its L/R current loop,
FMI 3.0, ``max_step`` 100 us so that the FMU's own bounds set its steps) coupled by
the cosim.couplings.stepper coupling, and through the naive model of
:mod:`cosim.testing.pokeys_naive` (one SimPy event per pulse). All are fed by the host model over
the USB link. Then every pulse of the segment run is checked (at most 25 per slot, spacing,
direction set-up) and the steppers' ``commanded_steps`` are compared with the engine counters.
Printed: wall time per part (engine, FMUs = the difference between the runs with and without
them, checks) and the real-time factors (simulated time / wall time). Run::

    .venv/bin/python bench/bench_pokeys.py [--seconds 60] [--no-naive] [--no-steppers] [--ideal-driver]
                                           [--max-step 1e-4]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from cosim.checks import DirectionSetup, MinPulseSpacing, PulsesPerWindow
from cosim.controllers.pokeys import AXES, SLOT_NS, EngineConfig, PulseEngine, uniform_axes
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.stepper import couple_stepper
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.presets import load_preset
from cosim.signals import Signal
from cosim.testing.pokeys_naive import naive_pulse_engine

FAR = (60_000, -45_000, 30_000)  # x at 25 kHz, y and z proportionally slower


def job(seconds: int, config: EngineConfig) -> list[bytes]:
    """Out-and-back moves until the job lasts at least ``seconds``."""
    counts: list[tuple[int, ...]] = []
    k = 0
    while len(counts) * SLOT_NS < seconds * 1_000_000_000:
        counts.extend(plan([Move(FAR if k % 2 == 0 else (0, 0, 0))], config.axes,
                           start=(0, 0, 0) if k % 2 == 0 else FAR))
        k += 1
    return to_entries(counts)


IDEAL_DRIVER = {"phase_inductance": 0.0}  # ideal current source: no L/R current loop
MAX_STEP_S = 1e-4  # the FMU's solver: its own bounds (natural period / 50, 0.25 rad electrical, pulses) govern


class StandIn:
    """A plant that takes every input and does nothing: measures the coupling's own cost."""

    def __init__(self, sim: Simulation, name: str) -> None:
        self.sim = sim
        self.name = name

    def variable_names(self) -> list[str]:
        return ["step_rate", "step_phase", "commanded_steps"]

    def set(self, values: Mapping[str, float]) -> None:
        pass

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        return lambda values: None

    def read(self, variable: str) -> object:
        return 0

    def watch(self, variable: str, *, signal: str | None = None, kind: str = "bit") -> Signal:
        raise NotImplementedError


def simulate(kind: Callable[..., Any], entries: list[bytes], config: EngineConfig, *,
             steppers: bool = False, stand_ins: bool = False, ideal_driver: bool = False,
             max_step_s: float = MAX_STEP_S) -> tuple[Simulation, float, int]:
    """Run the job; with ``steppers`` three Stepper FMUs (loaded before the clock starts) follow the
    axes, with ``stand_ins`` three plants that do nothing."""
    sim = Simulation(seed=1)
    engine: PulseEngine = kind(sim, config)
    HostApp(sim, engine, entries, link="usb", prefill_slots=100, period_ns=10_000_000)
    plants = []
    if stand_ins:
        for i, a in enumerate(AXES):
            couple_stepper(engine.step_dir(i), StandIn(sim, f"stand_in_{a}"))
    if steppers:
        preset = {**load_preset("nema17_17hs16_2004s1"), "max_step": max_step_s,
                  **(IDEAL_DRIVER if ideal_driver else {})}
        plants = [Plant.load(sim, "Stepper", name=f"stepper_{a}", parameters=preset) for a in AXES]
        for i, plant in enumerate(plants):
            couple_stepper(engine.step_dir(i), plant)
    until = (len(entries) + 200) * engine.slot_ticks
    started = time.perf_counter()
    sim.run(until=until)
    wall = time.perf_counter() - started
    assert engine.underruns == [], engine.underruns
    for i, plant in enumerate(plants):
        commanded = int(plant.read("commanded_steps"))
        assert commanded == engine.positions[i].value == engine.steps[i].position, (commanded, i)
    sim.close()
    return sim, wall, until


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=int, default=60, help="job length [s] (default 60)")
    parser.add_argument("--no-naive", action="store_true", help="skip the naive per-pulse model")
    parser.add_argument("--no-steppers", action="store_true", help="skip the run with three stepper FMUs")
    parser.add_argument("--ideal-driver", action="store_true",
                        help="stepper FMUs with an ideal current source (no L/R current loop)")
    parser.add_argument("--max-step", type=float, default=MAX_STEP_S,
                        help=f"the stepper FMUs' max_step [s] (default {MAX_STEP_S:g}; the FMU's own default is 10e-6)")
    args = parser.parse_args()

    config = EngineConfig(axes=uniform_axes(max_speed_hz=25_000, accel=500_000, decel=500_000))
    started = time.perf_counter()
    entries = job(args.seconds, config)
    plan_s = time.perf_counter() - started
    sim, engine_s, until = simulate(PulseEngine, entries, config)
    simulated_s = sim.timebase.seconds(until)
    pulses = sum(int(sim.trace.segments(f"pokeys.{a}.step")["count"].sum()) for a in AXES)

    started = time.perf_counter()
    results = []
    for a in AXES:
        step = f"pokeys.{a}.step"
        results += [PulsesPerWindow(step, 25, sim.ticks("1 ms")).evaluate(sim.trace),
                    MinPulseSpacing(step, sim.ticks("40 us")).evaluate(sim.trace),
                    DirectionSetup(step, f"pokeys.{a}.dir", sim.ticks(config.dir_setup_ns, "ns"),
                                   positive_level=0).evaluate(sim.trace)]
    checks_s = time.perf_counter() - started
    assert all(r.passed for r in results), [r.summary() for r in results if not r.passed]

    print(f"job: {simulated_s:.1f} s simulated, {len(entries)} slots, {pulses} pulses on 3 axes (max 25 kHz)")
    print(f"  planning (host planner, before the run)  {plan_s:8.3f} s")
    print(f"  engine + host simulation                 {engine_s:8.3f} s   RTF {simulated_s / engine_s:7.1f}x")
    print(f"  checks over every pulse ({len(results)} checks)      {checks_s:8.3f} s")
    total = engine_s + checks_s
    print(f"  engine + checks                          {total:8.3f} s   RTF {simulated_s / total:7.1f}x")
    if not args.no_steppers:
        _, stand_in_s, _ = simulate(PulseEngine, entries, config, stand_ins=True)
        print(f"  engine + host + coupling to 3 stand-ins   {stand_in_s:8.3f} s   (the coupling alone: "
              f"{stand_in_s - engine_s:.3f} s)")
        _, coupled_s, _ = simulate(PulseEngine, entries, config, steppers=True, ideal_driver=args.ideal_driver,
                                   max_step_s=args.max_step)
        print(f"  engine + host + 3 stepper FMUs           {coupled_s:8.3f} s   RTF {simulated_s / coupled_s:7.1f}x")
        print(f"    of which the FMUs and their coupling   {coupled_s - engine_s:8.3f} s   "
              "(commanded_steps = counters: checked)")
        print(f"    of which the FMU calls (adapter + C)   {coupled_s - stand_in_s:8.3f} s")
        full = coupled_s + checks_s
        print(f"  engine + FMUs + checks (the issue's job) {full:8.3f} s   RTF {simulated_s / full:7.1f}x")
    if not args.no_naive:
        naive_sim, naive_s, _ = simulate(naive_pulse_engine, entries, config)
        naive_pulses = sum(naive_sim.trace.pulses(f"pokeys.{a}.step")[0].size for a in AXES)
        assert naive_pulses == pulses
        print(f"  naive model, one event per pulse         {naive_s:8.3f} s   RTF {simulated_s / naive_s:7.1f}x")
        print(f"segment engine / naive model: {naive_s / engine_s:.1f}x faster "
              f"({(naive_s + checks_s) / total:.1f}x with the same checks added to both)")


if __name__ == "__main__":
    main()
