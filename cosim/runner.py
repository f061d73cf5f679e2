"""Running a scenario: parameters in, trace and verdict out.

:func:`run_scenario` resolves the parameters, builds the simulation through the scenario's
recipe, runs it, evaluates every declared check on the trace and writes the results folder:

``result.json``        scenario, parameter values used, seed, each check, declared hazards, figures, verdict
``trace.vcd``          every signal, for GTKWave and other waveform viewers; ``trace.gtkw`` opens it in
                       GTKWave; ``trace_digital.vcd`` holds the bits and pulse trains for sigrok/PulseView
``*.parquet``          the trace tables (see :mod:`cosim.export`), or ``*.csv`` and ``trace_wide.csv``
``trace_meta.json``    resolution and each signal's kind, unit and description

A long run keeps its trace on disk as it goes (in a temporary folder inside the results folder,
removed when the results are written): see :mod:`cosim.trace`.

The trace is written even when the run fails half-way (nothing recorded is lost), and the
result then carries the error. A plant FMU that asks to end the simulation
(:class:`~cosim.errors.PlantTerminated`) ends the run at that instant with verdict ``TERMINATED``:
the trace up to then is written, the checks are evaluated on it, and ``result.json`` says which
plant ended it, when, why, and its last log messages.
"""

from __future__ import annotations

import json
import math
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cosim.errors import ConfigurationError, CosimError, PlantTerminated, ScenarioError
from cosim.export import write_console, write_trace
from cosim.kernel import Simulation
from cosim.outdir import OutputFolder
from cosim.scenario import Run, ScenarioFile, Values, user_line, where
from cosim.timebase import TimeBase

RESULT_VERSION = 1
#: Console lines (PRINT, SEND, (MSG, ...), job stops) the terminal table shows; all are in console.txt.
CONSOLE_SHOWN = 10


@dataclass
class Result:
    """Outcome of one scenario run (the content of ``result.json``)."""

    scenario: str
    parameters: dict[str, Any]
    seed: int
    until: int
    checks: list[dict[str, Any]] = field(default_factory=list)
    figures: dict[str, dict[str, Any]] = field(default_factory=dict)
    error: str | None = None
    error_kind: str | None = None
    #: The plant that ended the run early: plant, fmu, t_ticks, t_s, reason, log (None if none did).
    terminated: dict[str, Any] | None = None
    #: Set when Ctrl-C or SIGTERM ended the run: signal, t_ticks, t_s (None otherwise).
    interrupted: dict[str, Any] | None = None
    #: What the run told the user besides checks and figures (Run.note), in order.
    notes: list[str] = field(default_factory=list)
    #: Settings that were set, not modelled (``sim.notes.not_modelled``): device, name, value, where.
    not_modelled: list[dict[str, Any]] = field(default_factory=list)
    #: How many console lines the run wrote (``console.txt``).
    console_lines: int = 0
    #: The first :data:`CONSOLE_SHOWN` console lines as the table shows them (``0.125 s  [trio.proc1]  text``).
    console_head: list[str] = field(default_factory=list)
    wall_time_s: float = 0.0
    simulated_s: float = 0.0
    out: Path | None = None

    @property
    def ordinary(self) -> list[dict[str, Any]]:
        """The checks that are not declared hazards."""
        return [c for c in self.checks if not c.get("hazard")]

    @property
    def hazard_checks(self) -> list[dict[str, Any]]:
        """The declared hazards (``run.hazard``): checks expected to fail."""
        return [c for c in self.checks if c.get("hazard")]

    @property
    def passed(self) -> int:
        """Ordinary checks that passed."""
        return sum(1 for c in self.ordinary if c["passed"])

    @property
    def failed(self) -> int:
        """Ordinary checks that failed (a violation, or the check could not be evaluated)."""
        return sum(1 for c in self.ordinary if outcome(c) in ("FAIL", "ERROR"))

    @property
    def unchecked(self) -> int:
        """Ordinary checks that examined nothing (outcome ``UNCHECKED``)."""
        return sum(1 for c in self.ordinary if outcome(c) == "UNCHECKED")

    @property
    def shown(self) -> int:
        """Declared hazards that were shown (their check failed with violations)."""
        return sum(1 for c in self.hazard_checks if hazard_shown(c))

    @property
    def verdict(self) -> str:
        """The run's verdict; the first that applies of:

        ``INTERRUPTED``   Ctrl-C or SIGTERM ended it (what it simulated is written and checked);
        ``ERROR``         the run broke, or a check or figure could not be evaluated;
        ``FAIL``          an ordinary check failed (had a violation);
        ``HAZARD MISSED`` a declared hazard (``run.hazard``) was not shown: its check passed or
                          examined nothing;
        ``UNCHECKED``     an ordinary check examined nothing without ``allow_empty`` (also beside
                          shown hazards: the hazard does not vouch for a check that saw nothing);
        ``HAZARD SHOWN``  every declared hazard was shown: its check failed with violations;
        ``TERMINATED``    a plant ended the run early (no check failed up to then);
        ``UNCHECKED``     no checks; or every check examined nothing (``checked == 0``, even with
                          ``allow_empty``);
        ``PASS``          otherwise: every check passed, and something was checked.
        """
        if self.interrupted is not None:
            return "INTERRUPTED"
        if self.error is not None:
            return "ERROR"
        if self.failed:
            return "FAIL"
        hazards = self.hazard_checks
        if self.shown < len(hazards):
            return "HAZARD MISSED"
        if self.unchecked:
            return "UNCHECKED"
        if hazards:
            return "HAZARD SHOWN"
        if self.terminated is not None:
            return "TERMINATED"
        if not self.checks or self.unchecked or all(int(c["checked"]) == 0 for c in self.checks):
            return "UNCHECKED"
        return "PASS"

    @property
    def hazards(self) -> list[dict[str, Any]]:
        """The declared hazards for ``result.json``: check name, what it shows, whether it was shown."""
        return [{"check": c["name"], "shows": c["hazard"], "shown": hazard_shown(c)} for c in self.hazard_checks]

    def counts(self) -> str:
        """The checks in a few words: ``3/3 checks passed``, ``1/1 hazards shown, 2/2 checks passed``."""
        parts = []
        if self.hazard_checks:
            parts.append(f"{self.shown}/{len(self.hazard_checks)} hazards shown")
        if self.ordinary or not self.checks:
            parts.append(f"{self.passed}/{len(self.ordinary)} checks passed")
        if self.unchecked:
            parts.append(f"{self.unchecked} examined nothing")
        return ", ".join(parts)

    @property
    def real_time_factor(self) -> float:
        return self.simulated_s / self.wall_time_s if self.wall_time_s > 0 else float("inf")

    def to_dict(self) -> dict[str, Any]:
        return {
            "result_version": RESULT_VERSION,
            "scenario": self.scenario,
            "verdict": self.verdict,
            "parameters": self.parameters,
            "seed": self.seed,
            "until_ticks": self.until,
            "summary": {"checks": len(self.checks), "passed": self.passed, "failed": self.failed,
                        "unchecked": self.unchecked, "hazards": len(self.hazard_checks),
                        "hazards_shown": self.shown},
            "hazards": self.hazards,
            "checks": [{**c, "verdict": check_outcome(c)} for c in self.checks],
            "figures": self.figures,
            "error": self.error,
            "terminated": self.terminated,
            "interrupted": self.interrupted,
            "notes": self.notes,
            "not_modelled": self.not_modelled,
            "console_lines": self.console_lines,
            "wall_time_s": round(self.wall_time_s, 4),
            "simulated_s": self.simulated_s,
            "real_time_factor": round(self.real_time_factor, 2),
        }

    def table(self) -> str:
        """Plain-text check table for the terminal."""
        lines = [f"scenario {self.scenario}: {self.verdict}  ({self.counts()}, {self.simulated_s:g} s simulated "
                 f"in {self.wall_time_s:.2f} s)"]
        for check in self.checks:
            lines.append(f"  {check_outcome(check)}  {check['name']}  "
                         f"[{check['checked']} checked, {check['n_violations']} violations]")
            if check.get("hazard"):
                lines.append(f"          hazard: {check['hazard']}")
            if check.get("nothing_checked"):
                lines.append(f"          examined nothing: {check['nothing_checked']}")
            for v in check["violations"][:3]:
                lines.append(f"          at t={v['t_ns']} ns: value {v['value']} vs limit {v['limit']}"
                             + (f" ({v['detail']})" if v.get("detail") else ""))
        for name, fig in self.figures.items():
            shown = "(could not be evaluated: see the error)" if fig["value"] is None else f"{fig['value']:.6g}"
            lines.append(f"  figure {name} = {shown} {fig['unit']}".rstrip())
        for note in self.notes[:10]:
            lines.append(f"  note {note}")
        if len(self.notes) > 10:
            lines.append(f"  ... and {len(self.notes) - 10} more notes in result.json")
        if self.console_lines:
            lines.append(f"  console ({self.console_lines} line{'s' if self.console_lines != 1 else ''}, all in "
                         "console.txt):")
            lines += [f"    {line}" for line in self.console_head]
            if self.console_lines > len(self.console_head):
                lines.append(f"    ... and {self.console_lines - len(self.console_head)} more")
        if self.error:
            lines.append(f"  ERROR {self.error}")
        if self.terminated:
            lines.append(f"  TERMINATED by {self.terminated['plant']} ({self.terminated['fmu']}) at "
                         f"t = {self.terminated['t_s']:g} s: {self.terminated['reason']}")
            lines += [f"    {line}" for line in self.terminated["log"][-5:]]
        return "\n".join(lines)


def outcome(check: dict[str, Any]) -> str:
    """A check entry's outcome, hazard or not: ``PASS``, ``FAIL``, ``UNCHECKED`` or ``ERROR``."""
    if check.get("error"):
        return "ERROR"
    return str(check.get("outcome") or ("PASS" if check["passed"] else "FAIL"))


def hazard_shown(check: dict[str, Any]) -> bool:
    """A declared hazard is shown when its check failed with violations (not when it examined nothing)."""
    return outcome(check) == "FAIL" and int(check["n_violations"]) > 0


def check_outcome(check: dict[str, Any]) -> str:
    """What the table says of one check: its outcome, or ``HAZARD SHOWN``/``HAZARD MISSED`` for a hazard."""
    if check.get("hazard") and outcome(check) != "ERROR":
        return "HAZARD SHOWN" if hazard_shown(check) else "HAZARD MISSED"
    return outcome(check)


def _plain(value: Any) -> Any:
    """JSON-safe copy: numpy scalars to Python, non-finite floats to the strings "inf", "-inf", "nan"."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, str | bytes):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def to_json(data: Any) -> str:
    """Strict JSON (no NaN/Infinity literals) of a result dict, readable by any JSON parser."""
    return json.dumps(_plain(data), indent=1, allow_nan=False)


def run_scenario(scenario: ScenarioFile, *, overrides: dict[str, str] | None = None, seed: int = 0,
                 until: str | int | None = None, out: str | Path | None = None,
                 formats: tuple[str, ...] = ("vcd", "parquet"), progress: bool = False) -> Result:
    """Run ``scenario`` and write its results.

    Parameters
    ----------
    scenario : ScenarioFile
        From :func:`cosim.catalog.load` (a scenario or a machine file).
    overrides : dict, optional
        ``--set`` values, parsed and range-checked against the declared parameters.
    seed : int
        Seed of the simulation's random generator.
    until : str or int, optional
        End time (``"20 ms"`` or ticks); default: the scenario's ``UNTIL``.
    out : path, optional
        Results folder; nothing is written without it.
    progress : bool
        Show a progress bar for runs that take more than two seconds (on a terminal only).

    Raises
    ------
    ConfigurationError, ScenarioError
        Bad parameters or a broken script (before anything runs).
    """
    values = scenario.resolve(overrides)
    with Simulation(seed=seed, timebase=TimeBase(scenario.resolution_for(values))) as sim:
        end = _end_time(sim, until if until is not None else scenario.until_for(values))
        staged = OutputFolder(out) if out is not None else None  # refused or unwritable: before the run
        if staged is not None:
            sim.trace.spool_dir = staged.staging  # a long run spills its trace beside its results, not to /tmp
        sim.trace.meta.update({"scenario": scenario.name, "seed": seed, "parameters": values})
        result = Result(scenario.name, values, seed, end)
        run = Run(sim=sim, p=Values(values), until=end, scenario=scenario.name)
        started = time.perf_counter()
        bar = _progress_bar(sim, end) if progress else None
        stop: int | None = None
        try:
            with interrupts_raise():
                scenario.function(run)
                if sim.now < run.until:  # a scenario that ends on its own may have ended the run early
                    sim.run(until=run.until)
        except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: the run ends here, with what it simulated
            result.interrupted = {"signal": str(exc) or "SIGINT", "t_ticks": sim.now,
                                  "t_s": sim.timebase.seconds(sim.now)}
        except PlantTerminated as exc:  # not a failure: the run ends at the plant's tick
            stop = exc.t
            result.terminated = {"plant": exc.plant, "fmu": exc.fmu, "t_ticks": exc.t,
                                 "t_s": sim.timebase.seconds(exc.t), "reason": exc.reason, "log": list(exc.log)}
        except (ConfigurationError, ScenarioError) as exc:
            result.error, result.error_kind = where(exc, scenario.path) + str(exc), "configuration"
        except CosimError as exc:
            result.error, result.error_kind = where(exc, scenario.path) + str(exc), "run"
        except SystemExit as exc:  # a script that calls sys.exit() ends its run, not cosim
            result.error = where(exc, scenario.path) + f"the scenario called sys.exit({exc.code!r})"
            result.error_kind = "script"
        except Exception as exc:  # a bug in a user's script: say where, keep the trace
            result.error = where(exc, scenario.path) + f"{type(exc).__name__}: {exc}"
            result.error_kind = "script"
        finally:
            if bar is not None:
                _close_progress_bar(bar, sim)
            sim.trace.end_t = sim.now if stop is None else stop
        result.until = run.until
        result.wall_time_s = time.perf_counter() - started
        result.simulated_s = sim.timebase.seconds(sim.trace.end_t)
        if result.error is None:
            _finish(run, result, scenario)
        result.notes = [*run.notes, *sim.notes.texts()]
        result.not_modelled = [item.to_dict() for item in sim.notes.unmodelled()]
        result.console_lines = sim.trace.console_count
        result.console_head = [f"{sim.timebase.seconds(line.t):g} s  [{line.source}]  {line.text}"
                               for line, _ in zip(sim.trace.console(), range(CONSOLE_SHOWN), strict=False)]
        if result.error is None:
            _evaluate(run, result, scenario)
        try:
            if staged is not None:
                write_trace(sim.trace, staged.staging, formats=formats)
                write_console(sim.trace, staged.staging / "console.txt")
                (staged.staging / "result.json").write_text(to_json(result.to_dict()))
        finally:
            sim.trace.discard_spill()
        if staged is not None:
            result.out = staged.commit()
    return result


@contextmanager
def interrupts_raise() -> Iterator[None]:
    """While inside, SIGTERM interrupts like Ctrl-C (KeyboardInterrupt naming the signal); main thread only."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_term(signum: int, _frame: object) -> None:
        raise KeyboardInterrupt("SIGTERM")

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _finish(run: Run, result: Result, scenario: ScenarioFile) -> None:
    """The run's :meth:`~cosim.scenario.Run.afterwards` callbacks (notes on the whole run); one raising is an error."""
    for callback in run.finishers:
        try:
            callback()
        except Exception as exc:
            _first_error(result, where(exc, scenario.path) + f"{type(exc).__name__}: {exc}", "script")


def _evaluate(run: Run, result: Result, scenario: ScenarioFile) -> None:
    """Every check and figure on its own: one that raises is an error entry, the others still count.

    The error names the line that raised in the user's code (a custom check's ``evaluate``), else
    where the check or figure was declared.
    """
    for spec, declared, shows in zip(run.checks, run.declared, run.hazards, strict=True):
        try:
            result.checks.append({**spec.evaluate(run.sim.trace).to_dict(), "hazard": shows})
        except Exception as exc:
            place = user_line(exc, scenario.path) or declared
            text = f"{place}check {_label(spec)}: {exc.args[0] if isinstance(exc, KeyError) else exc}"
            if not isinstance(exc, KeyError | CosimError):
                text = f"{place}check {_label(spec)}: {type(exc).__name__}: {exc}"
            result.checks.append({"name": _label(spec), "outcome": "ERROR", "passed": False, "checked": 0,
                                  "n_violations": 0, "violations": [], "measured": {}, "error": text,
                                  "hazard": shows})
            _first_error(result, text, "configuration" if isinstance(exc, KeyError | ConfigurationError) else "run")
    for name, (value, unit) in run.figures.items():
        declared_at = run.figure_declared.get(name)
        try:
            number = value() if callable(value) else value
            result.figures[name] = {"value": _number(number), "unit": unit}
        except Exception as exc:
            place = user_line(exc, scenario.path) or (f"{declared_at}: " if declared_at else "")
            text = place + f"figure {name}: {type(exc).__name__}: {exc}"
            result.figures[name] = {"value": None, "unit": unit, "error": text}
            _first_error(result, text, "script")


def _number(value: object) -> float:
    """A figure's value as a float; a value that is not a number is refused naming it (not float('abc'))."""
    if not isinstance(value, int | float) and not hasattr(value, "__float__"):
        raise TypeError(f"the value {value!r} is a {type(value).__name__}, not a number")
    return float(value)


def _label(spec: object) -> str:
    return str(getattr(spec, "label", None) or getattr(spec, "name", None) or type(spec).__name__)


def _first_error(result: Result, text: str, kind: str) -> None:
    if result.error is None:
        result.error, result.error_kind = text, kind


def _end_time(sim: Simulation, until: str | int) -> int:
    if isinstance(until, int):
        return sim.timebase.check_ticks(until, name="until", minimum=1)
    try:
        number = float(until)
    except ValueError:
        pass
    else:
        if not math.isfinite(number):
            raise ConfigurationError.out_of_range("until", until, "a finite time > 0 with a unit, e.g. '20 ms'")
        # a bare number: a time needs its unit
        raise ConfigurationError.out_of_range("until", until, f"a time with a unit: did you mean \"{until} s\"?")
    end = sim.ticks(until, name="until")
    if end <= 0:
        raise ConfigurationError.out_of_range("until", until, "a time > 0, e.g. '20 ms'")
    return end


def _progress_bar(sim: Simulation, end: int) -> Any:
    """A bar of simulated time on stderr, only on a terminal and only for runs longer than two seconds.

    Not on a terminal (a pipe, a log file, CI) there is no bar at all: carriage returns would run
    the bars and the results together. A bar that was shown stays, ending with a newline.
    """
    import sys

    if not sys.stderr.isatty():
        return None
    from tqdm import tqdm

    total_ms = sim.timebase.seconds(end) * 1e3
    bar = tqdm(total=round(total_ms, 3), delay=2.0, unit="ms", desc="simulated", leave=True, file=sys.stderr,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.1f}/{total} ms [{elapsed}<{remaining}]")

    def update(now: int) -> None:
        # tqdm.update, not refresh: refresh() draws at once, before the two-second delay, and
        # close() then believes the bar was never shown and leaves it without its newline.
        now_ms = round(sim.timebase.seconds(now) * 1e3, 3)
        if now_ms > bar.total:  # a scenario that runs on past UNTIL until its job is done
            bar.total = now_ms
        bar.update(now_ms - bar.n)

    sim.env.on_progress = update
    return bar


def _close_progress_bar(bar: Any, sim: Simulation) -> None:
    """Show where the run stopped (the last progress call may be earlier), then close the bar."""
    update = sim.env.on_progress
    if update is not None:
        update(sim.now)
    bar.close()
