"""Motion and coordinates: straight moves, arcs in three planes, splines, G10/G28/G30/G52/G92, offsets.

Arc rules, as LinuxCNC 2.9 checks them (numbers in the program's units):

* centre form (``I J K``, incremental unless ``G90.1``): the radii to the start and to the end may
  differ by up to 0.02 * sqrt(2) mm (0.002 * sqrt(2) in) or 0.1 %, whichever is larger; within it
  the arc is a spiral; a radius below 0.0005 mm (0.00005 in) is a zero-radius error;
* radius form (``R``, negative: more than half a turn): the end may be up to 0.005 mm (0.0005 in)
  beyond the diameter; an end on the start is an error;
* ``P`` turns (a whole number >= 1) add full turns; the words of the plane's other axis make a helix.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode.params import Number, integer, show
from cosim.controllers.pokeys.gcode.state import ZERO9
from cosim.controllers.pokeys.gcode.words import WordError, Words, code_name

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

LETTERS = "XYZABCUVW"
#: plane (G x 10) -> (first axis, second axis, normal axis, first offset letter, second offset letter)
PLANE_AXES = {170: (0, 1, 2, "I", "J"), 180: (2, 0, 1, "K", "I"), 190: (1, 2, 0, "J", "K")}
SQRT2 = math.sqrt(2)


class MotionError(WordError):
    """A motion LinuxCNC refuses."""


def ends(interp: Interpreter, w: Words, *, machine: bool = False) -> list[Number]:
    """The end point of a move in program coordinates (absolute, incremental, G53 or polar words)."""
    s = interp.state
    compensating = s.cutter != 400 and s.cutter_radius > 0
    pos = list(s.comp_programmed if compensating else s.position)
    if machine and s.incremental:
        raise MotionError("Cannot use G53 incremental (G91)", w.g_columns.get(0, 0))
    for i, letter in enumerate(LETTERS):
        v = w.values.get(letter)
        if v is None:
            continue
        if machine:
            pos[i] = v - s.origin[i] - s.axis_offset[i] - s.tlo[i]
        elif s.incremental:
            pos[i] = pos[i] + v
        else:
            pos[i] = v
    if w.has("@") or w.has("^"):
        if w.has("X") or w.has("Y"):
            raise MotionError("Cannot use polar coordinates (@ ^) with X or Y words", w.column("@") or w.column("^"))
        x, y = float(s.position[0]), float(s.position[1])
        radius, angle = math.hypot(x, y), math.degrees(math.atan2(y, x))
        if s.incremental:
            if x == 0 and y == 0:
                raise MotionError("Incremental motion with polar coordinates is indeterminate when at the origin",
                                  w.column("@") or w.column("^"))
            radius += float(w.values.get("@", 0))
            angle += float(w.values.get("^", 0))
        else:
            radius = float(w.values["@"]) if w.has("@") else radius
            angle = float(w.values["^"]) if w.has("^") else angle
        pos[0] = radius * math.cos(math.radians(angle))
        pos[1] = radius * math.sin(math.radians(angle))
    return pos


def _feed_check(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    name = code_name("G", code)
    if s.feed_mode == 930:
        if not w.has("F"):
            raise MotionError(f"F word missing with inverse time {name} move (G93 needs F on every feed move)",
                              w.g_columns.get(1, 0))
    elif s.feed == 0:
        raise MotionError(f"Cannot do {name} with zero feed rate (give F > 0)", w.g_columns.get(1, 0))


def straight(interp: Interpreter, w: Words, code: int, *, machine: bool = False) -> None:
    end = ends(interp, w, machine=machine)
    if code == 10:
        _feed_check(interp, w, code)
    if interp.state.cutter != 400 and not machine:
        from cosim.controllers.pokeys.gcode import compensation

        compensation.straight(interp, end, code)
        return
    if code == 10:
        inverse_time_feed(interp, w, _length(interp.state.position, end))
    interp.emit("STRAIGHT_TRAVERSE" if code == 0 else "STRAIGHT_FEED", *end)
    interp.state.position = tuple(end)


def _length(start: tuple[Number, ...] | list[Number], end: tuple[Number, ...] | list[Number]) -> float:
    xyz = math.sqrt(sum(float(end[i] - start[i]) ** 2 for i in (0, 1, 2)))
    if xyz > 0:
        return xyz
    return math.sqrt(sum(float(end[i] - start[i]) ** 2 for i in range(3, 9)))


def inverse_time_feed(interp: Interpreter, w: Words, length: float) -> None:
    """Under G93: the move's feed in units per minute (its length times F), emitted before it."""
    if interp.state.feed_mode == 930:
        interp.emit("SET_FEED_RATE", length * float(w.values["F"]))


def arc(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    name = code_name("G", code)
    if s.plane not in PLANE_AXES:
        raise MotionError(f"{name} in the {code_name('G', s.plane)} plane is not supported (arcs are in G17, G18 or "
                          "G19)", w.g_columns.get(1, 0))
    _feed_check(interp, w, code)
    first, second, normal, off1, off2 = PLANE_AXES[s.plane]
    plane_name = {170: "xy", 180: "xz", 190: "yz"}[s.plane]
    wrong = {"I", "J", "K"} - {off1, off2}
    for letter in wrong:
        if w.has(letter):
            raise MotionError(f"{letter} word given for arc in {plane_name} plane", w.column(letter))
    end = ends(interp, w)
    compensating = s.cutter != 400 and s.cutter_radius > 0 and not s.comp_first
    start = s.comp_programmed if compensating else s.position
    turns = 1
    if w.has("P"):
        p = integer(w.values["P"])
        if p is None or p < 1:
            raise MotionError(f"{name} P{show(w.values['P'])}: P (turns) must be a whole number >= 1", w.column("P"))
        turns = p
    rotation = turns if code == 30 else -turns
    inch = s.units == "inch"
    if w.has("R"):
        if w.has(off1) or w.has(off2):
            raise MotionError(f"{name}: give the centre one way, R or {off1}{off2}", w.column("R"))
        letter1, letter2 = LETTERS[first], LETTERS[second]
        if not w.has(letter1) and not w.has(letter2):
            raise MotionError(f"{letter1} and {letter2} words missing for arc in {plane_name} plane (an R arc needs "
                              "its end point)", w.column("R"))
        center: tuple[Number, Number] = _center_r(name, w.values["R"], (start[first], start[second]),
                                                  (end[first], end[second]), code, 0.0005 if inch else 0.005,
                                                  w.column("R"))
    else:
        if not w.has(off1) and not w.has(off2):
            raise MotionError(f"{off1} and {off2} words missing for arc in {plane_name} plane (give the centre, or R)",
                              w.g_columns.get(1, 0) or min(w.columns.values() or [0]))
        o1, o2 = w.values.get(off1, 0), w.values.get(off2, 0)
        center = (o1, o2) if s.ijk_absolute else (start[first] + o1, start[second] + o2)
        r1 = math.hypot(float(center[0] - start[first]), float(center[1] - start[second]))
        r2 = math.hypot(float(center[0] - end[first]), float(center[1] - end[second]))
        min_radius = 0.00005 if inch else 0.0005
        if r1 < min_radius or r2 < min_radius:
            raise MotionError(f"Zero radius arc: {name} with its centre on its start or end point",
                              w.column(off1) or w.column(off2))
        abs_err = abs(r1 - r2)
        rel_err = abs_err / max(r1, r2)
        tolerance = (0.002 if inch else 0.02) * SQRT2
        if abs_err > tolerance and rel_err > 0.001:
            unit = "in" if inch else "mm"
            raise MotionError(
                f"Radius to end of arc differs from radius to start: {name} start=({a(first)}{float(start[first]):.4f},"
                f"{a(second)}{float(start[second]):.4f}) center=({a(first)}{float(center[0]):.4f},"
                f"{a(second)}{float(center[1]):.4f}) end=({a(first)}{float(end[first]):.4f},"
                f"{a(second)}{float(end[second]):.4f}) r1={r1:.4f} r2={r2:.4f} (allowed: {tolerance:.4g} {unit} or "
                "0.1 %)", w.column(off1) or w.column(off2))
    if interp.state.cutter != 400:
        from cosim.controllers.pokeys.gcode import compensation

        compensation.arc(interp, end, center, rotation, first, second, normal)
        return
    if s.feed_mode == 930:
        r = math.hypot(float(start[first] - center[0]), float(start[second] - center[1]))
        a0 = math.atan2(float(start[second] - center[1]), float(start[first] - center[0]))
        a1 = math.atan2(float(end[second] - center[1]), float(end[first] - center[0]))
        sweep = (a1 - a0) % (2 * math.pi) if rotation > 0 else (a0 - a1) % (2 * math.pi)
        if sweep == 0:
            sweep = 2 * math.pi
        sweep += 2 * math.pi * (abs(rotation) - 1)
        inverse_time_feed(interp, w, math.hypot(r * sweep, float(end[normal] - start[normal])))
    interp.emit("ARC_FEED", end[first], end[second], center[0], center[1], rotation, end[normal], *end[3:])
    s.position = tuple(end)


def a(index: int) -> str:
    return LETTERS[index]


def _center_r(name: str, radius: Number, start: tuple[Number, Number], end: tuple[Number, Number], code: int,
              tolerance: float, column: int) -> tuple[float, float]:
    x0, y0, x1, y1 = (float(v) for v in (*start, *end))
    if (x0, y0) == (x1, y1):
        raise MotionError(f"{name} R{show(radius)}: Current point same as end point of arc (an R arc cannot be a "
                          "full circle: give the centre)", column)
    r = float(radius)
    abs_r = abs(r)
    mx, my = (x1 + x0) / 2, (y1 + y0) / 2
    half = math.hypot(mx - x1, my - y1)
    if half - abs_r > tolerance:
        raise MotionError(f"{name} R{show(radius)}: Arc radius too small to reach end point (the end is "
                          f"{2 * half:.6g} away: R must be at least {half:.6g})", column)
    if abs_r == 0 or half / abs_r > 1 - 1e-12:
        half = abs_r
    if abs_r == 0:
        raise MotionError(f"{name} R0: Arc radius too small to reach end point", column)
    theta = math.atan2(y1 - y0, x1 - x0) + (-math.pi / 2 if (code == 20) == (r > 0) else math.pi / 2)
    offset = abs_r * math.cos(math.asin(half / abs_r))
    return mx + offset * math.cos(theta), my + offset * math.sin(theta)


def spline(interp: Interpreter, w: Words, code: int) -> None:
    """G5 (cubic), G5.1 (quadratic) in the XY plane: ``SPLINE_FEED`` with the control points."""
    s = interp.state
    name = code_name("G", code)
    if s.plane != 170:
        raise MotionError(f"{name} only works in the XY plane (G17)", w.g_columns.get(1, 0))
    if code in (52, 53):
        raise MotionError(f"{name} (NURBS) is not supported: give the curve as G5 splines or lines",
                          w.g_columns.get(1, 0))
    _feed_check(interp, w, code)
    end = ends(interp, w)
    x0, y0 = s.position[0], s.position[1]
    if code == 50:
        if not (w.has("P") and w.has("Q")):
            raise MotionError("G5 needs P and Q (the offsets of the second control point from the end)",
                              w.g_columns.get(1, 0))
        if w.has("I") != w.has("J"):
            raise MotionError("G5: give both I and J, or neither (after a G5 they continue the curve)",
                              w.column("I") or w.column("J"))
        if w.has("I"):
            i, j = w.values["I"], w.values["J"]
        else:
            last = s.cycle_values.get("spline")
            if last is None:
                raise MotionError("G5: I and J are needed on the first spline", w.g_columns.get(1, 0))
            i, j = last[0], last[1]  # type: ignore[index]
        p, q = w.values["P"], w.values["Q"]
        points: tuple[Number, ...] = (x0 + i, y0 + j, end[0] + p, end[1] + q, end[0], end[1])
        s.cycle_values["spline"] = (-p, -q)  # type: ignore[assignment]
    else:
        if not (w.has("I") and w.has("J")):
            raise MotionError("G5.1 needs I and J (the control point's offset from the start)", w.g_columns.get(1, 0))
        points = (x0 + w.values["I"], y0 + w.values["J"], end[0], end[1])
    interp.emit("SPLINE_FEED", 3 if code == 50 else 2, points, *end)
    s.position = tuple(end)


def probe(interp: Interpreter, w: Words, code: int) -> None:
    end = ends(interp, w)
    _feed_check(interp, w, code)
    start = interp.state.position
    distance = math.sqrt(sum(float(end[i] - start[i]) ** 2 for i in range(9)))
    if code in (382, 383) and distance < (0.01 if interp.state.units == "inch" else 0.254):
        raise MotionError(f"{code_name('G', code)}: Start point too close to probe point (closer than 0.01 in)",
                          w.g_columns.get(1, 0))
    interp.emit("STRAIGHT_PROBE", *end)
    interp.note(f"{code_name('G', code)}: the probe is modelled as rs274 and LinuxCNC's preview model it: the move "
                "runs to its end, the machine backs off 0.01 in (0.254 mm) toward the start, #5070 (tripped) is 0")
    interp.params.numbered[5070] = 0
    for i in range(9):
        interp.params.numbered[5061 + i] = end[i]
    backoff = 0.01 if interp.state.units == "inch" else 0.254
    back = list(end)
    for i in range(3):
        back[i] = end[i] + (start[i] - end[i]) * backoff / distance if distance else end[i]
    interp.state.position = tuple(back)


# -- offsets ---------------------------------------------------------------------------------------
def _stored(interp: Interpreter, base: int) -> tuple[Number, ...]:
    return tuple(interp.machine_to_program(interp.params.numbered[base + i]) if i in (0, 1, 2, 6, 7, 8)
                 else interp.params.numbered[base + i] for i in range(9))


def select_coordinates(interp: Interpreter, n: int, *, end: bool = False) -> None:
    s = interp.state
    if n == s.coord and not end:
        return
    base = 5221 + 20 * (n - 1)
    origin = _stored(interp, base)
    s.position = tuple(p + o - n_ for p, o, n_ in zip(s.position, s.origin, origin, strict=True))
    s.origin, s.coord, s.rotation = origin, n, interp.params.numbered[base + 9]
    interp.params.numbered[5220] = n
    interp.emit("SET_G5X_OFFSET", n, *origin)
    if not end:
        interp.emit("SET_G92_OFFSET", *s.axis_offset)
    interp.emit("SET_XY_ROTATION", s.rotation)


def non_modal(interp: Interpreter, w: Words, g0: int) -> None:
    s = interp.state
    axes = w.axes()
    column = w.g_columns.get(0, 0)
    if g0 == 100:
        _g10(interp, w, column)
    elif g0 in (280, 300):
        base = 5161 if g0 == 280 else 5181
        if axes:
            middle = ends(interp, w)
            interp.emit("STRAIGHT_TRAVERSE", *middle)
            s.position = tuple(middle)
        else:
            interp.emit("STRAIGHT_TRAVERSE", *s.position)
        home = _stored(interp, base)
        target = list(s.position)
        for i, letter in enumerate(LETTERS):
            if not axes or letter in axes:
                target[i] = home[i] - s.origin[i] - s.axis_offset[i] - s.tlo[i]
        interp.emit("STRAIGHT_TRAVERSE", *target)
        s.position = tuple(target)
    elif g0 in (281, 301):
        base = 5161 if g0 == 281 else 5181
        for i in range(9):
            machine = s.position[i] + s.origin[i] + s.axis_offset[i] + s.tlo[i]
            interp.params.numbered[base + i] = interp.program_to_machine(machine) if i in (0, 1, 2, 6, 7, 8) \
                else machine
    elif g0 in (520, 920, 921, 922, 923) and s.cutter != 400:
        raise MotionError("Cannot change axis offsets with cutter radius comp", column)
    elif g0 in (520, 920):
        if not axes:
            raise MotionError(f"All axes missing with {code_name('G', g0)} (give the axis words)", column)
        offsets = list(s.axis_offset)
        moved = list(s.position)
        for i, letter in enumerate(LETTERS):
            if letter in axes:
                new = axes[letter] if g0 == 520 else moved[i] + offsets[i] - axes[letter]
                moved[i] = moved[i] + offsets[i] - new
                offsets[i] = new
        _set_axis_offset(interp, tuple(offsets), tuple(moved), store=True)
    elif g0 == 921:
        _set_axis_offset(interp, ZERO9, tuple(p + o for p, o in zip(s.position, s.axis_offset, strict=True)),
                         store=True)
    elif g0 == 922:
        _set_axis_offset(interp, ZERO9, tuple(p + o for p, o in zip(s.position, s.axis_offset, strict=True)),
                         store=False)
    elif g0 == 923:
        offset = _stored(interp, 5211)
        _set_axis_offset(interp, offset, tuple(p + o - n for p, o, n in zip(s.position, s.axis_offset, offset,
                                                                             strict=True)), store=False)


def _set_axis_offset(interp: Interpreter, offset: tuple[Number, ...], position: tuple[Number, ...], *,
                     store: bool) -> None:
    s = interp.state
    s.axis_offset, s.position = offset, position
    if store:
        for i, v in enumerate(offset):
            interp.params.numbered[5211 + i] = interp.program_to_machine(v) if i in (0, 1, 2, 6, 7, 8) else v
        interp.params.numbered[5210] = 1 if any(offset) else 0
    interp.emit("SET_G92_OFFSET", *offset)


def _g10(interp: Interpreter, w: Words, column: int) -> None:
    s = interp.state
    l_ = integer(w.get("L")) if w.has("L") else None
    p = integer(w.get("P")) if w.has("P") else None
    if l_ not in (1, 2, 10, 11, 20):
        raise MotionError("G10 needs L1, L2, L10, L11 or L20", w.column("L") or column)
    if l_ in (2, 20):
        if p is None or not 0 <= p <= 9:
            raise MotionError(f"G10 L{l_} needs P0..P9 (the coordinate system; 0: the active one)",
                              w.column("P") or column)
        n = p or s.coord
        base = 5221 + 20 * (n - 1)
        for i, letter in enumerate(LETTERS):
            v = w.values.get(letter)
            if v is None:
                continue
            value = v if l_ == 2 else s.position[i] + s.origin[i] - v
            interp.params.numbered[base + i] = interp.program_to_machine(value) if i in (0, 1, 2, 6, 7, 8) else value
        if w.has("R"):
            interp.params.numbered[base + 9] = w.values["R"]
        if n == s.coord:
            origin = _stored(interp, base)
            s.position = tuple(pp + o - nn for pp, o, nn in zip(s.position, s.origin, origin, strict=True))
            s.origin = origin
            s.rotation = interp.params.numbered[base + 9]
            interp.emit("SET_G5X_OFFSET", n, *origin)
            interp.emit("SET_XY_ROTATION", s.rotation)
        if s.rotation:
            interp.note("G10 L2 R (a rotated coordinate system) is set; the rotation is applied to the moves")
        return
    if p is None or p < 1:
        raise MotionError(f"G10 L{l_} needs P, a tool number >= 1", w.column("P") or column)
    from cosim.controllers.pokeys.gcode.state import Tool

    old = interp.tools.get(p) or Tool(p)
    z, x, diameter = old.z_offset, old.x_offset, old.diameter
    if w.has("R"):
        diameter = interp.program_to_machine(2 * w.values["R"])
    if l_ == 1:
        if w.has("Z"):
            z = interp.program_to_machine(w.values["Z"])
        if w.has("X"):
            x = interp.program_to_machine(w.values["X"])
    else:
        if w.has("Z"):
            machine_z = s.position[2] + s.tlo[2] + (s.origin[2] + s.axis_offset[2] if l_ == 10 else 0)
            z = interp.program_to_machine(machine_z - w.values["Z"] - (s.origin[2] + s.axis_offset[2]
                                                                        if l_ == 10 else 0))
        if w.has("X"):
            x = interp.program_to_machine(s.position[0] + s.tlo[0] - w.values["X"])
    interp.tools[p] = Tool(p, z, x, diameter, old.pocket)
    interp.emit("SET_TOOL_TABLE_ENTRY", p, z, x, diameter)


def tool_length(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    column = w.g_columns.get(8, 0)
    new = list(ZERO9)
    if code in (430, 432):
        h = integer(w.get("H")) if w.has("H") else s.tool
        if h is None or h < 0:
            raise MotionError("Negative H word used (G43 H needs a tool number)", w.column("H") or column)
        if h and h not in interp.tools:
            raise MotionError(f"Invalid tool number H{h}: not in the tool table", w.column("H") or column)
        tool = interp.tools.get(h)
        if tool is not None:
            new[0] = interp.machine_to_program(tool.x_offset)
            new[2] = interp.machine_to_program(tool.z_offset)
        if code == 432:
            new = [a_ + b for a_, b in zip(new, s.tlo, strict=True)]
    elif code == 431:
        for i, letter in enumerate(LETTERS):
            if letter in w.values:
                new[i] = w.values.pop(letter)
    old = s.tlo
    s.tlo = tuple(new)
    s.tool_length = code
    s.position = tuple(p + o - n for p, o, n in zip(s.position, old, new, strict=True))
    interp.emit("USE_TOOL_LENGTH_OFFSET", *new)


def cutter_comp(interp: Interpreter, w: Words, code: int) -> None:
    from cosim.controllers.pokeys.gcode import compensation

    compensation.switch(interp, w, code)
