"""Wall time and process-CPU time for the benches (every bench prints both).

Wall time says how long a user waits; process CPU time (user + system of this process, and of
its children where a bench starts some) says what the code costs, and is much less disturbed by
other work on a shared machine. A bench repeats its parts and prints min / median / max.

Not a benchmark itself: imported by the ``bench_*.py`` scripts (run from the repository root as
``.venv/bin/python bench/bench_x.py``, which puts this folder on ``sys.path``).
"""

from __future__ import annotations

import os
import resource
import statistics
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field


def cpu_s(*, children: bool = False) -> float:
    """Process CPU time so far [s]: user + system, plus finished (waited-for) children if asked."""
    own = time.process_time()
    if not children:
        return own
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own + usage.ru_utime + usage.ru_stime


@dataclass
class Lap:
    """Wall and CPU time of one measured part [s]."""

    wall_s: float = 0.0
    cpu_s: float = 0.0


@contextmanager
def measure(*, children: bool = False) -> Iterator[Lap]:
    """``with measure() as lap: ...``: ``lap`` holds the wall and CPU time of the block afterwards."""
    lap = Lap()
    wall0, cpu0 = time.perf_counter(), cpu_s(children=children)
    try:
        yield lap
    finally:
        lap.wall_s = time.perf_counter() - wall0
        lap.cpu_s = cpu_s(children=children) - cpu0


@dataclass
class Series:
    """Repeated measurements of one part."""

    laps: list[Lap] = field(default_factory=list)

    def add(self, lap: Lap) -> None:
        self.laps.append(lap)

    def cpu(self) -> list[float]:
        return [lap.cpu_s for lap in self.laps]

    def wall(self) -> list[float]:
        return [lap.wall_s for lap in self.laps]


def spread(values: Sequence[float], fmt: str = "{:.3f}") -> str:
    """``min / median / max`` of ``values`` (one value alone when there is one)."""
    if len(values) == 1:
        return fmt.format(values[0])
    return " / ".join(fmt.format(v) for v in (min(values), statistics.median(values), max(values)))


def machine_load() -> str:
    """The 1-minute load average and the number of CPUs (how busy the machine was)."""
    one, five, _ = os.getloadavg()
    return f"load average {one:.2f} (1 min), {five:.2f} (5 min) on {os.cpu_count()} CPUs"


#: Prefix of the line a bench prints for each acceptance figure (read by ``bench/bench_families.py``).
FIGURE_PREFIX = "FIGURE "


def figure_line(family: str, figure: str, values: Sequence[float], *, goal: float,
                higher_is_better: bool = True) -> str:
    """One line ``FIGURE {json}`` for an acceptance figure: family, figure, values (min/median/max), goal, met.

    ``met`` compares the median with the goal (at least ``goal`` when higher is better, at most otherwise);
    ``met_by_worst`` the worst of the values. ``bench/bench_families.py`` collects these lines from every bench.
    """
    import json

    ordered = sorted(values)
    median, worst = statistics.median(ordered), ordered[0] if higher_is_better else ordered[-1]

    def meets(value: float) -> bool:
        return value >= goal if higher_is_better else value <= goal

    return FIGURE_PREFIX + json.dumps({
        "family": family, "figure": figure, "min": ordered[0], "median": median, "max": ordered[-1],
        "goal": goal, "higher_is_better": higher_is_better, "met": meets(median), "met_by_worst": meets(worst)})
