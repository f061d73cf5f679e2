"""One FMU run alone: ``cosim run-fmu``, like fmpy's ``simulate_fmu`` and the Reference FMUs' ``fmusim``.

:func:`run_fmu` simulates one co-simulation FMU with the master: start values from ``--set``,
inputs over time from an input table (``--input``, :mod:`cosim.fmuinput`), every numeric output
recorded on a grid (start, start + step, ... and the end), written as the usual result folder by
:func:`cosim.runner.run_scenario`, plus ``outputs.csv``: the grid with the FMU's own variable names.

Names. The trace's scheme is lower case (``<device>.<signal>``, each part ``[a-z0-9_]``), FMU
variable names are not: :func:`trace_names` maps them one to one (it never gives two variables one
signal), and the run keeps the mapping (``trace_meta.json``: ``meta.fmu_variables``, trace name ->
FMU name) and writes ``outputs.csv`` with the FMU's names as they are.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any

from cosim.errors import ConfigurationError, PlantTerminated
from cosim.fmuvars import Variable, trace_names

__all__ = ["outputs_rows", "plant_name", "run_fmu", "trace_names"]

def plant_name(path: Path) -> str:
    """A device name for the trace from the FMU file's name (``TypesTest.fmu`` -> ``typestest``)."""
    name = re.sub(r"[^a-z0-9_]", "_", path.stem.lower())
    return name if re.match(r"[a-z]", name) else f"fmu_{name}"


def run_fmu(path: str | Path, *, sets: Mapping[str, str] | None = None, until: str | None = None,
            step: str | None = None, start: str | None = None, input_table: str | Path | None = None,
            validate: bool = True, out: str | Path | None = None, formats: tuple[str, ...] = ("vcd", "parquet"),
            progress: bool = False) -> Any:
    """Simulate one FMU alone and write the usual result folder (returns the :class:`~cosim.runner.Result`).

    Parameters
    ----------
    path : path
        The ``.fmu`` file (co-simulation).
    sets : mapping name -> text, optional
        Start values of parameters and inputs (``--set``), parsed by each variable's type.
    until : str, optional
        End time with unit (default: the FMU's default experiment stop time, else start + 1 s).
    step : str, optional
        Output grid with unit (default: the default experiment step, else 1/500 of the run).
    start : str, optional
        Start time with unit (default: the default experiment's start time, else 0).
    input_table : path, optional
        A CSV input table (``--input``): inputs over time (:mod:`cosim.fmuinput`).
    validate : bool
        Apply fmpy's validator to the model description (default). False (``--no-validate``) runs
        an FMU it flags, with a warning in the run's notes listing what it found.
    out : path, optional
        Results folder.
    formats : tuple of str
        Trace files to write (see :func:`cosim.export.write_trace`).
    progress : bool
        Show a progress bar for runs longer than two seconds (on a terminal only).

    Notes
    -----
    Integer, Boolean and enumeration outputs are recorded as numbers; strings and binaries are
    not recorded. An FMU that asks to end the simulation ends the run at that instant, with a last
    sample there (its outputs' values when it stopped).
    """
    from cosim.fmu import read_description, validation_findings
    from cosim.timebase import TimeBase

    path = Path(path)
    model = read_description(path, validate=validate)
    findings = [] if validate else validation_findings(path)
    version = 3 if model.fmiVersion.startswith("3") else 2
    variables = {sv.name: var for sv in model.modelVariables
                 if (var := Variable.from_model(sv, version)) is not None}
    values = _start_values(path, variables, sets or {})
    timebase = TimeBase()
    t_start, end, period = _times(model.defaultExperiment, timebase, start=start, until=until, step=step)
    table = None
    if input_table is not None:
        from cosim.fmuinput import read_input_table

        table = read_input_table(input_table, variables, timebase=timebase, where="--input")
        overlap = sorted(set(table.columns) & set(values))
        if overlap:
            raise ConfigurationError(f"--set and --input both give {', '.join(overlap)}: give each input once")
    outputs = [name for name, var in variables.items() if var.causality == "output" and var.kind.is_numeric]
    device = plant_name(path)
    names = trace_names(outputs, device, order=[sv.name for sv in model.modelVariables])
    notes = _validation_note(path, findings)
    rows: list[list[str]] = []
    result = _run(path, device=device, values=values, sets=sets or {}, variables=variables, names=names,
                  t_start=t_start, end=end, period=period, table=table, validate=validate, notes=notes, out=out,
                  formats=formats, progress=progress, rows=rows)
    if out is not None and rows and result.out is not None:
        with (Path(result.out) / "outputs.csv").open("w", newline="", encoding="utf-8") as handle:
            csv.writer(handle).writerows(rows)
    return result


def _start_values(path: Path, variables: Mapping[str, Variable], sets: Mapping[str, str]) -> dict[str, Any]:
    where = f"--set of {path.name}"
    values: dict[str, Any] = {}
    for name, text in sets.items():
        if name not in variables:
            import difflib

            close = difflib.get_close_matches(name, list(variables), n=3)
            raise ConfigurationError(f"{where}: {path.name} has no variable named {name!r}"
                                     + (f"; did you mean {', '.join(close)}?" if close else ""))
        if variables[name].causality not in ("parameter", "input"):
            raise ConfigurationError(f"{where}: {name} is an {variables[name].causality}; --set takes parameters "
                                     "and inputs")
        values[name] = variables[name].parse(text, where=where)
    return values


def _times(experiment: Any, timebase: Any, *, start: str | None, until: str | None,
           step: str | None) -> tuple[int, int, int]:
    """Start, end and output grid [ticks]: the options, else the default experiment, else 0, start + 1 s, 1/500."""
    def declared(key: str) -> float | None:
        value = getattr(experiment, key, None) if experiment is not None else None
        return None if value in (None, "") else float(value)

    if start is not None:
        t_start = timebase.ticks(start, name="--start")
    else:
        start_s = declared("startTime") or 0.0
        if start_s < 0:
            raise ConfigurationError(f"the FMU's default experiment starts at {start_s!r} s: cosim's time starts at "
                                     "0; give --start 0 s (or a later start)")
        t_start = timebase.ticks_from_seconds_ceil(start_s)
    timebase.check_ticks(t_start, name="--start", minimum=0)
    stop_s = declared("stopTime")
    if until is not None:
        end = timebase.ticks(until, name="--until")
    elif stop_s is not None:
        end = timebase.ticks_from_seconds_ceil(stop_s)
    else:
        end = t_start + timebase.ticks(1, "s")
    if end <= t_start:
        raise ConfigurationError(f"the run would end ({timebase.seconds(end)!r} s) at or before it starts "
                                 f"({timebase.seconds(t_start)!r} s): give --until after --start")
    step_s = declared("stepSize")
    if step is not None:
        period = timebase.ticks(step, name="--step")
    elif step_s:
        period = timebase.ticks_from_seconds_ceil(step_s)
    else:
        period = max(1, (end - t_start) // 500)
    timebase.check_ticks(period, name="--step", minimum=1)
    return t_start, end, period


def _validation_note(path: Path, findings: list[str]) -> list[str]:
    if not findings:
        return []
    shown = "; ".join(findings[:10]) + (f"; and {len(findings) - 10} more" if len(findings) > 10 else "")
    return [f"WARNING: {path.name} runs without validation (--no-validate): fmpy's validator finds "
            f"{len(findings)} problem(s) in its model description: {shown}"]


def _run(path: Path, *, device: str, values: dict[str, Any], sets: Mapping[str, str],
         variables: Mapping[str, Variable], names: dict[str, str], t_start: int, end: int, period: int,
         table: Any, validate: bool, notes: list[str], out: str | Path | None, formats: tuple[str, ...],
         progress: bool, rows: list[list[str]]) -> Any:
    from cosim.fmu import Fmu
    from cosim.master import Plant
    from cosim.runner import run_scenario
    from cosim.scenario import Param, Run, ScenarioFile

    def scenario(run: Run) -> None:
        sim = run.sim
        for note in notes:
            run.note(note)
        sim.trace.meta["fmu_variables"] = {trace: variable for variable, trace in names.items()}
        if t_start > sim.now:
            sim.run(until=t_start)  # nothing happens before the FMU's start
        fmu = Fmu(path, timebase=sim.timebase, instance_name=device, parameters=values, start=sim.now,
                  validate=validate)
        plant = Plant(sim, fmu, name=device)
        run.plants.append(plant)
        if table is not None:
            from cosim.fmuinput import drive_from_table

            drive_from_table(plant, table)
        sample = plant.record(names, period=period, at_events=False)  # the grid alone, as simulate_fmu
        try:
            try:
                run.run_until(run.until)
            except PlantTerminated:
                sample()  # the instant the FMU stopped at, as fmpy's simulate_fmu records it
                raise
            sample()  # the end instant too (or, if the FMU stops on the way there, its values where it stopped)
        finally:
            if out is not None:
                rows.extend(outputs_rows(sim.trace, names, integers={n for n, v in variables.items()
                                                                     if not v.kind.is_float}))

    params = tuple(Param(name, value if isinstance(value, bool | int | float | str) else text, variables[name].unit)
                   for (name, value), text in zip(values.items(), sets.values(), strict=True))
    scenario_file = ScenarioFile(name=device, path=path.resolve(), description=f"{path.name} alone",
                                 parameters=params, until=end, function=scenario)
    return run_scenario(scenario_file, until=end, out=out, formats=formats, progress=progress)


def outputs_rows(trace: Any, names: Mapping[str, str], *, integers: Collection[str] = ()) -> list[list[str]]:
    """The rows of ``outputs.csv``: a header (``time`` and the FMU's own names), then time [s] and every
    recorded output at each grid point; reals as Python writes them (``repr``: exact), the ``integers``
    (integer, Boolean and enumeration outputs) as whole numbers. Empty if the outputs were not sampled
    on one grid."""
    columns = [(variable, name) for variable, name in names.items() if name in trace.info]
    if not columns:
        return []
    series = [trace.edges(name) for _, name in columns]
    times = series[0][0].tolist()
    if any(t.tolist() != times for t, _ in series):
        return []
    seconds = trace.timebase.seconds
    rows = [["time", *(variable for variable, _ in columns)]]
    shown = [[str(int(x)) for x in values.tolist()] if variable in integers else [repr(x) for x in values.tolist()]
             for (variable, _), (_, values) in zip(columns, series, strict=True)]
    rows += [[repr(seconds(t)), *(column[i] for column in shown)] for i, t in enumerate(times)]
    return rows
