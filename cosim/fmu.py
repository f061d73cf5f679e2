"""The FMU adapter: the one module that imports fmpy.

:class:`Fmu` loads an FMI 2.0 or 3.0 co-simulation FMU, resolves variable names once, offers
typed get/set by name for every variable type and for arrays (see :mod:`cosim.fmuvars`), and
advances the FMU to an integer tick: the step size is computed from integer time here, at the FMI
boundary, and nowhere else. FMI errors become :class:`FmuError` carrying the FMU's own log
messages. On FMI 3.0, early return and event mode are used when the FMU offers them, so
:meth:`Fmu.advance_to` can stop exactly at an event inside a step.

An FMU that asks to end the simulation (FMI 2.0: ``fmi2Discard`` from ``doStep``, with
``fmi2Terminated``; FMI 3.0: ``terminateSimulation`` from ``doStep`` or in event mode) is
terminated at that instant and :class:`~cosim.errors.PlantTerminated` is raised with the tick, the
reason and the FMU's last log messages; the instance is freed by :meth:`Fmu.close`.

Model Exchange FMUs are refused with a message saying how to get a co-simulation one: cosim steps
FMUs exactly to the instants that matter, which needs the FMU's own solver.
"""

from __future__ import annotations

import contextlib
import ctypes
import difflib
import functools
import re
import shutil
import tempfile
import traceback
import zipfile
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any

from fmpy import extract, fmi2, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2LastSuccessfulTime, fmi2Terminated
from fmpy.fmi3 import FMU3Slave

from cosim import fmucache
from cosim.errors import ConfigurationError, CosimError, FmuError, PlantTerminated
from cosim.fmuvars import Value, Variable, accessors
from cosim.timebase import TimeBase

__all__ = ["Fmu", "Value", "Variable", "read_description"]

_STATUS = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal", 5: "Pending"}


def read_description(path: str | Path, *, cosimulation: bool = True, validate: bool = True) -> Any:
    """The model description of an FMU file (fmpy's), or :class:`ConfigurationError` saying what is wrong with it.

    A file that is not an FMU (not a zip archive, a zip without ``modelDescription.xml``, a machine
    file) or whose model description cannot be read is refused as a configuration error naming the
    file. With ``validate`` false, fmpy's validator (the FMI schema and the rules it checks) is not
    applied: :func:`validation_findings` lists what it would have said. Unless ``cosimulation`` is
    false, an FMU without co-simulation (Model Exchange only) is refused saying how to export a
    co-simulation FMU instead.
    """
    path = Path(path)
    _check_is_fmu(path)
    stat = path.stat()
    return _read_description(str(path.resolve()), stat.st_mtime_ns, stat.st_size, cosimulation, validate)


@functools.lru_cache(maxsize=32)
def _read_description(path_text: str, mtime_ns: int, size: int, cosimulation: bool, validate: bool) -> Any:
    """:func:`read_description` of one version of a file (read once: the schema check costs ~10 ms)."""
    path = Path(path_text)
    try:
        if path.is_dir():  # an unzipped FMU
            model = read_model_description(path_text, validate=validate)
        else:  # read once, then from the per-user FMU cache
            model = fmucache.description(path, validate, lambda: read_model_description(path_text, validate=validate))
    except Exception as exc:  # fmpy raises plain exceptions for broken XML and broken files
        traceback.clear_frames(exc.__traceback__)  # fmpy's frames hold the FMU's file open: close it now
        problems = getattr(exc, "problems", None)
        hint = ("; --no-validate runs it anyway (with a warning listing these findings)" if problems
                else "; `python -m fmpy validate` on the file lists what is wrong with it")
        raise ConfigurationError(f"{path}: cannot read modelDescription.xml ({_reason(path, exc)}){hint}") from exc
    if cosimulation and model.coSimulation is None:
        kinds = "a Model Exchange FMU" if model.modelExchange is not None else "an FMU without co-simulation"
        raise ConfigurationError(
            f"{path.name} is {kinds}: cosim needs a co-simulation FMU (one that brings its own "
            "solver, so the master can step it exactly to each instant that matters). Export it again "
            "with co-simulation enabled: most tools have it as the FMU type (OpenModelica: "
            "buildModelFMU(..., fmuType=\"cs\") or \"me_cs\"; Dymola: 'Co-simulation using Cvode' or "
            "'using Dymola solvers'; Simulink and 20-sim: their co-simulation FMU export). For a quick "
            "look at a Model Exchange FMU alone, fmpy.simulate_fmu runs it with its own solver.")
    _read_unsigned_ranges(path, model)
    return model


def validation_findings(path: str | Path) -> list[str]:
    """What fmpy's validator finds wrong with an FMU's model description (empty if nothing).

    The FMI schema first (as :func:`read_description` applies it), then fmpy's rules (variabilities,
    start values, units, model structure).
    """
    from fmpy.model_description import ValidationError
    from fmpy.validation import validate_model_description

    path = Path(path)
    _check_is_fmu(path)
    try:
        read_model_description(str(path), validate=True)
    except ValidationError as exc:
        return [str(problem) for problem in exc.problems]
    except Exception as exc:
        traceback.clear_frames(exc.__traceback__)
        return [f"{type(exc).__name__}: {exc}"]
    model = read_model_description(str(path), validate=False)
    return [str(problem) for problem in validate_model_description(model)]


def _check_is_fmu(path: Path) -> None:
    """Refuse, naming the file, what is not an FMU: a missing file, a folder, a file that is not a zip archive
    holding a ``modelDescription.xml``."""
    if not path.exists():
        raise ConfigurationError(f"FMU file {path} does not exist")
    if path.is_dir():
        if (path / "modelDescription.xml").is_file():
            return  # an unzipped FMU
        raise ConfigurationError(f"{path} is a folder without modelDescription.xml, not an FMU")
    what = {".toml": "a machine file (run it with `cosim run`)", ".py": "a scenario script (run it with `cosim run`)",
            ".bas": "a program", ".csv": "a table"}.get(path.suffix.lower(), "")
    if not zipfile.is_zipfile(path):
        raise ConfigurationError(f"{path} is not an FMU: {what or 'not a zip archive'} (an FMU is a zip archive "
                                 "holding modelDescription.xml)")
    try:
        with zipfile.ZipFile(path) as archive:
            names = set(archive.namelist())
    except (OSError, zipfile.BadZipFile) as exc:
        raise ConfigurationError(f"{path} is not an FMU: {exc}") from None
    if "modelDescription.xml" not in names:
        raise ConfigurationError(f"{path} is not an FMU: the zip archive has no modelDescription.xml at its top "
                                 f"level ({len(names)} entries)")


def _reason(path: Path, exc: Exception) -> str:
    """What fmpy's exception means: a KeyError of a number is a value reference no variable has
    (FMI 3.0 ModelStructure and dependencies name variables by value reference)."""
    if isinstance(exc, KeyError) and isinstance(exc.args[0], int):
        vr = exc.args[0]
        try:
            with zipfile.ZipFile(path) as fmu:
                text = fmu.read("modelDescription.xml").decode("utf-8", "replace")
        except (OSError, KeyError, zipfile.BadZipFile):
            text = ""
        pattern = re.compile(rf'valueReference="{vr}"|dependencies="[^"]*\b{vr}\b')
        lines = [str(n) for n, line in enumerate(text.splitlines(), 1) if pattern.search(line)]
        at = f" at line {', '.join(lines[:5])}" if lines else ""
        return f"value reference {vr} is named{at} but no variable has it"
    return f"{type(exc).__name__}: {exc}"


def _read_unsigned_ranges(path: Path, model: Any) -> None:
    """Fill in ``min``/``max`` of FMI 3.0 UInt variables, which fmpy's reader leaves out."""
    unsigned = {v.name: v for v in model.modelVariables if v.type.startswith("UInt") and v.min is None
                and v.max is None}
    if not unsigned:
        return
    import zipfile
    from xml.etree import ElementTree

    try:
        text = ((path / "modelDescription.xml").read_bytes() if path.is_dir()
                else zipfile.ZipFile(path).read("modelDescription.xml"))
        root = ElementTree.fromstring(text)
    except (OSError, KeyError, zipfile.BadZipFile, ElementTree.ParseError):
        return
    for element in root.iterfind("ModelVariables/*"):
        sv = unsigned.get(element.get("name", ""))
        if sv is not None:
            sv.min, sv.max = element.get("min"), element.get("max")


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
        Start values of parameters and inputs, set before initialisation (checked as :meth:`set` does).
    start : int
        Start time [ticks].
    logging : bool
        Ask the FMU for debug logging (errors are always captured).
    validate : bool
        Apply fmpy's validator to the model description (default); False runs an FMU whose
        description it flags (see :func:`validation_findings`), as fmpy's ``validate=False`` does.

    Attributes
    ----------
    variables : dict of str to Variable
        Every variable the adapter reaches (all types but clocks), with type, unit, range, shape.
    terminated : str or None
        Why the FMU ended the simulation, once it has (it then stays at :attr:`t`).
    notes : list of str
        What the adapter did differently from the FMU's declarations (an FMU that declares event
        mode and refuses it runs without), for the run's notes.

    Examples
    --------
    >>> with Fmu("models/fmi3/Laser.fmu", parameters={"peak_power": 40.0}) as laser:  # doctest: +SKIP
    ...     laser.set("enable", True)
    ...     laser.advance_to(1_000_000)
    ...     laser.get("energy")
    """

    def __init__(self, path: str | Path, *, timebase: TimeBase | None = None, instance_name: str = "fmu",
                 parameters: Mapping[str, Value] | None = None, start: int = 0,
                 logging: bool = False, validate: bool = True) -> None:
        self.path = Path(path)
        self.timebase = timebase or TimeBase()
        self.instance_name = instance_name
        self.log: deque[str] = deque(maxlen=200)
        self.notes: list[str] = []
        self.t = start
        self.events = 0
        self.terminated: str | None = None
        self._ended: CosimError | None = None  # why it cannot step any more: terminated or closed
        self._unzipdir: str | None = None
        self._owns_unzipdir = False
        self._fmu: Any = None
        self.model = read_description(self.path, validate=validate)
        self.fmi_version = 3 if self.model.fmiVersion.startswith("3") else 2
        self._where = f"{instance_name} ({self.path.name})"
        cs = self.model.coSimulation
        if self.path.is_dir():  # an unzipped FMU: a private copy, as fmpy makes it
            self._unzipdir = tempfile.mkdtemp(prefix="cosim-fmu-")
            self._owns_unzipdir = True
            extract(str(self.path), unzipdir=self._unzipdir)
        else:  # unzipped once into the per-user FMU cache (a private copy if it may be loaded only once)
            folder, self._owns_unzipdir = fmucache.unzipped(self.path,
                                                            shared=not cs.canBeInstantiatedOnlyOncePerProcess)
            self._unzipdir = str(folder)
        self.early_return = self.fmi_version == 3 and bool(cs.mightReturnEarlyFromDoStep)
        self.event_mode = self.fmi_version == 3 and bool(cs.hasEventMode)
        self.variables: dict[str, Variable] = {}
        for sv in self.model.modelVariables:
            var = Variable.from_model(sv, self.fmi_version)
            if var is not None:
                self.variables[var.name] = var
        values = {name: self.variable(name).check(value, where=self._where)
                  for name, value in (parameters or {}).items()}
        try:
            self._start_instance(logging, values)
        except _EventModeRefused as refused:
            # fmpy runs such an FMU without event mode (its default): so does cosim, and says so
            self._free_instance()
            self.event_mode = False
            self.notes.append(f"{self._where} declares event mode (hasEventMode) but refused it ({refused}); it "
                              "runs without event mode: events inside a step are handled at its end")
            self._start_instance(logging, values)
        self._prepare_step()

    def _start_instance(self, logging: bool, values: dict[str, Any]) -> None:
        """Instantiate, prepare the accessors and initialise (raises _EventModeRefused for a refused event mode)."""
        self._instantiate(logging)
        self._resolve()
        self._call("initialise", self._initialise, values)

    def _free_instance(self) -> None:
        fmu, self._fmu = self._fmu, None
        if fmu is not None and getattr(fmu, "component", None):
            with contextlib.suppress(Exception):
                fmu.freeInstance()

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
                self._fmu = FMU2SlaveOnce(**common)
                self._logger = fmi2CallbackLoggerTYPE(self._log_fmi2)
                callbacks = fmi2CallbackFunctions()
                callbacks.logger = self._logger
                callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
                callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
                self._callbacks = callbacks
                self._fmu.instantiate(callbacks=callbacks, loggingOn=logging)
            else:
                self._fmu = FMU3SlaveOnce(**common)
                self._fmu.instantiate(loggingOn=logging, eventModeUsed=self.event_mode,
                                      earlyReturnAllowed=self.early_return, logMessage=self._log_fmi3)
        except Exception as exc:
            if self.event_mode:
                raise _EventModeRefused(f"instantiation with eventModeUsed = true failed: {exc}") from exc
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
        for var in self.variables.values():
            var.get, var.set = self._accessors(var)

    def _function(self, name: str) -> Callable[..., int]:
        """The FMI function ``name`` taking ctypes arguments and returning its status."""
        raw = self._raw(name)
        if raw is not None:
            return raw
        wrapped = getattr(self._fmu, name)

        def call(*args: Any) -> int:
            try:
                wrapped(*args)
            except FMICallException as exc:
                return int(exc.status)
            return 0

        return call

    def _failed(self, what: str, status: int) -> FmuError:
        return FmuError(f"{self._where} at t={self.t} ticks: {what} failed with status "
                        f"{_STATUS.get(status, status)}", self.log)

    def _accessors(self, var: Variable) -> tuple[Callable[[], Value], Callable[[Any], None]]:
        prefix = f"fmi{self.fmi_version}"
        get, put = f"{prefix}Get{var.kind.function}", f"{prefix}Set{var.kind.function}"
        if var.kind.name != "Binary" and not var.shape and var.kind.python is not str:
            # numbers and Booleans: the functions without argtypes, given ctypes objects of the exact C types
            bare_get, bare_put = self._bare(get), self._bare(put)
            if bare_get is not None and bare_put is not None:
                return accessors(var, bare_get, bare_put, component=self._fmu.component, fmi3=self.fmi_version == 3,
                                 failed=self._failed)
        return accessors(var, self._function(get), self._function(put), component=self._fmu.component,
                         fmi3=self.fmi_version == 3, failed=self._failed)

    def _initialise(self, parameters: dict[str, Any]) -> None:
        t0 = self.timebase.seconds(self.t)
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
                try:
                    asked = self._settle_events()
                    if not asked:
                        self._fmu.enterStepMode()
                except (FMICallException, FmuError) as exc:
                    raise _EventModeRefused(f"the initial event mode failed: {exc}") from exc
                if asked:
                    self._end(self.t, "asked to terminate in event mode during initialisation")

    # -- access -----------------------------------------------------------------------------
    def variable(self, name: str) -> Variable:
        """The resolved variable ``name``; unknown names raise with the closest matches."""
        try:
            return self.variables[name]
        except KeyError:
            close = difflib.get_close_matches(name, list(self.variables), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigurationError(
                f"{self.instance_name} ({self.path.name}) has no variable named {name!r}{hint}"
            ) from None

    def get(self, name: str) -> Value:
        """Current value of variable ``name`` (the FMU is not advanced; see the master).

        A scalar as ``float``, ``int``, ``bool``, ``str`` or ``bytes``; an array variable as a numpy
        array of its shape.
        """
        return self.variable(name).get()

    def set(self, name: str, value: Any) -> None:
        """Set variable ``name``.

        The value is checked first (:meth:`Variable.check`): an integer outside its type's range or
        the variable's declared ``min``/``max`` raises :class:`ConfigurationError` naming the value
        and the range, and never reaches the FMU. A value the FMU refuses raises :class:`FmuError`
        with the FMU's own message.
        """
        var = self.variable(name)
        var.set(var.check(value, where=self._where))

    def _call(self, what: str, fn: Callable[..., Any], *args: Any) -> Any:
        try:
            return fn(*args)
        except FMICallException as exc:
            raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: {what} "
                           f"failed ({exc})", self.log) from exc

    # -- time -------------------------------------------------------------------------------
    # -- hot path ---------------------------------------------------------------------------
    # doStep, batched reads and prepared writers call the FMU's functions directly with ctypes
    # arguments made once (fmpy's wrappers build new ctypes objects on every call), through function
    # pointers without argtypes, so ctypes does not convert and check each argument on every call
    # (about half of a call's cost). Statuses are checked here.
    def _raw(self, name: str) -> Any:
        functions = getattr(self._fmu, "_functions", None)
        return None if functions is None else functions.get(name)

    def _bare(self, name: str) -> Any:
        """FMI function ``name`` without argtypes: its callers pass ctypes objects of the exact C types."""
        raw = self._raw(name)
        address = None if raw is None else ctypes.cast(raw, ctypes.c_void_p).value
        return None if address is None else ctypes.CFUNCTYPE(ctypes.c_int)(address)

    def _prepare_step(self) -> None:
        """Prepare :meth:`advance_to`'s common case: one doStep without event, early return or termination.

        The step's arguments are ctypes objects made once; the float times are those of
        :meth:`TimeBase.seconds` (``ticks / 10**9`` at 1 ns, correctly rounded). Anything else
        (an event, an early return, a terminate request, a Discard or Error status, going back in
        time, an ended FMU) goes through the general path, :meth:`_advance_general`.
        """
        self._event = ctypes.c_bool()
        self._terminate = ctypes.c_bool()
        self._early = ctypes.c_bool()
        self._last = ctypes.c_double()
        do_step = self._bare(f"fmi{self.fmi_version}DoStep")
        self._advance: Callable[[int], int] = self._advance_general
        if do_step is None:
            self._do_step = self._do_step_fmpy
            return
        t_arg, h_arg = ctypes.c_double(), ctypes.c_double()
        component = ctypes.c_void_p(self._fmu.component)
        resolution = self.timebase.resolution_s
        per_second = resolution.denominator if resolution.numerator == 1 else 0
        seconds, general, finish = self.timebase.seconds, self._advance_general, self._finish
        if self.fmi_version == 2:
            args2 = (component, t_arg, h_arg, ctypes.c_int(1))

            def do_step2(t_s: float, h_s: float) -> tuple[int, bool, bool, bool, float]:
                t_arg.value = t_s
                h_arg.value = h_s
                return do_step(*args2), False, False, False, t_s + h_s

            def advance2(t: int) -> int:
                now = self.t
                if t <= now or self._ended is not None:
                    return general(t)
                t_s, h_s = (now / per_second, (t - now) / per_second) if per_second else (seconds(now),
                                                                                           seconds(t - now))
                t_arg.value = t_s
                h_arg.value = h_s
                status = do_step(*args2)
                if status > 1:
                    return finish(t, t_s, h_s, (status, False, False, False, t_s + h_s))
                self.t = t
                return t

            self._do_step = do_step2
            self._advance = advance2
            return
        event, terminate, early, last = self._event, self._terminate, self._early, self._last
        args3 = (component, t_arg, h_arg, ctypes.c_bool(True), ctypes.byref(event), ctypes.byref(terminate),
                 ctypes.byref(early), ctypes.byref(last))
        event_mode = self.event_mode

        def do_step3(t_s: float, h_s: float) -> tuple[int, bool, bool, bool, float]:
            t_arg.value = t_s
            h_arg.value = h_s
            return do_step(*args3), event.value, terminate.value, early.value, last.value

        def advance3(t: int) -> int:
            now = self.t
            if t <= now or self._ended is not None:
                return general(t)
            t_s, h_s = (now / per_second, (t - now) / per_second) if per_second else (seconds(now), seconds(t - now))
            t_arg.value = t_s
            h_arg.value = h_s
            status = do_step(*args3)
            if status > 1 or terminate.value or early.value or (event_mode and event.value):
                return finish(t, t_s, h_s, (status, event.value, terminate.value, early.value, last.value))
            self.t = t
            return t

        self._do_step = do_step3
        self._advance = advance3

    def _do_step_fmpy(self, t_s: float, h_s: float) -> tuple[int, bool, bool, bool, float]:
        if self.fmi_version == 2:
            self._fmu.doStep(t_s, h_s)
            return 0, False, False, False, t_s + h_s
        event, terminate, early, last = self._fmu.doStep(t_s, h_s)
        return 0, event, terminate, early, last

    def _step(self, t_s: float, h_s: float) -> tuple[bool, str, bool, float]:
        """One doStep: (event, why the FMU asks to terminate or "", early return, last successful time [s])."""
        try:
            outcome = self._do_step(t_s, h_s)
        except FMICallException as exc:
            outcome = (exc.status, False, False, False, t_s)
        return self._interpret(t_s, h_s, outcome)

    def _interpret(self, t_s: float, h_s: float,
                   outcome: tuple[int, bool, bool, bool, float]) -> tuple[bool, str, bool, float]:
        status, event, terminate, early, last = outcome
        if status == 2:  # Discard: the FMU could not (or would not) go on
            return False, self._discarded(t_s, h_s, last), False, self._last_successful(last)
        if status > 1:
            raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: doStep from {t_s!r} s "
                           f"by {h_s!r} s failed with status {_STATUS.get(status, status)}", self.log)
        why = f"asked to terminate from doStep at t={last!r} s" if terminate else ""
        return event, why, early, last

    def _discarded(self, t_s: float, h_s: float, last: float) -> str:
        reason = f"doStep from {t_s!r} s by {h_s!r} s returned Discard"
        if self.fmi_version == 2:
            try:
                asked = bool(self._fmu.getBooleanStatus(fmi2Terminated))
            except FMICallException:
                asked = False
            return reason + (" (fmi2Terminated: the FMU asks to end the simulation)" if asked else "")
        return reason + f" (last successful time {last!r} s)"

    def _last_successful(self, last: float) -> float:
        """FMI 2.0 after Discard: fmi2LastSuccessfulTime (the step's start if the FMU cannot say)."""
        if self.fmi_version == 3:
            return last
        try:
            return float(self._fmu.getRealStatus(fmi2LastSuccessfulTime))
        except FMICallException:
            return self.timebase.seconds(self.t)

    def reader(self, names: list[str]) -> Callable[[], list[Value]]:
        """A function returning the current values of ``names``, prepared once (see :meth:`sampler`)."""
        values: list[Value] = [0.0] * len(names)
        sinks = [partial(_put, values, i) for i in range(len(names))]
        fill = self.sampler(names, sinks)

        def read() -> list[Value]:
            fill(0)
            return list(values)

        return read

    def sampler(self, names: Sequence[str], sinks: Sequence[Callable[[int, Any], None]]) -> Callable[[int], None]:
        """A function ``fill(t)`` that reads ``names`` and passes each value to its sink: ``sinks[i](t, value)``.

        Prepared once, for the master's sampling: scalars of the numeric and Boolean types are read
        with one FMI call per type (Float64, Int32, Boolean outputs: three calls) into buffers made
        once, and their values go to the sinks as ctypes gives them (``float``, ``int``, ``bool``;
        FMI 2.0 Booleans as 0/1), without a list in between. Strings, binaries and arrays are read
        as :meth:`get` does (an array as a numpy array).
        """
        variables = [self.variable(name) for name in names]
        if len(sinks) != len(variables):
            raise ConfigurationError(f"{self.instance_name}: {len(sinks)} sinks for {len(variables)} variables")
        groups: dict[str, list[int]] = {}
        for i, var in enumerate(variables):
            if var.kind.is_numeric and not var.shape:
                groups.setdefault(var.kind.function, []).append(i)
        getters = {function: self._bare(f"fmi{self.fmi_version}Get{function}") for function in groups}
        if any(get is None for get in getters.values()):
            groups = {}
        component = ctypes.c_void_p(self._fmu.component)
        calls = []
        for function, indices in groups.items():
            n = len(indices)
            vrs = (ctypes.c_uint32 * n)(*[variables[i].vr for i in indices])
            size = ctypes.c_size_t(n)
            buffer = (variables[indices[0]].kind.ctype * n)()
            args = (component, vrs, size, buffer) + (() if self.fmi_version == 2 else (size,))
            calls.append((getters[function], args, buffer, tuple(sinks[i] for i in indices)))
        grouped = {i for indices in groups.values() for i in indices}
        others = [(variables[i].get, sinks[i]) for i in range(len(variables)) if i not in grouped]
        where = f"{self.instance_name} ({self.path.name})"

        def closed() -> FmuError:
            return FmuError(f"{self._where} is closed (its simulation has ended)")

        def failed(status: int) -> FmuError:
            return FmuError(f"{where} at t={self.t} ticks: reading {', '.join(names)} failed with status "
                            f"{_STATUS.get(status, status)}", self.log)

        if len(calls) == 1 and not others:  # one type (e.g. all Float64): one call
            get, args, buffer, group_sinks = calls[0]

            def fill_one_type(t: int) -> None:
                if self._fmu is None:
                    raise closed()
                status = get(*args)
                if status > 1:
                    raise failed(status)
                for sink, value in zip(group_sinks, buffer, strict=True):
                    sink(t, value)

            return fill_one_type

        def fill(t: int) -> None:
            if self._fmu is None:
                raise closed()
            for get, args, buffer, group_sinks in calls:
                status = get(*args)
                if status > 1:
                    raise failed(status)
                for sink, value in zip(group_sinks, buffer, strict=True):
                    sink(t, value)
            for get_one, sink in others:
                sink(t, get_one())

        return fill

    def block_sampler(self, names: Sequence[str], sinks: Sequence[Callable[[Any, Any], None]], *,
                      rows: int = 1024) -> BlockSampler | None:
        """A :class:`BlockSampler` of ``names``, or None if one of them is not a numeric or Boolean scalar.

        ``sinks[i](t, values)`` receives the samples of variable ``i`` in blocks: numpy arrays of the
        ticks (int64) and of the values (the variable's C type), at most ``rows`` at a time.
        """
        variables = [self.variable(name) for name in names]
        if not variables or any(not v.kind.is_numeric or v.shape for v in variables) or len(sinks) != len(variables):
            return None
        groups: dict[str, list[int]] = {}
        for i, var in enumerate(variables):
            groups.setdefault(var.kind.function, []).append(i)
        getters = {function: self._bare(f"fmi{self.fmi_version}Get{function}") for function in groups}
        if any(get is None for get in getters.values()):
            return None
        return BlockSampler(self, [(getters[function], [variables[i] for i in indices],
                                    [sinks[i] for i in indices]) for function, indices in groups.items()], rows=rows)

    def grid_row(self, block: BlockSampler) -> Any:
        """A :class:`cosim.gridloop.GridRow` stepping this FMU over grid instants and sampling into ``block`` in C,
        or None where the C loop is not available (no C compiler, a resolution that is not 1/n s, no direct
        access to the FMU's functions): the master then steps in Python, with the same results."""
        from cosim import gridloop

        resolution = self.timebase.resolution_s
        do_step = self._raw(f"fmi{self.fmi_version}DoStep")
        if resolution.numerator != 1 or do_step is None or block.fmu is not self:
            return None
        lib = gridloop.library()
        if lib is None:
            return None
        getters = [(_address(get), head[1], head[2].value, base, stride)
                   for get, head, base, stride, _ in block._groups]
        return gridloop.GridRow(lib, self, block, do_step=_address(do_step), per_second=resolution.denominator,
                                getters=getters)

    def writer(self, names: list[str]) -> Callable[[Sequence[float]], None]:
        """A function setting ``names`` (all Float64/Real scalar inputs) to its argument's values in one FMI call.

        The hot path of couplings that change an input every slot. A value the FMU refuses raises
        :class:`FmuError` with the FMU's own message (which names the variable and its range).
        """
        variables = [self.variable(name) for name in names]
        if not variables or any(v.kind.name != "Float64" or v.shape for v in variables):
            raise ConfigurationError(f"{self.instance_name}: writer() takes Float64 variables only; got "
                                     + ", ".join(f"{v.name} ({v.type}{v.dimensions})" for v in variables))
        put = self._bare("fmi2SetReal" if self.fmi_version == 2 else "fmi3SetFloat64")
        if put is None:
            def write_each(values: Sequence[float]) -> None:
                for v, x in zip(variables, values, strict=True):
                    self.set(v.name, float(x))

            return write_each
        n = len(variables)
        vrs = (ctypes.c_uint32 * n)(*[v.vr for v in variables])
        buffer = (ctypes.c_double * n)()
        size = ctypes.c_size_t(n)
        args = (ctypes.c_void_p(self._fmu.component), vrs, size, buffer) + (() if self.fmi_version == 2 else (size,))

        def write(values: Sequence[float]) -> None:
            if len(values) != n:
                raise ConfigurationError(f"{self.instance_name}: {len(values)} values for {n} variables "
                                         f"({', '.join(names)})")
            if self._fmu is None:
                raise FmuError(f"{self._where} is closed (its simulation has ended)")
            for i, x in enumerate(values):
                buffer[i] = x
            status = put(*args)
            if status > 1:
                raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: setting "
                               + ", ".join(f"{name} = {x!r}" for name, x in zip(names, values, strict=True))
                               + f" failed with status {_STATUS.get(status, status)}", self.log)

        return write

    def array_writer(self, name: str, values: Any) -> Callable[[], None]:
        """A function writing the current contents of ``values`` to the Float64 array input ``name`` in one FMI call.

        ``values`` is a C-contiguous float64 numpy array with as many elements as the variable
        (any shape); the call is prepared once (the array's memory is passed as it is, without
        conversion), so the caller fills ``values`` and calls the function. FMI 3.0 only (FMI 2.0
        has no arrays). A value the FMU refuses raises :class:`FmuError` with the FMU's own message.
        """
        import numpy as np

        var = self.variable(name)
        if var.kind.name != "Float64" or not var.shape or self.fmi_version != 3:
            raise ConfigurationError(f"{self.instance_name}: array_writer() takes a Float64 array of an FMI 3.0 FMU; "
                                     f"got {var.name} ({var.type}{var.dimensions}, FMI {self.fmi_version}.0)")
        size = int(np.prod(var.shape))
        if not (isinstance(values, np.ndarray) and values.dtype == np.float64 and values.flags.c_contiguous
                and values.size == size):
            raise ConfigurationError(f"{self.instance_name}: array_writer({name!r}) needs a C-contiguous float64 "
                                     f"numpy array of {size} elements")
        put = self._bare("fmi3SetFloat64")
        if put is None:
            return lambda: var.set(values)
        vrs = (ctypes.c_uint32 * 1)(var.vr)
        args = (ctypes.c_void_p(self._fmu.component), vrs, ctypes.c_size_t(1),
                ctypes.c_void_p(values.ctypes.data), ctypes.c_size_t(size))

        def write() -> None:
            if self._fmu is None:
                raise FmuError(f"{self._where} is closed (its simulation has ended)")
            status = put(*args)
            if status > 1:
                raise FmuError(f"{self.instance_name} ({self.path.name}) at t={self.t} ticks: setting {name} failed "
                               f"with status {_STATUS.get(status, status)}", self.log)

        return write

    def array_reader(self, name: str, out: Any) -> Callable[[], None]:
        """A function reading the array variable ``name`` into ``out`` in one FMI call (prepared once).

        ``out`` is a C-contiguous numpy array of the variable's C type (float64 for Float64, int32
        for Int32...) with as many elements as the variable; FMI 3.0 only. A status above Warning
        raises :class:`FmuError`.
        """
        import numpy as np

        var = self.variable(name)
        if not var.shape or self.fmi_version != 3 or not var.kind.is_numeric:
            raise ConfigurationError(f"{self.instance_name}: array_reader() takes a numeric array of an FMI 3.0 FMU; "
                                     f"got {var.name} ({var.type}{var.dimensions}, FMI {self.fmi_version}.0)")
        if not (isinstance(out, np.ndarray) and out.dtype == np.dtype(var.kind.ctype) and out.flags.c_contiguous
                and out.size == var.size):
            raise ConfigurationError(f"{self.instance_name}: array_reader({name!r}) needs a C-contiguous numpy array "
                                     f"of {var.size} {np.dtype(var.kind.ctype)} elements")
        get = self._bare(f"fmi3Get{var.kind.function}")
        if get is None:
            def read_slowly() -> None:
                out[...] = np.asarray(var.get()).reshape(out.shape)

            return read_slowly
        size = ctypes.c_size_t(var.size)
        args = (ctypes.c_void_p(self._fmu.component), (ctypes.c_uint32 * 1)(var.vr), ctypes.c_size_t(1),
                ctypes.c_void_p(out.ctypes.data), size)

        def read() -> None:
            if self._fmu is None:
                raise FmuError(f"{self._where} is closed (its simulation has ended)")
            status = get(*args)
            if status > 1:
                raise FmuError(f"{self._where} at t={self.t} ticks: reading {name} failed with status "
                               f"{_STATUS.get(status, status)}", self.log)

        return read

    def advance_to(self, t: int) -> int:
        """Advance the FMU to tick ``t``; returns the tick it reached.

        With FMI 3.0 early return, the FMU may stop at an event before ``t``: the adapter then
        handles the event (event mode when the FMU has it), steps on to the first whole tick at
        or after the event instant, and returns that tick (< ``t``). Otherwise returns ``t``.

        Raises
        ------
        PlantTerminated
            The FMU asked to end the simulation in this step (or did so before): it is terminated
            at the first whole tick at or after that instant, which the exception carries.
        """
        return self._advance(t)

    def stepper(self) -> Callable[[int], int]:
        """:meth:`advance_to` as a bound function, prepared once (for the master's hot loops)."""
        return self._advance

    def _advance_general(self, t: int) -> int:
        if self._ended is not None:
            raise self._ended
        if t == self.t:
            return t
        if t < self.t:
            raise FmuError(f"{self.instance_name} is at t={self.t} ticks and cannot go back to t={t}")
        t_from = self.timebase.seconds(self.t)
        h = self.timebase.seconds(t - self.t)
        try:
            outcome = self._do_step(t_from, h)
        except FMICallException as exc:
            outcome = (exc.status, False, False, False, t_from)
        return self._finish(t, t_from, h, outcome)

    def _finish(self, t: int, t_from: float, h: float, outcome: tuple[int, bool, bool, bool, float]) -> int:
        """The rest of a step to ``t`` taken from ``t_from`` by ``h`` [s]: events, early return, termination."""
        event, terminate, early, t_last = self._interpret(t_from, h, outcome)
        t_event = min(max(self.timebase.ticks_from_seconds_ceil(t_last), self.t), t) if early or terminate else t
        if terminate:
            self._end(t_event, terminate)
        if self.fmi_version == 2:
            self.t = t
            return t
        if event and self.event_mode and self._call("event mode", self._handle_event):
            self._end(t_event, f"asked to terminate in event mode at t={t_last!r} s")
        if not early:
            self.t = t
            return t
        self.events += 1
        gap = self.timebase.seconds(t_event) - t_last
        if gap > 0:
            event, terminate, _, _ = self._step(t_last, gap)
            if terminate:
                self._end(t_event, terminate)
        self.t = t_event
        return t_event

    def _handle_event(self) -> bool:
        """Event mode at the FMU's current instant; True if the FMU asks to terminate there."""
        self._fmu.enterEventMode()
        if self._settle_events():
            return True
        self._fmu.enterStepMode()
        return False

    def _settle_events(self) -> bool:
        for _ in range(100):
            needed, terminate, *_rest = self._fmu.updateDiscreteStates()
            if terminate:
                return True
            if not needed:
                return False
        raise FmuError(f"{self.instance_name}: discrete states did not settle after 100 iterations", self.log)

    def _end(self, t: int, reason: str) -> None:
        """The FMU asked to end the simulation at tick ``t``: terminate it there and raise PlantTerminated."""
        self.t = t
        self.terminated = reason
        with contextlib.suppress(FMICallException):  # the FMU's own message is in the log
            self._fmu.terminate()
        ended = PlantTerminated(f"{self._where} {reason}; it is terminated at t={t} ticks",
                                plant=self.instance_name, fmu=self.path.name, t=t, reason=reason, log=tuple(self.log))
        self._ended = ended
        raise ended

    # -- teardown ---------------------------------------------------------------------------
    def close(self) -> None:
        """Terminate (unless the FMU ended the simulation itself) and free the instance, remove its folder.

        Idempotent.
        """
        fmu, self._fmu = self._fmu, None
        if fmu is not None:
            closed = FmuError(f"{self._where} is closed (its simulation has ended)")
            self._ended = closed
            for var in self.variables.values():  # the prepared calls hold the freed instance: refuse them
                var.get = var.set = partial(_refuse, closed)
            try:
                if self.terminated is None:
                    fmu.terminate()
            except FMICallException:
                pass
            finally:
                fmu.freeInstance()
        self._cleanup()

    def _cleanup(self) -> None:
        if self._unzipdir:
            if self._owns_unzipdir:  # (a folder of the FMU cache stays for the next run)
                shutil.rmtree(self._unzipdir, ignore_errors=True)
            self._unzipdir = None

    def __enter__(self) -> Fmu:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()


def _refuse(error: Exception, *args: Any) -> Any:
    raise error


class BlockSampler:
    """Samples of an FMU's numeric outputs taken into blocks, handed on a block at a time.

    Made by :meth:`Fmu.block_sampler`. :meth:`take` reads every variable at tick ``t`` with one FMI
    call per type, the getter writing straight into the next row of a numpy block (no Python value
    is made per variable); :meth:`flush` hands each variable's samples so far to its sink. The
    master flushes before anything else can look at the trace, so a block is never seen half full.
    """

    def __init__(self, fmu: Fmu, groups: list[tuple[Any, list[Variable], list[Callable[[Any, Any], None]]]], *,
                 rows: int) -> None:
        import numpy as np

        self.fmu = fmu
        self.rows = rows
        self.count = 0
        self.times = np.zeros(rows, dtype=np.int64)
        component = ctypes.c_void_p(fmu._fmu.component)
        #: per row, the calls that read into it: (getter, its arguments with that row's address), made when
        #: the row is first used (a short run takes a few samples: most rows are never made)
        self._rows: list[list[tuple[Any, tuple[Any, ...]]] | None] = [None] * rows
        self._groups: list[tuple[Any, tuple[Any, ...], Any, int, tuple[Any, ...]]] = []
        self._blocks: list[tuple[Any, list[Callable[[Any, Any], None]]]] = []
        for get, variables, sinks in groups:
            n = len(variables)
            block = np.zeros((rows, n), dtype=np.dtype(variables[0].kind.ctype))
            size = ctypes.c_size_t(n)
            vrs = (ctypes.c_uint32 * n)(*[v.vr for v in variables])
            tail: tuple[Any, ...] = () if fmu.fmi_version == 2 else (size,)
            self._groups.append((get, (component, vrs, size), block.ctypes.data, block.strides[0], tail))
            self._blocks.append((block, sinks))
        self._names = ", ".join(v.name for _, variables, _ in groups for v in variables)

    def _row(self, i: int) -> list[tuple[Any, tuple[Any, ...]]]:
        """The calls that read into row ``i`` (made once)."""
        calls = self._rows[i] = [(get, (*head, ctypes.c_void_p(base + i * stride), *tail))
                                 for get, head, base, stride, tail in self._groups]
        return calls

    def take(self, t: int) -> None:
        """Read every variable now, as the sample at tick ``t``."""
        fmu = self.fmu
        if fmu._fmu is None:
            raise FmuError(f"{fmu._where} is closed (its simulation has ended)")
        i = self.count
        for get, args in self._rows[i] or self._row(i):
            status = get(*args)
            if status > 1:
                raise FmuError(f"{fmu._where} at t={fmu.t} ticks: reading {self._names} failed with status "
                               f"{_STATUS.get(status, status)}", fmu.log)
        self.times[i] = t
        self.count = i + 1
        if self.count == self.rows:
            self.flush()

    def flush(self) -> None:
        """Hand the samples taken so far to the sinks (in time order), and start a new block."""
        n, self.count = self.count, 0
        if not n:
            return
        times = self.times[:n].copy()
        for block, sinks in self._blocks:
            for j, sink in enumerate(sinks):
                sink(times, block[:n, j].copy())


def _address(function: Any) -> int:
    """The address of a loaded C function."""
    return int(ctypes.cast(function, ctypes.c_void_p).value or 0)


def _put(values: list[Any], i: int, t: int, value: Any) -> None:
    values[i] = value


#: The FMI functions fmpy's FMU classes load, with their ctypes argument and result types, by class: what
#: fmpy's ``_loadFunctions`` works out with ``inspect`` for every instance (~75 signatures, several ms), once.
_FUNCTION_TYPES: dict[type, list[tuple[str, list[str], list[Any], Any]]] = {}


def _load_functions(fmu: Any, load: Callable[[], None]) -> None:
    """fmpy's ``_loadFunctions`` for ``fmu``: run once per class (``load``), then repeated from its record."""
    table = _FUNCTION_TYPES.get(type(fmu))
    if table is None:
        load()
        functions = getattr(fmu, "_functions", None)
        if isinstance(functions, dict):
            _FUNCTION_TYPES[type(fmu)] = [(name, list(getattr(f, "argnames", [])), list(f.argtypes or []), f.restype)
                                          for name, f in functions.items()]
        return
    for name, argnames, argtypes, restype in table:
        c_fun = getattr(fmu.dll, name)
        c_fun.argnames = argnames
        c_fun.argtypes = argtypes
        c_fun.restype = restype
        fmu._functions[name] = c_fun


# (fmpy tells the FMI version from the class name's start: FMU2..., FMU3...)
class FMU2SlaveOnce(FMU2Slave):
    def _loadFunctions(self) -> None:
        _load_functions(self, super()._loadFunctions)


class FMU3SlaveOnce(FMU3Slave):
    def _loadFunctions(self) -> None:
        _load_functions(self, super()._loadFunctions)


class _EventModeRefused(Exception):
    """The FMU declares event mode and refused it at instantiation or in the initial event mode."""
