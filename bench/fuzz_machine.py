"""Long fuzz run of the machine-file loader (outside the suite): mutated and generated machine files.

Every input must either load and build or raise one of cosim's own errors (CosimError); anything
else is a crash, printed with the input that caused it. Run::

    .venv/bin/python bench/fuzz_machine.py --minutes 10
"""

from __future__ import annotations

import argparse
import copy
import random
import sys
import tempfile
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from test_machine_fuzz import KEYS, SEED, load_machine_from

from cosim.errors import CosimError
from cosim.machine import load_machine
from cosim.machine.check import check_machine

VALUES = [0, 1, -1, 2**31, 2**64, 1e300, float("nan"), float("inf"), "", "1 ms", "-1 s", "1e9 s", "abc", "pokeys",
          "trio", "usb", "x", "max", True, False, [1, 2], [], {"a": 1}, 25, 0.5, "0 s", "nan", "\x00"]


def mutate(rng: random.Random) -> bytes:
    text = bytearray(SEED.encode())
    for _ in range(rng.randint(1, 6)):
        k = rng.randrange(len(text))
        op = rng.choice("rdi")
        if op == "r":
            text[k] = rng.randrange(256)
        elif op == "d":
            del text[k]
        else:
            text.insert(k, rng.randrange(256))
    return bytes(text)


def generated(rng: random.Random, folder: Path) -> Path | None:
    import tomllib

    document = tomllib.loads(SEED)
    for _ in range(rng.randint(1, 3)):
        node = document
        path = [rng.choice(KEYS) for _ in range(rng.randint(1, 3))]
        for part in path[:-1]:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        node[path[-1]] = copy.deepcopy(rng.choice(VALUES))  # a shared dict would be mutated, even into itself
    return load_machine_from(document, folder)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    folder = Path(tempfile.mkdtemp(prefix="cosim-fuzz-machine-"))
    deadline = time.monotonic() + 60 * args.minutes
    inputs = crashes = built = 0
    while time.monotonic() < deadline:
        if rng.random() < 0.5:
            path: Path | None = folder / "machine.toml"
            path.write_bytes(mutate(rng))  # type: ignore[union-attr]
        else:
            path = generated(rng, folder)
        if path is None:
            continue
        inputs += 1
        try:
            check_machine(load_machine(path))
            built += 1
        except CosimError:
            pass
        except Exception:
            crashes += 1
            print(f"CRASH on input {inputs}:\n{path.read_text(errors='replace')}\n{traceback.format_exc()}", flush=True)
    print(f"{inputs} inputs in {args.minutes:g} min: {built} built, {inputs - built - crashes} refused with "
          f"cosim's errors, {crashes} crashes")
    return 1 if crashes else 0


if __name__ == "__main__":
    raise SystemExit(main())
