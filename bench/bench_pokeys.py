"""Real-time factor of a 60 s 3-axis PoKeys job at up to 25 kHz with three Stepper FMUs, beside a naive model.

The job: out-and-back straight 3-axis moves (x at up to 25 kHz, y and z at 3/4 and 1/2 of it),
planned by the host planner, streamed by the host model over USB with a 10 ms loop into
:class:`PulseEngine` (one pulse-train segment per slot and axis). Timed parts, each ``--repeat``
times (min / median / max), in wall time and in process CPU time:

* **planning**: the host planner turning the moves into per-slot counts (before the run);
* **engine + host**: the simulation without plants;
* **engine + host + 3 Stepper FMUs**: each axis drives a Stepper FMU loaded exactly as the
  bundled ``pokeys_job`` scenario loads it (FMI 3.0, the NEMA 17 preset, the FMU's own
  ``max_step``: nothing is set for the bench), coupled by :func:`couple_stepper`; the time spent
  inside the FMU calls (adapter and C) is measured around each call, not as a difference of runs;
* **checks**: 9 checks over every pulse (at most 25 per slot, 40 us spacing, direction set-up, on
  each axis), run on the stepper run's trace;
* **the issue's job** = planning + engine + host + FMUs + checks: its real-time factor
  (simulated time / process CPU time) is the headline figure;
* the **naive model** (:mod:`cosim.testing.pokeys_naive`: one SimPy event per pulse, no plants),
  compared with the engine alone.

The steppers' ``commanded_steps`` are compared with the engine's counters after every run. Run::

    .venv/bin/python bench/bench_pokeys.py [--seconds 60] [--repeat 3] [--no-naive] [--no-steppers]
                                           [--ideal-driver] [--max-step S] [--fmi 3]

``--max-step`` and ``--ideal-driver`` change the plants away from the scenario's (the output then
says so).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

from clock import Lap, Series, figure_line, machine_load, measure, spread

from cosim.checks import DirectionSetup, MinPulseSpacing, PulsesPerWindow
from cosim.controllers.pokeys import AXES, SLOT_NS, EngineConfig, PulseEngine, uniform_axes
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.stepper import couple_stepper
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.presets import load_preset
from cosim.testing.pokeys_naive import naive_pulse_engine

FAR = (60_000, -45_000, 30_000)  # x at 25 kHz, y and z proportionally slower
PRESET = "nema17_17hs16_2004s1"  # the bundled pokeys_job scenario's plants
IDEAL_DRIVER = {"phase_inductance": 0.0}  # ideal current source: no L/R current loop
JOB_GOAL_RTF = 50  # issue 29: the whole job at 50x real time or faster


def moves_for(seconds: int, config: EngineConfig) -> list[Move]:
    """Out-and-back moves, enough for the job to last at least ``seconds`` (worked out before any timing)."""
    slots_per_move = len(plan([Move(FAR)], config.axes))
    count = -(-seconds * 1_000_000_000 // (slots_per_move * SLOT_NS))
    return [Move(FAR if k % 2 == 0 else (0, 0, 0)) for k in range(count)]


def job(moves: list[Move], config: EngineConfig) -> list[bytes]:
    """The job's slot entries: the moves planned in one call, as the pokeys_job scenario plans them."""
    return to_entries(plan(moves, config.axes))


class CallTimer:
    """Process CPU and wall time spent inside one FMU's calls (doStep, get, set, prepared writers)."""

    def __init__(self) -> None:
        self.lap = Lap()
        self.calls = 0

    def wrap(self, function: Callable[..., Any]) -> Callable[..., Any]:
        lap, cpu, wall = self.lap, time.process_time, time.perf_counter

        def timed(*args: Any, **kwargs: Any) -> Any:
            self.calls += 1
            w0, c0 = wall(), cpu()
            try:
                return function(*args, **kwargs)
            finally:
                lap.cpu_s += cpu() - c0
                lap.wall_s += wall() - w0

        return timed

    def instrument(self, plant: Plant) -> None:
        plant._step = self.wrap(plant._step)  # the master's prepared doStep (made when the plant was loaded)
        fmu = plant.fmu
        for name in ("advance_to", "get", "set"):
            setattr(fmu, name, self.wrap(getattr(fmu, name)))
        writer, reader = fmu.writer, fmu.reader
        fmu.writer = lambda *a, **k: self.wrap(writer(*a, **k))  # type: ignore[method-assign]
        fmu.reader = lambda *a, **k: self.wrap(reader(*a, **k))  # type: ignore[method-assign]


def simulate(kind: Callable[..., Any], entries: list[bytes], config: EngineConfig, *,
             plant_parameters: dict[str, Any] | None = None, fmi_version: int = 3,
             timer: CallTimer | None = None) -> tuple[Simulation, Lap, int]:
    """Run the job; with ``plant_parameters`` three Stepper FMUs (loaded before the clock starts) follow the axes."""
    sim = Simulation(seed=1)
    engine: PulseEngine = kind(sim, config)
    HostApp(sim, engine, entries, link="usb", prefill_slots=100, period_ns=10_000_000)
    plants = []
    if plant_parameters is not None:
        plants = [Plant.load(sim, "Stepper", name=f"stepper_{a}", fmi_version=fmi_version,
                             parameters=plant_parameters) for a in AXES]
        for i, plant in enumerate(plants):
            if timer is not None:
                timer.instrument(plant)
            couple_stepper(engine.step_dir(i), plant)
    until = (len(entries) + 200) * engine.slot_ticks
    with measure() as lap:
        sim.run(until=until)
    assert engine.underruns == [], engine.underruns
    for i, plant in enumerate(plants):
        commanded = int(plant.read("commanded_steps"))
        assert commanded == engine.positions[i].value == engine.steps[i].position, (commanded, i)
    sim.close()
    return sim, lap, until


def check_every_pulse(sim: Simulation, config: EngineConfig) -> Lap:
    """The 9 pulse checks of the job over every pulse of ``sim``'s trace (they must pass)."""
    with measure() as lap:
        results = []
        for a in AXES:
            step = f"pokeys.{a}.step"
            results += [PulsesPerWindow(step, 25, sim.ticks("1 ms")).evaluate(sim.trace),
                        MinPulseSpacing(step, sim.ticks("40 us")).evaluate(sim.trace),
                        DirectionSetup(step, f"pokeys.{a}.dir", sim.ticks(config.dir_setup_ns, "ns"),
                                       positive_level=0).evaluate(sim.trace)]
    assert all(r.passed for r in results), [r.summary() for r in results if not r.passed]
    return lap


def line(label: str, series: Series, simulated_s: float | None = None, note: str = "") -> str:
    text = f"  {label:44s} cpu {spread(series.cpu())} s   wall {spread(series.wall())} s"
    if simulated_s is not None:
        text += f"   RTF cpu {spread([simulated_s / c for c in series.cpu()], '{:.1f}')}x"
    return text + (f"   {note}" if note else "")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=int, default=60, help="job length [s] (default 60)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of every part (default 3: min/median/max)")
    parser.add_argument("--no-naive", action="store_true", help="skip the naive per-pulse model")
    parser.add_argument("--no-steppers", action="store_true", help="skip the runs with three Stepper FMUs")
    parser.add_argument("--ideal-driver", action="store_true",
                        help="NOT the scenario's plants: Stepper FMUs with an ideal current source (no L/R loop)")
    parser.add_argument("--max-step", type=float, default=None,
                        help="NOT the scenario's plants: the Stepper FMUs' max_step [s] (default: the FMU's own)")
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=3, help="the Stepper FMUs' FMI version (default 3)")
    args = parser.parse_args()

    config = EngineConfig(axes=uniform_axes(max_speed_hz=25_000, accel=500_000, decel=500_000))
    parameters: dict[str, Any] = dict(load_preset(PRESET))
    changed = []
    if args.max_step is not None:
        parameters["max_step"] = args.max_step
        changed.append(f"max_step = {args.max_step:g} s")
    if args.ideal_driver:
        parameters.update(IDEAL_DRIVER)
        changed.append("ideal driver")
    if args.fmi != 3:
        changed.append(f"FMI {args.fmi}.0")
    print(f"machine: {machine_load()} (before)")

    planning, engine, engine_checks, coupled, fmu_calls, checks, naive = (Series() for _ in range(7))
    job_total: list[Lap] = []
    entries: list[bytes] = []
    simulated_s, pulses, calls = 0.0, 0, 0
    moves = moves_for(args.seconds, config)
    for _ in range(args.repeat):
        with measure() as lap:
            entries = job(moves, config)
        planning.add(lap)
        sim, lap, until = simulate(PulseEngine, entries, config)
        engine.add(lap)
        engine_checks.add(check_every_pulse(sim, config))
        simulated_s = sim.timebase.seconds(until)
        pulses = sum(int(sim.trace.segments(f"pokeys.{a}.step")["count"].sum()) for a in AXES)
        if not args.no_steppers:
            timer = CallTimer()
            sim, lap, _ = simulate(PulseEngine, entries, config, plant_parameters=parameters,
                                   fmi_version=args.fmi, timer=timer)
            coupled.add(lap)
            fmu_calls.add(timer.lap)
            calls = timer.calls
            check_lap = check_every_pulse(sim, config)
            checks.add(check_lap)
            job_total.append(Lap(planning.laps[-1].wall_s + lap.wall_s + check_lap.wall_s,
                                 planning.laps[-1].cpu_s + lap.cpu_s + check_lap.cpu_s))
        if not args.no_naive:
            naive_sim, lap, _ = simulate(naive_pulse_engine, entries, config)
            naive.add(lap)
            assert sum(naive_sim.trace.pulses(f"pokeys.{a}.step")[0].size for a in AXES) == pulses

    print(f"job: {simulated_s:.1f} s simulated, {len(entries)} slots, {pulses} pulses on 3 axes (max 25 kHz); "
          f"{args.repeat} runs: min / median / max")
    print(line("planning (host planner, before the run)", planning))
    print(line("engine + host simulation", engine, simulated_s))
    print(line("checks over every pulse (9 checks)", engine_checks))
    if not args.no_steppers:
        plants = f"3 Stepper FMUs ({PRESET}" + (", " + ", ".join(changed) if changed else ", as pokeys_job") + ")"
        print(line(f"engine + host + {plants}"[:44], coupled, simulated_s, plants))
        print(line("  of which inside the FMU calls", fmu_calls, None,
                   f"({calls} calls per run, adapter + C, timed around each call)"))
        rest = Series([Lap(c.wall_s - f.wall_s - e.wall_s, c.cpu_s - f.cpu_s - e.cpu_s)
                       for c, f, e in zip(coupled.laps, fmu_calls.laps, engine.laps, strict=True)])
        print(line("  coupling and master (the rest)", rest, None, "(stepper run - FMU calls - engine run)"))
        print(line("checks over every pulse of that run", checks))
        total = Series(job_total)
        print(line("THE JOB: planning + run + FMUs + checks", total, simulated_s))
        print(figure_line("pokeys", "the job (planning, engine + host + 3 Stepper FMUs, checks) [x real time]",
                          [simulated_s / c for c in total.cpu()], goal=JOB_GOAL_RTF))
    if not args.no_naive:
        print(line("naive model, one event per pulse", naive, simulated_s))
        ratio = [n / e for n, e in zip(naive.cpu(), engine.cpu(), strict=True)]
        print(f"  segment engine / naive model (engine + host alone, cpu): {spread(ratio, '{:.1f}')}x faster")
        if not args.no_steppers:
            ratio = [n / t.cpu_s for n, t in zip(naive.cpu(), job_total, strict=True)]
            print(f"  naive model (no plants, no checks) / the job (cpu): {spread(ratio, '{:.1f}')}x")
    print(f"machine: {machine_load()} (after)")


if __name__ == "__main__":
    main()
