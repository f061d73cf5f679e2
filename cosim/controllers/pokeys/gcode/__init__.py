"""G-code programs for the PoKeys host: the milling and engraving subset LinuxCNC users write.

``read_program(text)`` and ``load_program(path)`` parse and check a program and interpret it into a
:class:`~cosim.controllers.pokeys.toolpath.Toolpath` in machine units; the host planner
(:func:`~cosim.controllers.pokeys.planner.plan_toolpath`) turns that into slots. The supported
words are listed in :mod:`.reader`, the interpretation rules in :mod:`.interpreter`. Every error
names the file and the line: ``pocket.nc:12: G5 is not supported (supported: G0, G1, ...)``.
"""

from __future__ import annotations

from pathlib import Path

from cosim.controllers.pokeys.gcode.interpreter import ARC_RADIUS_TOLERANCE_MM, MM_PER_INCH, UNITS, interpret
from cosim.controllers.pokeys.gcode.reader import Block, Blocks, Word, read_file, read_text
from cosim.controllers.pokeys.toolpath import Toolpath


def read_program(text: str, *, source: str = "program.nc", units: str = "mm",
                 allow_unsupported: bool = False) -> Toolpath:
    """The tool path of G-code ``text`` in machine ``units`` (``mm`` or ``inch``)."""
    return interpret(read_text(text, source=source, allow_unsupported=allow_unsupported), units=units)


def load_program(path: str | Path, *, units: str = "mm", allow_unsupported: bool = False) -> Toolpath:
    """The tool path of the G-code file ``path`` (errors name ``path:line``)."""
    return interpret(read_file(path, allow_unsupported=allow_unsupported), units=units)


__all__ = ["ARC_RADIUS_TOLERANCE_MM", "MM_PER_INCH", "UNITS", "Block", "Blocks", "Toolpath", "Word", "interpret",
           "load_program", "read_file", "read_program", "read_text"]
