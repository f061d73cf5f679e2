"""Fuzz the PMAC text readers for a while: generated and mutated text may only raise the project's errors.

Every input (see :mod:`cosim.testing.pmac_text`: token soups with every kind of line end, and
mutations of real setup, motion and PLC files and of a project's files with preprocessor
directives) goes to the download preprocessor, ``parse_setup``, ``parse_text`` and the online
command parser; one in ``--run-every`` is also loaded into a controller, started with
``&1 B1 R`` and run for 3 ms of simulated time. Prints the inputs per reader, the crashes (the
first input of each kind is written to ``--out``) and the rate. Run::

    .venv/bin/python bench/bench_pmac_fuzz.py [--minutes 12] [--seed 1] [--run-every 20] [--out /tmp/pmac-fuzz]
"""

from __future__ import annotations

import argparse
import random
import time
import traceback
from pathlib import Path

from cosim.errors import CosimError
from cosim.testing.pmac_text import READERS, draw


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=12.0)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--run-every", type=int, default=20)
    parser.add_argument("--out", type=Path, default=Path("/tmp/pmac-fuzz"))
    args = parser.parse_args()
    rng = random.Random(args.seed)
    counts = dict.fromkeys(READERS, 0)
    crashes: dict[tuple[str, str], int] = {}
    started = time.perf_counter()
    end = started + args.minutes * 60
    n = 0
    while time.perf_counter() < end:
        for _ in range(200):
            text = draw(rng)
            n += 1
            names = [*READERS] if n % args.run_every == 0 else ["preprocess", "parse_setup", "parse_text", "command"]
            for name in names:
                counts[name] += 1
                try:
                    READERS[name](text)
                except CosimError:
                    pass
                except Exception as exc:  # a crash: record the first input of each kind
                    key = (name, type(exc).__name__)
                    crashes[key] = crashes.get(key, 0) + 1
                    if crashes[key] == 1:
                        args.out.mkdir(parents=True, exist_ok=True)
                        (args.out / f"{name}-{type(exc).__name__}.pmc").write_text(text, encoding="utf-8")
                        traceback.print_exc()
    seconds = time.perf_counter() - started
    print(f"{n:,} inputs in {seconds:.0f} s ({n / seconds:,.0f}/s), seed {args.seed}")
    for name, count in counts.items():
        lost = sum(c for (reader, _kind), c in crashes.items() if reader == name)
        print(f"  {name:13s} {count:>10,} inputs  {lost} crashes")
    for (name, kind), count in sorted(crashes.items()):
        print(f"  CRASH {name}: {kind} x {count} (first input in {args.out})")


if __name__ == "__main__":
    main()
