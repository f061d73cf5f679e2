"""One FMU on its own: what is in it (``cosim fmu-info``) and a quick run (``cosim run-fmu``).

:func:`fmu_info` reads an FMU file without instantiating it: FMI version, interfaces, variables
(type, causality, variability, unit, start, range, dimensions), default experiment, the platforms
it has binaries for, and which couplings it can serve: each coupling's roles
(:mod:`cosim.couplings`) are looked up among its variables, so the answer says which roles are
found under the bundled FMUs' names and which need a ``variables={role: name}`` mapping.

:func:`run_fmu` simulates one FMU alone with the master, like fmpy's ``simulate_fmu``: start
values from ``--set``, every numeric output recorded on a grid (0, step, 2 step, ... and the end),
written as the usual result folder by :func:`cosim.runner.run_scenario`.
"""

from __future__ import annotations

import re
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosim.errors import ConfigurationError, PlantTerminated
from cosim.fmuvars import Variable, fmi_type

_INTERFACES = (("coSimulation", "CoSimulation"), ("modelExchange", "ModelExchange"),
               ("scheduledExecution", "ScheduledExecution"))


@dataclass(frozen=True)
class FmuInfo:
    """What :func:`fmu_info` found in an FMU file (also its JSON, :meth:`as_dict`)."""

    path: Path
    fmi_version: str
    model_name: str
    description: str
    generation_tool: str
    interfaces: dict[str, dict[str, Any]]
    variables: list[dict[str, Any]]
    default_experiment: dict[str, float | None]
    platforms: list[str]
    has_sources: bool
    couplings: dict[str, dict[str, Any]] = field(default_factory=dict)

    @property
    def co_simulation(self) -> bool:
        return "CoSimulation" in self.interfaces

    def as_dict(self) -> dict[str, Any]:
        return {"path": str(self.path), "fmi_version": self.fmi_version, "model_name": self.model_name,
                "description": self.description, "generation_tool": self.generation_tool,
                "interfaces": self.interfaces, "default_experiment": self.default_experiment,
                "platforms": self.platforms, "has_sources": self.has_sources, "variables": self.variables,
                "couplings": self.couplings}


def fmu_info(path: str | Path) -> FmuInfo:
    """Read an FMU file's model description and list of files (nothing is instantiated)."""
    from cosim.fmu import read_description

    path = Path(path)
    model = read_description(path, cosimulation=False)
    version = 3 if model.fmiVersion.startswith("3") else 2
    interfaces = {}
    for attribute, name in _INTERFACES:
        interface = getattr(model, attribute, None)
        if interface is not None:
            flags = ("canHandleVariableCommunicationStepSize", "hasEventMode", "mightReturnEarlyFromDoStep",
                     "canGetAndSetFMUstate", "canSerializeFMUstate")
            interfaces[name] = {"modelIdentifier": interface.modelIdentifier,
                                **{flag: bool(getattr(interface, flag)) for flag in flags
                                   if getattr(interface, flag, False)}}
    rows = [_row(sv, version) for sv in model.modelVariables]
    experiment = model.defaultExperiment
    default = {key: _float(getattr(experiment, key, None)) for key in ("startTime", "stopTime", "stepSize",
                                                                        "tolerance")}
    platforms, sources = _files(path)
    return FmuInfo(path, model.fmiVersion, model.modelName or "", model.description or "",
                   model.generationTool or "", interfaces, rows, default, platforms, sources,
                   couplings_served({row["name"]: row for row in rows if row["supported"]}))


def _float(value: Any) -> float | None:
    return None if value is None else float(value)


def _row(sv: Any, fmi_version: int) -> dict[str, Any]:
    var = Variable.from_model(sv, fmi_version)
    declared = sv.declaredType.name if sv.declaredType is not None else ""
    return {"name": sv.name, "type": sv.type + (f"({declared})" if declared and sv.type == "Enumeration" else ""),
            "causality": sv.causality or "", "variability": sv.variability or "",
            "unit": var.unit if var is not None else (sv.unit or ""),
            "start": sv.start if sv.start is None else str(sv.start),
            "min": var.min if var is not None else sv.min, "max": var.max if var is not None else sv.max,
            "dimensions": list(sv.shape or ()), "items": var.items if var is not None else {},
            "description": sv.description or "", "supported": fmi_type(sv.type, fmi_version) is not None}


def _files(path: Path) -> tuple[list[str], bool]:
    """Platforms with a binary, and whether the FMU carries its sources."""
    if path.is_dir():
        names = [p.relative_to(path).as_posix() for p in path.rglob("*") if p.is_file()]
    else:
        with zipfile.ZipFile(path) as zf:
            names = zf.namelist()
    platforms = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2
                        and not n.endswith("/")})
    return platforms, any(n.startswith("sources/") and not n.endswith("/") for n in names)


# -- couplings --------------------------------------------------------------------------------------
def _coupling_roles() -> dict[str, tuple[Mapping[str, str | None], tuple[str, ...], bool]]:
    """Each coupling: its roles (bundled names), the roles it may leave unconnected, and whether any one suffices."""
    from cosim.couplings import encoder, laser, servo, stepper, switches

    return {"stepper": (stepper.ROLES, ("step_segments", "commanded_steps"), False),
            "laser": (laser.ROLES, ("clock_hz",), False),
            "switches": (switches.ROLES, tuple(switches.ROLES), True),
            "encoder": (encoder.ROLES, (), False),
            "mark": (encoder.MARK_ROLES, (), False),
            "servo": (servo.ROLES, (), False)}


def couplings_served(variables: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """For each coupling: ``ready`` (every required role found under its bundled name), the roles found,
    and the required roles missing, with the bundled FMU's name for each (map them with
    ``variables={role: name}``)."""
    served = {}
    for coupling, (roles, optional, any_one) in _coupling_roles().items():
        found = {role: name for role, name in roles.items() if name is not None and name in variables}
        missing = {role: name for role, name in roles.items()
                   if role not in found and (any_one or role not in optional)}
        ready = bool(found) if any_one else not missing
        served[coupling] = {"ready": ready, "found": found, "missing": {} if ready else missing,
                            "needs": "any role" if any_one else "every required role"}
    return served


def format_info(info: FmuInfo) -> str:
    """The text ``cosim fmu-info`` prints."""
    lines = [f"{info.path.name}: {info.model_name} (FMI {info.fmi_version})"]
    if info.description:
        lines.append(f"  {info.description}")
    if info.generation_tool:
        lines.append(f"  generated by {info.generation_tool}")
    for name, flags in info.interfaces.items():
        extra = ", ".join(k for k in flags if k != "modelIdentifier")
        lines.append(f"  interface {name} ({flags['modelIdentifier']}){': ' + extra if extra else ''}")
    if not info.co_simulation:
        lines.append("  not usable as a cosim plant: co-simulation is required (see docs/fmus.md)")
    experiment = ", ".join(f"{k} {v:g}" for k, v in info.default_experiment.items() if v is not None)
    lines.append(f"  default experiment: {experiment or 'none'}")
    lines.append(f"  platforms: {', '.join(info.platforms) or 'none'}"
                 + ("; sources included" if info.has_sources else ""))
    lines.append("")
    head = ("name", "type", "causality", "variability", "unit", "start", "range", "dims")
    rows = [head] + [(v["name"], v["type"] + ("" if v["supported"] else "*"), v["causality"],
                      v["variability"], v["unit"], _short(v["start"]), _range(v),
                      "x".join(map(str, v["dimensions"]))) for v in info.variables]
    widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
    lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip() for row in rows]
    if not all(v["supported"] for v in info.variables):
        lines.append("  * a type cosim does not read or set (clocks)")
    lines += ["", "couplings (ready: every role found under the bundled FMU's name; otherwise map the roles "
              "with variables={role: name}):"]
    for coupling, served in info.couplings.items():
        if served["ready"]:
            state = "ready (" + ", ".join(f"{r}={n}" for r, n in served["found"].items()) + ")"
        else:
            state = ("map " + (" or " if served["needs"] == "any role" else ", ").join(
                f"{role} (bundled: {name})" for role, name in served["missing"].items()))
        lines.append(f"  {coupling:<9} {state}")
    return "\n".join(lines) + "\n"


def _short(value: str | None, width: int = 24) -> str:
    text = "" if value is None else value
    return text if len(text) <= width else text[: width - 3] + "..."


def _range(v: Mapping[str, Any]) -> str:
    if v["items"]:
        return ", ".join(f"{value} {name}" for name, value in v["items"].items())
    low, high = v["min"], v["max"]
    if low is None and high is None:
        return ""
    return f"{'' if low is None else low}..{'' if high is None else high}"


# -- run-fmu ----------------------------------------------------------------------------------------
def trace_names(variables: list[str], prefix: str) -> dict[str, str]:
    """Trace signal names for FMU variables: ``<prefix>.<name>``, lower case, other characters as ``_``."""
    names: dict[str, str] = {}
    for variable in variables:
        parts = [re.sub(r"[^a-z0-9_]", "_", part.lower()) or "_" for part in re.split(r"\.", variable)]
        name = ".".join([prefix, *parts])
        base, n = name, 2
        while name in names.values():
            name, n = f"{base}_{n}", n + 1
        names[variable] = name
    return names


def plant_name(path: Path) -> str:
    """A device name for the trace from the FMU file's name (``TypesTest.fmu`` -> ``typestest``)."""
    name = re.sub(r"[^a-z0-9_]", "_", path.stem.lower())
    return name if re.match(r"[a-z]", name) else f"fmu_{name}"


def run_fmu(path: str | Path, *, sets: Mapping[str, str] | None = None, until: str | None = None,
            step: str | None = None, out: str | Path | None = None,
            formats: tuple[str, ...] = ("vcd", "parquet"), progress: bool = False) -> Any:
    """Simulate one FMU alone and write the usual result folder (returns the :class:`~cosim.runner.Result`).

    Parameters
    ----------
    path : path
        The ``.fmu`` file (co-simulation).
    sets : mapping name -> text, optional
        Start values of parameters and inputs (``--set``), parsed by each variable's type.
    until : str, optional
        End time with unit (default: the FMU's default experiment stop time, else 1 s).
    step : str, optional
        Output grid with unit (default: the default experiment step, else 1/500 of the run).
    out : path, optional
        Results folder.
    formats : tuple of str
        Trace files to write (see :func:`cosim.export.write_trace`).
    progress : bool
        Show a progress bar for runs longer than two seconds (on a terminal only).

    Notes
    -----
    The run starts at 0 s (a default experiment's start time is not used). Integer, Boolean and
    enumeration outputs are recorded as numbers; strings and binaries are not recorded.
    """
    from cosim.fmu import read_description
    from cosim.runner import run_scenario
    from cosim.scenario import Param, Run, ScenarioFile
    from cosim.timebase import TimeBase

    path = Path(path)
    model = read_description(path)
    version = 3 if model.fmiVersion.startswith("3") else 2
    variables = {sv.name: var for sv in model.modelVariables
                 if (var := Variable.from_model(sv, version)) is not None}
    where = f"--set of {path.name}"
    values: dict[str, Any] = {}
    for name, text in (sets or {}).items():
        if name not in variables:
            import difflib

            close = difflib.get_close_matches(name, list(variables), n=3)
            raise ConfigurationError(f"{where}: {path.name} has no variable named {name!r}"
                                     + (f"; did you mean {', '.join(close)}?" if close else ""))
        if variables[name].causality not in ("parameter", "input"):
            raise ConfigurationError(f"{where}: {name} is an {variables[name].causality}; --set takes parameters "
                                     "and inputs")
        values[name] = variables[name].parse(text, where=where)
    experiment = model.defaultExperiment
    timebase = TimeBase()
    stop_s = float(experiment.stopTime) if experiment is not None and experiment.stopTime else 1.0
    end = timebase.ticks(until, name="until") if until is not None else timebase.ticks_from_seconds_ceil(stop_s)
    if step is not None:
        period = timebase.ticks(step, name="step")
    elif experiment is not None and experiment.stepSize:
        period = timebase.ticks_from_seconds_ceil(float(experiment.stepSize))
    else:
        period = max(1, end // 500)
    timebase.check_ticks(period, name="step", minimum=1)
    outputs = [name for name, var in variables.items() if var.causality == "output" and var.kind.is_numeric]
    device = plant_name(path)
    names = trace_names(outputs, device)

    def scenario(run: Run) -> None:
        plant = run.plant(path, name=device, parameters=values)
        sample = plant.record(names, period=period, at_events=False)  # the grid alone, as simulate_fmu
        try:
            run.run_until(run.until)
        except PlantTerminated:
            sample()  # the instant the FMU stopped at, as fmpy's simulate_fmu records it
            raise
        sample()  # the end instant too

    params = tuple(Param(name, value if isinstance(value, bool | int | float | str) else text, variables[name].unit)
                   for (name, value), text in zip(values.items(), (sets or {}).values(), strict=True))
    scenario_file = ScenarioFile(name=device, path=path.resolve(), description=f"{path.name} alone",
                                 parameters=params, until=end, function=scenario)
    return run_scenario(scenario_file, until=end, out=out, formats=formats, progress=progress)
