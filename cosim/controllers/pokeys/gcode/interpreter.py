"""Interpreting checked G-code blocks into a tool path, as LinuxCNC's interpreter would.

The modal state starts as: no motion mode (axis words before the first ``G0``..``G3`` are an
error), absolute distances (``G90``), the machine's own units, XY plane, no feed, spindle off at
speed 0, no ``G92`` offset. Within a line the words act in RS274/NGC's order: ``F``, ``S``,
``M3``/``M4``/``M5``, ``G4``, ``G17``, ``G20``/``G21``, ``G90``/``G91``, ``G92``, the motion,
``M2``/``M30``. Coordinates and feeds are converted to machine units exactly (1 inch = 25.4 mm).

Errors (``FILE:LINE: reason``), before anything runs: a feed move (``G1``, ``G2``, ``G3``) with no
feed rate yet or ``F0``; axis words with no motion mode; an arc whose end point is off its circle
by more than :data:`ARC_RADIUS_TOLERANCE_MM` (:data:`ARC_RADIUS_TOLERANCE_INCH` in an inch
program; IJ form), whose radius cannot reach its end point or that would be a full circle (R
form), or with a zero radius; ``G4`` without ``P`` or with a negative ``P``; ``G92`` without axis
words; two commands that both want the axis words.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from fractions import Fraction
from math import sqrt

from cosim.controllers.pokeys.gcode.reader import Block, Blocks
from cosim.controllers.pokeys.toolpath import Arc, Line, Pause, Point, Spindle, Step, Toolpath
from cosim.errors import ConfigurationError

MM_PER_INCH = Fraction(254, 10)
UNITS = ("mm", "inch")
ARC_RADIUS_TOLERANCE_MM = Fraction(5, 1000)
"""How far an arc's end may be off the circle through its start in a millimetre program [mm] (LinuxCNC's
``TOLERANCE_MM``); the radius then changes linearly along the arc so that it ends exactly at its end point."""
ARC_RADIUS_TOLERANCE_INCH = Fraction(5, 10000)
"""The same in an inch program [in] (LinuxCNC's ``TOLERANCE_INCH``)."""
AXES = "XYZ"
SPINDLE_OFF = Spindle(False, False, Fraction(0), 0)


@dataclass(frozen=True)
class _State:
    motion: int | None = None
    incremental: bool = False
    scale: Fraction = Fraction(1)  # program units -> machine units
    feed: Fraction | None = None  # program units per minute
    spindle: Spindle = SPINDLE_OFF
    offset: Point = (Fraction(0), Fraction(0), Fraction(0))  # machine = program + offset
    inch: bool = False  # the program's units are inches

    @property
    def tolerance(self) -> Fraction:
        """The arc radius tolerance in machine units."""
        return (ARC_RADIUS_TOLERANCE_INCH if self.inch else ARC_RADIUS_TOLERANCE_MM) * self.scale


def interpret(blocks: Blocks, *, units: str = "mm") -> Toolpath:
    """The tool path of ``blocks`` in machine ``units`` (``mm`` or ``inch``) from the machine origin."""
    if units not in UNITS:
        raise ConfigurationError.out_of_range("units", units, ", ".join(UNITS))
    machine_mm = Fraction(1) if units == "mm" else MM_PER_INCH
    state = _State(inch=units == "inch")
    position: Point = (Fraction(0), Fraction(0), Fraction(0))
    steps: list[Step] = []
    for block in blocks.blocks:
        where = f"{blocks.source}:{block.line}"
        try:
            state, position, end = _block(block, state, position, steps, machine_mm)
        except _Refused as exc:
            raise ConfigurationError(f"{where}: {exc.args[0]}") from None
        if end:
            break
    return Toolpath(tuple(steps), source=blocks.source, skipped=blocks.skipped)


class _Refused(Exception):
    """A block's error, without its place (added by :func:`interpret`)."""


def _block(block: Block, state: _State, position: Point, steps: list[Step],
           machine_mm: Fraction) -> tuple[_State, Point, bool]:
    g = [int(v) for v in block.codes("G")]
    m = [int(v) for v in block.codes("M")]
    axis_words = {a: v for a in AXES if (v := block.get(a)) is not None}
    feed = block.get("F")
    if feed is not None:
        if feed < 0:
            raise _Refused(f"F{_num(feed)}: a feed rate is >= 0")
        state = replace(state, feed=feed)
    speed = block.get("S")
    spindle = state.spindle
    if speed is not None:
        if speed < 0:
            raise _Refused(f"S{_num(speed)}: a spindle speed is >= 0")
        spindle = replace(spindle, speed=speed)
    for code in m:
        if code in (3, 4):
            spindle = replace(spindle, on=True, ccw=code == 4)
        elif code == 5:
            spindle = replace(spindle, on=False, ccw=False)
    if (spindle.on, spindle.ccw, spindle.speed) != (state.spindle.on, state.spindle.ccw, state.spindle.speed):
        spindle = replace(spindle, line=block.line)
        steps.append(spindle)
        state = replace(state, spindle=spindle)
    if 4 in g:
        seconds = block.get("P")
        if seconds is None or seconds < 0:
            raise _Refused("G4 needs P, the dwell time in seconds (>= 0)" if seconds is None
                           else f"G4 P{_num(seconds)}: the dwell time is >= 0 s")
        if axis_words:
            raise _Refused("G4 with axis words: a dwell does not move")
        steps.append(Pause(seconds, block.line))
    elif block.get("P") is not None:
        raise _Refused("P without G4: P is the dwell time of G4")
    for code in g:
        if code in (20, 21):
            program_mm = MM_PER_INCH if code == 20 else Fraction(1)
            state = replace(state, scale=program_mm / machine_mm, inch=code == 20)
        elif code in (90, 91):
            state = replace(state, incremental=code == 91)
        elif code in (0, 1, 2, 3):
            state = replace(state, motion=code)
    if 92 in g:
        if not axis_words:
            raise _Refused("G92 needs axis words: the coordinates the current point gets (e.g. G92 X0 Y0)")
        if any(c in g for c in (0, 1, 2, 3)):
            raise _Refused("G92 and a motion on one line: both would use the axis words")
        offset = list(state.offset)
        for i, a in enumerate(AXES):
            if a in axis_words:
                offset[i] = position[i] - axis_words[a] * state.scale
        return replace(state, offset=(offset[0], offset[1], offset[2])), position, _ends(m)
    arc_words = any(block.get(letter) is not None for letter in "IJR")
    if axis_words or (arc_words and state.motion in (2, 3)):
        position = _motion(block, state, position, axis_words, steps)
    elif arc_words:
        raise _Refused("I, J or R without an arc: they belong to G2 or G3")
    return state, position, _ends(m)


def _ends(m: list[int]) -> bool:
    return 2 in m or 30 in m


def _motion(block: Block, state: _State, position: Point, words: dict[str, Fraction],
            steps: list[Step]) -> Point:
    if state.motion is None:
        raise _Refused("axis words with no motion mode: give G0, G1, G2 or G3 first")
    target = list(position)
    for i, a in enumerate(AXES):
        value = words.get(a)
        if value is None:
            continue
        target[i] = position[i] + value * state.scale if state.incremental else value * state.scale + state.offset[i]
    end: Point = (target[0], target[1], target[2])
    if state.motion == 0:
        steps.append(Line(end, None, block.line))
        return end
    feed = _feed(state, block)
    if state.motion == 1:
        if block.get("R") is not None or block.get("I") is not None or block.get("J") is not None:
            raise _Refused("I, J or R on a straight move (G1): arcs are G2 and G3")
        steps.append(Line(end, feed, block.line))
        return end
    steps.append(_arc(block, state, position, end, feed))
    return end


def _feed(state: _State, block: Block) -> Fraction:
    code = f"G{state.motion}"
    if state.feed is None:
        raise _Refused(f"{code} with no feed rate: give F (units per minute) on or before the first feed move")
    if state.feed == 0:
        raise _Refused(f"{code} with feed rate F0: a feed move needs F > 0")
    return state.feed * state.scale / 60


def _arc(block: Block, state: _State, start: Point, end: Point, feed: Fraction) -> Arc:
    code = f"G{state.motion}"
    clockwise = state.motion == 2
    radius = block.get("R")
    i, j = block.get("I"), block.get("J")
    tolerance = float(state.tolerance)
    if radius is not None and (i is not None or j is not None):
        raise _Refused(f"{code} with both R and I/J: give the centre one way")
    if radius is None and i is None and j is None:
        raise _Refused(f"{code} needs I and J (centre offsets) or R (radius)")
    if radius is None:
        center = (start[0] + (i or 0) * state.scale, start[1] + (j or 0) * state.scale)
        r_start = _dist(start, center)
        r_end = _dist(end, center)
        if r_start == 0:
            raise _Refused(f"{code} with a zero radius: I and J put the centre on the start point")
        if abs(r_end - r_start) > tolerance:
            raise _Refused(f"{code}: the end point is not on the arc: radius to the start {r_start:.6g}, to the end "
                           f"{r_end:.6g} (they differ by {abs(r_end - r_start):.4g}; allowed: {tolerance:g} machine "
                           f"units); centre X{float(center[0]):g} Y{float(center[1]):g}")
        return Arc(end, center, clockwise, feed, block.line)
    r = float(radius * state.scale)
    dx, dy = float(end[0] - start[0]), float(end[1] - start[1])
    chord = sqrt(dx * dx + dy * dy)
    if chord == 0:
        raise _Refused(f"{code} R{_num(radius)} with the end point on the start point: an R arc cannot be a full "
                       "circle (give I and J)")
    if r == 0:
        raise _Refused(f"{code} R0: the radius is not 0")
    half = chord / 2
    if half > abs(r) + tolerance:
        raise _Refused(f"{code} R{_num(radius)}: the radius is too small to reach the end point (the end is "
                       f"{chord:.6g} away: R must be at least {half:.6g})")
    h = sqrt(max(0.0, r * r - half * half))
    # centre to the right of the chord for G2 with R > 0 (an arc of at most half a turn), left for G3
    side = (1 if clockwise else -1) * (1 if r > 0 else -1)
    cx = float(start[0]) + dx / 2 + side * h * dy / chord
    cy = float(start[1]) + dy / 2 - side * h * dx / chord
    return Arc(end, (Fraction(cx), Fraction(cy)), clockwise, feed, block.line)


def _dist(point: Point, center: tuple[Fraction, Fraction]) -> float:
    return sqrt(float((point[0] - center[0]) ** 2 + (point[1] - center[1]) ** 2))


def _num(value: Fraction) -> str:
    return str(value.numerator) if value.denominator == 1 else f"{float(value):g}"
