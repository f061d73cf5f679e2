"""Per-communication-step cost of cosim's master against fmpy's ``simulate_fmu``, and run-fmu's start-up.

Issue 32 names three FMUs of the Modelica Reference-FMUs, VanDerPol, BouncingBall and Dahlquist;
their binaries are on GitHub, which this project cannot reach, so ``bench/fmus/`` holds our own
models of the same equations, start values, default experiments and internal solver steps (built
here into ``models/bench/``). Issue 29 names the bundled Servo FMU on the PMAC's 442 us servo
grid (u_cmd = 2 V: the motor turns and the encoder counts, as in a PMAC run).

Both importers run the same FMU on the same fixed output grid and record the same outputs (all
of them, as ``cosim run-fmu`` does): fmpy's ``simulate_fmu(output_interval=...)``, and cosim's
master as ``run-fmu`` drives it (``Plant.record(at_events=False)``: the grid alone). The figure is
process CPU time per step, start-up cancelled: (cost of N steps - cost of N/10 steps) / (0.9 N).
Each is measured ``--repeat`` times (min / median / max), alternating the importers; the ratio is
taken run by run. cosim steps and samples rows of grid instants in C where a C compiler is at hand
(``cosim.gridloop``); its Python loop (what runs without a compiler) is measured beside it, and the
two must give identical samples. Also shown: the same doSteps and one getter call per type through
ctypes with arguments made once, nothing recorded (what a Python loop cannot go below: the C loop
does, as it makes no ctypes call per step). The values of cosim and fmpy are compared (the same FMU
must give the same outputs; BouncingBall would differ near a bounce, which cosim locates with early
return and fmpy at the next grid point).

Start-up: ``cosim run-fmu`` and fmpy's ``simulate_fmu`` on Dahlquist (101 steps) and the Servo
(their default experiments), each in a fresh interpreter, CPU time of the child process (target
< 0.4 s), byte code compiled and the FMU cache filled as in a user's second run.

Run::

    .venv/bin/python bench/bench_master.py [--steps N] [--fmi 2|3] [--repeat 3] [--only Servo] [--no-extras]
"""

from __future__ import annotations

import argparse
import ctypes
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from clock import figure_line, machine_load, measure, spread
from fmpy import simulate_fmu

from cosim import gridloop
from cosim.fmu import Fmu
from cosim.fmubuild import CHECKOUT, MODELS_DIR, SOURCE_DIR, ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant

BENCH_MODELS = Path(__file__).resolve().parent / "fmus"


@dataclass(frozen=True)
class Case:
    """One FMU on one grid: what both importers run."""

    name: str
    step_ns: int
    outputs: tuple[str, ...]
    start_values: dict[str, float]
    target: float  # the ratio cosim/fmpy to reach


CASES = (
    Case("VanDerPol", 10_000_000, ("x0", "x1"), {}, 1.0),
    Case("BouncingBall", 10_000_000, ("h", "v"), {}, 1.0),
    Case("Dahlquist", 100_000_000, ("x",), {}, 1.0),
    Case("Servo", 442_000, ("angle", "speed", "current", "motor_voltage", "torque", "stuck", "encoder_count",
                            "edge_count", "edge_direction", "t_last_edge", "t_prev_edge"), {"u_cmd": 2.0}, 0.5),
)


def bench_fmus(fmi_version: int) -> dict[str, Path]:
    """Build the bench models (bench/fmus) into models/bench, in a child process (the build reads its folders
    from the environment); the Servo is the bundled one."""
    target = (CHECKOUT / "models" / "bench") if CHECKOUT is not None else MODELS_DIR / "bench"
    with tempfile.TemporaryDirectory(prefix="cosim-bench-src-") as tmp:
        sources = Path(tmp)
        (sources / "common").symlink_to(SOURCE_DIR / "common")
        for model in ("VanDerPol", "BouncingBall", "Dahlquist"):
            (sources / model).symlink_to(BENCH_MODELS / model)
        env = dict(os.environ, COSIM_FMU_SRC=str(sources), COSIM_MODELS=str(target))
        subprocess.run([sys.executable, "-m", "cosim.fmubuild", "--quiet"], env=env, check=True)
    paths = {model: target / f"fmi{fmi_version}" / f"{model}.fmu" for model in ("VanDerPol", "BouncingBall",
                                                                                  "Dahlquist")}
    paths["Servo"] = ensure_fmu("Servo", fmi_version)
    return paths


def run_fmpy(path: Path, case: Case, steps: int) -> tuple[float, dict[str, np.ndarray]]:
    with measure() as lap:
        result = simulate_fmu(str(path), start_time=0.0, stop_time=steps * case.step_ns * 1e-9,
                              output_interval=case.step_ns * 1e-9, start_values=case.start_values,
                              output=list(case.outputs), fmi_type="CoSimulation")
    return lap.cpu_s, {name: result[name].astype(float) for name in case.outputs}


def run_cosim(path: Path, case: Case, steps: int) -> tuple[float, dict[str, np.ndarray]]:
    with measure() as lap, Simulation() as sim:
        plant = Plant(sim, Fmu(path, timebase=sim.timebase, instance_name="m", parameters=case.start_values),
                      name="m")
        sample = plant.record(list(case.outputs), period=case.step_ns, at_events=False)  # as run-fmu does
        sim.run(until=steps * case.step_ns)
        sample()
        values = {name: sim.trace.edges(f"m.{name}")[1] for name in case.outputs}
    return lap.cpu_s, values


def run_cosim_python(path: Path, case: Case, steps: int) -> tuple[float, dict[str, np.ndarray]]:
    """cosim's master with its Python loop (no C compiler at hand: ``cosim.gridloop`` unavailable)."""
    kept = list(gridloop._LOADED)
    gridloop._LOADED[:] = [None]
    try:
        return run_cosim(path, case, steps)
    finally:
        gridloop._LOADED[:] = kept


def run_floor(path: Path, case: Case, steps: int) -> tuple[float, dict[str, np.ndarray]]:
    """The C the importers call, and nothing else: each step one doStep and one getter call per type, made
    with ctypes arguments prepared once (no recording, no checks): what no Python importer can go below."""
    fmu = Fmu(path, parameters=case.start_values)
    try:
        function = f"fmi{fmu.fmi_version}DoStep"
        do_step = fmu._bare(function)
        component = ctypes.c_void_p(fmu._fmu.component)
        t_arg, h_arg = ctypes.c_double(), ctypes.c_double(case.step_ns * 1e-9)
        flags = [ctypes.c_bool() for _ in range(3)]
        last = ctypes.c_double()
        args = ((component, t_arg, h_arg, ctypes.c_int(1)) if fmu.fmi_version == 2 else
                (component, t_arg, h_arg, ctypes.c_bool(True), *map(ctypes.byref, flags), ctypes.byref(last)))
        groups: dict[str, list[Any]] = {}
        for name in case.outputs:
            var = fmu.variable(name)
            groups.setdefault(var.kind.function, []).append(var)
        calls = []
        for kind, variables in groups.items():
            n = len(variables)
            size = ctypes.c_size_t(n)
            buffer = (variables[0].kind.ctype * n)()
            tail = () if fmu.fmi_version == 2 else (size,)
            calls.append((fmu._bare(f"fmi{fmu.fmi_version}Get{kind}"),
                          (component, (ctypes.c_uint32 * n)(*[v.vr for v in variables]), size, buffer, *tail)))
        with measure() as lap:
            for k in range(steps):
                t_arg.value = k * case.step_ns / 1e9
                do_step(*args)
                for get, get_args in calls:
                    get(*get_args)
    finally:
        fmu.close()
    return lap.cpu_s, {}


def per_step(run: object, path: Path, case: Case, steps: int) -> tuple[float, dict[str, np.ndarray]]:
    """CPU seconds per step, start-up cancelled (N steps minus N/10 steps), and the long run's values."""
    long_s, values = run(path, case, steps)  # type: ignore[operator]
    short_s, _ = run(path, case, steps // 10)  # type: ignore[operator]
    return (long_s - short_s) / (steps - steps // 10), values


def startup(path: Path, repeat: int) -> tuple[list[float], list[float]]:
    """CPU seconds of ``cosim run-fmu`` and of fmpy's ``simulate_fmu`` on the FMU's default experiment, each in a
    fresh interpreter (the child's user + system time), alternating.

    Both as a user has them: byte code compiled (a first run, not measured, writes cosim's ``.pyc`` files where
    ``PYTHONDONTWRITEBYTECODE`` kept them from being written; an installed package has them from its
    installation), the FMU in cosim's per-user cache and the C grid loop built (both once per user)."""
    cosim_laps, fmpy_laps = [], []
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    with tempfile.TemporaryDirectory(prefix="cosim-bench-") as tmp:
        cosim = [sys.executable, "-m", "cosim", "run-fmu", str(path), "--out", str(Path(tmp) / "out")]
        fmpy = [sys.executable, "-c", f"from fmpy import simulate_fmu; simulate_fmu({str(path)!r})"]
        subprocess.run(cosim, check=True, stdout=subprocess.DEVNULL, env=env)
        for _ in range(repeat):
            for command, laps in ((cosim, cosim_laps), (fmpy, fmpy_laps)):
                with measure(children=True) as lap:
                    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=env)
                laps.append(lap.cpu_s)
    return cosim_laps, fmpy_laps


def laser_samples(repeat: int) -> None:
    """The engraver's case: the Laser recorded every 100 us for 4 s with nothing else stepping it; the samples
    taken inside its steps (its sample_schedule) against a doStep per sample."""
    from cosim import sampleschedule

    inside = sampleschedule.capacity
    for name, capacity in (("a doStep per sample", lambda *args: 0), ("inside its steps", inside)):
        sampleschedule.capacity = capacity  # type: ignore[assignment]
        laps, steps = [], 0
        for _ in range(repeat):
            with Simulation() as sim:
                laser = Plant.load(sim, "Laser", name="laser", parameters={"enable": True, "gate": True,
                                                                            "pwm_period": 1000, "pwm_on": 400})
                with measure() as lap:
                    laser.record(["power", "energy"], period=100_000)
                    sim.run(until=4_000_000_000)
                laps.append(lap.cpu_s * 1e3)
                steps = laser.steps
        print(f"  Laser every 0.1 ms for 4 s (40,000 samples), {name:<20}: {steps:6d} doSteps, CPU "
              f"{spread(laps, '{:.1f}')} ms")
    sampleschedule.capacity = inside  # type: ignore[assignment]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000, help="communication steps of the long run")
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=3)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3: min/median/max)")
    parser.add_argument("--only", nargs="*", choices=[case.name for case in CASES], help="these FMUs only")
    parser.add_argument("--no-extras", action="store_true", help="per-step figures only (no Laser, no start-up)")
    args = parser.parse_args()
    paths = bench_fmus(args.fmi)
    print(f"machine: {machine_load()}; C grid loop: {'built' if gridloop.library() is not None else 'NOT available'}")
    print(f"FMI {args.fmi}.0, {args.steps} steps minus {args.steps // 10}, {args.repeat} runs each; CPU us per step "
          "(min / median / max), with recording")
    for case in CASES:
        if args.only and case.name not in args.only:
            continue
        path = paths[case.name]
        run_fmpy(path, case, 200)  # warm up (loading, caches)
        run_cosim(path, case, 200)
        fmpy_us, cosim_us, python_us, floor_us, ratios, python_ratios = [], [], [], [], [], []
        for _ in range(args.repeat):
            c_floor, _ = per_step(run_floor, path, case, args.steps)
            f, fmpy_values = per_step(run_fmpy, path, case, args.steps)
            c, cosim_values = per_step(run_cosim, path, case, args.steps)
            p, python_values = per_step(run_cosim_python, path, case, args.steps)
            floor_us.append(c_floor * 1e6)
            fmpy_us.append(f * 1e6)
            cosim_us.append(c * 1e6)
            python_us.append(p * 1e6)
            ratios.append(c / f)
            python_ratios.append(p / f)
        worst = max(float(np.max(np.abs(fmpy_values[n] - cosim_values[n]))) for n in case.outputs)
        same = all(cosim_values[n].tobytes() == python_values[n].tobytes() for n in case.outputs)
        ok = "ok" if max(ratios) <= case.target else "NOT MET"
        print(f"  {case.name:<12} every {case.step_ns / 1e6:g} ms: fmpy {spread(fmpy_us, '{:.2f}')}  cosim "
              f"{spread(cosim_us, '{:.2f}')}  ratio {spread(ratios, '{:.2f}')} (target <= {case.target}: {ok})")
        print(f"  {'':<12} cosim's Python loop (no C compiler) {spread(python_us, '{:.2f}')}, ratio "
              f"{spread(python_ratios, '{:.2f}')}; the C loop's samples {'identical' if same else 'DIFFER'}")
        print(f"  {'':<12} doStep + getters through ctypes, nothing else {spread(floor_us, '{:.2f}')}; largest "
              f"difference of the values cosim - fmpy {worst:.3g}")
        if case.name == "Servo":
            print(figure_line("master", f"per step, Servo every {case.step_ns / 1e6:g} ms, cosim / fmpy [x]", ratios,
                              goal=case.target, higher_is_better=False))
    if args.no_extras:
        return
    laser_samples(args.repeat)
    for name in ("Dahlquist", "Servo"):
        laps, fmpy_laps = startup(paths[name], args.repeat)
        print(f"  start-up, default experiment in a fresh interpreter, {name:<9}: cosim run-fmu CPU "
              f"{spread(laps, '{:.3f}')} s (target < 0.4 s: {'ok' if max(laps) < 0.4 else 'NOT MET'}); fmpy "
              f"simulate_fmu {spread(fmpy_laps, '{:.3f}')} s")


if __name__ == "__main__":
    main()
