"""The FMU adapter: the one module that imports fmpy.

:class:`Fmu` loads an FMI 2.0 or 3.0 co-simulation FMU, resolves variable names once, offers
typed get/set by name, and advances the FMU to an integer tick: the step size is computed from
integer time here, at the FMI boundary, and nowhere else. FMI errors become :class:`FmuError`
carrying the FMU's own log messages. On FMI 3.0, early return and event mode are used when the
FMU offers them, so :meth:`Fmu.advance_to` can stop exactly at an event inside a step.
"""

from __future__ import annotations

import ctypes
import difflib
import shutil
import tempfile
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from fmpy import extract, fmi2, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.fmi3 import FMU3Slave

from cosim import validate
from cosim.errors import ConfigurationError, FmuError
from cosim.timebase import TimeBase

Value = float | int | bool

_STATUS = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal", 5: "Pending"}


class _Variable:
    """A resolved variable: value reference plus typed accessors."""

    __slots__ = ("causality", "get", "name", "set", "type", "unit", "variability", "vr")

    def __init__(self, name: str, vr: int, type_: str, causality: str, variability: str, unit: str) -> None:
        self.name = name
        self.vr = vr
        self.type = type_
        self.causality = causality
        self.variability = variability
        self.unit = unit
        self.get: Callable[[], Value] = lambda: 0
        self.set: Callable[[Value], None] = lambda value: None


class Fmu:
    """One instance of a co-simulation FMU, instantiated and initialised at ``start``.

    Parameters
    ----------
    path : path
        The ``.fmu`` file.
    timebase : TimeBase, optional
        Resolution of the integer times given to :meth:`advance_to` (1 ns by default).
    instance_name : str
        Name used in log messages and errors.
    parameters : mapping, optional
        Start values of parameters and inputs, set before initialisation.
    start : int
        Start time [ticks].
    logging : bool
        Ask the FMU for debug logging (errors are always captured).

    Examples
    --------
    >>> with Fmu("models/fmi3/Laser.fmu", parameters={"peak_power": 40.0}) as laser:  # doctest: +SKIP
    ...     laser.set("enable", True)
    ...     laser.advance_to(1_000_000)
    ...     laser.get("energy")
    """

    def __init__(self, path: str | Path, *, timebase: TimeBase | None = None, instance_name: str = "fmu",
                 parameters: Mapping[str, Value] | None = None, start: int = 0,
                 logging: bool = False) -> None:
        self.path = Path(path)
        self.timebase = timebase or TimeBase()
        self.instance_name = instance_name
        self.log: deque[str] = deque(maxlen=200)
        self.t = start
        self.events = 0
        self._unzipdir: str | None = None
        self._fmu: Any = None
        if not self.path.exists():
            raise ConfigurationError(f"FMU file {self.path} does not exist")
        try:
            self.model = read_model_description(str(self.path))
        except Exception as exc:  # fmpy raises plain exceptions for broken XML
            raise FmuError(f"{self.path}: cannot read modelDescription.xml: {exc}") from exc
        if self.model.coSimulation is None:
            raise ConfigurationError(f"{self.path} is not a co-simulation FMU")
        self.fmi_version = 3 if self.model.fmiVersion.startswith("3") else 2
        self._unzipdir = tempfile.mkdtemp(prefix="cosim-fmu-")
        extract(str(self.path), unzipdir=self._unzipdir)
        cs = self.model.coSimulation
        self.early_return = self.fmi_version == 3 and bool(cs.mightReturnEarlyFromDoStep)
        self.event_mode = self.fmi_version == 3 and bool(cs.hasEventMode)
        self.variables: dict[str, _Variable] = {}
        self._instantiate(logging)
        self._resolve()
        self._call("initialise", self._initialise, dict(parameters or {}))
        self._prepare_step()

    # -- setup ------------------------------------------------------------------------------
    def _instantiate(self, logging: bool) -> None:
        common = {
            "guid": self.model.guid,
            "unzipDirectory": self._unzipdir,
            "modelIdentifier": self.model.coSimulation.modelIdentifier,
            "instanceName": self.instance_name,
        }
        try:
            if self.fmi_version == 2:
                self._fmu = FMU2Slave(**common)
                self._logger = fmi2CallbackLoggerTYPE(self._log_fmi2)
                callbacks = fmi2CallbackFunctions()
                callbacks.logger = self._logger
                callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
                callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
                self._callbacks = callbacks
                self._fmu.instantiate(callbacks=callbacks, loggingOn=logging)
            else:
                self._fmu = FMU3Slave(**common)
                self._fmu.instantiate(loggingOn=logging, eventModeUsed=self.event_mode,
                                      earlyReturnAllowed=self.early_return, logMessage=self._log_fmi3)
        except Exception as exc:
            self._cleanup()
            raise FmuError(f"{self.instance_name}: instantiation of {self.path.name} failed: {exc}",
                           self.log) from exc

    def _log_fmi2(self, env: object, instance: bytes | None, status: int, category: bytes | None,
                  message: bytes | None) -> None:
        self._remember(status, category, message)

    def _log_fmi3(self, env: object, status: int, category: bytes | None, message: bytes | None) -> None:
        self._remember(status, category, message)

    def _remember(self, status: int, category: bytes | None, message: bytes | None) -> None:
        cat = category.decode(errors="replace") if category else ""
        text = message.decode(errors="replace") if message else ""
        self.log.append(f"[{_STATUS.get(status, status)}] {cat}: {text}")

    def _resolve(self) -> None:
        for sv in self.model.modelVariables:
            unit = sv.unit or (sv.declaredType.unit if sv.declaredType is not None else "") or ""
            var = _Variable(sv.name, sv.valueReference, sv.type, sv.causality, sv.variability, unit)
            accessors = self._accessors(sv.type, [sv.valueReference])
            if accessors is None:
                continue
            var.get, var.set = accessors
            self.variables[sv.name] = var

    def _accessors(self, type_: str, vr: list[int]) -> tuple[Callable[[], Value],
                                                            Callable[[Value], None]] | None:
        f = self._fmu
        v2 = self.fmi_version == 2
        if type_ in ("Real", "Float64"):
            get_real = f.getReal if v2 else f.getFloat64
            set_real = f.setReal if v2 else f.setFloat64
            return (lambda: float(get_real(vr)[0])), (lambda value: set_real(vr, [float(value)]))
        if type_ in ("Integer", "Int32", "Enumeration"):
            get_int = f.getInteger if v2 else f.getInt32
            set_int = f.setInteger if v2 else f.setInt32
            return (lambda: int(get_int(vr)[0])), (lambda value: set_int(vr, [int(value)]))
        if type_ == "Boolean":
            return (lambda: bool(f.getBoolean(vr)[0])), (lambda value: f.setBoolean(vr, [bool(value)]))
        return None

    def _initialise(self, parameters: dict[str, Value]) -> None:
        t0 = self.timebase.seconds(self.t)
        for name, value in parameters.items():
            self._check_value(self.variable(name), value)
        if self.fmi_version == 2:
            self._fmu.setupExperiment(startTime=t0)
            for name, value in parameters.items():
                self.variables[name].set(value)
            self._fmu.enterInitializationMode()
            self._fmu.exitInitializationMode()
        else:
            for name, value in parameters.items():
                self.variables[name].set(value)
            self._fmu.enterInitializationMode(startTime=t0)
            self._fmu.exitInitializationMode()
            if self.event_mode:
                self._settle_events()
                self._fmu.enterStepMode()

    # -- access -----------------------------------------------------------------------------
    def variable(self, name: str) -> _Variable:
        """The resolved variable ``name``; unknown names raise with the closest matches."""
        try:
            return self.variables[name]
        except KeyError:
            close = difflib.get_close_matches(name, list(self.variables), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigurationError(
                f"{self.instance_name} ({self.path.name}) has no variable named {name!r}{hint}"
            ) from None

    @staticmethod
    def _check_value(var: _Variable, value: Value) -> None:
        if var.type == "Boolean" and not isinstance(value, bool | int):
            raise ConfigurationError(f"{var.name} is Boolean; got {value!r}")
        if var.type in ("Integer", "Int32"):  # an Int32 never wraps: 2**32 + 1000 is refused, not stored as 1000
            validate.integer(value, var.name, low=-(2**31), high=2**31 - 1, whole=True, kind="an integer",
                             allowed=f"{-(2**31)}..{2**31 - 1} (Int32)")

    def get(self, name: str) -> Value:
        """Current value of variable ``name`` (the FMU is not advanced; see the master)."""
        var = self.variable(name)
        value: Value = self._call(f"get {name}", var.get)
        return value

    def set(self, name: str, value: Value) -> None:
        """Set variable ``name``; an FMU that rejects it raises :class:`FmuError` with its message."""
        var = self.variable(name)
        self._check_value(var, value)
        self._call(f"set {name} = {value!r}", var.set, value)

    def _call(self, what: str, fn: Callable[..., Any], *args: Any) -> Any:
        try:
            return fn(*args)
        except FMICallException as exc:
            raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: {what} "
                           f"failed ({exc})", self.log) from exc

    # -- time -------------------------------------------------------------------------------
    # -- hot path ---------------------------------------------------------------------------
    # doStep and batched reads call the FMU's ctypes functions directly with arguments prepared
    # once (fmpy's wrappers build new ctypes objects on every call). Statuses are checked here.
    def _raw(self, name: str) -> Any:
        functions = getattr(self._fmu, "_functions", None)
        return None if functions is None else functions.get(name)

    def _prepare_step(self) -> None:
        self._event = ctypes.c_bool()
        self._terminate = ctypes.c_bool()
        self._early = ctypes.c_bool()
        self._last = ctypes.c_double()
        do_step = self._raw(f"fmi{self.fmi_version}DoStep")
        component = self._fmu.component
        if do_step is None:
            self._do_step = self._do_step_fmpy
        elif self.fmi_version == 2:
            self._do_step = lambda t_s, h_s: (do_step(component, t_s, h_s, 1), False, False, False, t_s + h_s)
        else:
            refs = (ctypes.byref(self._event), ctypes.byref(self._terminate), ctypes.byref(self._early),
                    ctypes.byref(self._last))
            self._do_step = lambda t_s, h_s: (do_step(component, t_s, h_s, True, *refs), self._event.value,
                                              self._terminate.value, self._early.value, self._last.value)

    def _do_step_fmpy(self, t_s: float, h_s: float) -> tuple[int, bool, bool, bool, float]:
        if self.fmi_version == 2:
            self._fmu.doStep(t_s, h_s)
            return 0, False, False, False, t_s + h_s
        event, terminate, early, last = self._fmu.doStep(t_s, h_s)
        return 0, event, terminate, early, last

    def _step(self, t_s: float, h_s: float) -> tuple[bool, bool, bool, float]:
        try:
            status, event, terminate, early, last = self._do_step(t_s, h_s)
        except FMICallException as exc:
            status, event, terminate, early, last = exc.status, False, False, False, t_s
        if status > 1:
            raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: doStep from {t_s!r} s "
                           f"by {h_s!r} s failed with status {_STATUS.get(status, status)}", self.log)
        return event, terminate, early, last

    def reader(self, names: list[str]) -> Callable[[], list[Value]]:
        """A function returning the current values of ``names`` (one FMI call when all are Float64)."""
        variables = [self.variable(name) for name in names]
        get = self._raw("fmi2GetReal" if self.fmi_version == 2 else "fmi3GetFloat64")
        if get is None or not variables or any(v.type not in ("Real", "Float64") for v in variables):
            return lambda: [self._call(f"get {v.name}", v.get) for v in variables]
        n = len(variables)
        vrs = (ctypes.c_uint32 * n)(*[v.vr for v in variables])
        values = (ctypes.c_double * n)()
        args = (self._fmu.component, vrs, n, values) + (() if self.fmi_version == 2 else (n,))

        def read() -> list[Value]:
            status = get(*args)
            if status > 1:
                raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: reading "
                               f"{', '.join(names)} failed with status {_STATUS.get(status, status)}", self.log)
            return list(values)

        return read

    def writer(self, names: list[str]) -> Callable[[Sequence[float]], None]:
        """A function setting ``names`` (all Float64/Real inputs) to its argument's values in one FMI call.

        The hot path of couplings that change an input every slot. A value the FMU refuses raises
        :class:`FmuError` with the FMU's own message (which names the variable and its range).
        """
        variables = [self.variable(name) for name in names]
        if not variables or any(v.type not in ("Real", "Float64") for v in variables):
            raise ConfigurationError(f"{self.instance_name}: writer() takes Float64 variables only; got "
                                     + ", ".join(f"{v.name} ({v.type})" for v in variables))
        put = self._raw("fmi2SetReal" if self.fmi_version == 2 else "fmi3SetFloat64")
        if put is None:
            def write_each(values: Sequence[float]) -> None:
                for v, x in zip(variables, values, strict=True):
                    self.set(v.name, float(x))

            return write_each
        n = len(variables)
        vrs = (ctypes.c_uint32 * n)(*[v.vr for v in variables])
        buffer = (ctypes.c_double * n)()
        tail = () if self.fmi_version == 2 else (n,)
        component = self._fmu.component

        def write(values: Sequence[float]) -> None:
            if len(values) != n:
                raise ConfigurationError(f"{self.instance_name}: {len(values)} values for {n} variables "
                                         f"({', '.join(names)})")
            for i, x in enumerate(values):
                buffer[i] = x
            status = put(component, vrs, n, buffer, *tail)
            if status > 1:
                raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: setting "
                               + ", ".join(f"{name} = {x!r}" for name, x in zip(names, values, strict=True))
                               + f" failed with status {_STATUS.get(status, status)}", self.log)

        return write

    def advance_to(self, t: int) -> int:
        """Advance the FMU to tick ``t``; returns the tick it reached.

        With FMI 3.0 early return, the FMU may stop at an event before ``t``: the adapter then
        handles the event (event mode when the FMU has it), steps on to the first whole tick at
        or after the event instant, and returns that tick (< ``t``). Otherwise returns ``t``.
        """
        if t == self.t:
            return t
        if t < self.t:
            raise FmuError(f"{self.instance_name} is at t={self.t} ticks and cannot go back to t={t}")
        t_from = self.timebase.seconds(self.t)
        h = self.timebase.seconds(t - self.t)
        event, terminate, early, t_last = self._step(t_from, h)
        if self.fmi_version == 2:
            self.t = t
            return t
        if terminate:
            raise FmuError(f"{self.instance_name} asked to terminate at t={t_last} s", self.log)
        if event and self.event_mode:
            self._call("event mode", self._handle_event)
        if not early:
            self.t = t
            return t
        self.events += 1
        t_event = min(max(self.timebase.ticks_from_seconds_ceil(t_last), self.t), t)
        gap = self.timebase.seconds(t_event) - t_last
        if gap > 0:
            self._step(t_last, gap)
        self.t = t_event
        return t_event

    def _handle_event(self) -> None:
        self._fmu.enterEventMode()
        self._settle_events()
        self._fmu.enterStepMode()

    def _settle_events(self) -> None:
        for _ in range(100):
            needed, terminate, *_rest = self._fmu.updateDiscreteStates()
            if terminate:
                raise FmuError(f"{self.instance_name} asked to terminate in event mode", self.log)
            if not needed:
                return
        raise FmuError(f"{self.instance_name}: discrete states did not settle after 100 iterations", self.log)

    # -- teardown ---------------------------------------------------------------------------
    def close(self) -> None:
        """Terminate and free the instance and remove its unzipped folder (idempotent)."""
        fmu, self._fmu = self._fmu, None
        if fmu is not None:
            try:
                fmu.terminate()
            except FMICallException:
                pass
            finally:
                fmu.freeInstance()
        self._cleanup()

    def _cleanup(self) -> None:
        if self._unzipdir:
            shutil.rmtree(self._unzipdir, ignore_errors=True)
            self._unzipdir = None

    def __enter__(self) -> Fmu:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()

