"""Sweep speed-up on Dask: the same 200-run sweep with 1 and with 2 local workers.

Prints both wall times, the process CPU time of each sweep (this process and its worker
processes, counted once they have ended), the speed-up and whether the two tables are identical
(they must be). Run::

    .venv/bin/python bench/bench_sweep.py [--runs 200] [--scenario laser_pwm] [--random pwm_on=0:1000]
    .venv/bin/python bench/bench_sweep.py --scenario trio_speed_link --random speed=200:1000

The fixed cost of starting the local cluster (about 0.6 s here) weighs on sweeps of very short
runs (laser_pwm: 20 ms each); the second line is a study whose runs take 0.1-0.2 s.
"""

from __future__ import annotations

import argparse

import pandas as pd
from clock import machine_load, measure

from cosim.sweep import parse_random, plan, sweep


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--scenario", default="laser_pwm")
    parser.add_argument("--random", default="pwm_on=0:1000", metavar="NAME=LOW:HIGH",
                        help="the parameter drawn per run")
    args = parser.parse_args()
    runs = plan(args.scenario, random=parse_random([args.random]), samples=args.runs, seed=1)
    tables = {}
    print(f"machine: {machine_load()}")
    for workers in (1, 2):
        with measure(children=True) as lap:
            tables[workers] = sweep(args.scenario, runs, workers=workers, progress=False)
        attrs = tables[workers].attrs
        print(f"  {workers} worker(s): {attrs['wall_time_s']:7.2f} s for {len(runs)} runs "
              f"(of which {attrs['startup_s']:.2f} s starting the cluster); process CPU {lap.cpu_s:.2f} s "
              "(with the workers')")
    pd.testing.assert_frame_equal(tables[1], tables[2])
    one, two = tables[1].attrs, tables[2].attrs
    print(f"  speed-up 2 vs 1 workers: {one['wall_time_s'] / two['wall_time_s']:.2f}x in all, "
          f"{(one['wall_time_s'] - one['startup_s']) / (two['wall_time_s'] - two['startup_s']):.2f}x once "
          f"the cluster is up (target >= 1.6); tables identical")


if __name__ == "__main__":
    main()
