"""One FMU on its own: what is in it (``cosim fmu-info``); the quick run (``cosim run-fmu``) is :mod:`cosim.fmurun`.

:func:`fmu_info` reads an FMU file without instantiating it: FMI version, interfaces, variables
(type, causality, variability, unit, start, range, dimensions), default experiment, the platforms
it has binaries for, what fmpy's validator finds wrong with its model description (an FMU it flags
is still described), and which couplings it can serve: each coupling's roles
(:mod:`cosim.couplings`) are looked up among its variables, so the answer says which roles are
found under the bundled FMUs' names and which need a ``variables={role: name}`` mapping.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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
    validation: list[str] = field(default_factory=list)

    @property
    def co_simulation(self) -> bool:
        return "CoSimulation" in self.interfaces

    def as_dict(self) -> dict[str, Any]:
        return {"path": str(self.path), "fmi_version": self.fmi_version, "model_name": self.model_name,
                "description": self.description, "generation_tool": self.generation_tool,
                "interfaces": self.interfaces, "default_experiment": self.default_experiment,
                "platforms": self.platforms, "has_sources": self.has_sources, "variables": self.variables,
                "couplings": self.couplings, "validation": self.validation}


def fmu_info(path: str | Path) -> FmuInfo:
    """Read an FMU file's model description and list of files (nothing is instantiated)."""
    from cosim.fmu import read_description, validation_findings

    path = Path(path)
    model = read_description(path, cosimulation=False, validate=False)
    findings = validation_findings(path)
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
                   couplings_served({row["name"]: row for row in rows if row["supported"]}), findings)


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
    if info.validation:
        lines.append(f"  fmpy's validator finds {len(info.validation)} problem(s) (run-fmu needs --no-validate):")
        lines += [f"    {problem}" for problem in info.validation]
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


def __getattr__(name: str) -> Any:
    """``run_fmu``, ``trace_names`` and ``plant_name`` moved to :mod:`cosim.fmurun` (still reachable here)."""
    if name in ("run_fmu", "trace_names", "plant_name"):
        from cosim import fmurun

        return getattr(fmurun, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
