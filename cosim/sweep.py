"""Parameter sweeps of a scenario on Dask.

A sweep is a list of runs: every combination of the ``grid`` values, each repeated for ``samples``
seeded random draws of the ``random`` parameters. Run ``i`` gets its parameters and its simulation
seed from ``(sweep seed, i)`` alone, so the table is the same whatever the number of workers or the
order in which runs finish. A run that breaks is a row with its error, not the end of the sweep.

Random draws stay on a grid the scenario can use (:func:`sampler`):

* integer parameters: whole numbers in ``low..high``;
* a declared step (``NAME=LOW:HIGH:STEP`` on the command line): ``low + k * step``;
* float parameters whose unit is a time unit (``s``, ``ms``, ``us``, ``ns``): whole ticks of the
  simulation's resolution (1 ns), so ``gate_ms`` drawn from ``0.5:3`` gives values like
  ``1.734521`` ms, never a time that the scenario would have to refuse;
* other float parameters: uniform.

Every value is passed on as the exact decimal text a user would type with ``--set``.

Runs go to a Dask cluster: a local cluster of ``workers`` processes by default, an existing
scheduler when ``scheduler`` gives its address, or this process when ``workers == 0``.

The table has short, stable column names: ``p.<parameter>``, ``verdict``, ``error``, ``failed``
(the checks that did not come out as declared: an ordinary check that failed, examined nothing
or could not be evaluated, a declared hazard that was missed), ``c<k>.verdict`` (``PASS``,
``FAIL``, ``UNCHECKED``, ``ERROR``, ``HAZARD SHOWN``, ``HAZARD MISSED``) / ``c<k>.passed`` /
``c<k>.n_violations`` / ``c<k>.<measured>`` for the k-th check in declaration order, ``fig.<figure>``.
:func:`sweep` returns the legend (``c<k>`` to the check's name) in ``table.attrs["legend"]`` and,
with ``out``, writes next to ``sweep.parquet`` a ``sweep.json`` (legend, units, verdict counts) and
the report ``sweep.html`` (:mod:`cosim.sweep_report`).
"""

from __future__ import annotations

import itertools
import json
import math
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from cosim.catalog import load
from cosim.errors import ConfigurationError
from cosim.machine import MachineFile
from cosim.machine.check import check_machine
from cosim.machine.document import leaves
from cosim.scenario import Param, ScenarioFile
from cosim.timebase import NANOSECOND, UNITS_S
from cosim.validate import shown

#: A draw: a random generator in, the ``--set`` text of the value out.
Sampler = Callable[[np.random.Generator], str]


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: its index, seed and the ``--set`` values it uses."""

    index: int
    seed: int
    overrides: dict[str, str]


def plan(scenario: str | Path, *, grid: Mapping[str, Sequence[Any]] | None = None,
         random: Mapping[str, tuple[Any, ...] | None] | None = None, samples: int = 1,
         seed: int = 0) -> list[RunSpec]:
    """The runs of a sweep, in index order.

    Parameters
    ----------
    scenario : str or path
        Bundled scenario name or script path.
    grid : mapping, optional
        Parameter name -> values (in the parameter's unit); every combination is run.
    random : mapping, optional
        Parameter name -> ``(low, high)``, ``(low, high, step)`` (in the parameter's unit) or None
        (the declared range); drawn per sample on the grid described in the module docstring.
    samples : int
        Random draws per grid point (>= 1).
    seed : int
        Sweep seed.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ConfigurationError.out_of_range("samples", samples, "an integer >= 1")
    script = load(scenario)
    declared = {p.name: p for p in script.parameters}
    grid = dict(grid or {})
    samplers = {name: sampler(_param(declared, name), bounds) for name, bounds in (random or {}).items()}
    for name in grid:
        _param(declared, name)
    points = list(itertools.product(*grid.values())) if grid else [()]
    runs = []
    for index, (point, _sample) in enumerate(itertools.product(points, range(samples))):
        sequence = np.random.SeedSequence([seed, index])
        rng = np.random.default_rng(sequence)
        values = {name: str(value) for name, value in zip(grid, point, strict=True)}
        for name, draw in samplers.items():
            values[name] = draw(rng)
        run_seed = int(sequence.generate_state(1, dtype=np.uint32)[0])
        runs.append(RunSpec(index, run_seed, values))
    checked: set[tuple[tuple[str, str], ...]] = set()
    built: set[tuple[str, str]] = set()
    for spec in runs:  # every value against its declared range before the first run (not a NaN row after it)
        key = tuple(sorted(spec.overrides.items()))
        if key not in checked:
            checked.add(key)
            try:
                script.resolve(spec.overrides)
                # a machine key's range is checked where the machine is built: once per distinct value of
                # each swept key (a build costs a tenth of a second; ranges that hang on several keys at
                # once are still checked by each run)
                if isinstance(script, MachineFile) and not set(spec.overrides.items()) <= built:
                    check_machine(script, overrides=spec.overrides)
                    built |= set(spec.overrides.items())
            except ConfigurationError as exc:
                raise ConfigurationError(f"sweep run {spec.index} ({_shown_values(spec.overrides)}): {exc}") from None
    return runs


def _shown_values(values: Mapping[str, str]) -> str:
    return ", ".join(f"{name}={value}" for name, value in values.items()) or "the defaults"


def _param(declared: Mapping[str, Param], name: str) -> Param:
    if name not in declared:
        raise ConfigurationError(f"the scenario has no parameter {name!r} (declared: {', '.join(declared)})")
    return declared[name]


def sampler(param: Param, bounds: tuple[Any, ...] | None = None) -> Sampler:
    """How values of ``param`` are drawn: on its grid (see the module docstring), within ``bounds``.

    Parameters
    ----------
    param : Param
        The declared parameter (its type, unit and range decide the grid).
    bounds : tuple, optional
        ``(low, high)`` or ``(low, high, step)`` in the parameter's unit; default the declared range.

    Raises
    ------
    ConfigurationError
        For flags and strings (sweep them with a grid), a range outside the declared one or empty,
        a step that is not positive, or a time step that is not a whole number of ticks.
    """
    name = param.name
    if isinstance(param.default, bool | str):
        raise ConfigurationError(f"parameter {name} is a {type(param.default).__name__}: sweep it with a grid")
    if bounds is None:
        if param.range is None:
            raise ConfigurationError(f"parameter {name} declares no range: give one as {name}=LOW:HIGH")
        bounds = (param.range[0], param.range[1])
    if len(bounds) not in (2, 3):
        raise ConfigurationError(f"random range of {name}: expected (low, high) or (low, high, step), got {bounds!r}")
    low_value, high_value = (param.parse(str(b)) for b in bounds[:2])  # range-checked against the declaration
    low, high = _exact(low_value, name), _exact(high_value, name)
    if high < low:
        raise ConfigurationError(f"random range of {name}: {low_value}..{high_value} is empty")
    tick = NANOSECOND.resolution_s / UNITS_S[param.unit] if param.unit in UNITS_S else None
    if len(bounds) == 3:
        step = _exact(bounds[2], f"step of {name}")
        if step <= 0 or (isinstance(param.default, int) and step.denominator != 1):
            raise ConfigurationError.out_of_range(f"step of {name}", shown(step),
                                                  "> 0" + (", whole" if isinstance(param.default, int) else ""))
        if tick is not None and ((step / tick).denominator != 1 or (low / tick).denominator != 1):
            raise ConfigurationError(f"random range of {name}: low {low_value} and step {bounds[2]} {param.unit} "
                                     f"must be whole numbers of the time resolution ({NANOSECOND.unit})")
        return _on_grid(low, step, 0, int((high - low) // step), integer=isinstance(param.default, int))
    if isinstance(param.default, int):
        return _on_grid(Fraction(0), Fraction(1), math.ceil(low), math.floor(high), integer=True)
    if tick is not None:
        first, last = math.ceil(low / tick), math.floor(high / tick)
        if last < first:
            raise ConfigurationError(f"random range of {name}: {low_value}..{high_value} {param.unit} "
                                     f"holds no whole number of ticks ({NANOSECOND.unit})")
        return _on_grid(Fraction(0), tick, first, last, integer=False)
    low_f, high_f = float(low), float(high)
    return lambda rng: repr(float(rng.uniform(low_f, high_f)))


def _on_grid(origin: Fraction, step: Fraction, first: int, last: int, *, integer: bool) -> Sampler:
    """Draw ``origin + k * step`` for a uniform integer ``k`` in ``first..last``."""
    def draw(rng: np.random.Generator) -> str:
        value = origin + int(rng.integers(first, last, endpoint=True)) * step
        return str(int(value)) if integer else _decimal(value)

    return draw


def _exact(value: object, what: str) -> Fraction:
    """A number as the exact decimal it prints as."""
    try:
        return Fraction(Decimal(str(value)))
    except (InvalidOperation, ValueError):
        raise ConfigurationError(f"{what} = {value!r} is not a number") from None


def _decimal(value: Fraction) -> str:
    """Exact decimal text of a fraction whose denominator divides a power of ten (``1734521/10**6`` -> ``1.734521``)."""
    digits = 0
    while (value * 10**digits).denominator != 1:
        digits += 1
        if digits > 30:
            raise ValueError(f"{value} has no short decimal form")
    text = format(Decimal(int(value * 10**digits)).scaleb(-digits), "f")
    return text.rstrip("0").rstrip(".") if "." in text else text


def run_one(scenario: str | ScenarioFile, spec: RunSpec) -> dict[str, Any]:
    """Run one sweep point and flatten its result into a row (no files written).

    The checks go into ``row["_checks"]`` as ``(name, passed, n_violations, measured, verdict)``; :func:`sweep`
    turns them into the short ``c<k>.*`` columns and the legend.
    """
    from cosim.runner import check_outcome, run_scenario

    row: dict[str, Any] = {"index": spec.index, "seed": spec.seed}
    try:
        script = load(scenario) if isinstance(scenario, str) else scenario
        # a machine file's values by their dotted keys (the ones --grid names), a scenario's by name
        row.update({f"p.{k}": v for k, v in leaves(script.resolve(spec.overrides))})
        result = run_scenario(script, overrides=spec.overrides, seed=spec.seed)
    except Exception as exc:  # a broken run is a row, not the end of the sweep
        row.update({"verdict": "ERROR", "error": f"{type(exc).__name__}: {exc}", "_checks": []})
        return row
    row.update({"verdict": result.verdict, "error": result.error or "", "checks_passed": result.passed,
                "checks_failed": result.failed})
    row["_checks"] = [(c["name"], bool(c["passed"]), int(c["n_violations"]), dict(c["measured"]), check_outcome(c))
                      for c in result.checks]
    row["_units"] = {name: figure["unit"] for name, figure in result.figures.items()}
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
             timing: dict[str, float], say: Callable[[str], None]) -> Iterator[dict[str, Any]]:
    if workers == 0 and scheduler is None:
        try:
            script: str | ScenarioFile = load(scenario)
        except Exception:  # each run reports the error in its own row
            script = scenario
        for spec in runs:
            yield run_one(script, spec)
        return
    from dask.distributed import Client, LocalCluster, as_completed

    started = time.perf_counter()
    say(f"connecting to the Dask scheduler at {scheduler} ..." if scheduler
        else f"starting {workers} local Dask worker process{'es' if workers != 1 else ''} ...")
    cluster = None if scheduler else LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                  dashboard_address=None, preload=["cosim.runner"])
    try:
        with Client(scheduler or cluster) as client:
            timing["startup_s"] = time.perf_counter() - started
            n_workers = max(1, len(client.scheduler_info().get("workers", {})))
            say(f"{n_workers} worker{'s' if n_workers != 1 else ''} ready after {timing['startup_s']:.1f} s")
            # Runs go out in chunks (about four per worker) so that short runs are not dominated
            # by the scheduler's per-task cost.
            size = max(1, -(-len(runs) // (4 * n_workers)))
            chunks = [runs[i:i + size] for i in range(0, len(runs), size)]
            futures = client.map(run_chunk, [scenario] * len(chunks), chunks, pure=False)
            for future in as_completed(futures):
                yield from future.result()
    finally:
        if cluster is not None:
            cluster.close()


class _Progress:
    """Progress across runs: a bar on a terminal, a plain line every tenth of the runs otherwise (pipes, CI)."""

    def __init__(self, name: str, total: int, *, enabled: bool) -> None:
        self.name, self.total, self.enabled = name, total, enabled
        self.tty = enabled and sys.stderr.isatty()
        self.done = 0
        self.verdicts: dict[str, int] = {}
        self.started = time.perf_counter()
        self.every = max(1, total // 10)
        self.bar: Any = None

    def say(self, text: str) -> None:
        if self.enabled:
            print(f"sweep {self.name}: {text}", file=sys.stderr, flush=True)

    def update(self, verdict: str) -> None:
        self.done += 1
        self.verdicts[verdict] = self.verdicts.get(verdict, 0) + 1
        counts = ", ".join(f"{n} {v}" for v, n in sorted(self.verdicts.items()))
        if self.tty:
            if self.bar is None:
                from tqdm import tqdm

                self.bar = tqdm(total=self.total, desc=f"sweep {self.name}", unit="run", leave=True,
                                file=sys.stderr)
            self.bar.set_postfix_str(counts, refresh=False)
            self.bar.update(1)
        elif self.enabled and (self.done % self.every == 0 or self.done == self.total):
            self.say(f"{self.done}/{self.total} runs ({counts}) {time.perf_counter() - self.started:.1f} s")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()  # leave=True: the bar's line ends with a newline


def sweep(scenario: str | Path, runs: list[RunSpec], *, workers: int = 2, scheduler: str | None = None,
          out: str | Path | None = None, progress: bool = True, report: bool = True,
          on_row: Callable[[dict[str, Any]], None] | None = None) -> Any:
    """Run ``runs`` of ``scenario``; returns a pandas DataFrame ordered by run index.

    Parameters
    ----------
    scenario : str or path
        Bundled scenario name or script path.
    runs : list of RunSpec
        From :func:`plan`.
    workers : int
        Local Dask worker processes (0: run here, one after the other).
    scheduler : str, optional
        Address of an existing Dask scheduler (``workers`` is then ignored).
    out : path, optional
        Folder for ``sweep.parquet``, ``sweep.json`` and (with ``report``) ``sweep.html``.
    progress : bool
        Report start-up and progress across runs on stderr.
    report : bool
        Write the HTML report when ``out`` is given.
    on_row : callable, optional
        Called with each raw row as it arrives (in completion order).

    Returns
    -------
    pandas.DataFrame
        One row per run. ``table.attrs`` holds ``wall_time_s`` [s], ``startup_s`` [s] (starting the
        cluster, part of the wall time), ``legend`` (``c<k>`` -> check name), ``units`` (figure ->
        unit) and ``swept`` (the parameters that vary).
    """
    import pandas as pd

    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ConfigurationError.out_of_range("workers", workers, "an integer >= 0")
    if out is not None:  # refused before the first run, not after the last
        _writable(Path(out))
    name = str(scenario)
    rows: list[dict[str, Any]] = []
    timing = {"startup_s": 0.0}
    started = time.perf_counter()
    bar = _Progress(Path(name).stem, len(runs), enabled=progress)
    try:
        for row in _results(name, runs, workers, scheduler, timing, bar.say):
            rows.append(row)
            if on_row is not None:
                on_row(row)
            bar.update(row["verdict"])
    finally:
        bar.close()
    rows.sort(key=lambda r: int(r["index"]))
    legend, units = _flatten(rows)
    table = pd.DataFrame(rows)
    table.attrs.update({"wall_time_s": time.perf_counter() - started, "startup_s": timing["startup_s"],
                        "legend": legend, "units": units,
                        "swept": sorted({k for spec in runs for k in spec.overrides})})
    if out is not None:
        write(table, Path(out), scenario=Path(name).stem, report=report)
    return table


def _flatten(rows: list[dict[str, Any]]) -> tuple[dict[str, str], dict[str, str]]:
    """Replace each row's ``_checks`` by ``c<k>.*`` columns; returns the legend and the figure units.

    ``k`` counts checks in the order they first appear, runs taken by index: the declaration order
    for every scenario whose checks do not depend on its parameters.
    """
    keys: dict[str, str] = {}
    units: dict[str, str] = {}
    for row in rows:
        units.update(row.pop("_units", {}))
        failed = []
        for check_name, passed, n_violations, measured, verdict in row.pop("_checks", []):
            key = keys.setdefault(check_name, f"c{len(keys) + 1}")
            row[f"{key}.verdict"] = verdict
            row[f"{key}.passed"] = passed
            row[f"{key}.n_violations"] = n_violations
            for measure, value in measured.items():
                row[f"{key}.{measure}"] = value
            if verdict not in ("PASS", "HAZARD SHOWN"):
                failed.append(key)
        row["failed"] = ", ".join(failed)
    return {key: check_name for check_name, key in keys.items()}, units


def _writable(folder: Path) -> None:
    """Make ``folder`` (and its parents), or say why it cannot be."""
    blocker = next((p for p in (folder, *folder.parents) if p.exists() and not p.is_dir()), None)
    if blocker is not None:
        raise ConfigurationError(f"--out {folder}: {blocker} is a file, not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigurationError(f"--out {folder}: cannot write there ({exc.strerror or exc}); choose a folder you "
                                 "can write to") from None


def write(table: Any, folder: Path, *, scenario: str, report: bool = True) -> None:
    """Write ``sweep.parquet``, ``sweep.json`` (legend, units, counts) and the report ``sweep.html``."""
    folder.mkdir(parents=True, exist_ok=True)
    table.to_parquet(folder / "sweep.parquet", index=False)
    from cosim.sweep_report import verdict_counts, write_report

    meta = {"scenario": scenario, "runs": len(table), "verdicts": verdict_counts(table),
            "swept": table.attrs["swept"], "legend": table.attrs["legend"], "units": table.attrs["units"],
            "wall_time_s": round(table.attrs["wall_time_s"], 3)}
    (folder / "sweep.json").write_text(json.dumps(meta, indent=1) + "\n")
    if report:
        write_report(table, folder / "sweep.html", scenario=scenario)


def parse_grid(items: Sequence[str]) -> dict[str, list[str]]:
    """``NAME=v1,v2,...`` items of the command line."""
    grid = {}
    for item in items:
        name, sep, values = item.partition("=")
        if not sep or not values:
            raise ConfigurationError(f"--grid {item!r}: expected NAME=v1,v2,...")
        grid[name.strip()] = [v.strip() for v in values.split(",")]
    return grid


def parse_random(items: Sequence[str]) -> dict[str, tuple[str, ...] | None]:
    """``NAME``, ``NAME=LOW:HIGH`` or ``NAME=LOW:HIGH:STEP`` items of the command line."""
    ranges: dict[str, tuple[str, ...] | None] = {}
    for item in items:
        name, sep, bounds = item.partition("=")
        if not sep:
            ranges[name.strip()] = None
            continue
        parts = tuple(b.strip() for b in bounds.split(":"))
        if len(parts) not in (2, 3) or not all(parts):
            raise ConfigurationError(f"--random {item!r}: expected NAME, NAME=LOW:HIGH or NAME=LOW:HIGH:STEP")
        ranges[name.strip()] = parts
    return ranges
