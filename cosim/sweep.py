"""Parameter sweeps of a scenario on Dask.

A sweep is a list of runs: every combination of the ``grid`` values, each repeated for ``samples``
seeded random draws of the ``random`` parameters (uniform within their declared ranges, whole
numbers for integer parameters). Run ``i`` gets its parameters and its simulation seed from
``(sweep seed, i)`` alone, so the table is the same whatever the number of workers or the order
in which runs finish. A run that breaks is a row with its error, not the end of the sweep.

Runs go to a Dask cluster: a local cluster of ``workers`` processes by default, an existing
scheduler when ``scheduler`` gives its address, or this process when ``workers == 0``.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cosim.errors import ConfigurationError
from cosim.scenario import Param, ScenarioFile, load


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: its index, seed and the ``--set`` values it uses."""

    index: int
    seed: int
    overrides: dict[str, str]


def plan(scenario: str | Path, *, grid: Mapping[str, Sequence[Any]] | None = None,
         random: Mapping[str, tuple[Any, Any] | None] | None = None, samples: int = 1,
         seed: int = 0) -> list[RunSpec]:
    """The runs of a sweep, in index order.

    Parameters
    ----------
    scenario : str or path
        Bundled scenario name or script path.
    grid : mapping, optional
        Parameter name -> values; every combination is run.
    random : mapping, optional
        Parameter name -> ``(low, high)`` or None (the declared range); drawn per sample.
    samples : int
        Random draws per grid point (>= 1).
    seed : int
        Sweep seed.
    """
    if samples < 1:
        raise ConfigurationError.out_of_range("samples", samples, ">= 1")
    declared = {p.name: p for p in load(scenario).parameters}
    grid = dict(grid or {})
    ranges = {name: _range(declared, name, bounds) for name, bounds in (random or {}).items()}
    for name in grid:
        _param(declared, name)
    points = list(itertools.product(*grid.values())) if grid else [()]
    runs = []
    for index, (point, _sample) in enumerate(itertools.product(points, range(samples))):
        sequence = np.random.SeedSequence([seed, index])
        rng = np.random.default_rng(sequence)
        values = {name: str(value) for name, value in zip(grid, point, strict=True)}
        for name, (low, high) in ranges.items():
            if isinstance(declared[name].default, int):
                values[name] = str(int(rng.integers(low, high, endpoint=True)))
            else:
                values[name] = repr(float(rng.uniform(low, high)))
        run_seed = int(sequence.generate_state(1, dtype=np.uint32)[0])
        runs.append(RunSpec(index, run_seed, values))
    return runs


def _param(declared: Mapping[str, Param], name: str) -> Param:
    if name not in declared:
        raise ConfigurationError(f"the scenario has no parameter {name!r} (declared: {', '.join(declared)})")
    return declared[name]


def _range(declared: Mapping[str, Param], name: str, bounds: tuple[Any, Any] | None) -> tuple[Any, Any]:
    param = _param(declared, name)
    if isinstance(param.default, bool | str):
        raise ConfigurationError(f"parameter {name} is a {type(param.default).__name__}: sweep it with a grid")
    if bounds is None:
        if param.range is None:
            raise ConfigurationError(f"parameter {name} declares no range: give one as {name}=LOW:HIGH")
        bounds = (param.range[0], param.range[1])
    low, high = (param.parse(str(b)) for b in bounds)  # range-checked against the declaration
    if high < low:  # type: ignore[operator]
        raise ConfigurationError(f"random range of {name}: {low}..{high} is empty")
    return low, high


def run_one(scenario: str | ScenarioFile, spec: RunSpec) -> dict[str, Any]:
    """Run one sweep point and flatten its result into a table row (no files written)."""
    from cosim.runner import run_scenario

    row: dict[str, Any] = {"index": spec.index, "seed": spec.seed}
    try:
        script = load(scenario) if isinstance(scenario, str) else scenario
        row.update({f"p.{k}": v for k, v in script.resolve(spec.overrides).items()})
        result = run_scenario(script, overrides=spec.overrides, seed=spec.seed)
    except Exception as exc:  # a broken run is a row, not the end of the sweep
        row.update({"verdict": "ERROR", "error": f"{type(exc).__name__}: {exc}"})
        return row
    row.update({"verdict": result.verdict, "error": result.error or "", "checks_passed": result.passed,
                "checks_failed": result.failed})
    for check in result.checks:
        key = f"check.{check['name']}"
        row[f"{key}.passed"] = bool(check["passed"])
        row[f"{key}.n_violations"] = int(check["n_violations"])
        for name, value in check["measured"].items():
            row[f"{key}.{name}"] = value
    for name, figure in result.figures.items():
        row[f"fig.{name}"] = figure["value"]
    return row


def run_chunk(scenario: str, specs: list[RunSpec]) -> list[dict[str, Any]]:
    """Run several sweep points one after the other (one Dask task; the script is loaded once)."""
    try:
        script: str | ScenarioFile = load(scenario)
    except Exception:  # each run reports the error in its own row
        script = scenario
    return [run_one(script, spec) for spec in specs]


def _results(scenario: str, runs: list[RunSpec], workers: int, scheduler: str | None,
             timing: dict[str, float]) -> Iterator[dict[str, Any]]:
    if workers == 0 and scheduler is None:
        yield from run_chunk(scenario, runs)
        return
    from dask.distributed import Client, LocalCluster, as_completed

    started = time.perf_counter()
    cluster = None if scheduler else LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                  dashboard_address=None, preload=["cosim.runner"])
    try:
        with Client(scheduler or cluster) as client:
            timing["startup_s"] = time.perf_counter() - started
            # Runs go out in chunks (about four per worker) so that short runs are not dominated
            # by the scheduler's per-task cost.
            n_workers = max(1, len(client.scheduler_info().get("workers", {})))
            size = max(1, -(-len(runs) // (4 * n_workers)))
            chunks = [runs[i:i + size] for i in range(0, len(runs), size)]
            futures = client.map(run_chunk, [scenario] * len(chunks), chunks, pure=False)
            for future in as_completed(futures):
                yield from future.result()
    finally:
        if cluster is not None:
            cluster.close()


def sweep(scenario: str | Path, runs: list[RunSpec], *, workers: int = 2, scheduler: str | None = None,
          out: str | Path | None = None, progress: bool = True,
          on_row: Callable[[dict[str, Any]], None] | None = None) -> Any:
    """Run ``runs`` of ``scenario``; returns a pandas DataFrame ordered by run index.

    The table is also written to ``out/sweep.parquet`` when ``out`` is given.
    """
    import pandas as pd
    from tqdm import tqdm

    if workers < 0:
        raise ConfigurationError.out_of_range("workers", workers, ">= 0")
    name = str(scenario)
    rows: list[dict[str, Any]] = []
    timing = {"startup_s": 0.0}
    started = time.perf_counter()
    with tqdm(total=len(runs), desc=f"sweep {Path(name).stem}", unit="run", disable=not progress) as bar:
        for row in _results(name, runs, workers, scheduler, timing):
            rows.append(row)
            if on_row is not None:
                on_row(row)
            bar.update(1)
    rows.sort(key=lambda r: int(r["index"]))
    table = pd.DataFrame(rows)
    table.attrs["wall_time_s"] = time.perf_counter() - started
    table.attrs["startup_s"] = timing["startup_s"]  # starting the local cluster (part of wall_time_s)
    if out is not None:
        folder = Path(out)
        folder.mkdir(parents=True, exist_ok=True)
        table.to_parquet(folder / "sweep.parquet", index=False)
    return table


def parse_grid(items: Sequence[str]) -> dict[str, list[str]]:
    """``NAME=v1,v2,...`` items of the command line."""
    grid = {}
    for item in items:
        name, sep, values = item.partition("=")
        if not sep or not values:
            raise ConfigurationError(f"--grid {item!r}: expected NAME=v1,v2,...")
        grid[name.strip()] = [v.strip() for v in values.split(",")]
    return grid


def parse_random(items: Sequence[str]) -> dict[str, tuple[str, str] | None]:
    """``NAME`` or ``NAME=LOW:HIGH`` items of the command line."""
    ranges: dict[str, tuple[str, str] | None] = {}
    for item in items:
        name, sep, bounds = item.partition("=")
        if not sep:
            ranges[name.strip()] = None
            continue
        low, colon, high = bounds.partition(":")
        if not colon:
            raise ConfigurationError(f"--random {item!r}: expected NAME or NAME=LOW:HIGH")
        ranges[name.strip()] = (low.strip(), high.strip())
    return ranges
