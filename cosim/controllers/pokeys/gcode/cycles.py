"""Canned cycles G73, G74, G81-G89 in the G17, G18 and G19 planes, with G98/G99 and L repeats.

As LinuxCNC runs them: the cycle switches to exact path (``G61``) for its moves and back after;
if the tool is below the R plane it first rises to it; then for each of ``L`` repeats (the XY
point moves by X/Y each time under ``G91``) it rapids over the hole at the clearance height, down
to R, runs the cycle's body and retracts to the clearance height: the initial height under
``G98`` (if above R), R under ``G99``. Under ``G91`` R is measured from the initial height and Z
from R. ``G83`` retracts to R between pecks and rapids back to 0.254 mm (0.010 in) above the
last depth; ``G73`` backs off 0.254 mm (0.010 in) only.

``G87`` (back boring) and ``G88`` (boring, spindle stop, manual retract) are documented by
LinuxCNC 2.9 as "accepted, behaviour undefined"; they run here as its ``rs274`` runs them.
``G87``: from R over the hole, the tool moves to the offset point (the plane's offset words, ``I
J`` in G17, relative to the hole), the spindle stops and is oriented, the tool goes down to the
bottom there and back over the hole, the spindle starts, the cut is fed up to the back-bore height
(the depth axis' offset word, ``K`` in G17; from the bottom under ``G91``) and down to the bottom
again, the spindle stops and is oriented, the tool returns to the offset point and rises there to
the clearance height, comes back over the hole and the spindle starts. ``G88``: feed to the bottom,
dwell ``P``, stop the spindle, program stop (the operator retracts by hand: the next move starts
from the bottom), restart the spindle. ``G74``, ``G84``, ``G86``-``G88`` need the spindle turning
(``G74`` counter-clockwise, ``G84`` clockwise), as LinuxCNC checks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode.motion import ends
from cosim.controllers.pokeys.gcode.params import Number, integer, show
from cosim.controllers.pokeys.gcode.words import WordError, Words, code_name

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

#: plane -> (first axis, second axis, the cycle's depth axis) indices in x..w
CYCLE_AXES = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}
#: plane -> G87's offset words of the plane's first and second axes
OFFSET_LETTERS = {170: ("I", "J"), 180: ("K", "I"), 190: ("J", "K")}
#: direction of the spindle (1 clockwise, -1 counter-clockwise) -> ORIENT_SPINDLE's mode (CANON_CLOCKWISE 2, ..)
ORIENT_MODE = {1: 2, -1: 3}
PECK_CLEARANCE_INCH = 0.010


def cycle(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    name = code_name("G", code)
    if s.cutter != 400:
        raise WordError(f"Cannot use {name} with cutter radius compensation on", w.g_columns.get(1, 0))
    if s.plane not in CYCLE_AXES:
        raise WordError(f"{name} in the {code_name('G', s.plane)} plane is not supported", w.g_columns.get(1, 0))
    first, second, depth = CYCLE_AXES[s.plane]
    letters = "XYZABCUVW"
    values = s.cycle_values
    for letter in "RPQIJK" if code == 870 else "RPQ":
        if w.has(letter):
            values[letter] = w.values[letter]
    depth_letter = letters[depth]
    if w.has(depth_letter):
        values["depth"] = w.values[depth_letter]
    if "R" not in values:
        raise WordError(f"R clearance plane unspecified in canned cycle {name}", w.g_columns.get(1, 0))
    if "depth" not in values:
        raise WordError(f"{depth_letter} value unspecified in canned cycle {name}", w.g_columns.get(1, 0))
    if s.feed == 0 and s.feed_mode != 930:
        raise WordError(f"Cannot do {name} with zero feed rate (give F > 0)", w.g_columns.get(1, 0))
    repeats = 1
    if w.has("L"):
        n = integer(w.values["L"])
        if n is None or n < 0:
            raise WordError(f"{name} L{show(w.values['L'])}: L (repeats) must be a whole number >= 0", w.column("L"))
        if n == 0:
            raise WordError("Cannot do zero repeats of cycle", w.column("L"))
        repeats = n
    if code in (730, 830):
        q = values.get("Q")
        if q is None or q <= 0:
            raise WordError(f"Q word missing or not positive with {name} (the peck depth)", w.g_columns.get(1, 0))
    if code in (820, 860, 880, 890, 740, 840) and values.get("P", 0) < 0:
        raise WordError(f"{name} P{show(values['P'])}: the dwell is >= 0 s", w.column("P"))
    _spindle_check(interp, w, code, name)
    if code == 870:
        for letter in "IJK":
            if letter not in values:
                raise WordError(f"{letter} word missing with {name.lower()}", w.g_columns.get(1, 0))
    pos = list(s.position)
    old_cc = pos[depth]
    initial = s.cycle_old_z
    if s.incremental:
        r = initial + values["R"]
        bottom = r + values["depth"]
    else:
        r = values["R"]
        bottom = values["depth"]
    if bottom > r:
        raise WordError(f"{name}: the bottom ({depth_letter}{show(bottom)}) is above the R plane (R{show(r)})",
                        w.column(depth_letter) or w.g_columns.get(1, 0))
    clear = r if s.retract == 990 else max(r, initial)
    cc = old_cc
    if initial < r:
        pos[depth] = r
        interp.emit("STRAIGHT_TRAVERSE", *pos)
        cc = r
    interp.emit("SET_MOTION_CONTROL_MODE", "EXACT_PATH", 0)
    a1, a2 = letters[first], letters[second]
    polar = w.has("@") or w.has("^")
    for k in range(repeats):
        if polar:
            s.position = tuple(pos)
            point = ends(interp, w)
            pos[first], pos[second] = point[first], point[second]
        elif s.incremental:
            pos[first] = pos[first] + w.values.get(a1, 0)
            pos[second] = pos[second] + w.values.get(a2, 0)
        else:
            if a1 in w.values:
                pos[first] = w.values[a1]
            if a2 in w.values:
                pos[second] = w.values[a2]
        for i, letter in enumerate(letters):
            if i not in (first, second, depth) and letter in w.values:
                pos[i] = w.values[letter] if not s.incremental else pos[i] + (w.values[letter] if k == 0 else 0)
        pos[depth] = cc
        interp.emit("STRAIGHT_TRAVERSE", *pos)
        if cc != r:
            pos[depth] = r
            interp.emit("STRAIGHT_TRAVERSE", *pos)
        if code == 870:
            _back_bore(interp, values, pos, (first, second, depth), bottom, clear)
        else:
            _body(interp, code, pos, depth, r, bottom, clear, values)
        pos[depth] = clear
        cc = clear
    s.position = tuple(pos)
    _restore_mode(interp)


def _body(interp: Interpreter, code: int, pos: list[Number], depth: int, r: Number, bottom: Number,
          clear: Number, values: dict[str, Number]) -> None:
    s = interp.state

    def feed(z: Number) -> None:
        pos[depth] = z
        interp.emit("STRAIGHT_FEED", *pos)

    def rapid(z: Number) -> None:
        pos[depth] = z
        interp.emit("STRAIGHT_TRAVERSE", *pos)

    delta = PECK_CLEARANCE_INCH * (25.4 if s.units == "mm" else 1)
    if code in (810, 820):
        feed(bottom)
        if code == 820:
            interp.emit("DWELL", values.get("P", 0))
        rapid(clear)
    elif code in (730, 830):
        q = values["Q"]
        current = r
        while current - q > bottom:
            current = current - q
            feed(current)
            if code == 830:
                rapid(r)
                rapid(current + delta)
            else:
                rapid(current + delta)
        feed(bottom)
        rapid(clear)
    elif code in (850, 890):
        feed(bottom)
        if code == 890:
            interp.emit("DWELL", values.get("P", 0))
        feed(r)
        if clear != r:
            rapid(clear)
    elif code == 880:
        feed(bottom)
        interp.emit("DWELL", values.get("P", 0))
        interp.emit("STOP_SPINDLE_TURNING", 0)
        interp.emit("PROGRAM_STOP")
        _spindle_back(interp)
        interp.note("G88 (boring, manual retract): the operator's retract is not simulated; the move after the "
                    "pause starts from the bottom of the hole")
    elif code == 860:
        feed(bottom)
        interp.emit("DWELL", values.get("P", 0))
        interp.emit("STOP_SPINDLE_TURNING", 0)
        rapid(clear)
        _spindle_back(interp)
    elif code in (840, 740):
        interp.emit("DISABLE_FEED_OVERRIDE")
        interp.emit("DISABLE_SPEED_OVERRIDE", 0)
        feed(bottom)
        interp.emit("STOP_SPINDLE_TURNING", 0)
        interp.emit("START_SPINDLE_COUNTERCLOCKWISE" if code == 840 else "START_SPINDLE_CLOCKWISE", 0)
        interp.emit("DWELL", values.get("P", 0))
        feed(r)
        interp.emit("STOP_SPINDLE_TURNING", 0)
        _spindle_back(interp)
        interp.emit("ENABLE_FEED_OVERRIDE")
        interp.emit("ENABLE_SPEED_OVERRIDE", 0)
        if clear != r:
            rapid(clear)
        interp.note(f"{'G84' if code == 840 else 'G74'} (tapping): the spindle reversal is signalled; the feed is "
                    "not synchronised with the spindle")


def _spindle_check(interp: Interpreter, w: Words, code: int, name: str) -> None:
    """LinuxCNC's errors for the cycles that need the spindle turning (its messages, its spelling)."""
    spindle = interp.state.spindle
    column = w.g_columns.get(1, 0)
    if code in (740, 840, 860, 870, 880) and spindle == 0:
        raise WordError(f"Spindle not turning in {name if code in (740, 840) else name.lower()}", column)
    if code == 740 and spindle == 1:
        raise WordError("Spindle turning clockwise in G74", column)
    if code == 840 and spindle == -1:
        raise WordError("Spindle turning counterclockwise in G84", column)


def _back_bore(interp: Interpreter, values: dict[str, Number], pos: list[Number], axes: tuple[int, int, int],
               bottom: Number, clear: Number) -> None:
    """G87 from R over the hole, as rs274 runs it (see the module text)."""
    s = interp.state
    first, second, depth = axes
    letter1, letter2 = OFFSET_LETTERS[s.plane]
    height = values["IJK"[depth]]
    top = bottom + height if s.incremental else height
    hole = (pos[first], pos[second])
    offset = (hole[0] + values[letter1], hole[1] + values[letter2])
    start = "START_SPINDLE_CLOCKWISE" if s.spindle == 1 else "START_SPINDLE_COUNTERCLOCKWISE"

    def go(name: str, at: tuple[Number, Number], z: Number) -> None:
        pos[first], pos[second], pos[depth] = at[0], at[1], z
        interp.emit(name, *pos)

    def stop_and_orient() -> None:
        interp.emit("STOP_SPINDLE_TURNING", 0)
        interp.emit("ORIENT_SPINDLE", 0, 0, ORIENT_MODE[s.spindle])

    go("STRAIGHT_TRAVERSE", offset, pos[depth])
    stop_and_orient()
    go("STRAIGHT_TRAVERSE", offset, bottom)
    go("STRAIGHT_TRAVERSE", hole, bottom)
    interp.emit(start, 0)
    go("STRAIGHT_FEED", hole, top)
    go("STRAIGHT_FEED", hole, bottom)
    stop_and_orient()
    go("STRAIGHT_TRAVERSE", offset, bottom)
    go("STRAIGHT_TRAVERSE", offset, clear)
    go("STRAIGHT_TRAVERSE", hole, clear)
    interp.emit(start, 0)


def _spindle_back(interp: Interpreter) -> None:
    s = interp.state
    if s.spindle == 1:
        interp.emit("START_SPINDLE_CLOCKWISE", 0)
    elif s.spindle == -1:
        interp.emit("START_SPINDLE_COUNTERCLOCKWISE", 0)


def _restore_mode(interp: Interpreter) -> None:
    s = interp.state
    mode = {611: "EXACT_STOP", 610: "EXACT_PATH", 640: "CONTINUOUS"}[s.path]
    interp.emit("SET_MOTION_CONTROL_MODE", mode, s.path_p if s.path == 640 else 0)
    interp.emit("SET_NAIVECAM_TOLERANCE", s.path_q)
