"""Per-communication-step cost of cosim's master against fmpy's own ``simulate_fmu``.

Both drive the same Laser FMU on the same fixed grid (the scenario asks for sampling every
``STEP_NS``) and record the same outputs; the figure is the ratio of wall time per step,
measured in one process, one after the other. Run::

    .venv/bin/python bench/bench_master.py [--steps N] [--fmi 2|3]
"""

from __future__ import annotations

import argparse
import time

from fmpy import simulate_fmu

from cosim.fmubuild import ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant

STEP_NS = 10_000  # 10 us communication step
INPUTS = {"enable": True, "gate": True, "pwm_period": 1000, "pwm_on": 400}
OUTPUTS = ["power", "energy"]


def run_fmpy(path: str, steps: int) -> float:
    started = time.perf_counter()
    simulate_fmu(path, start_time=0.0, stop_time=steps * STEP_NS * 1e-9, output_interval=STEP_NS * 1e-9,
                 start_values=INPUTS, output=OUTPUTS, fmi_type="CoSimulation")
    return time.perf_counter() - started


def run_cosim(path: str, steps: int) -> float:
    started = time.perf_counter()
    with Simulation() as sim:
        laser = Plant.load(sim, path, name="laser")
        laser.set(INPUTS)
        laser.record(OUTPUTS, period=STEP_NS)
        sim.run(until=steps * STEP_NS + 1)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=3)
    args = parser.parse_args()
    path = str(ensure_fmu("Laser", args.fmi))
    run_fmpy(path, 1000)  # warm up (loading, caches)
    run_cosim(path, 1000)
    t_fmpy = run_fmpy(path, args.steps)
    t_cosim = run_cosim(path, args.steps)
    print(f"Laser FMI {args.fmi}.0, {args.steps} steps of {STEP_NS} ns, outputs {OUTPUTS}")
    print(f"  fmpy simulate_fmu : {t_fmpy / args.steps * 1e6:8.2f} us/step")
    print(f"  cosim master      : {t_cosim / args.steps * 1e6:8.2f} us/step")
    print(f"  ratio cosim/fmpy  : {t_cosim / t_fmpy:8.3f}  (target <= 1.0)")


if __name__ == "__main__":
    main()
