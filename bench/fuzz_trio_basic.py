"""Long fuzz run of the Trio BASIC parser and interpreter: count inputs and crashes.

Half the inputs are programs written by ``tests/trio_fuzz_programs.generate`` (statements of the modelled
subset with odd numbers and nesting), half are mutations of those or of the TN20-81 example (characters
inserted, deleted or replaced, every kind of line end, lines swapped). Each input is parsed and compiled;
every ``--run-every``-th input that parses (default: each) is also run for 30 simulated ms. A crash is any
exception that is not one of the project's own errors (:class:`cosim.errors.CosimError`); the first ones are
written to ``--crashes`` with their traceback. An input that takes more than ``SLOW_S`` of wall time is
counted as slow and written there too.

Run (``--workers`` processes, each with its own seed, for ``--minutes`` or until ``--inputs`` inputs in all;
``--progress FILE`` rewrites FILE with each worker's counts every 10,000 inputs)::

    .venv/bin/python bench/fuzz_trio_basic.py --minutes 30 --workers 2
    .venv/bin/python bench/fuzz_trio_basic.py --inputs 1000000 --workers 2 --progress /tmp/trio_fuzz.txt
    .venv/bin/python bench/fuzz_trio_basic.py --inputs 1000000 --run-every 50   # the reader, runs sampled
"""

from __future__ import annotations

import argparse
import multiprocessing
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from fuzzing import SLOW_S, Tally
from trio_fuzz_programs import exercise, generate, mutate

from cosim.controllers.trio.basic import example


def worker(seed: int, seconds: float, crash_dir: str, limit: int | None = None,
           progress: str | None = None, run_every: int = 1) -> tuple[int, int, int, float, int, int]:
    """Fuzz for ``seconds`` or ``limit`` inputs; returns (inputs, parsed, crashes, slowest input [s], slow inputs,
    inputs also run)."""
    rng = random.Random(seed)
    note = example("tn20_81").text
    tally = Tally(seed, crash_dir)
    parsed = ran = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end and (limit is None or tally.inputs < limit):
        roll = rng.random()
        text = generate(rng) if roll < 0.5 else mutate(rng, note if roll < 0.7 else generate(rng))
        run = parsed % run_every == 0
        ok = tally.exercise(text, lambda: exercise(text, run=run))  # noqa: B023 (called at once)
        parsed += ok
        ran += ok and run
        if progress and tally.inputs % 10_000 == 0:
            Path(f"{progress}.{seed}").write_text(f"{tally.inputs} inputs, {parsed} parsed, {ran} run, "
                                                  f"{tally.crashes} crashes, slowest {tally.slowest:.2f} s\n")
    return tally.inputs, parsed, tally.crashes, tally.slowest, tally.slow, ran


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=None, help="default 10, or no limit with --inputs")
    parser.add_argument("--inputs", type=int, default=None, help="stop after this many inputs in all")
    parser.add_argument("--progress", default=None, help="write each worker's counts to FILE.<seed>")
    parser.add_argument("--run-every", type=int, default=1, metavar="N",
                        help="run every N-th input that parses for 30 ms (default 1: each); "
                             "every input is parsed and compiled")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--crashes", default="fuzz_crashes")
    args = parser.parse_args()
    minutes = args.minutes if args.minutes is not None else (10.0 if args.inputs is None else 1e9)
    seconds = minutes * 60
    share = None if args.inputs is None else -(-args.inputs // args.workers)
    started = time.monotonic()
    with multiprocessing.Pool(args.workers) as pool:
        results = pool.starmap(worker, [(args.seed + k, seconds, args.crashes, share, args.progress,
                                         max(1, args.run_every)) for k in range(args.workers)])
    inputs = sum(r[0] for r in results)
    print(f"{inputs} inputs ({sum(r[1] for r in results)} parsed, {sum(r[5] for r in results)} of them run), "
          f"{sum(r[2] for r in results)} crashes, "
          f"slowest input {max(r[3] for r in results):.2f} s, {sum(r[4] for r in results)} slower than {SLOW_S:g} s, "
          f"{time.monotonic() - started:.0f} s wall, "
          f"{args.workers} workers")


if __name__ == "__main__":
    main()
