"""A tool path in machine coordinates: what a G-code program asks of the host planner.

The G-code reader (:mod:`~cosim.controllers.pokeys.gcode`) turns a program into these records;
the planner (:func:`~cosim.controllers.pokeys.planner.plan_toolpath`) turns them into per-slot
counts. Coordinates are exact fractions in the machine's units (mm or inch, after ``G20``/``G21``
and ``G92`` are applied; rotary axes A, B, C in degrees), feeds are in machine units per second
along the move's *feed axes* (:func:`feed_axes`); every record carries the program line it comes
from, for the planner's notes.

A point has a coordinate for each axis of the tool path (:attr:`Toolpath.axes`): x, y, z, then
the other axes the machine drives (``"xyzab"``: x, y, z, a, b).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

Point = tuple[Fraction, ...]
"""x, y, z, then the tool path's other axes (:attr:`Toolpath.axes`) [machine units; degrees for a, b, c]."""
LINEAR_GROUPS = ("xyz", "uvw")
"""The axis groups whose lengths are the path length of a feed (in this order), before the rotary a, b, c."""


def feed_axes(start: Point, end: Point, axes: str = "xyz") -> str:
    """The axes along which a move's feed is measured, as LinuxCNC's reference says it.

    "If any of XYZ are moving, F is in units per minute in the XYZ cartesian system ...
    otherwise, if any of UVW are moving, F is in units per minute in the UVW cartesian system ...
    otherwise, the move is pure rotary motion and the F word is in rotary units in the ABC
    pseudo-cartesian system" (LinuxCNC 2.9, "Feed Rate"). ``axes`` names the points'
    coordinates; the result is the letters of the group (``"xyz"``, ``"uvw"`` or ``"abc"``),
    ``""`` when nothing moves.
    """
    moving = {name for name, a, b in zip(axes, start, end, strict=False) if a != b}
    for group in (*LINEAR_GROUPS, "abc"):
        if moving & set(group):
            return group
    return ""


@dataclass(frozen=True)
class Line:
    """A straight move to ``end``: a feed move at ``feed`` [units/s along its :func:`feed_axes`; degrees/s for a
    pure rotary move], or a rapid (``feed`` None)."""

    end: Point
    feed: Fraction | None
    line: int


@dataclass(frozen=True)
class Arc:
    """A circular (helical) move from the current point to ``end`` around ``center``, in ``plane``.

    ``plane`` is ``"xy"`` (G17), ``"zx"`` (G18) or ``"yz"`` (G19); ``center`` is the centre's
    coordinates on the plane's first and second axes (x, y for G17; z, x for G18; y, z for G19)
    [units]; ``clockwise`` is G2, seen from the positive normal axis. A full circle has ``end``
    equal to the start on the plane's axes; ``turns`` > 1 adds full turns (G2/G3 ``P``); the
    normal axis moves linearly with the angle (a helix). When the end radius differs from the
    start radius (within the reader's tolerance) the radius changes linearly with the angle.
    """

    end: Point
    center: tuple[Fraction, Fraction]
    clockwise: bool
    feed: Fraction
    line: int
    plane: str = "xy"
    turns: int = 1


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


@dataclass(frozen=True)
class Output:
    """An output of the host that changes between two moves: ``<engine>.<name>`` gets ``value``.

    Names: ``coolant_flood``, ``coolant_mist`` (M7, M8, M9), ``tool`` (the tool in the spindle,
    M6, M61), ``tool_changing`` (1 during a tool change), ``paused`` (1 during an M0/M1/M60
    pause), ``waiting`` (1 while an M66 waits on an input), ``dout<n>`` and ``aout<n>`` (M62-M65,
    M67, M68).
    """

    name: str
    value: float
    line: int


@dataclass(frozen=True)
class PathControl:
    """How the moves from here on meet (G61, G61.1, G64 P): ``mode`` and ``tolerance`` [units].

    ``mode`` is ``"exact_stop"`` (G61.1: every move ends at rest), ``"exact_path"`` (G61: a corner
    that is not straight on is passed at rest) or ``"blend"`` (G64: corners at the junction-deviation
    speed of ``tolerance``; ``None``: the machine file's ``path_tolerance``).
    """

    mode: str
    tolerance: Fraction | None
    line: int


@dataclass(frozen=True)
class Message:
    """A ``(MSG, ...)``, ``(DEBUG, ...)`` or ``(PRINT, ...)`` text: the run's console shows it when the
    host reaches it (the moves before it end there, as at any output)."""

    kind: str
    text: str
    line: int


WAIT_MODES = ("immediate", "rise", "fall", "high", "low")
"""M66's wait types by their L number (LinuxCNC's reference)."""


@dataclass(frozen=True)
class Wait:
    """The program waits for an input of the machine: the moves before it end at rest, then the host waits.

    ``input`` is the input's name on the engine (``din<n>``, ``ain<n>``: M66 P/E; ``cycle_start``:
    the operator's resume of an M0/M1/M60 pause); ``mode`` M66's wait type (0 immediate: read once,
    1 rise, 2 fall, 3 high, 4 low; :data:`WAIT_MODES`); ``timeout`` [s] (None: none); ``reads``: the
    program goes on with the value read (M66's ``#5399``: the input, or -1 after the timeout).
    """

    input: str
    mode: int
    timeout: Fraction | None
    line: int
    reads: bool = True


Step = Line | Arc | Pause | Spindle | Output | PathControl | Message | Wait


@dataclass(frozen=True)
class Toolpath:
    """A program's moves in order, from ``start`` [units], with the source name for messages.

    ``axes`` names the coordinates of every point: ``"xyz"``, or x, y, z and the other axes the
    machine drives (``"xyza"``). ``start`` has a coordinate for each (missing ones are 0).
    """

    steps: tuple[Step, ...]
    source: str = "program"
    start: Point = (Fraction(0), Fraction(0), Fraction(0))
    skipped: tuple[str, ...] = field(default=())
    """Words skipped under ``allow_unsupported`` (``file:line:column: word ...; word skipped``)."""
    notes: tuple[str, ...] = field(default=())
    """What the program sets that is accepted and not modelled."""
    ending: str = "M2"
    """How the program ended: ``M2``, ``M30``, ``%``, or ``""`` (the file ended without any of them)."""
    axes: str = "xyz"
    """The axes of the points: x, y, z, then the machine's other axes in the engine's order."""

    @property
    def end(self) -> Point:
        """Where the program ends [units]."""
        for step in reversed(self.steps):
            if isinstance(step, Line | Arc):
                return step.end
        return self.start
