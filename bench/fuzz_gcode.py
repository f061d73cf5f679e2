"""Long fuzz run of the G-code reader (syntax, interpreter, tool path): count inputs and crashes.

The inputs come from ``tests/gcode_fuzz_programs.draw``: 70 % are one to three lines (words of every modal
group, parameters, expressions, O-words, comments, odd numbers; some mutated), 15 % whole generated
programs, 10 % mutations of those or of the bundled programs (characters inserted, deleted or replaced,
every kind of line end, lines swapped), 5 % random text. Each input is parsed, interpreted (an endless
loop is refused after 20,000 lines) and turned into a tool path. A crash is any exception that is not
one of the project's own errors (:class:`cosim.errors.CosimError`); the first ones are written to
``--crashes`` with their traceback. An input that takes more than ``SLOW_S`` of wall time is counted as
slow and written there too.

Run (``--workers`` processes, each with its own seed, ``--inputs`` in all or for ``--minutes``; ``--live``:
as a machine file runs the program, the interpreter stopping at each M66 and going on with a value, the host
following it with waits, cycle start and an A axis)::

    .venv/bin/python bench/fuzz_gcode.py --inputs 1000000 --workers 2
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
from gcode_fuzz_programs import draw, exercise, seeds


def worker(seed: int, seconds: float, crash_dir: str, limit: int, live: bool = False
           ) -> tuple[int, int, int, float, int]:
    """Fuzz for ``seconds`` or ``limit`` inputs; returns (inputs, run to a tool path, crashes, slowest [s], slow)."""
    rng = random.Random(seed)
    texts = seeds()
    tally = Tally(seed, crash_dir)
    parsed = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end and tally.inputs < limit:
        text = draw(rng, texts)
        parsed += tally.exercise(text, lambda: exercise(text, live=live))  # noqa: B023 (called at once)
    return tally.inputs, parsed, tally.crashes, tally.slowest, tally.slow


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=600.0)
    parser.add_argument("--inputs", type=int, default=1_000_000, help="inputs in all (split over the workers)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--crashes", default="fuzz_crashes")
    parser.add_argument("--live", action="store_true", help="run each input live (M66 stops, waits, an A axis)")
    args = parser.parse_args()
    seconds = args.minutes * 60
    started = time.monotonic()
    with multiprocessing.Pool(args.workers) as pool:
        share = -(-args.inputs // args.workers)
        results = pool.starmap(worker, [(args.seed + k, seconds, args.crashes, share, args.live)
                                        for k in range(args.workers)])
    inputs = sum(r[0] for r in results)
    print(f"{inputs} inputs ({sum(r[1] for r in results)} ran to a tool path), {sum(r[2] for r in results)} crashes, "
          f"slowest input {max(r[3] for r in results):.2f} s, {sum(r[4] for r in results)} slower than {SLOW_S:g} s, "
          f"{time.monotonic() - started:.0f} s wall, "
          f"{args.workers} workers")


if __name__ == "__main__":
    main()
