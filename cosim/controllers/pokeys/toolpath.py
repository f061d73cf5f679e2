"""A tool path in machine coordinates: what a G-code program asks of the host planner.

The G-code reader (:mod:`~cosim.controllers.pokeys.gcode`) turns a program into these records;
the planner (:func:`~cosim.controllers.pokeys.planner.plan_toolpath`) turns them into per-slot
counts. Coordinates are exact fractions in the machine's units (mm or inch, after ``G20``/``G21``
and ``G92`` are applied), feeds are in machine units per second; every record carries the program
line it comes from, for the planner's notes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

Point = tuple[Fraction, Fraction, Fraction]
"""x, y, z [machine units]."""


@dataclass(frozen=True)
class Line:
    """A straight move to ``end``: a feed move at ``feed`` [units/s], or a rapid (``feed`` None)."""

    end: Point
    feed: Fraction | None
    line: int


@dataclass(frozen=True)
class Arc:
    """A circular (helical) move in the XY plane from the current point to ``end`` around ``center``.

    ``center`` is (x, y) [units]; ``clockwise`` is G2. A full circle has ``end`` equal to the start
    in x and y; z moves linearly with the angle (a helix). When the end radius differs from the
    start radius (within the reader's tolerance) the radius changes linearly with the angle.
    """

    end: Point
    center: tuple[Fraction, Fraction]
    clockwise: bool
    feed: Fraction
    line: int


@dataclass(frozen=True)
class Pause:
    """``G4``: stand still for ``seconds`` [s]."""

    seconds: Fraction
    line: int


@dataclass(frozen=True)
class Spindle:
    """The spindle (or laser) outputs from here on: ``on`` (M3/M4 vs M5), ``ccw`` (M4), ``speed`` (S)."""

    on: bool
    ccw: bool
    speed: Fraction
    line: int


Step = Line | Arc | Pause | Spindle


@dataclass(frozen=True)
class Toolpath:
    """A program's moves in order, from ``start`` [units], with the source name for messages."""

    steps: tuple[Step, ...]
    source: str = "program"
    start: Point = (Fraction(0), Fraction(0), Fraction(0))
    skipped: tuple[str, ...] = field(default=())
    """Lines skipped under ``allow_unsupported`` (``file:line: word ... skipped``)."""

    @property
    def end(self) -> Point:
        """Where the program ends [units]."""
        for step in reversed(self.steps):
            if isinstance(step, Line | Arc):
                return step.end
        return self.start
