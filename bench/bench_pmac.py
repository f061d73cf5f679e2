"""Real-time factor of the PMAC runs with their FMUs, start-up cancelled, and where the time goes.

Runs, each as the main job runs it (``cosim.runner.run_scenario``, no results written):

* the flying shear (``examples/pmac_flying_shear/shear.toml``: the Conveyor FMU as master encoder with
  its registration mark, the Servo FMU under a 100 Hz PID, a PLC arming the triggered time base);
* ``pmac_fmu_slave`` (the same on a Python scenario, no PLC);
* the line (``examples/pmac_external_time_base/line.toml``: external time base from the Conveyor FMU).

Each is run for a short and a long simulated time (0.25 s and 2.25 s by default) ``--repeat`` times;
the **marginal real-time factor** is ``(long - short) simulated s / (long - short) process CPU s``, which
cancels start-up (imports, FMU loading, the PID design). Printed as min / median / max over the
repeats (pairing the i-th short with the i-th long run), with the machine's load.

``--floor`` also runs the plants and the kernel alone, without the controller: the Conveyor FMU
(watched mark, so stepped at every event) and the Servo FMU, and per servo cycle exactly the FMU
traffic a PMAC run makes (both encoders read, the DAC written to ``u_cmd``), plus the empty events
of quiet PLC rounds where a run has them (the shear scans every 200 us: two per servo cycle). Its
marginal real-time factor is the ceiling of a PMAC run with today's master and kernel: no
controller, however fast, makes the run faster than that.

``--profile`` adds, for one long run of each, the share of the CPU time per part of the code (cProfile
self time grouped by module): the PMAC controller, the FMU master and adapter, the kernel, the
trace and signals, and the rest. ``--startup`` also times ``cosim run <line.toml> --until 1ms`` in a
fresh process (imports included). Run from the repository root::

    .venv/bin/python bench/bench_pmac.py [--repeat 3] [--short 0.25] [--long 2.25] [--profile] [--startup] [--floor]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import resource
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Generator
from pathlib import Path

from clock import figure_line, machine_load, spread

from cosim.catalog import load
from cosim.runner import run_scenario

ROOT = Path(__file__).resolve().parent.parent
RUNS = {
    "flying shear": str(ROOT / "examples/pmac_flying_shear/shear.toml"),
    "pmac_fmu_slave": "pmac_fmu_slave",
    "line": str(ROOT / "examples/pmac_external_time_base/line.toml"),
}
GROUPS = (
    ("PMAC controller", ("cosim/controllers/pmac/", "cosim/couplings/", "cosim/encoders.py", "cosim/rigs.py")),
    ("FMU master and adapter", ("cosim/master.py", "cosim/fmu.py", "cosim/fmuvars.py", "fmpy", "ctypes")),
    ("kernel (SimPy)", ("cosim/kernel.py", "simpy/", "cosim/timebase.py")),
    ("trace and signals", ("cosim/trace.py", "cosim/signals.py", "cosim/tracestore.py")),
    ("Fraction", ("fractions.py",)),
)


def cpu_run(name: str, seconds: float) -> tuple[float, str]:
    """Process CPU time [s] of one run of ``seconds`` simulated, and its verdict."""
    scenario = load(name)
    started = time.process_time()
    result = run_scenario(scenario, until=f"{seconds * 1000:g} ms")
    return time.process_time() - started, result.verdict


def profile(name: str, seconds: float) -> list[tuple[str, float]]:
    """Share of self time per group of modules in one run."""
    scenario = load(name)
    profiler = cProfile.Profile()
    profiler.enable()
    run_scenario(scenario, until=f"{seconds * 1000:g} ms")
    profiler.disable()
    shares: Counter[str] = Counter()
    for (filename, _line, _function), (_cc, _nc, self_time, _ct, _callers) in pstats.Stats(profiler).stats.items():
        group = next((label for label, parts in GROUPS if any(p in filename for p in parts)), "other")
        shares[group] += self_time
    total = sum(shares.values())
    return [(label, shares[label] / total) for label, _parts in (*GROUPS, ("other", ()))]


FLOORS = {  # label: (conveyor speed [counts/ms], period of quiet PLC rounds [ns] or 0)
    "flying shear": (256, 200_000),
    "pmac_fmu_slave": (32, 0),
}


def floor_run(seconds: float, *, counts_per_ms: int, scan_period: int) -> float:
    """Process CPU time [s] of the plants and the kernel alone, with a PMAC run's FMU traffic per servo cycle."""
    from cosim.controllers.pmac.units import I10_DEFAULT, ServoClock
    from cosim.couplings.encoder import PlantEncoder, watch_mark
    from cosim.couplings.servo import dac_volts
    from cosim.kernel import At, Simulation
    from cosim.master import Plant
    from cosim.plants.conveyor import ConveyorParameters
    from cosim.presets import load_preset
    from cosim.signals import Signal
    from cosim.timebase import Priority

    sim = Simulation()
    preset = load_preset("conveyor_web_200mm_wheel")
    speed = counts_per_ms * 1000 / preset["counts_per_metre"]
    belt = ConveyorParameters.from_mapping({**preset, "mark_offset": 0.0200071, "speed_start": speed})
    conveyor = Plant.load(sim, "Conveyor", name="conveyor", parameters=belt.as_fmu_parameters())
    conveyor.set({"speed_cmd": speed})
    servo = Plant.load(sim, "Servo", name="servo", parameters=load_preset("servo_maxon_re40_24v"))
    watch_mark(conveyor)
    master, slave = PlantEncoder(conveyor), PlantEncoder(servo)
    dac = Signal(sim, "dac", kind="int", unit="bits")
    servo.drive("u_cmd", dac, convert=dac_volts)
    clock, env = ServoClock(I10_DEFAULT), sim.env

    def cycles() -> Generator[At, None, None]:
        k = 0
        while True:
            t = clock.t(k)
            yield At(env, t, Priority.SERVO)
            master.extended(t, 8)
            follower = slave.extended(t, 5)
            dac.set((k * 40 - follower) % 2001 - 1000)  # changes every cycle
            k += 1

    def quiet_rounds() -> Generator[At, None, None]:  # the instants of a PLC background that has nothing to do
        k = 0
        while True:
            yield At(env, k * scan_period, Priority.HOST + 5)  # runtime.BACKGROUND
            k += 1

    sim.process(cycles())
    if scan_period:
        sim.process(quiet_rounds())
    started = time.process_time()
    sim.run(until=sim.ticks(f"{seconds * 1000:g} ms"))
    used = time.process_time() - started
    sim.close()
    return used


def startup() -> float:
    """CPU time [s] of ``cosim run line.toml --until 1ms`` in a fresh process (children's rusage)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([sys.executable, "-m", "cosim", "run", RUNS["line"], "--until", "1ms", "--out",
                           "/tmp/bench-pmac"], check=False, capture_output=True)
    if done.returncode not in (0, 1):  # 1: its checks (about 100 ms and the end) fail after 1 ms, as they should
        raise RuntimeError(done.stderr.decode())
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--short", type=float, default=0.25, help="short run [simulated s]")
    parser.add_argument("--long", type=float, default=2.25, help="long run [simulated s]")
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--startup", action="store_true")
    parser.add_argument("--floor", action="store_true", help="also the plants and kernel alone (the ceiling)")
    args = parser.parse_args()
    print(f"PMAC runs, {args.short:g} s vs {args.long:g} s simulated, {args.repeat} repeats; {machine_load()}")
    for label, name in RUNS.items():
        cpu_run(name, 0.001)  # warm: FMUs built and loaded once, modules imported
        shorts, longs, verdicts = [], [], set()
        for _ in range(args.repeat):
            short, verdict_short = cpu_run(name, args.short)
            long, verdict_long = cpu_run(name, args.long)
            shorts.append(short)
            longs.append(long)
            verdicts |= {verdict_short, verdict_long}
        factors = [(args.long - args.short) / max(long - short, 1e-9)
                   for short, long in zip(shorts, longs, strict=True)]
        print(f"  {label:15s} marginal real-time factor {spread(factors, '{:.1f}')}x   (CPU short "
              f"{spread(shorts)} s, long {spread(longs)} s; verdicts {', '.join(sorted(verdicts))})")
        print(figure_line("pmac", f"{label.strip()} marginal real-time factor [x]", factors, goal=25))
        if args.profile:
            for group, share in profile(name, args.long):
                print(f"      {group:24s} {100 * share:5.1f} %")
    if args.floor:
        for label, (counts_per_ms, scan_period) in FLOORS.items():
            floor_run(0.001, counts_per_ms=counts_per_ms, scan_period=scan_period)
            pairs = [(floor_run(args.short, counts_per_ms=counts_per_ms, scan_period=scan_period),
                      floor_run(args.long, counts_per_ms=counts_per_ms, scan_period=scan_period))
                     for _ in range(args.repeat)]
            factors = [(args.long - args.short) / max(long - short, 1e-9) for short, long in pairs]
            rounds = f"an empty event every {scan_period // 1000} us" if scan_period else "no other events"
            print(f"  floor of the {label:15s} {spread(factors, '{:.1f}')}x   (plants and kernel alone: conveyor "
                  f"at {counts_per_ms} counts/ms, {rounds})")
    if args.startup:
        laps = [startup() for _ in range(args.repeat)]
        print(f"  start-up: cosim run line.toml --until 1ms, process CPU {spread(laps)} s")


if __name__ == "__main__":
    main()
