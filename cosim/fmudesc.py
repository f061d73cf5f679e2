"""Plant variable tables (``fmu_src/<Model>/model.toml``) and what is generated from them.

One table per plant gives its variables once; from it come the C declarations the model and the
FMI wrappers share (``model_vars.h`` and ``model_vars.c``), the FMI 2.0 and FMI 3.0
``modelDescription.xml`` and the FMI 3.0 ``buildDescription.xml``. Value references follow the
table's order (``time`` is 0), so the C code and both XML files cannot disagree.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from cosim.errors import ConfigurationError

#: SI base-unit exponents (and factor) of the units the plants use; FMI tools check units by these.
UNITS: dict[str, tuple[dict[str, int], float]] = {
    "s": ({"s": 1}, 1.0),
    "Hz": ({"s": -1}, 1.0),
    "W": ({"kg": 1, "m": 2, "s": -3}, 1.0),
    "J": ({"kg": 1, "m": 2, "s": -2}, 1.0),
    "m": ({"m": 1}, 1.0),
    "mm": ({"m": 1}, 1e-3),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "m/s2": ({"m": 1, "s": -2}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, math.pi / 180.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "rad/s2": ({"rad": 1, "s": -2}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "N.m": ({"kg": 1, "m": 2, "s": -2}, 1.0),
    "N.m/A": ({"kg": 1, "m": 2, "s": -2, "A": -1}, 1.0),
    "N.m.s/rad": ({"kg": 1, "m": 2, "s": -1, "rad": -1}, 1.0),
    "N.m/rad": ({"kg": 1, "m": 2, "s": -2, "rad": -1}, 1.0),
    "kg": ({"kg": 1}, 1.0),
    "kg.m2": ({"kg": 1, "m": 2}, 1.0),
    "A": ({"A": 1}, 1.0),
    "V": ({"kg": 1, "m": 2, "s": -3, "A": -1}, 1.0),
    "V.s/rad": ({"kg": 1, "m": 2, "s": -2, "A": -1, "rad": -1}, 1.0),
    "Ohm": ({"kg": 1, "m": 2, "s": -3, "A": -2}, 1.0),
    "H": ({"kg": 1, "m": 2, "s": -2, "A": -2}, 1.0),
    "counts/m": ({"m": -1}, 1.0),  # encoder counts per metre (counts are dimensionless)
    "V/V": ({}, 1.0),         # a voltage gain (dimensionless)
}

_TYPES = {"Float64": ("double", "VT_FLOAT64", "Real"), "Int32": ("int32_t", "VT_INT32", "Integer"),
          "Boolean": ("int", "VT_BOOL", "Boolean")}
_CAUSALITIES = {"parameter": "CA_PARAMETER", "calculatedParameter": "CA_CALCULATED_PARAMETER",
                "input": "CA_INPUT", "output": "CA_OUTPUT", "local": "CA_LOCAL"}
LOG_CATEGORIES = ("logStatusWarning", "logStatusError", "logEvents")


@dataclass(frozen=True)
class Variable:
    """One plant variable as declared in ``model.toml``."""

    name: str
    vr: int
    type: str
    causality: str
    description: str = ""
    unit: str = ""
    start: Any = None
    min: float | None = None
    max: float | None = None
    positive: bool = False
    tunable: bool = False

    @property
    def variability(self) -> str:
        if self.causality == "parameter":
            return "tunable" if self.tunable else "fixed"
        if self.causality == "calculatedParameter":
            return "fixed"
        return "continuous" if self.type == "Float64" else "discrete"


@dataclass(frozen=True)
class ModelSpec:
    """A plant: its model settings and variable table."""

    name: str
    description: str
    token: str
    version: str
    sources: tuple[str, ...]
    folder: Path
    shared: tuple[str, ...] = ()
    event_indicators: int = 0
    has_events: bool = False
    default_step: float = 1e-3
    stop_time: float = 1.0
    variables: tuple[Variable, ...] = field(default_factory=tuple)

    @property
    def outputs(self) -> list[Variable]:
        return [v for v in self.variables if v.causality == "output"]

    def variable(self, name: str) -> Variable:
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(name)


def load_spec(folder: Path) -> ModelSpec:
    """Read and check ``folder/model.toml``."""
    path = folder / "model.toml"
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigurationError(f"{path}: {exc}") from exc
    model = data.get("model", {})
    for key in ("name", "description", "instantiation_token", "version", "sources"):
        if key not in model:
            raise ConfigurationError(f"{path}: [model] has no {key!r}")
    variables = [Variable("time", 0, "Float64", "independent", "Simulation time", "s")]
    for i, raw in enumerate(data.get("variable", []), start=1):
        variables.append(_variable(path, i, raw))
    names = [v.name for v in variables]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise ConfigurationError(f"{path}: variables declared twice: {', '.join(duplicates)}")
    return ModelSpec(
        name=model["name"], description=model["description"], token=model["instantiation_token"],
        version=model["version"], sources=tuple(model["sources"]), folder=folder,
        shared=tuple(model.get("shared", ())),
        event_indicators=int(model.get("event_indicators", 0)), has_events=bool(model.get("events", False)),
        default_step=float(model.get("default_step", 1e-3)), stop_time=float(model.get("stop_time", 1.0)),
        variables=tuple(variables),
    )


def _variable(path: Path, vr: int, raw: dict[str, Any]) -> Variable:
    where = f"{path}: variable {raw.get('name', f'#{vr}')!r}"
    type_ = raw.get("type")
    if type_ not in _TYPES:
        raise ConfigurationError(f"{where}: type {type_!r} is not one of {', '.join(_TYPES)}")
    causality = raw.get("causality")
    if causality not in _CAUSALITIES:
        raise ConfigurationError(f"{where}: causality {causality!r} is not one of {', '.join(_CAUSALITIES)}")
    unit = raw.get("unit", "")
    if unit and unit not in UNITS:
        raise ConfigurationError(f"{where}: unit {unit!r} is not in cosim.fmudesc.UNITS; add it there")
    if causality in ("parameter", "input") and "start" not in raw:
        raise ConfigurationError(f"{where}: a {causality} needs a start value")
    known = {"name", "type", "causality", "description", "unit", "start", "min", "max", "positive", "tunable"}
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ConfigurationError(f"{where}: unknown keys {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    return Variable(name=raw["name"], vr=vr, type=type_, causality=causality,
                    description=raw.get("description", ""), unit=unit, start=raw.get("start"),
                    min=raw.get("min"), max=raw.get("max"), positive=bool(raw.get("positive", False)),
                    tunable=bool(raw.get("tunable", False)))


# -- C -------------------------------------------------------------------------------------------
def _c_value(v: Variable, value: Any) -> str:
    if v.type == "Float64":
        return repr(float(value))
    if v.type == "Boolean":
        return "1" if value else "0"
    return str(int(value))


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def model_vars_h(spec: ModelSpec) -> str:
    """The generated header: ModelData, value references and the variable table's declaration."""
    fields = "\n".join(f"    {_TYPES[v.type][0]} {v.name}; /* {v.causality}{' [' + v.unit + ']' if v.unit else ''} */"
                       for v in spec.variables[1:])
    vrs = "\n".join(f"#define VR_{v.name.upper()} {v.vr}" for v in spec.variables)
    return f"""/* Generated by cosim.fmubuild from model.toml: do not edit. */
#ifndef MODEL_VARS_H
#define MODEL_VARS_H

#define MODEL_IDENTIFIER {_c_string(spec.name)}
#define INSTANTIATION_TOKEN {_c_string(spec.token)}
#define N_EVENT_INDICATORS {spec.event_indicators}
#define N_MODEL_VARS {len(spec.variables)}

{vrs}

typedef struct {{
{fields}
}} ModelData;

extern const VarDef MODEL_VARS[N_MODEL_VARS];
void model_vars_defaults(ModelData *v);

#endif
"""


def model_vars_c(spec: ModelSpec) -> str:
    """The generated variable table and start values."""
    rows = []
    for v in spec.variables:
        offset = "(size_t)-1" if v.causality == "independent" else f"offsetof(ModelData, {v.name})"
        causality = "CA_INDEPENDENT" if v.causality == "independent" else _CAUSALITIES[v.causality]
        rows.append(
            f"    {{{v.vr}, {_c_string(v.name)}, {_c_string(v.unit)}, {_TYPES[v.type][1]}, {causality}, "
            f"{int(v.tunable)}, {int(v.min is not None)}, {int(v.max is not None)}, "
            f"{float(v.min or 0.0)!r}, {float(v.max or 0.0)!r}, {int(v.positive)}, {offset}}},")
    starts = "\n".join(f"    v->{v.name} = {_c_value(v, v.start if v.start is not None else 0)};"
                       for v in spec.variables[1:])
    return f"""/* Generated by cosim.fmubuild from model.toml: do not edit. */
#include "cosim_fmu.h"

const VarDef MODEL_VARS[N_MODEL_VARS] = {{
{chr(10).join(rows)}
}};

void model_vars_defaults(ModelData *v) {{
{starts}
}}
"""


# -- XML -----------------------------------------------------------------------------------------
def _xml_value(v: Variable, value: Any) -> str:
    if v.type == "Boolean":
        return "true" if value else "false"
    if v.type == "Int32":
        return str(int(value))
    return repr(float(value))


def _units_xml(spec: ModelSpec) -> str:
    used = sorted({v.unit for v in spec.variables if v.unit})
    lines = ["  <UnitDefinitions>"]
    for name in used:
        exponents, factor = UNITS[name]
        attrs = " ".join(f'{k}="{e}"' for k, e in exponents.items())
        if factor != 1.0:
            attrs += f' factor="{factor!r}"'
        lines.append(f'    <Unit name={quoteattr(name)}>\n      <BaseUnit {attrs}/>\n    </Unit>')
    lines.append("  </UnitDefinitions>")
    return "\n".join(lines) if used else ""


def _common_attrs(v: Variable) -> str:
    attrs = f"name={quoteattr(v.name)} valueReference=\"{v.vr}\""
    if v.description:
        attrs += f" description={quoteattr(v.description)}"
    attrs += f' causality="{v.causality}" variability="{v.variability}"'
    if v.causality == "parameter":
        attrs += ' initial="exact"'
    elif v.causality in ("output", "calculatedParameter", "local"):
        attrs += ' initial="calculated"'
    return attrs


def _type_attrs(v: Variable) -> str:
    attrs = ""
    if v.start is not None and v.causality in ("parameter", "input"):
        attrs += f' start="{_xml_value(v, v.start)}"'
    if v.unit:
        attrs += f" unit={quoteattr(v.unit)}"
    if v.type != "Boolean":
        if v.min is not None:
            attrs += f' min="{_xml_value(v, v.min)}"'
        if v.max is not None:
            attrs += f' max="{_xml_value(v, v.max)}"'
    return attrs


def _categories() -> str:
    return "  <LogCategories>\n" + "\n".join(f'    <Category name="{c}"/>' for c in LOG_CATEGORIES) + \
        "\n  </LogCategories>"


def model_description_fmi2(spec: ModelSpec) -> str:
    """FMI 2.0 ``modelDescription.xml`` (co-simulation, sources listed for rebuilding)."""
    variables = []
    for v in spec.variables:
        variables.append(f"    <ScalarVariable {_common_attrs(v)}>\n"
                         f"      <{_TYPES[v.type][2]}{_type_attrs(v)}/>\n    </ScalarVariable>")
    index = {v.name: i for i, v in enumerate(spec.variables, start=1)}
    outputs = "\n".join(f'      <Unknown index="{index[v.name]}"/>' for v in spec.outputs)
    initial_unknowns = "\n".join(f'      <Unknown index="{index[v.name]}"/>' for v in spec.variables
                                 if v.causality in ("output", "calculatedParameter"))
    files = "\n".join(f'      <File name="{name}"/>' for name in sources_for(spec, 2))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="{spec.name}" guid="{spec.token}"
  description={quoteattr(spec.description)} generationTool="cosim.fmubuild" version="{spec.version}"
  variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{spec.name}" canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUstate="true" canSerializeFMUstate="true" canNotUseMemoryManagementFunctions="true">
    <SourceFiles>
{files}
    </SourceFiles>
  </CoSimulation>
{_units_xml(spec)}
{_categories()}
  <DefaultExperiment startTime="0" stopTime="{spec.stop_time!r}" stepSize="{spec.default_step!r}"/>
  <ModelVariables>
{chr(10).join(variables)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{outputs}
    </Outputs>
    <InitialUnknowns>
{initial_unknowns}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def model_description_fmi3(spec: ModelSpec) -> str:
    """FMI 3.0 ``modelDescription.xml`` (co-simulation; early return and event mode if it has events)."""
    variables = []
    for v in spec.variables:
        variables.append(f"    <{v.type} {_common_attrs(v)}{_type_attrs(v)}/>")
    outputs = "\n".join(f'    <Output valueReference="{v.vr}"/>' for v in spec.outputs)
    initial_unknowns = "\n".join(f'    <InitialUnknown valueReference="{v.vr}"/>' for v in spec.variables
                                 if v.causality in ("output", "calculatedParameter"))
    events = "true" if spec.has_events else "false"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="{spec.name}" instantiationToken="{spec.token}"
  description={quoteattr(spec.description)} generationTool="cosim.fmubuild" version="{spec.version}"
  variableNamingConvention="flat">
  <CoSimulation modelIdentifier="{spec.name}" canHandleVariableCommunicationStepSize="true"
    canGetAndSetFMUState="true" canSerializeFMUState="true" hasEventMode="{events}"
    mightReturnEarlyFromDoStep="{events}" canReturnEarlyAfterIntermediateUpdate="false"
    providesIntermediateUpdate="false"/>
{_units_xml(spec)}
{_categories()}
  <DefaultExperiment startTime="0" stopTime="{spec.stop_time!r}" stepSize="{spec.default_step!r}"/>
  <ModelVariables>
{chr(10).join(variables)}
  </ModelVariables>
  <ModelStructure>
{outputs}
{initial_unknowns}
  </ModelStructure>
</fmiModelDescription>
"""


def build_description_fmi3(spec: ModelSpec) -> str:
    """FMI 3.0 ``sources/buildDescription.xml``."""
    files = "\n".join(f'      <SourceFile name="{name}"/>' for name in sources_for(spec, 3))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiBuildDescription fmiVersion="3.0">
  <BuildConfiguration modelIdentifier="{spec.name}" description="Plain C99; the FMI 3.0 headers come from the importer">
    <SourceFileSet language="C99">
{files}
    </SourceFileSet>
    <Library name="m" description="C math library"/>
  </BuildConfiguration>
</fmiBuildDescription>
"""


#: Files of ``fmu_src/common/`` that every FMU holds: the model interface and the FMI call-state table.
COMMON_SOURCES = ("cosim_fmu.h", "cosim_fmu.c", "fmi_calls.h", "fmi_calls.c")


def sources_for(spec: ModelSpec, fmi_version: int) -> list[str]:
    """The C files compiled for one FMI version (headers are in the same folder)."""
    shared = [name for name in spec.shared if name.endswith(".c")]
    common = [name for name in COMMON_SOURCES if name.endswith(".c")]
    return [*spec.sources, *shared, "model_vars.c", *common, f"fmi{fmi_version}_cs.c"]
