"""G-code programs for the PoKeys host, as LinuxCNC 2.9 interprets them.

The front end is in layers, each a module with one job::

    text ──syntax.py──> SourceLine (words, parameter settings, O-word; values unevaluated)
         ──flow.py────> SourceFile (a file parsed whole, O-word labels indexed; subroutine files)
         ──interpreter.py (+ ocode, words, params, execute, motion, cycles, compensation, messages)──> CanonProgram
                        (canonical calls named and shaped like rs274's: STRAIGHT_FEED, ARC_FEED, ...)
         ──program.py──> Toolpath (machine coordinates and units: moves, pauses, outputs, path control)
         ──pathplan.plan_toolpath──> per-slot counts

:func:`load_program` and :func:`read_program` run the whole chain to a
:class:`~cosim.controllers.pokeys.toolpath.Toolpath`; :func:`canonical` stops at the canonical
program. Every refusal is a :class:`~cosim.errors.ConfigurationError` naming ``file:line:column``
and the construct: ``pocket.nc:12:4: G38.2 needs a probe input: add probe = true to [host] ...``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from pathlib import Path

from cosim.controllers.pokeys.gcode.canon import Canon, CanonProgram
from cosim.controllers.pokeys.gcode.flow import ProgramError, SourceFile, parse_text, read_source
from cosim.controllers.pokeys.gcode.interpreter import Interpreter
from cosim.controllers.pokeys.gcode.program import HostSetup, toolpath
from cosim.controllers.pokeys.gcode.state import MM_PER_INCH, Tool
from cosim.controllers.pokeys.toolpath import Toolpath
from cosim.errors import ConfigurationError

UNITS = ("mm", "inch")


def canonical(source: SourceFile, *, units: str = "mm", tools: Sequence[Tool] = (),
              search_path: Sequence[str | Path] = (), allow_unsupported: bool = False, probe: bool = False,
              axes: str = "xyzabc", block_delete: bool = False, no_axis: Mapping[str, str] | None = None
              ) -> CanonProgram:
    """The canonical program of a parsed file on a machine in ``units`` (``ConfigurationError`` if refused).

    ``axes`` are the axis letters the machine has; a word of another axis is refused with
    ``no_axis[letter]`` as the reason (what the machine lacks: the model has not got the axis, or
    the machine file does not tune it).
    """
    if units not in UNITS:
        raise ConfigurationError.out_of_range("units", units, ", ".join(UNITS))
    interp = Interpreter(machine_units=units, tools=tools, search_path=search_path,
                         allow_unsupported=allow_unsupported, probe=probe, axes=axes, block_delete=block_delete,
                         no_axis=no_axis)
    try:
        return interp.run(source)
    except ProgramError as exc:
        raise ConfigurationError(str(exc)) from None


def read_text(text: str, *, source: str = "program.nc") -> SourceFile:
    """Parse G-code ``text`` whole (``ConfigurationError`` at the first line that is not G-code)."""
    try:
        return parse_text(text, source)
    except ProgramError as exc:
        raise ConfigurationError(str(exc)) from None


def read_file(path: str | Path) -> SourceFile:
    """Read and parse a G-code file."""
    try:
        return read_source(path)
    except ProgramError as exc:
        raise ConfigurationError(str(exc)) from None


def read_program(text: str, *, source: str = "program.nc", units: str = "mm", allow_unsupported: bool = False,
                 host: HostSetup | None = None, **options: object) -> Toolpath:
    """The tool path of G-code ``text`` on a machine in ``units`` (``mm`` or ``inch``)."""
    program = canonical(read_text(text, source=source), units=units, allow_unsupported=allow_unsupported,
                        **options)  # type: ignore[arg-type]
    return toolpath(program, host or HostSetup(units=units))


def load_program(path: str | Path, *, units: str = "mm", allow_unsupported: bool = False,
                 host: HostSetup | None = None, **options: object) -> Toolpath:
    """The tool path of the G-code file ``path`` (errors name ``path:line:column``)."""
    program = canonical(read_file(path), units=units, allow_unsupported=allow_unsupported,
                        **options)  # type: ignore[arg-type]
    return toolpath(program, host or HostSetup(units=units))


__all__ = ["MM_PER_INCH", "UNITS", "Canon", "CanonProgram", "Fraction", "HostSetup", "Interpreter", "SourceFile",
           "Tool", "Toolpath", "canonical", "load_program", "read_file", "read_program", "read_text", "toolpath"]
