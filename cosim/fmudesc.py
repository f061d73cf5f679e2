"""Plant variable tables (``fmu_src/<Model>/model.toml``) and what is generated from them.

One table per plant gives its variables once; from it come the C declarations the model and the
FMI wrappers share (``model_vars.h`` and ``model_vars.c``), the FMI 2.0 and FMI 3.0
``modelDescription.xml`` and the FMI 3.0 ``buildDescription.xml``. Value references follow the
table's order (``time`` is 0), so the C code and both XML files cannot disagree.

Every FMI 3.0 variable type can be declared (``Float32``, ``Float64``, ``Int8`` .. ``UInt64``,
``Boolean``, ``String``, ``Binary``, ``Enumeration`` with ``declared_type`` naming one of the
``[enumerations]`` table), numeric and Boolean variables also as arrays (``dimensions = [2, 3]``).
The FMI 2.0 model description holds the subset FMI 2.0 has: scalar Float64 (Real), Int32 (Integer),
Boolean, String and Enumeration variables; the others exist in the FMI 3.0 build only.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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

#: Each type of model.toml: its C storage, its VarType constant, its FMI 2.0 element (None: FMI 3.0 only).
_TYPES: dict[str, tuple[str, str, str | None]] = {
    "Float64": ("double", "VT_FLOAT64", "Real"), "Float32": ("float", "VT_FLOAT32", None),
    "Int8": ("int8_t", "VT_INT8", None), "UInt8": ("uint8_t", "VT_UINT8", None),
    "Int16": ("int16_t", "VT_INT16", None), "UInt16": ("uint16_t", "VT_UINT16", None),
    "Int32": ("int32_t", "VT_INT32", "Integer"), "UInt32": ("uint32_t", "VT_UINT32", None),
    "Int64": ("int64_t", "VT_INT64", None), "UInt64": ("uint64_t", "VT_UINT64", None),
    "Boolean": ("int", "VT_BOOL", "Boolean"), "String": ("char", "VT_STRING", "String"),
    "Binary": ("CfBinary", "VT_BINARY", None), "Enumeration": ("int64_t", "VT_ENUM", "Enumeration"),
}
#: The value range of each integer type (an Enumeration is stored as Int64).
INTEGER_RANGES: dict[str, tuple[int, int]] = {
    **{f"Int{bits}": (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) for bits in (8, 16, 32, 64)},
    **{f"UInt{bits}": (0, 2**bits - 1) for bits in (8, 16, 32, 64)},
}
_FLOATS = ("Float32", "Float64")
_CAUSALITIES = {"parameter": "CA_PARAMETER", "calculatedParameter": "CA_CALCULATED_PARAMETER",
                "input": "CA_INPUT", "output": "CA_OUTPUT", "local": "CA_LOCAL"}
LOG_CATEGORIES = ("logStatusWarning", "logStatusError", "logEvents")


def quoteattr(text: str) -> str:
    """``xml.sax.saxutils.quoteattr``, imported when a description is written (it pulls in urllib, http, ssl)."""
    from xml.sax.saxutils import quoteattr as quote

    return quote(text)


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
    dimensions: tuple[int, ...] = ()
    declared_type: str = ""
    items: tuple[str, ...] = ()
    discrete: bool = False

    @property
    def variability(self) -> str:
        if self.causality == "parameter":
            return "tunable" if self.tunable else "fixed"
        if self.causality == "calculatedParameter":
            return "fixed"
        return "continuous" if self.type in _FLOATS and not self.discrete else "discrete"

    @property
    def size(self) -> int:
        """Number of elements: 1 for a scalar, the product of the dimensions for an array."""
        return math.prod(self.dimensions)

    @property
    def in_fmi2(self) -> bool:
        """True if FMI 2.0 has this variable (a scalar of a type FMI 2.0 knows)."""
        return _TYPES[self.type][2] is not None and not self.dimensions

    def starts(self) -> list[Any]:
        """The start value of each element (a scalar start is used for every element)."""
        start = self.start if self.start is not None else _ZERO[self.type]
        if isinstance(start, list):
            return list(start)
        return [start] * self.size


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
    enumerations: dict[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def outputs(self) -> list[Variable]:
        return [v for v in self.variables if v.causality == "output"]

    def for_fmi(self, fmi_version: int) -> list[Variable]:
        """The variables of one FMI version's model description (FMI 2.0: the subset it has)."""
        return [v for v in self.variables if fmi_version == 3 or v.in_fmi2]

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
    enumerations = {name: tuple(items) for name, items in data.get("enumerations", {}).items()}
    for name, items in enumerations.items():
        if not items or not all(isinstance(item, str) and item for item in items):
            raise ConfigurationError(f"{path}: enumeration {name!r} needs a list of item names")
    variables = [Variable("time", 0, "Float64", "independent", "Simulation time", "s")]
    for i, raw in enumerate(data.get("variable", []), start=1):
        variables.append(_variable(path, i, raw, enumerations))
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
        variables=tuple(variables), enumerations=enumerations,
    )


def _variable(path: Path, vr: int, raw: dict[str, Any], enumerations: dict[str, tuple[str, ...]]) -> Variable:
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
    if unit and type_ not in _FLOATS:
        raise ConfigurationError(f"{where}: only Float32 and Float64 variables have a unit in FMI")
    if causality in ("parameter", "input") and "start" not in raw:
        raise ConfigurationError(f"{where}: a {causality} needs a start value")
    known = {"name", "type", "causality", "description", "unit", "start", "min", "max", "positive", "tunable",
             "dimensions", "declared_type", "variability"}
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ConfigurationError(f"{where}: unknown keys {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    dimensions = tuple(raw.get("dimensions", ()))
    if dimensions and (type_ in ("String", "Binary") or not all(isinstance(d, int) and d > 0 for d in dimensions)):
        raise ConfigurationError(f"{where}: dimensions {list(dimensions)} are not allowed (allowed: positive "
                                 "integers, for numeric and Boolean variables)")
    declared_type = raw.get("declared_type", "")
    variability = raw.get("variability", "")
    if variability and (variability != "discrete" or type_ not in _FLOATS or causality not in ("input", "output")):
        raise ConfigurationError(f"{where}: variability {variability!r} is not allowed (allowed: \"discrete\", for a "
                                 "Float32 or Float64 input or output; the others follow from type and causality)")
    items: tuple[str, ...] = ()
    if type_ == "Enumeration":
        if declared_type not in enumerations:
            raise ConfigurationError(f"{where}: declared_type {declared_type!r} is not one of the [enumerations] "
                                     f"({', '.join(enumerations) or 'none'})")
        items = enumerations[declared_type]
    variable = Variable(name=raw["name"], vr=vr, type=type_, causality=causality,
                        description=raw.get("description", ""), unit=unit, start=raw.get("start"),
                        min=raw.get("min"), max=raw.get("max"), positive=bool(raw.get("positive", False)),
                        tunable=bool(raw.get("tunable", False)), dimensions=dimensions,
                        declared_type=declared_type, items=items, discrete=variability == "discrete")
    _check_starts(where, variable)
    return variable


_ZERO: dict[str, Any] = {**dict.fromkeys(_TYPES, 0), "Float32": 0.0, "Float64": 0.0, "Boolean": False,
                         "String": "", "Binary": "", "Enumeration": 1}


def _check_starts(where: str, v: Variable) -> None:
    """Refuse start values of the wrong count or type, and integers outside their type's range."""
    if isinstance(v.start, list) and len(v.start) != v.size:
        raise ConfigurationError(f"{where}: {len(v.start)} start values for {v.size} elements")
    limits = INTEGER_RANGES.get(v.type) or ((1, len(v.items)) if v.type == "Enumeration" else None)
    for value in [*v.starts(), *(x for x in (v.min, v.max) if x is not None)]:
        if v.type == "String":
            ok = isinstance(value, str)
        elif v.type == "Binary":
            ok = isinstance(value, str) and _is_hex(value)
        elif v.type == "Boolean":
            ok = isinstance(value, bool)
        elif v.type in _FLOATS:
            ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
        else:
            ok = isinstance(value, int) and not isinstance(value, bool) and limits is not None and \
                limits[0] <= value <= limits[1]
        if not ok:
            allowed = f"{limits[0]}..{limits[1]}" if limits else f"a {v.type} value"
            raise ConfigurationError.out_of_range("start, min or max", value, allowed, where=where)


def _is_hex(text: str) -> bool:
    try:
        bytes.fromhex(text)
    except ValueError:
        return False
    return True


# -- C -------------------------------------------------------------------------------------------
def _c_value(v: Variable, value: Any) -> str:
    if v.type in _FLOATS:
        return repr(float(value)) + ("f" if v.type == "Float32" else "")
    if v.type == "Boolean":
        return "1" if value else "0"
    number = int(value)
    low, _ = INTEGER_RANGES.get(v.type, (0, 0))
    if v.type.startswith("Int") and number == low:
        return f"INT{v.type[3:]}_MIN"
    if v.type in ("Int64", "Enumeration"):
        return f"INT64_C({number})"
    if v.type == "UInt64":
        return f"UINT64_C({number})"
    return f"{number}u" if v.type.startswith("UInt") else str(number)


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _c_bytes(data: bytes) -> str:
    """A C string literal of any bytes: printable ASCII as it is, the rest as three-digit octal escapes
    (which never run into the next character)."""
    return '"' + "".join(chr(b) if 32 <= b < 127 and chr(b) not in '"\\?' else f"\\{b:03o}" for b in data) + '"'


def _c_field(v: Variable) -> str:
    if v.type == "String":
        return f"char {v.name}[CF_STRING_CAPACITY]"
    if v.dimensions:
        return f"{_TYPES[v.type][0]} {v.name}[{v.size}]"
    return f"{_TYPES[v.type][0]} {v.name}"


def model_vars_h(spec: ModelSpec) -> str:
    """The generated header: ModelData, value references and the variable table's declaration."""
    fields = "\n".join(f"    {_c_field(v)}; /* {v.causality}{' [' + v.unit + ']' if v.unit else ''} */"
                       for v in spec.variables[1:])
    vrs = "\n".join(f"#define VR_{v.name.upper()} {v.vr}" for v in spec.variables)
    sizes = "\n".join(f"#define N_{v.name.upper()} {v.size}" for v in spec.variables if v.dimensions)
    return f"""/* Generated by cosim.fmubuild from model.toml: do not edit. */
#ifndef MODEL_VARS_H
#define MODEL_VARS_H

#define MODEL_IDENTIFIER {_c_string(spec.name)}
#define INSTANTIATION_TOKEN {_c_string(spec.token)}
#define N_EVENT_INDICATORS {spec.event_indicators}
#define N_MODEL_VARS {len(spec.variables)}

{vrs}
{sizes}

typedef struct {{
{fields}
}} ModelData;

extern const VarDef MODEL_VARS[N_MODEL_VARS];
void model_vars_defaults(ModelData *v);

#endif
"""


def _c_limits(v: Variable) -> tuple[Any, Any]:
    if v.type == "Enumeration":
        return 1, len(v.items)
    return v.min, v.max


def _c_defaults(v: Variable) -> list[str]:
    if v.type == "String":
        data = str(v.starts()[0]).encode()
        return [f"    memcpy(v->{v.name}, {_c_bytes(data)}, {len(data) + 1});"]
    if v.type == "Binary":
        data = bytes.fromhex(str(v.starts()[0]))
        return [f"    v->{v.name}.size = {len(data)};"] + (
            [f"    memcpy(v->{v.name}.data, {_c_bytes(data)}, {len(data)});"] if data else [])
    if not v.dimensions:
        return [f"    v->{v.name} = {_c_value(v, v.starts()[0])};"]
    return [f"    v->{v.name}[{i}] = {_c_value(v, value)};" for i, value in enumerate(v.starts())]


def model_vars_c(spec: ModelSpec) -> str:
    """The generated variable table and start values."""
    rows = []
    for v in spec.variables:
        offset = "(size_t)-1" if v.causality == "independent" else f"offsetof(ModelData, {v.name})"
        causality = "CA_INDEPENDENT" if v.causality == "independent" else _CAUSALITIES[v.causality]
        low, high = _c_limits(v)
        rows.append(
            f"    {{{v.vr}, {_c_string(v.name)}, {_c_string(v.unit)}, {_TYPES[v.type][1]}, {causality}, "
            f"{int(v.tunable)}, {int(low is not None)}, {int(high is not None)}, "
            f"{float(low or 0.0)!r}, {float(high or 0.0)!r}, {int(v.positive)}, {offset}, {v.size}}},")
    starts = "\n".join(line for v in spec.variables[1:] for line in _c_defaults(v))
    return f"""/* Generated by cosim.fmubuild from model.toml: do not edit. */
#include <string.h>

#include "cosim_fmu.h"

const VarDef MODEL_VARS[N_MODEL_VARS] = {{
{chr(10).join(rows)}
}};

void model_vars_defaults(ModelData *v) {{
{starts}
}}
"""


# -- XML -----------------------------------------------------------------------------------------
#: Bytes a Binary variable holds (CF_BINARY_CAPACITY of fmu_src/common/cosim_fmu.h), its FMI 3.0 maxSize.
BINARY_CAPACITY = 256


def _xml_value(v: Variable, value: Any) -> str:
    if v.type == "Boolean":
        return "true" if value else "false"
    if v.type in _FLOATS:
        return repr(float(value))
    if v.type == "String":
        return str(value)
    if v.type == "Binary":
        return str(value).lower()
    return str(int(value))


def _xml_start(v: Variable) -> str | None:
    """The start value as the model description writes it (array elements space-separated)."""
    if v.start is None or v.causality not in ("parameter", "input"):
        return None
    return " ".join(_xml_value(v, value) for value in v.starts())


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


def _types_xml(spec: ModelSpec, fmi_version: int) -> str:
    """``<TypeDefinitions>`` of the enumerations the version's variables use, on new lines ("" if none)."""
    used = sorted({v.declared_type for v in spec.for_fmi(fmi_version) if v.type == "Enumeration"})
    if not used:
        return ""
    lines = ["", "  <TypeDefinitions>"]
    for name in used:
        items = [f'<Item name={quoteattr(item)} value="{i}"/>' for i, item in enumerate(spec.enumerations[name], 1)]
        if fmi_version == 2:
            lines += [f"    <SimpleType name={quoteattr(name)}>", "      <Enumeration>",
                      *(f"        {item}" for item in items), "      </Enumeration>", "    </SimpleType>"]
        else:
            lines += [f"    <EnumerationType name={quoteattr(name)}>", *(f"      {item}" for item in items),
                      "    </EnumerationType>"]
    lines.append("  </TypeDefinitions>")
    return "\n".join(lines)


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


def _type_attrs(v: Variable, fmi_version: int) -> str:
    attrs = f" declaredType={quoteattr(v.declared_type)}" if v.declared_type else ""
    start = _xml_start(v)
    if start is not None and (fmi_version == 2 or v.type not in ("String", "Binary")):
        attrs += f" start={quoteattr(start)}"
    if v.unit:
        attrs += f" unit={quoteattr(v.unit)}"
    if v.type not in ("Boolean", "String", "Binary", "Enumeration"):
        if v.min is not None:
            attrs += f' min="{_xml_value(v, v.min)}"'
        if v.max is not None:
            attrs += f' max="{_xml_value(v, v.max)}"'
    if v.type == "Binary":
        attrs += f' maxSize="{BINARY_CAPACITY}"'
    return attrs


def _fmi3_variable(v: Variable) -> str:
    attrs = f"{_common_attrs(v)}{_type_attrs(v, 3)}"
    start = _xml_start(v)
    children = [f"<Start value={quoteattr(start)}/>"] if start is not None and v.type in ("String", "Binary") else []
    children += [f'<Dimension start="{d}"/>' for d in v.dimensions]
    if not children:
        return f"    <{v.type} {attrs}/>"
    return f"    <{v.type} {attrs}>\n" + "".join(f"      {c}\n" for c in children) + f"    </{v.type}>"


def _categories() -> str:
    return "  <LogCategories>\n" + "\n".join(f'    <Category name="{c}"/>' for c in LOG_CATEGORIES) + \
        "\n  </LogCategories>"


def model_description_fmi2(spec: ModelSpec) -> str:
    """FMI 2.0 ``modelDescription.xml`` (co-simulation, sources listed for rebuilding)."""
    subset = spec.for_fmi(2)
    variables = []
    for v in subset:
        variables.append(f"    <ScalarVariable {_common_attrs(v)}>\n"
                         f"      <{_TYPES[v.type][2]}{_type_attrs(v, 2)}/>\n    </ScalarVariable>")
    index = {v.name: i for i, v in enumerate(subset, start=1)}
    outputs = "\n".join(f'      <Unknown index="{index[v.name]}"/>' for v in subset if v.causality == "output")
    initial_unknowns = "\n".join(f'      <Unknown index="{index[v.name]}"/>' for v in subset
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
{_units_xml(spec)}{_types_xml(spec, 2)}
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
    variables = [_fmi3_variable(v) for v in spec.variables]
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
{_units_xml(spec)}{_types_xml(spec, 3)}
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
