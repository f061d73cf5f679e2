"""FMI variables as the FMU adapter sees them: every type, arrays, declared ranges, checked values.

:data:`TYPES` describes each FMI 2.0 and 3.0 co-simulation variable type once (its C element, the
Python and numpy types of its values, the range of an integer type, the name of its FMI getter and
setter); :class:`Variable` is one variable of a model description with what the adapter needs to
check a value before it reaches the FMU (:meth:`Variable.check`) and to turn what the FMU returns
into Python (:meth:`Variable.value_of`). No fmpy here: :mod:`cosim.fmu` makes the calls.

Values in Python:

==========================  ===========================  ======================================
FMI type                    scalar                       array (``dimensions``)
==========================  ===========================  ======================================
Float32, Float64 (Real)     ``float``                    ``numpy.ndarray`` float32 / float64
Int8 .. UInt64 (Integer)    ``int``                      ``numpy.ndarray`` int8 .. uint64
Enumeration                 ``int`` (set: also the name) ``numpy.ndarray`` int64
Boolean                     ``bool``                     ``numpy.ndarray`` bool
String                      ``str``                      ``numpy.ndarray`` of ``str`` (object)
Binary (FMI 3.0)            ``bytes``                    ``numpy.ndarray`` of ``bytes`` (object)
==========================  ===========================  ======================================

Integers are checked against their type's range and the variable's declared ``min``/``max`` (an
Enumeration against its items), so a value never wraps at the FMU boundary. Float values are
checked for being numbers (and Float32 for fitting); their declared ranges are the FMU's to check,
with its own message.
"""

from __future__ import annotations

import ctypes
import math
import numbers
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from cosim.errors import ConfigurationError

#: A scalar value of an FMU variable.
Scalar = float | int | bool | str | bytes
#: Any value of an FMU variable: a scalar, or an array for variables with dimensions.
Value = Scalar | npt.NDArray[Any]


@dataclass(frozen=True)
class FmiType:
    """One FMI variable type as the adapter handles it.

    Parameters
    ----------
    name : str
        The FMI 3.0 name (``Float64``, ``Int8``, ...), also for the FMI 2.0 types it stands for.
    ctype : ctypes type
        One element of the getter's and setter's values array.
    python : type
        Python type of a scalar value.
    dtype : str
        numpy dtype of an array value (``object`` for strings and binaries).
    limits : tuple of int, optional
        Range of an integer type.
    function : str
        Suffix of the FMI functions: ``fmi3Get<function>`` / ``fmi2Get<function>``.
    """

    name: str
    ctype: Any
    python: type
    dtype: str
    limits: tuple[int, int] | None
    function: str

    @property
    def is_float(self) -> bool:
        return self.python is float

    @property
    def is_integer(self) -> bool:
        return self.limits is not None

    @property
    def is_numeric(self) -> bool:
        """Numbers and Booleans: what a trace records and a signal carries."""
        return self.python in (float, int, bool)


def _integer(name: str, ctype: Any, bits: int, signed: bool, function: str | None = None) -> FmiType:
    limits = (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2**bits - 1)
    return FmiType(name, ctype, int, name.lower(), limits, function or name)


_FMI3: dict[str, FmiType] = {
    "Float64": FmiType("Float64", ctypes.c_double, float, "float64", None, "Float64"),
    "Float32": FmiType("Float32", ctypes.c_float, float, "float32", None, "Float32"),
    "Int8": _integer("Int8", ctypes.c_int8, 8, True),
    "UInt8": _integer("UInt8", ctypes.c_uint8, 8, False),
    "Int16": _integer("Int16", ctypes.c_int16, 16, True),
    "UInt16": _integer("UInt16", ctypes.c_uint16, 16, False),
    "Int32": _integer("Int32", ctypes.c_int32, 32, True),
    "UInt32": _integer("UInt32", ctypes.c_uint32, 32, False),
    "Int64": _integer("Int64", ctypes.c_int64, 64, True),
    "UInt64": _integer("UInt64", ctypes.c_uint64, 64, False),
    "Enumeration": _integer("Int64", ctypes.c_int64, 64, True),  # FMI 3.0 reads enumerations as Int64
    "Boolean": FmiType("Boolean", ctypes.c_bool, bool, "bool", None, "Boolean"),
    "String": FmiType("String", ctypes.c_char_p, str, "object", None, "String"),
    "Binary": FmiType("Binary", ctypes.c_void_p, bytes, "object", None, "Binary"),
}
_FMI2: dict[str, FmiType] = {
    "Real": FmiType("Float64", ctypes.c_double, float, "float64", None, "Real"),
    "Integer": _integer("Int32", ctypes.c_int, 32, True, "Integer"),
    "Enumeration": _integer("Int32", ctypes.c_int, 32, True, "Integer"),
    "Boolean": FmiType("Boolean", ctypes.c_int, bool, "bool", None, "Boolean"),
    "String": FmiType("String", ctypes.c_char_p, str, "object", None, "String"),
}
#: The variable types of each FMI version (by the name the model description uses).
TYPES: dict[int, dict[str, FmiType]] = {2: _FMI2, 3: _FMI3}


def fmi_type(type_name: str, fmi_version: int) -> FmiType | None:
    """The type of a variable declared as ``type_name``; None for types the adapter does not reach (Clock)."""
    return TYPES[fmi_version].get(type_name)


def _number(text: str | None, kind: FmiType) -> float | int | None:
    if text is None or text == "":
        return None
    try:
        return int(text) if kind.is_integer else float(text)
    except ValueError:
        return None


@dataclass
class Variable:
    """A variable of an FMU, resolved once: what it is, what it accepts, how to get and set it.

    ``get`` and ``set`` are filled in by :class:`cosim.fmu.Fmu` (prepared FMI calls). ``type`` is
    the name the model description uses (``Real`` in FMI 2.0, ``Float64`` in FMI 3.0); ``kind``
    says how it is accessed.
    """

    name: str
    vr: int
    type: str
    kind: FmiType
    causality: str
    variability: str
    unit: str = ""
    shape: tuple[int, ...] = ()
    min: float | int | None = None
    max: float | int | None = None
    start: str | None = None
    description: str = ""
    items: dict[str, int] = field(default_factory=dict)
    get: Callable[[], Value] = field(default=lambda: 0, repr=False)
    set: Callable[[Any], None] = field(default=lambda value: None, repr=False)

    @classmethod
    def from_model(cls, sv: Any, fmi_version: int) -> Variable | None:
        """From an fmpy model variable; None if its type is not one the adapter reaches."""
        kind = fmi_type(sv.type, fmi_version)
        if kind is None:
            return None
        declared = sv.declaredType
        unit = sv.unit or (declared.unit if declared is not None else "") or ""
        low = _number(sv.min if sv.min is not None else getattr(declared, "min", None), kind)
        high = _number(sv.max if sv.max is not None else getattr(declared, "max", None), kind)
        items = {item.name: int(item.value) for item in getattr(declared, "items", None) or []}
        if sv.type == "Enumeration" and items:
            low = min(items.values()) if low is None else low
            high = max(items.values()) if high is None else high
        return cls(sv.name, sv.valueReference, sv.type, kind, sv.causality, sv.variability or "", unit,
                   tuple(sv.shape or ()), low, high, None if sv.start is None else str(sv.start),
                   sv.description or "", items)

    @property
    def size(self) -> int:
        """Number of elements: 1 for a scalar."""
        return math.prod(self.shape)

    @property
    def dimensions(self) -> str:
        """``"[2, 3]"`` for an array, ``""`` for a scalar."""
        return f"[{', '.join(map(str, self.shape))}]" if self.shape else ""

    def allowed(self) -> str:
        """What a value may be, as the messages say it."""
        if self.kind.is_integer:
            low, high = self.limits()
            text = f"{low}..{high}"
            if self.items:
                text += " (" + ", ".join(f"{v} {k}" for k, v in self.items.items()) + ")"
            return text
        if self.kind.is_float:
            parts = [f">= {self.min!r}" if self.min is not None else "", f"<= {self.max!r}" if self.max is not None
                     else ""]
            return " and ".join(p for p in parts if p) or "any finite number"
        return {"Boolean": "true or false", "String": "text (a str without NUL)", "Binary": "bytes"}[self.kind.name]

    def limits(self) -> tuple[int, int]:
        """The integer range: the type's, narrowed by the declared ``min``/``max``."""
        assert self.kind.limits is not None
        low, high = self.kind.limits
        if isinstance(self.min, int):
            low = max(low, self.min)
        if isinstance(self.max, int):
            high = min(high, self.max)
        return low, high

    # -- checking values going in ---------------------------------------------------------------
    def check(self, value: Any, *, where: str = "") -> Any:
        """``value`` as the FMU takes it (a flat list for an array), or ConfigurationError naming it and its range."""
        if not self.shape:
            return self._check_scalar(value, where)
        array = np.asarray(value, dtype=object if self.kind.dtype == "object" else None)
        if array.size != self.size or (array.ndim > 1 and array.shape != self.shape):
            raise ConfigurationError.out_of_range(f"shape of {self.name}", array.shape,
                                                  f"{self.shape} or {self.size} elements", where=where)
        return [self._check_scalar(x.item() if isinstance(x, np.generic) else x, where) for x in array.ravel()]

    def _check_scalar(self, value: Any, where: str) -> Any:
        kind = self.kind
        if isinstance(value, np.generic):
            value = value.item()
        if kind.is_integer:
            return self._check_integer(value, where)
        if kind.is_float:
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ConfigurationError.out_of_range(self.name, value, f"a number ({self.type})", where=where)
            number = float(value)
            if kind.name == "Float32" and math.isfinite(number) and abs(number) > float(np.finfo(np.float32).max):
                raise ConfigurationError.out_of_range(self.name, value, "a Float32 (|x| <= 3.4028235e+38)",
                                                      where=where)
            return number
        if kind.python is bool:
            if isinstance(value, bool) or (isinstance(value, int) and value in (0, 1)):
                return bool(value)
            raise ConfigurationError.out_of_range(self.name, value, "true or false", where=where)
        if kind.python is str:
            if not isinstance(value, str) or "\0" in value:
                raise ConfigurationError.out_of_range(self.name, value, "text (a str without NUL)", where=where)
            return value
        if not isinstance(value, bytes | bytearray | memoryview):
            raise ConfigurationError.out_of_range(self.name, value, "bytes", where=where)
        return bytes(value)

    def _check_integer(self, value: Any, where: str) -> int:
        if isinstance(value, str) and value in self.items:
            return self.items[value]
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if not isinstance(value, int):
            raise ConfigurationError.out_of_range(self.name, value, self.allowed(), where=where)
        low, high = self.limits()
        if not low <= value <= high or (self.items and value not in self.items.values()):
            raise ConfigurationError.out_of_range(self.name, value, self.allowed(), where=where)
        return int(value)

    def parse(self, text: str, *, where: str = "") -> Any:
        """A value from text (``--set NAME=VALUE``, an input table's cell), checked as :meth:`check` does.

        Numbers as Python writes them (integers also ``0x..``; reals finite: not ``nan`` or ``inf``),
        ``true``/``false`` (``1``/``0``, ``on``/``off``, ``yes``/``no``), an Enumeration's item name,
        a Binary in hex, a String as it is; an array's elements separated by commas or spaces
        (brackets allowed).
        """
        if self.shape:
            parts = [part for part in re.split(r"[\s,;]+", text.strip().strip("[]")) if part]
            return self.check([self._parse_one(part, where) for part in parts], where=where)
        return self.check(self._parse_one(text, where), where=where)

    def _parse_one(self, text: str, where: str) -> Any:
        kind = self.kind
        try:
            if kind.is_integer:
                return self.items[text] if text in self.items else int(text, 0)
            if kind.is_float:
                number = float(text)
                if not math.isfinite(number):  # no FMU input or parameter is given nan or inf from text
                    allowed = self.allowed()
                    raise ConfigurationError.out_of_range(
                        self.name, text, allowed if allowed.startswith("any") else f"a finite number {allowed}",
                        where=where)
                return number
            if kind.python is bool:
                return {"1": True, "true": True, "on": True, "yes": True,
                        "0": False, "false": False, "off": False, "no": False}[text.strip().lower()]
            if kind.python is bytes:
                return bytes.fromhex(text)
        except (ValueError, KeyError):
            raise ConfigurationError.out_of_range(self.name, text, self.allowed(), where=where) from None
        return text

    # -- values coming out ------------------------------------------------------------------------
    def value_of(self, elements: list[Any]) -> Value:
        """Python value of what the FMU returned (one element per element of the variable)."""
        kind = self.kind
        if kind.python is str:
            elements = [b"" if e is None else e for e in elements]
            elements = [e.decode("utf-8", errors="replace") for e in elements]
        elif kind.python is bool:
            elements = [bool(e) for e in elements]
        if not self.shape:
            return elements[0]
        if kind.dtype == "object":
            array = np.empty(self.size, dtype=object)
            array[:] = elements
            return array.reshape(self.shape)
        return np.array(elements, dtype=kind.dtype).reshape(self.shape)



# -- prepared FMI calls -----------------------------------------------------------------------------
Status = Callable[..., int]


def accessors(var: Variable, get_fn: Status, set_fn: Status, *, component: Any, fmi3: bool,
              failed: Callable[[str, int], Exception]) -> tuple[Callable[[], Value], Callable[[Any], None]]:
    """The prepared getter and setter of one variable: ctypes arguments made once, the status checked.

    ``get_fn`` and ``set_fn`` are the FMI functions of its type (taking ctypes arguments, returning
    the status); ``failed(what, status)`` makes the error to raise for a status above Warning. The
    setter takes a value checked by :meth:`Variable.check` (a flat list for an array).
    """
    kind, n, name, array = var.kind, var.size, var.name, bool(var.shape)
    vrs = (ctypes.c_uint32 * 1)(var.vr)
    if kind.name == "Binary":
        return _binary_accessors(var, get_fn, set_fn, component, failed)
    buffer = (kind.ctype * n)()
    tail = (n,) if fmi3 else ()

    def call(fn: Status, what: str) -> None:
        status = fn(component, vrs, 1, buffer, *tail)
        if status > 1:
            raise failed(what, status)

    if kind.python is str or array:
        def get_elements() -> Value:
            call(get_fn, f"get {name}")
            return var.value_of(list(buffer))

        def put_elements(value: Any) -> None:
            elements = value if array else [value]
            buffer[:] = [e.encode("utf-8") for e in elements] if kind.python is str else elements
            call(set_fn, f"set {name}")

        return get_elements, put_elements

    convert = kind.python
    # a scalar's call with ctypes arguments made once (the hot path of reads and driven inputs)
    args = (ctypes.c_void_p(component), vrs, ctypes.c_size_t(1), buffer, *((ctypes.c_size_t(n),) if fmi3 else ()))

    def get_scalar() -> Value:
        status = get_fn(*args)
        if status > 1:
            raise failed(f"get {name}", status)
        return convert(buffer[0])

    def put_scalar(value: Any) -> None:
        buffer[0] = value
        status = set_fn(*args)
        if status > 1:
            raise failed(f"set {name} = {value!r}", status)

    return get_scalar, put_scalar


def _binary_accessors(var: Variable, get_fn: Status, set_fn: Status, component: Any,
                      failed: Callable[[str, int], Exception]) -> tuple[Callable[[], Value], Callable[[Any], None]]:
    n = var.size
    vrs = (ctypes.c_uint32 * 1)(var.vr)
    byte_p = ctypes.POINTER(ctypes.c_uint8)
    sizes, pointers = (ctypes.c_size_t * n)(), (byte_p * n)()

    def get() -> Value:
        status = get_fn(component, vrs, 1, sizes, pointers, n)
        if status > 1:
            raise failed(f"get {var.name}", status)
        return var.value_of([ctypes.string_at(ctypes.cast(pointers[i], ctypes.c_void_p).value or 0, sizes[i])
                             if sizes[i] else b"" for i in range(n)])

    def put(value: Any) -> None:
        blobs = [bytes(b) for b in (value if var.shape else [value])]
        keep = [(ctypes.c_uint8 * max(len(b), 1)).from_buffer_copy(b.ljust(1, b"\0")) for b in blobs]
        for i, (blob, data) in enumerate(zip(blobs, keep, strict=True)):
            sizes[i] = len(blob)
            pointers[i] = ctypes.cast(data, byte_p)
        status = set_fn(component, vrs, 1, sizes, pointers, n)
        if status > 1:
            raise failed(f"set {var.name}", status)

    return get, put


# -- trace names ------------------------------------------------------------------------------------
_NOT_IN_A_PART = re.compile(r"[^a-z0-9_]")


def _fold(variable: str) -> str:
    """``Float64_out`` -> ``float64_out``, ``der(x)`` -> ``der_x_``, ``a.B[1]`` -> ``a.b_1_``."""
    return ".".join(_NOT_IN_A_PART.sub("_", part.lower()) or "_" for part in variable.split("."))


def trace_names(variables: Sequence[str], prefix: str, *, order: Sequence[str] | None = None) -> dict[str, str]:
    """Trace signal names for FMU variables, one each: never the same name for two variables.

    The trace's names are lower case, dot-separated, each part ``[a-z0-9_]`` (:mod:`cosim.trace`);
    FMU variable names are not. A variable gets ``<prefix>.<name>`` with each dot-separated part of
    its name in lower case and every other character than ``[a-z0-9_]`` as ``_``
    (``Float64_continuous_output`` -> ``float64_continuous_output``, ``der(x)`` -> ``der_x_``).
    Where that gives several variables one name (names that differ only in case, ``x`` and ``X``,
    or in such characters, ``a(1)`` and ``a_1_``), the one whose name is already in the scheme keeps
    it and every other gets ``_v<n>``, ``n`` being its position (from 1) among the model
    description's variables (``order``; default: ``variables``), e.g. ``X`` -> ``x_v7``. The name
    of a variable depends only on the FMU, not on which variables are asked for or in which order.

    Examples
    --------
    >>> trace_names(["Speed", "speed", "der(x)"], "m")
    {'Speed': 'm.speed_v1', 'speed': 'm.speed', 'der(x)': 'm.der_x_'}
    """
    positions = {name: i for i, name in enumerate(order if order is not None else variables, start=1)}
    names = {v: f"{prefix}.{_fold(v)}" for v in variables}
    while True:
        taken: dict[str, list[str]] = {}
        for variable, name in names.items():
            taken.setdefault(name, []).append(variable)
        clashes = {name: group for name, group in taken.items() if len(group) > 1}
        if not clashes:
            return names
        for name, group in clashes.items():
            for variable in group:
                if name != f"{prefix}.{variable}":  # a changed name moves; an unchanged one keeps its name
                    names[variable] = f"{name}_v{positions[variable]}"
