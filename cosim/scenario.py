"""Scenario scripts: linear recipes with declared parameters and checks.

A scenario is a Python file (bundled ones live in :mod:`cosim.scenarios`) with

* a module docstring (first line = the one-line description shown by ``cosim list``, which reads
  it without running the file: see :func:`description`),
* ``PARAMETERS``: a tuple of :class:`Param` (name, default, unit, allowed range, help),
* ``UNTIL``: default end time (a string with a unit or ticks),
* ``def scenario(run: Run) -> None``: create plants and controllers, connect signals, declare
  checks and figures, in that order, top to bottom. It may call ``run.run_until(t)`` for
  phases (never past the end: ``--until`` shorter than the phases is refused); whatever is left
  is run to ``UNTIL`` by the runner, then the checks are evaluated. A scenario that ends on its
  own (when its job is done) runs with ``run.run_job(done, step=...)`` and gives a safety limit as
  ``UNTIL``; ``--until`` then stops it earlier.
* the finding it demonstrates, if it is a hazard scenario: ``run.hazard(check, shows="...")``, a
  check written as the healthy rule that is expected to fail (verdict ``HAZARD SHOWN``).

Example (ten lines)::

    \"\"\"Laser on for 1 ms at 40 % duty.\"\"\"
    from cosim.scenario import Param, Run
    PARAMETERS = (Param("pwm_on", 400, "clocks", (0, 65535), "on-time per period"),)
    UNTIL = "2 ms"

    def scenario(run: Run) -> None:
        laser = run.plant("Laser", name="laser")
        laser.set({"enable": True, "gate": True, "pwm_period": 1000, "pwm_on": run.p.pwm_on})
        run.figure("energy_J", lambda: laser.read("energy"), "J")
"""

from __future__ import annotations

import ast
import math
import sys
import traceback
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Protocol

from cosim.errors import ConfigurationError, ScenarioError

if TYPE_CHECKING:  # imported where used, so that `cosim list` and `cosim params` need no fmpy
    from cosim.fmu import Value
    from cosim.kernel import Simulation
    from cosim.master import Plant

BUNDLED = Path(__file__).resolve().parent / "scenarios"

#: How a parameter's type is named in messages ("is not an integer").
_KIND_NAMES = {bool: "a flag (true/false, on/off, yes/no, 1/0)", int: "an integer", float: "a number",
               str: "a string"}


@dataclass(frozen=True)
class Param:
    """A declared scenario parameter.

    Parameters
    ----------
    name : str
        Identifier used with ``--set NAME=VALUE``.
    default : int, float, bool or str
        Default value; its type is the parameter's type.
    unit : str
        Unit of the value (``""`` for counts and flags).
    range : tuple, optional
        ``(low, high)`` inclusive bounds for numbers, or a tuple of allowed values for strings.
    help : str
        One line for ``cosim params``.
    """

    name: str
    default: int | float | bool | str
    unit: str = ""
    range: tuple[Any, ...] | None = None
    help: str = ""

    def allowed(self) -> str:
        """The allowed range as text."""
        if self.range is None:
            return {bool: "true, false", int: "any integer", float: "any number", str: "any text"}.get(
                type(self.default), "any " + type(self.default).__name__)
        if isinstance(self.default, str):
            return ", ".join(map(str, self.range))
        low, high = self.range
        return f"{low}..{high}" + (f" {self.unit}" if self.unit else "")

    def parse(self, text: str | Value) -> int | float | bool | str:
        """Convert and range-check a value (text from ``--set`` or a Python value)."""
        kind = type(self.default)
        try:
            if kind is bool:
                value: int | float | bool | str = (
                    text if isinstance(text, bool) else str(text).lower() in ("1", "true", "on", "yes"))
                if not isinstance(text, bool) and str(text).lower() not in (
                        "0", "1", "true", "false", "on", "off", "yes", "no"):
                    raise ValueError(text)
            elif kind is int:
                value = int(str(text), 0) if isinstance(text, str) else int(text)
                if isinstance(text, float) and not text.is_integer():
                    raise ValueError(text)
            elif kind is float:
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError(text)
            else:
                value = str(text)
        except ValueError:
            raise ConfigurationError(
                f"parameter {self.name} = {text!r} is not {_KIND_NAMES.get(kind, kind.__name__)} "
                f"(allowed: {self.allowed()})"
            ) from None
        if self.range is not None:
            ok = value in self.range if isinstance(self.default, str) else (
                self.range[0] <= value <= self.range[1])
            if not ok:
                raise ConfigurationError.out_of_range(f"parameter {self.name}", value, self.allowed())
        return value


class Values:
    """Attribute access to the resolved parameter values; unknown names name the declared ones."""

    def __init__(self, values: Mapping[str, Any]) -> None:
        self._values = dict(values)

    def __getattr__(self, name: str) -> Any:
        try:
            return self._values[name]
        except KeyError:
            raise ScenarioError(
                f"the scenario uses parameter {name!r}, which it does not declare in PARAMETERS "
                f"(declared: {', '.join(self._values) or 'none'})"
            ) from None

    def as_dict(self) -> dict[str, Any]:
        """All values, by name."""
        return dict(self._values)


class CheckSpec(Protocol):
    """Anything with ``evaluate(trace) -> CheckResult`` (see :mod:`cosim.checks`)."""

    def evaluate(self, trace: Any) -> Any: ...


@dataclass
class Run:
    """What a scenario function gets: the simulation, its parameters, and ways to add things.

    Attributes
    ----------
    sim : Simulation
    p : Values
        Parameter values (``run.p.pwm_on``).
    until : int
        End time [ticks].
    """

    sim: Simulation
    p: Values
    until: int
    checks: list[CheckSpec] = field(default_factory=list)
    #: Where each check was declared (``file:line: `` of the caller), for messages after the run.
    declared: list[str] = field(default_factory=list)
    #: For each check, the hazard it shows when it fails (:meth:`hazard`), or None for an ordinary check.
    hazards: list[str | None] = field(default_factory=list)
    #: The scenario's name, for messages.
    scenario: str = ""
    figures: dict[str, tuple[Callable[[], float] | float, str]] = field(default_factory=dict)
    #: Where each figure was declared (``file:line`` or ``file: key``), for messages after the run.
    figure_declared: dict[str, str] = field(default_factory=dict)
    plants: list[Plant] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: Called once the simulation has ended, before the notes are collected (:meth:`afterwards`).
    finishers: list[Callable[[], None]] = field(default_factory=list)

    def plant(self, model: str | Path, *, name: str, fmi_version: int = 3, preset: str | None = None,
              parameters: Mapping[str, Value] | None = None) -> Plant:
        """Add a plant FMU (bundled model name or ``.fmu`` path), optionally from a preset."""
        from cosim.master import Plant

        values: dict[str, Value] = {}
        if preset is not None:
            from cosim.presets import load_preset

            values.update(load_preset(preset))
        values.update(parameters or {})
        plant = Plant.load(self.sim, model, name=name, fmi_version=fmi_version, parameters=values)
        self.plants.append(plant)
        return plant

    def check(self, spec: CheckSpec, *, where: str | None = None) -> None:
        """Declare a check, evaluated on the trace after the run.

        ``where`` says where it was declared, for messages after the run (default: the calling
        line of the script, ``file:line``).
        """
        self._declare(spec, where, None)

    def hazard(self, spec: CheckSpec, *, shows: str, where: str | None = None) -> None:
        """Declare the finding the scenario exists to demonstrate: a check that is expected to fail.

        ``spec`` is written as the healthy machine's rule ("the buffer never runs empty"), so that the
        scenario's fixed twin can declare the same rule with :meth:`check` and pass. ``shows`` says in
        one line what the hazard is. The hazard is *shown* when the check fails with violations; if it
        passes, or examines nothing, the hazard is *missed* (verdicts ``HAZARD SHOWN`` and
        ``HAZARD MISSED``: see :attr:`cosim.runner.Result.verdict`).
        """
        if not str(shows).strip():
            raise ConfigurationError("run.hazard(shows=''): say in one line what the hazard is")
        self._declare(spec, where, str(shows).strip())

    def _declare(self, spec: CheckSpec, where: str | None, shows: str | None) -> None:
        if where is None:
            caller = sys._getframe(2)
            where = f"{caller.f_code.co_filename}:{caller.f_lineno}"
        self.checks.append(spec)
        self.declared.append(f"{where}: ")
        self.hazards.append(shows)

    def note(self, text: str) -> None:
        """Tell the user something about the run that is neither a check nor a figure (in result.json and the table).

        E.g. a G-code line the planner slowed down, or a skipped unsupported word.
        """
        self.notes.append(str(text))

    def figure(self, name: str, value: Callable[[], float] | float, unit: str = "", *,
               where: str | None = None) -> None:
        """Declare a key figure for the summary (a callable is evaluated after the run).

        ``where`` says where it was declared, for a value that is not a number (default: the calling
        line of the script, ``file:line``).
        """
        if where is None:
            caller = sys._getframe(1)
            where = f"{caller.f_code.co_filename}:{caller.f_lineno}"
        self.figures[name] = (value, unit)
        self.figure_declared[name] = where

    def afterwards(self, callback: Callable[[], None]) -> None:
        """Call ``callback`` once the simulation has ended, before the notes are collected.

        For what can only be said of the whole run, from its trace: a laser that never fired, an
        axis that never moved (:meth:`note` it there).
        """
        self.finishers.append(callback)

    def job(self, controller: Any, *, shows: str | None = None, ends: str | None = None,
            where: str | None = None) -> bool:
        """Declare that ``controller``'s job must complete, and the figure ``job_s`` (when it ended [s]).

        The check is :class:`cosim.checks.JobCompleted` on the controller's ``<device>.job`` signal
        (``controller.job``, a :class:`cosim.job.Job`): every program reached its end, without a
        limit, emergency or error stop. ``job_s`` is the instant the job ended (nan if it did not).

        Parameters
        ----------
        controller : object
            A controller with a ``job``; one without declares nothing (returns False).
        shows : str, optional
            The scenario demonstrates that the job does *not* complete: the check is declared as
            this hazard (:meth:`hazard`): ``HAZARD SHOWN`` when the job stops.
        ends : {'error', 'limit', 'emergency', 'aborted'}, optional
            With ``shows``: the stop that shows it; a second, ordinary check then requires the job
            to end in that stop (a job that stops otherwise, or completes, is a ``FAIL``).
        where : str, optional
            Where it was declared, for messages (default: the calling line).
        """
        from cosim.checks import JobCompleted
        from cosim.checks.job import ENDS, job_end_t

        job = getattr(controller, "job", None)
        if job is None:
            return False
        if where is None:
            caller = sys._getframe(1)
            where = f"{caller.f_code.co_filename}:{caller.f_lineno}"
        signal = job.signal.name
        if ends is not None:
            if shows is None:
                raise ConfigurationError(f"{where}: a job's expected stop (ends = {ends!r}) is a hazard the "
                                         "scenario shows: say which with shows = \"...\"")
            from cosim import validate

            validate.choice(ends, "ends", tuple(e for e in ENDS if e != "done"), where=where)
        healthy = JobCompleted(signal, name=f"the {signal.rpartition('.')[0]} job completed")
        if shows is None:
            self.check(healthy, where=where)
        else:
            self.hazard(healthy, shows=shows, where=where)
            if ends is not None:
                self.check(JobCompleted(signal, ends=ends, name=f"the {signal.rpartition('.')[0]} job ends in a "
                                                                 f"{ends} stop"), where=where)
        trace, timebase = self.sim.trace, self.sim.timebase

        def ended() -> float:
            t = job_end_t(trace, signal)
            return float("nan") if t is None else timebase.seconds(t)

        self.figure("job_s", ended, "s", where=where)
        return True

    def run_until(self, t: int) -> None:
        """Run the simulation to tick ``t`` (for scenarios with phases).

        Raises
        ------
        ConfigurationError
            ``t`` is past the run's end (``--until`` shorter than the scenario's phases): the run is
            refused rather than run past the end the user asked for.
        """
        if t > self.until:
            tb = self.sim.timebase
            raise ConfigurationError(
                f"scenario {self.scenario or '?'}: until = {tb.seconds(self.until):g} s is not allowed "
                f"(allowed: at least {tb.seconds(t):g} s: the scenario runs in phases to that time)")
        if t > self.sim.now:
            self.sim.run(until=t)

    def run_job(self, done: Callable[[], bool], *, step: int, what: str = "the job") -> bool:
        """Run in steps of ``step`` [ticks] until ``done()`` is true or the run's end; True if the job is done.

        For scenarios that end on their own (their ``UNTIL`` is then a safety limit): the run ends
        when the job is done (``until`` becomes that instant: the runner runs no further), or at
        ``--until`` if that comes first. A job cut short by the end gets a note saying so (``what``
        names the job in it): checks of the whole job then fail, they do not pass on part of it.
        """
        if not done() and self.sim.now < self.until:  # one run: a recorder's open stretch is not cut at each step
            self.sim.run(until=self.until, stop_when=done, every=step)
        if done():
            self.until = self.sim.now
            return True
        self.note(f"the run ended at {self.sim.timebase.seconds(self.sim.now):g} s (until) before {what} "
                  "ended: checks of the whole job do not hold for the part simulated")
        return False


@dataclass(frozen=True)
class ScenarioFile:
    """A loaded scenario script."""

    name: str
    path: Path
    description: str
    parameters: tuple[Param, ...]
    until: str | int
    function: Callable[[Run], None]

    def until_for(self, values: Mapping[str, Any]) -> str | int:
        """The end time of a run with these parameter values (``UNTIL``)."""
        return self.until

    def resolution_for(self, values: Mapping[str, Any]) -> Fraction:
        """The simulation's resolution [s per tick] for a run with these values (1 ns)."""
        return Fraction(1, 10**9)

    def resolve(self, overrides: Mapping[str, str | Value] | None = None) -> dict[str, Any]:
        """Default parameter values with ``overrides`` parsed and range-checked."""
        declared = {p.name: p for p in self.parameters}
        values = {p.name: p.default for p in self.parameters}
        for name, text in (overrides or {}).items():
            if name not in declared:
                raise ConfigurationError(
                    f"scenario {self.name} has no parameter {name!r} "
                    f"(its parameters: {', '.join(declared) or 'none'}; see `cosim params {self.name}`)"
                )
            values[name] = declared[name].parse(text)
        return values


def bundled() -> list[str]:
    """Names of the bundled scenarios."""
    return sorted(p.stem for p in BUNDLED.glob("*.py") if not p.stem.startswith("_"))


def description(name_or_path: str | Path) -> str:
    """The one-line description of a scenario (first line of its docstring), without running it.

    The file is parsed, not imported, so listing scenarios costs milliseconds and needs neither
    fmpy nor the controllers. A file that does not parse gets an empty description (``cosim run``
    reports the syntax error with its line).
    """
    path = _path(name_or_path)
    try:
        doc = ast.get_docstring(ast.parse(path.read_bytes(), str(path))) or ""
    except (SyntaxError, ValueError, OSError):
        return ""
    return doc.strip().splitlines()[0] if doc.strip() else ""


def load(name_or_path: str | Path) -> ScenarioFile:
    """Load a bundled scenario by name or a scenario script by path.

    Raises
    ------
    ScenarioError
        With file and line for a syntax error or a script that fails on import.
    ConfigurationError
        If no such scenario exists.
    """
    path = _path(name_or_path)
    module = _import(path)
    function = getattr(module, "scenario", None)
    if not callable(function):
        raise ScenarioError(f"{path}: defines no function `scenario(run)`")
    doc = (module.__doc__ or "").strip()
    params = tuple(getattr(module, "PARAMETERS", ()))
    for p in params:
        if not isinstance(p, Param):
            raise ScenarioError(f"{path}: PARAMETERS must hold cosim.scenario.Param objects, got {p!r}")
        p.parse(p.default)
    return ScenarioFile(name=path.stem, path=path.resolve(), description=doc.splitlines()[0] if doc else "",
                        parameters=params, until=getattr(module, "UNTIL", "10 ms"), function=function)


def _path(name_or_path: str | Path) -> Path:
    """The file of a bundled scenario name or a script path; ConfigurationError if there is none."""
    path = Path(name_or_path)
    if path.suffix != ".py":
        path = BUNDLED / f"{name_or_path}.py"
        if not path.exists():
            raise ConfigurationError(
                f"no bundled scenario named {name_or_path!r} (bundled: {', '.join(bundled())}); "
                "give a path to a .py scenario script or a .toml machine file for your own"
            )
    if not path.is_file():
        folder = " (it is a folder)" if path.is_dir() else ""
        raise ConfigurationError(f"scenario file {path} does not exist{folder}")
    return path


def _import(path: Path) -> ModuleType:
    try:
        source = path.read_bytes()  # as bytes: Python reads a `# -*- coding: latin-1 -*-` line itself
    except OSError as exc:
        raise ConfigurationError(f"{path}: cannot read the scenario file ({exc.strerror or exc})") from None
    try:
        code = compile(source, str(path), "exec")
    except SyntaxError as exc:
        if (exc.msg or "").startswith("(unicode error)"):
            raise ScenarioError(f"{path}:{exc.lineno}: not UTF-8 text: {exc.msg.removeprefix('(unicode error) ')} "
                                "(save the file as UTF-8, or name its encoding on its first line, e.g. "
                                "# -*- coding: latin-1 -*-)") from None
        line = (exc.text or "").rstrip()
        raise ScenarioError(f"{path}:{exc.lineno}: syntax error: {exc.msg}\n    {line}") from None
    except ValueError as exc:  # a NUL byte in the source
        raise ScenarioError(f"{path}: not a Python scenario file ({exc})") from None
    module = ModuleType(f"cosim_scenario_{path.stem}")
    module.__file__ = str(path)
    sys.modules[module.__name__] = module  # dataclasses and pickling look modules up here
    try:
        exec(code, module.__dict__)
    except Exception as exc:
        del sys.modules[module.__name__]
        raise ScenarioError(where(exc, path) + f"{type(exc).__name__}: {exc}") from exc
    return module


def user_line(exc: BaseException, path: Path) -> str:
    """``file:line: `` of the innermost frame of ``exc`` in the user's code, or ``""``.

    The user's code is the scenario file ``path`` (as :func:`where`), else any Python file outside
    cosim's package, the standard library and the installed packages: a custom check's module.
    """
    found = where(exc, path)
    if found:
        return found
    import sysconfig

    ours = [str(Path(__file__).resolve().parent)] + [
        str(Path(p).resolve()) for key in ("stdlib", "platstdlib", "purelib", "platlib")
        if (p := sysconfig.get_paths().get(key))]

    def users(name: str) -> str | None:
        return None if name.startswith("<") or any(str(Path(name).resolve()).startswith(o) for o in ours) else name

    return _innermost(exc, users)


def where(exc: BaseException, path: Path) -> str:
    """``file:line: `` of the innermost frame of ``exc`` (or its causes) in the scenario ``path``.

    SimPy re-raises a failed process's exception as a copy whose cause is the original, so the
    chain of causes is searched too.
    """
    target = str(path.resolve())
    return _innermost(exc, lambda name: str(path) if str(Path(name).resolve()) == target else None)


def _innermost(exc: BaseException, shown: Callable[[str], str | None]) -> str:
    """``file:line: `` of the innermost frame of ``exc`` whose file ``shown`` names (None: not one of those),
    searching its causes too when it has none; ``""`` when no frame is."""
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        location = ""
        for frame, line in traceback.walk_tb(current.__traceback__):
            name = shown(frame.f_code.co_filename)
            if name is not None:
                location = f"{name}:{line}: "
        if location:
            return location
        current = current.__cause__ or current.__context__
    return ""
