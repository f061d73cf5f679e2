"""Per-communication-step cost of cosim's master against fmpy's own ``simulate_fmu``.

Both drive the same Laser FMU on the same fixed grid (the scenario asks for sampling every
``STEP_NS``) and record the same outputs; the figure is the ratio of time per step, in process
CPU time (and wall time beside it), measured in one process, one after the other, ``--repeat``
times (min / median / max). Run::

    .venv/bin/python bench/bench_master.py [--steps N] [--fmi 2|3] [--repeat 3]
"""

from __future__ import annotations

import argparse

from clock import Lap, machine_load, measure, spread
from fmpy import simulate_fmu

from cosim.fmubuild import ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant

STEP_NS = 10_000  # 10 us communication step
INPUTS = {"enable": True, "gate": True, "pwm_period": 1000, "pwm_on": 400}
OUTPUTS = ["power", "energy"]


def run_fmpy(path: str, steps: int) -> Lap:
    with measure() as lap:
        simulate_fmu(path, start_time=0.0, stop_time=steps * STEP_NS * 1e-9, output_interval=STEP_NS * 1e-9,
                     start_values=INPUTS, output=OUTPUTS, fmi_type="CoSimulation")
    return lap


def run_cosim(path: str, steps: int) -> Lap:
    with measure() as lap, Simulation() as sim:
        laser = Plant.load(sim, path, name="laser")
        laser.set(INPUTS)
        laser.record(OUTPUTS, period=STEP_NS)
        sim.run(until=steps * STEP_NS + 1)
    return lap


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=3)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (default 3: min/median/max)")
    args = parser.parse_args()
    path = str(ensure_fmu("Laser", args.fmi))
    print(f"machine: {machine_load()}")
    run_fmpy(path, 1000)  # warm up (loading, caches)
    run_cosim(path, 1000)
    fmpy_laps, cosim_laps = [], []
    for _ in range(args.repeat):
        fmpy_laps.append(run_fmpy(path, args.steps))
        cosim_laps.append(run_cosim(path, args.steps))
    per_step = 1e6 / args.steps
    print(f"Laser FMI {args.fmi}.0, {args.steps} steps of {STEP_NS} ns, outputs {OUTPUTS}; {args.repeat} runs: "
          "min / median / max [us/step]")
    for name, laps in (("fmpy simulate_fmu", fmpy_laps), ("cosim master", cosim_laps)):
        print(f"  {name:18s}: cpu {spread([lap.cpu_s * per_step for lap in laps], '{:.2f}')}   "
              f"wall {spread([lap.wall_s * per_step for lap in laps], '{:.2f}')}")
    ratio = [c.cpu_s / f.cpu_s for c, f in zip(cosim_laps, fmpy_laps, strict=True)]
    print(f"  ratio cosim/fmpy (cpu, run by run): {spread(ratio)}  (target <= 1.0)")


if __name__ == "__main__":
    main()
