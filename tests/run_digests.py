"""Per-signal digests of every bundled run's trace: the record that hot-path rewrites must not change.

Every bundled scenario and example machine is run as the main job runs it; each signal of its
trace is reduced to a SHA-256 over its pulses (instant, direction) or changes (instant, value),
which is what the run's VCD shows. ``tests/data/run_digests.json`` holds the digests taken with
the code before a rewrite; ``tests/test_runs_unchanged.py`` compares. Signals added later (a new
``<device>.job`` state, say) are not in the stored table and do not count; a stored signal that
disappears or changes does.

Write the table anew only for a change that is *meant* to change a run, and say so in the commit::

    .venv/bin/python tests/run_digests.py --write [RUN ...]
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from cosim.catalog import examples, load
from cosim.kernel import Simulation
from cosim.runner import Result, run_scenario
from cosim.scenario import bundled
from cosim.trace import Trace

TABLE = Path(__file__).parent / "data" / "run_digests.json"


def run_names() -> list[str]:
    """Every bundled run, by the name the table keys it with (scenario name or examples/... path)."""
    root = Path(__file__).resolve().parent.parent
    return [*bundled(), *(str(Path(p).resolve().relative_to(root)) for p in examples())]


def signal_digests(trace: Trace) -> dict[str, str]:
    """SHA-256 per signal over its pulses or changes: instants as int64, values as float64."""
    digests = {}
    for name in trace.names():
        t, v = trace.pulses(name) if trace.info[name].kind == "pulse" else trace.edges(name)
        h = hashlib.sha256()
        h.update(np.asarray(t, dtype="<i8").tobytes())
        h.update(np.asarray(v, dtype="<f8").tobytes())
        digests[name] = h.hexdigest()
    return digests


def run_with_trace(name: str) -> tuple[Result, Trace]:
    """Run one bundled run (no results written) and keep its trace."""
    root = Path(__file__).resolve().parent.parent
    traces: list[Trace] = []
    close = Simulation.close

    def keep_trace(self: Simulation) -> None:
        traces.append(self.trace)
        close(self)

    Simulation.close = keep_trace  # type: ignore[method-assign]
    try:
        result = run_scenario(load(root / name if name.endswith(".toml") else name))
    finally:
        Simulation.close = close  # type: ignore[method-assign]
    return result, traces[-1]


def main(argv: list[str]) -> int:
    if not argv or argv[0] != "--write":
        print(__doc__)
        return 2
    table = json.loads(TABLE.read_text()) if TABLE.exists() else {}
    for name in argv[1:] or run_names():
        result, trace = run_with_trace(name)
        table[name] = {"verdict": result.verdict, "signals": signal_digests(trace)}
        print(f"{name}: {result.verdict}, {len(trace.names())} signals", flush=True)
    TABLE.parent.mkdir(exist_ok=True)
    TABLE.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
