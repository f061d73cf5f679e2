"""One line's words executed in RS274/NGC's order (:data:`~.interpreter.ORDER`)."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode import cycles, motion
from cosim.controllers.pokeys.gcode.flow import ProgramError, Stop
from cosim.controllers.pokeys.gcode.params import Number, integer, show
from cosim.controllers.pokeys.gcode.state import MM_PER_INCH, State
from cosim.controllers.pokeys.gcode.words import WordError, Words

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

MAX_DWELL_S = 86_400
"""The longest dwell simulated [s] (a day; the engine would hold that many empty slots)."""
PLANES = {170: "XY", 180: "XZ", 190: "YZ", 171: "UV", 181: "WU", 191: "VW"}
FEED_MODES = {940: 0, 930: 1, 950: 2}


def block(interp: Interpreter, w: Words) -> None:
    s = interp.state
    g, m = w.g, w.m
    if 5 in g:
        s.feed_mode = g[5]
        interp.emit("SET_FEED_MODE", 0, FEED_MODES[g[5]])
        if g[5] != 930:
            s.feed = 0
            interp.emit("SET_FEED_RATE", 0)
    if w.has("F"):
        f = w.values["F"]
        if f < 0:
            raise WordError(f"Negative F word found: F{show(f)}", w.column("F"))
        s.feed = f
        if s.feed_mode != 930:
            interp.emit("SET_FEED_RATE", f)
    if w.has("S"):
        speed = w.values["S"]
        if speed < 0:
            raise WordError(f"Negative spindle speed used: S{show(speed)}", w.column("S"))
        s.speed = speed
        interp.emit("SET_SPINDLE_SPEED", 0, speed)
    if w.has("T"):
        tool = integer(w.values["T"])
        if tool is None or tool < 0:
            raise WordError(f"Negative tool number or not an integer: T{show(w.values['T'])}", w.column("T"))
        if tool and tool not in interp.tools:
            raise WordError(f"Requested tool {tool} not found in the tool table (add a [[host.tool]] table for "
                            "it to the machine file)", w.column("T"))
        s.selected = tool
        interp.emit("SELECT_TOOL", tool)
    if 5 in m:
        _io(interp, w, m[5])
    if 6 in m:
        _tool_change(interp, w, m[6])
    if 7 in m:
        code = m[7]
        if code == 3:
            s.spindle = 1
            interp.emit("START_SPINDLE_CLOCKWISE", 0)
        elif code == 4:
            s.spindle = -1
            interp.emit("START_SPINDLE_COUNTERCLOCKWISE", 0)
        elif code == 5:
            s.spindle = 0
            interp.emit("STOP_SPINDLE_TURNING", 0)
        else:
            _orient(interp, w)
    if 11 in m:
        _state_save(interp, m[11])
    if 8 in m:
        code = m[8]
        if code == 7:
            s.mist = True
            interp.emit("MIST_ON")
        elif code == 8:
            s.flood = True
            interp.emit("FLOOD_ON")
        else:
            s.mist = s.flood = False
            interp.emit("MIST_OFF")
            interp.emit("FLOOD_OFF")
    if 9 in m:
        _overrides(interp, w, m[9])
    if g.get(0) == 40:
        p = w.get("P")
        if p is None or p < 0:
            raise WordError("Dwell time missing with G4 (G4 P seconds, P >= 0)" if p is None else
                            f"Dwell time P{show(p)} is negative", w.g_columns[0])
        if p > MAX_DWELL_S:
            raise WordError(f"G4 P{show(p)}: a dwell of more than {MAX_DWELL_S} s is not simulated", w.column("P"))
        interp.emit("DWELL", p)
    if 2 in g:
        s.plane = g[2]
        if g[2] not in (170, 180, 190):
            interp.note(f"G{g[2] // 10}.1 ({PLANES[g[2]]} plane): arcs in it are not modelled")
        interp.emit("SELECT_PLANE", PLANES[g[2]])
    if 6 in g:
        _units(interp, "inch" if g[6] == 200 else "mm")
    if 7 in g:
        motion.cutter_comp(interp, w, g[7])
    if 8 in g:
        motion.tool_length(interp, w, g[8])
    if 12 in g:
        motion.select_coordinates(interp, {540: 1, 550: 2, 560: 3, 570: 4, 580: 5, 590: 6, 591: 7, 592: 8,
                                           593: 9}[g[12]])
    if 13 in g:
        _path_control(interp, w, g[13])
    if 3 in g:
        s.incremental = g[3] == 910
    if 4 in g:
        s.ijk_absolute = g[4] == 901
    if 10 in g:
        s.retract = g[10]
    if 14 in g:
        s.css = g[14] == 960
        interp.emit("SET_SPINDLE_MODE", 0, w.get("D") or 0 if s.css else 0)
        if s.css:
            interp.note("G96 (constant surface speed) is accepted and not modelled: the spindle speed is S")
    if 15 in g:
        s.lathe = g[15]
        interp.note(f"G{g[15] // 10} (lathe diameter/radius mode) is accepted and not modelled on a mill")
    g0 = g.get(0)
    if g0 in (100, 280, 281, 300, 301, 520, 920, 921, 922, 923):
        motion.non_modal(interp, w, g0)
    if 1 in g:
        if g[1] != s.motion and 730 <= g[1] <= 890:
            s.cycle_values = {}
            s.cycle_old_z = s.position[{170: 2, 180: 1, 190: 0}.get(s.plane, 2)]
        s.motion = g[1]
        if g[1] == 800:
            s.cycle_r = None
            s.cycle_values = {}
    axes = w.axes()
    polar = w.has("@") or w.has("^")
    uses_axes = g0 in (100, 280, 300, 520, 920)
    explicit = 1 in g and g[1] != 800
    if not uses_axes and (axes or polar or explicit
                          or (s.motion in (20, 30) and (w.has("I") or w.has("J") or w.has("K")))):
        _motion(interp, w, g0 == 530)
    elif g0 == 530 and not axes:
        raise WordError("G53 needs axis words (and G0 or G1)", w.g_columns[0])
    if 4 in m:
        _stop(interp, m[4])


def _motion(interp: Interpreter, w: Words, machine: bool) -> None:
    s = interp.state
    code = s.motion
    if code == 800:
        raise WordError("Cannot use axis values without a G code that uses them (G80 is in effect: give G0, G1, "
                        "G2 or G3)", min(w.columns.values() or [0]))
    if machine and code not in (0, 10):
        raise WordError("Must use G0 or G1 with G53", w.g_columns[0])
    if code in (0, 10):
        motion.straight(interp, w, code, machine=machine)
    elif code in (20, 30):
        motion.arc(interp, w, code)
    elif code in (50, 51, 52, 53):
        motion.spline(interp, w, code)
    elif code in (382, 383, 384, 385):
        motion.probe(interp, w, code)
    elif 730 <= code <= 890:
        cycles.cycle(interp, w, code)
    else:  # pragma: no cover - refused before
        raise WordError(f"G{code / 10:g} is not supported", w.g_columns.get(1, 0))


def _io(interp: Interpreter, w: Words, code: int) -> None:
    p, e, q = w.get("P"), w.get("E"), w.get("Q")
    if code in (62, 63, 64, 65):
        n = integer(p) if p is not None else None
        if n is None or n < 0:
            raise WordError(f"M{code} needs P, the output number (>= 0)", w.m_columns[5])
        name = {62: "SET_MOTION_OUTPUT_BIT", 63: "CLEAR_MOTION_OUTPUT_BIT", 64: "SET_AUX_OUTPUT_BIT",
                65: "CLEAR_AUX_OUTPUT_BIT"}[code]
        interp.emit(name, n)
    elif code in (67, 68):
        n = integer(e) if e is not None else None
        if n is None or n < 0 or q is None:
            raise WordError(f"M{code} needs E, the analog output number, and Q, its value", w.m_columns[5])
        interp.emit("SET_MOTION_OUTPUT_VALUE" if code == 67 else "SET_AUX_OUTPUT_VALUE", n, q)
    else:  # M66
        _wait(interp, w)


def _wait(interp: Interpreter, w: Words) -> None:
    """M66 P- | E- L- Q-, with LinuxCNC's checks and messages (rs274 2.9's wording)."""
    p, e, q, l_ = w.get("P"), w.get("E"), w.get("Q"), w.get("L")
    column = w.m_columns[5]
    if p is not None and e is not None:
        raise WordError("Invalid to select both a digital and an analog input with M66", column)
    number = p if p is not None else e
    if number is None or number < 0:
        raise WordError("Need to have either a valid P or a valid E word with M66", column)
    index = integer(number)
    if index is None:
        raise WordError(f"M66 {'P' if p is not None else 'E'}{show(number)}: the input number is a whole number",
                        column)
    mode = integer(l_) if l_ is not None else 0
    if mode is None or not 0 <= mode <= 4:
        raise WordError(f"M66 L{show(l_ or 0)}: the wait type is 0 (immediate), 1 (rise), 2 (fall), 3 (high) or "
                        "4 (low)", w.column("L"))
    if e is not None and mode != 0:
        raise WordError("Can't select analog input with wait type != immediate return", column)
    timeout = q if q is not None and mode != 0 else 0
    if mode != 0 and timeout <= 0:
        raise WordError("Zero timeout with wait type != immediate return", column)
    digital = p is not None
    if interp.inputs is not None:
        kind = "digital" if digital else "analog"
        count = interp.inputs[kind]
        if index >= count:
            have = f"{kind} inputs 0..{count - 1}" if count else f"no {kind} inputs"
            raise WordError(f"M66 {'P' if digital else 'E'}{index}: the machine has {have} (host.{kind}_inputs = "
                            f"{count} in the machine file; a [[stimulus]] drives each)", column)
    interp.emit("WAIT", index, 1 if digital else 0, mode, timeout)
    if interp.inputs is not None:
        interp.suspended = True  # #5399 is the input as read when the motion before has ended: run() returns
    else:
        interp.params.numbered[5399] = 0  # as rs274 without a machine: its inputs read 0


def _orient(interp: Interpreter, w: Words) -> None:
    """M19 R- Q- P-: ORIENT_SPINDLE(0, R, P) when R or P is given, WAIT_ORIENT_COMPLETE(Q) when Q is (rs274 2.9)."""
    r, p, q = w.get("R"), w.get("P"), w.get("Q")
    column = w.m_columns[7]
    if r is not None and not 0 <= r <= 360:
        raise WordError("R value must be within 0..360 with M19", column)
    if p is not None and p not in (0, 1, 2):
        raise WordError("P value must be 0,1,or 2 with M19", column)
    if r is not None or p is not None:
        interp.emit("ORIENT_SPINDLE", 0, r if r is not None else 0, int(p or 0))
        interp.note("M19 (orient spindle) is signalled; the spindle's angle is not modelled")
    if q is not None:
        if q <= 0:
            raise WordError("Q word with M19 requires a value > 0", column)
        interp.emit("WAIT_ORIENT_COMPLETE", 0, q)


def _tool_change(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    if code == 6 and s.cutter != 400:
        raise WordError("Cannot change tools with cutter radius compensation on", w.m_columns[6])
    if code == 6:
        if s.selected < 0:
            interp.note("M6 with no tool selected (T) keeps the tool")
            return
        interp.emit("START_CHANGE")
        interp.emit("STOP_SPINDLE_TURNING", 0)
        s.spindle = 0
        interp.emit("CHANGE_TOOL", s.selected)
        s.tool = s.selected
        interp.params.numbered[5400] = s.tool
        tool = interp.tools.get(s.tool)
        interp.params.numbered[5410] = tool.diameter if tool else 0
        return
    q = w.get("Q")
    n = integer(q) if q is not None else None
    if n is None or n < 0:
        raise WordError("M61 needs Q, a tool number (>= 0)", w.m_columns[6])
    if n and n not in interp.tools:
        raise WordError(f"Requested tool {n} not found in the tool table (add a [[host.tool]] table for it "
                        "to the machine file)", w.m_columns[6])
    s.tool = n
    interp.params.numbered[5400] = n
    interp.emit("CHANGE_TOOL_NUMBER", n)


def _overrides(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    p = w.get("P")
    on = True if p is None else p != 0
    if code in (48, 49):
        s.feed_override = s.speed_override = code == 48
        verb = "ENABLE" if code == 48 else "DISABLE"
        interp.emit(f"{verb}_FEED_OVERRIDE")
        interp.emit(f"{verb}_SPEED_OVERRIDE", 0)
    elif code == 50:
        s.feed_override = on
        interp.emit("ENABLE_FEED_OVERRIDE" if on else "DISABLE_FEED_OVERRIDE")
    elif code == 51:
        s.speed_override = on
        interp.emit("ENABLE_SPEED_OVERRIDE" if on else "DISABLE_SPEED_OVERRIDE", 0)
    elif code == 52:
        s.adaptive = on
        interp.emit("ENABLE_ADAPTIVE_FEED" if on else "DISABLE_ADAPTIVE_FEED")
        interp.note("M52 (adaptive feed) is accepted and not modelled")
    else:
        s.feed_hold = on
        interp.emit("ENABLE_FEED_HOLD" if on else "DISABLE_FEED_HOLD")


def _units(interp: Interpreter, units: str) -> None:
    s = interp.state
    if units != s.units:
        k: Number = MM_PER_INCH if units == "mm" else 1 / MM_PER_INCH

        def conv(t: tuple[Number, ...]) -> tuple[Number, ...]:
            return tuple(v * k if i in (0, 1, 2, 6, 7, 8) else v for i, v in enumerate(t))

        s.position, s.origin, s.axis_offset, s.tlo = conv(s.position), conv(s.origin), conv(s.axis_offset), \
            conv(s.tlo)
        s.cutter_radius = s.cutter_radius * k
        if s.cycle_r is not None:
            s.cycle_r = s.cycle_r * k
        s.units = units
    interp.emit("USE_LENGTH_UNITS", "MM" if units == "mm" else "INCHES")


def _path_control(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    s.path = code
    if code == 611:
        interp.emit("SET_MOTION_CONTROL_MODE", "EXACT_STOP", 0)
    elif code == 610:
        interp.emit("SET_MOTION_CONTROL_MODE", "EXACT_PATH", 0)
    else:
        p = w.get("P")
        q = w.get("Q")
        p = p if p is not None and p >= 0 else None  # rs274: a negative P or Q is as none (CONTINUOUS, 0)
        q = q if q is not None and q >= 0 else None
        s.path_p = p if p is not None else 0
        s.path_q = q if q is not None else s.path_p
        interp.emit("SET_MOTION_CONTROL_MODE", "CONTINUOUS", s.path_p)
        interp.emit("SET_NAIVECAM_TOLERANCE", s.path_q)


def _state_save(interp: Interpreter, code: int) -> None:
    if code in (70, 73):
        interp.saved_states.append(interp.state.copy())
        if code == 73:
            frame = interp.frames[-1]
            if len(interp.frames) == 1:
                interp.note("M73 outside a subroutine saves the state and never restores it (as in LinuxCNC)")
            frame.repeats[-1] = len(interp.saved_states)  # marker: restored on return
    elif code == 71:
        if interp.saved_states:
            interp.saved_states.pop()
    else:
        if not interp.saved_states:
            raise ProgramError(interp.where, "M72: no state saved (M70) to restore")
        restore(interp, interp.saved_states.pop())


def restore(interp: Interpreter, saved: State) -> None:
    """Bring back the modal state of ``saved`` (M72), emitting the calls that change."""
    s = interp.state
    if saved.units != s.units:
        _units(interp, saved.units)
    if saved.plane != s.plane:
        s.plane = saved.plane
        interp.emit("SELECT_PLANE", PLANES[s.plane])
    if saved.feed_mode != s.feed_mode:
        interp.emit("SET_FEED_MODE", 0, FEED_MODES[saved.feed_mode])
    if saved.feed != s.feed:
        interp.emit("SET_FEED_RATE", saved.feed)
    if saved.speed != s.speed:
        interp.emit("SET_SPINDLE_SPEED", 0, saved.speed)
    if saved.spindle != s.spindle:
        interp.emit({1: "START_SPINDLE_CLOCKWISE", -1: "START_SPINDLE_COUNTERCLOCKWISE",
                     0: "STOP_SPINDLE_TURNING"}[saved.spindle], 0)
    if (saved.mist, saved.flood) != (s.mist, s.flood):
        interp.emit("MIST_ON" if saved.mist else "MIST_OFF")
        interp.emit("FLOOD_ON" if saved.flood else "FLOOD_OFF")
    if (saved.path, saved.path_p) != (s.path, s.path_p):
        interp.emit("SET_MOTION_CONTROL_MODE", {611: "EXACT_STOP", 610: "EXACT_PATH", 640: "CONTINUOUS"}[saved.path],
                    saved.path_p)
    # M72 restores the modes; where the machine is, its offsets and its tool stay as they are now
    interp.state = replace(saved, position=s.position, origin=s.origin, axis_offset=s.axis_offset, tlo=s.tlo,
                           coord=s.coord, tool=s.tool, selected=s.selected, rotation=s.rotation,
                           tool_length=s.tool_length)
    interp.state.units, interp.state.plane = saved.units, saved.plane


def _stop(interp: Interpreter, code: int) -> None:
    s = interp.state
    if code == 0:
        interp.emit("PROGRAM_STOP")
    elif code == 1:
        interp.emit("OPTIONAL_PROGRAM_STOP")
    elif code == 60:
        interp.emit("PALLET_SHUTTLE")
        interp.emit("PROGRAM_STOP")
    else:
        from cosim.controllers.pokeys.gcode import compensation

        compensation.dequeue(interp)
        s.cutter, s.cutter_radius = 400, 0
        motion.select_coordinates(interp, 1, end=True)
        if s.plane != 170:
            s.plane = 170
            interp.emit("SELECT_PLANE", "XY")
        s.incremental = False
        s.feed_mode = 940
        interp.emit("SET_FEED_MODE", 0, 0)
        interp.emit("SET_FEED_RATE", 0)
        s.feed = 0
        if not s.feed_override:
            interp.emit("ENABLE_FEED_OVERRIDE")
        if not s.speed_override:
            interp.emit("ENABLE_SPEED_OVERRIDE", 0)
        s.feed_override = s.speed_override = True
        s.cutter = 400
        s.spindle = 0
        interp.emit("STOP_SPINDLE_TURNING", 0)
        interp.emit("SET_SPINDLE_MODE", 0, 0)
        s.css = False
        if s.mist:
            interp.emit("MIST_OFF")
        if s.flood:
            interp.emit("FLOOD_OFF")
        s.mist = s.flood = False
        s.motion = 10
        if code == 30:
            interp.emit("PALLET_SHUTTLE")
        interp.emit("PROGRAM_END")
        interp.program.end = f"M{code}"
        interp.program.end_where = interp.where
        raise Stop
