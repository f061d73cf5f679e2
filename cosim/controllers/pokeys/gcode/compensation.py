"""Cutter radius compensation G40, G41, G42, G41.1, G42.1, as LinuxCNC 2.9's interpreter computes it.

The tool centre runs one tool radius to the left (G41) or right (G42) of the programmed path, in
the XY plane (or XZ, G18, for lathes). The radius is half the diameter of the D tool of the
machine's tool table (default: the tool in the spindle), or half the D value of G41.1/G42.1.

* **Entry** (the first move after G41/G42): a straight move ends one radius to the side of its
  programmed end, perpendicular to the move (it must be longer than the radius: "Length of cutter
  compensation entry move is not greater than the tool radius"); an arc ends on the programmed
  arc moved out or in by the radius.
* **Corners**: a convex corner (the tool outside it) gets an arc of the tool radius around the
  programmed corner; a concave corner moves the end of the previous move back to where the two
  offset paths meet. So a move is held back until the next one is known (LinuxCNC's queue of
  canonical calls, here :class:`Queue`); feed, dwell, spindle, coolant and comment calls made in
  between wait in the queue with it.
* The corner tolerance is 0.01 rad (LinuxCNC's ``TOLERANCE_CONCAVE_CORNER``); a rapid around a
  convex corner goes straight to the start of the next offset move.
* **G40**: the held move ends where it is; the next move is not compensated and goes to its
  programmed end from where the tool is (the interpreter's current point is the programmed one).

Its errors are LinuxCNC's: a tool that cannot fit a concave corner or an inside arc, a move too
short to reach, a tool change or a G92 while compensation is on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from cosim.controllers.pokeys.gcode.params import Number, integer
from cosim.controllers.pokeys.gcode.words import WordError, Words

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

SMALL = 0.01  # rad: LinuxCNC's TOLERANCE_CONCAVE_CORNER
LEFT, RIGHT = 410, 420
QUEUED = frozenset({"SET_FEED_RATE", "DWELL", "SET_FEED_MODE", "MIST_ON", "MIST_OFF", "FLOOD_ON", "FLOOD_OFF",
                    "START_SPINDLE_CLOCKWISE", "START_SPINDLE_COUNTERCLOCKWISE", "STOP_SPINDLE_TURNING",
                    "SET_SPINDLE_MODE", "SET_SPINDLE_SPEED", "COMMENT"})
#: plane -> indices of the compensation plane's first and second axes in x..w
COMP_AXES = {170: (0, 1), 180: (2, 0)}


class CompensationError(WordError):
    """A move LinuxCNC refuses under cutter radius compensation."""


@dataclass
class _Item:
    name: str
    args: list[Any]
    line: int
    direction: tuple[float, float] = (0.0, 0.0)  # of the programmed line (straight moves)
    turns: float = 0.0  # the arc's original angular length (arcs)


@dataclass
class Queue:
    """Canonical calls held back while cutter radius compensation decides the end of the last move."""

    items: list[_Item] = field(default_factory=list)
    endpoint: tuple[float, float] = (0.0, 0.0)  # where the held moves start (in the compensation plane)
    valid: bool = False  # the endpoint is set for the held moves (it keeps its value when not)

    def __bool__(self) -> bool:
        return bool(self.items)


def _side(interp: Interpreter) -> int:
    return LEFT if interp.state.cutter in (410, 411) else RIGHT


def _inside(side: int, turn: float) -> bool:
    """The tool is inside the arc (LinuxCNC's TOOL_INSIDE_ARC)."""
    return (side == LEFT and turn > 0) or (side == RIGHT and turn < 0)


def switch(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    column = w.g_columns.get(7, 0)
    if code == 400:
        dequeue(interp)
        if s.cutter != 400 and s.cutter_radius > 0:
            # the interpreter's point is the programmed one again; the next move starts from the tool
            s.position = tuple(s.comp_programmed[:3]) + tuple(s.position[3:])
        s.cutter, s.cutter_radius = 400, 0
        s.comp_first = False
        return
    if s.cutter != 400:
        raise CompensationError("Cannot turn cutter radius comp on when already on", column)
    if s.plane not in COMP_AXES:
        raise CompensationError("Cannot turn cutter radius comp on out of XY (or, on a lathe, XZ) plane", column)
    if code in (410, 420):
        d = integer(w.get("D")) if w.has("D") else s.tool
        if d is None or d < 0:
            raise CompensationError("Negative D word tool radius index used", w.column("D") or column)
        if d and d not in interp.tools:
            raise CompensationError(f"Requested tool {d} not found in the tool table", w.column("D") or column)
        tool = interp.tools.get(d)
        radius: Number = interp.machine_to_program(tool.diameter) / 2 if tool else 0
    else:
        radius = (w.get("D") or 0) / 2
    side = 410 if code in (410, 411) else 420
    if radius < 0:  # a negative diameter swaps the side
        radius, side = -radius, 830 - side
    s.cutter, s.cutter_radius = side, radius
    s.comp_first = True
    s.comp_programmed = s.position


# -- the queue --------------------------------------------------------------------------------------
def enqueue(interp: Interpreter, name: str, args: list[Any], **extra: Any) -> None:
    interp.comp_queue.items.append(_Item(name, args, interp.line, **extra))


def dequeue(interp: Interpreter) -> None:
    """Emit every held call in order."""
    queue = interp.comp_queue
    items, queue.items = queue.items, []
    queue.valid = False
    for item in items:
        interp.emit_now(item.name, item.line, *item.args)


def set_endpoint(interp: Interpreter, x: float, y: float) -> None:
    interp.comp_queue.endpoint = (x, y)
    interp.comp_queue.valid = True


def move_endpoint_and_flush(interp: Interpreter, x: float, y: float) -> None:
    """End every held move at (x, y) of the compensation plane, then emit them."""
    queue = interp.comp_queue
    if not queue.items:
        return
    first, second = COMP_AXES.get(interp.state.plane, (0, 1))
    for item in queue.items:
        if item.name == "ARC_FEED":
            c1, c2 = float(item.args[2]), float(item.args[3])
            r1 = math.hypot(float(item.args[0]) - c1, float(item.args[1]) - c2)
            item.args[0], item.args[1] = x, y
            r2 = math.hypot(x - c1, y - c2)
            start = queue.endpoint
            turns = find_turn(start[0], start[1], c1, c2, int(item.args[4]), x, y)
            if abs(r1 - r2) > 0.01:
                raise CompensationError(f"cutter compensation made an arc with mismatched radii r1 {r1:f} r2 {r2:f}")
            if item.turns and abs(turns) > abs(item.turns):
                raise CompensationError("Arc move in concave corner is too short to be reachable by the tool "
                                        "without gouging")
        elif item.name in ("STRAIGHT_FEED", "STRAIGHT_TRAVERSE"):
            if queue.valid:
                dot = item.direction[0] * (x - queue.endpoint[0]) + item.direction[1] * (y - queue.endpoint[1])
                if dot < 0:
                    raise CompensationError("Straight move in concave corner is too short to be reachable by the "
                                            "tool without gouging")
            item.args[first], item.args[second] = x, y
    dequeue(interp)
    set_endpoint(interp, x, y)


def find_turn(x1: float, y1: float, cx: float, cy: float, turn: int, x2: float, y2: float) -> float:
    """The signed angle an arc of ``turn`` turns sweeps from (x1, y1) to (x2, y2) around (cx, cy) [rad]."""
    alpha = math.atan2(y1 - cy, x1 - cx)
    beta = math.atan2(y2 - cy, x2 - cx)
    if turn > 0:
        if beta <= alpha:
            beta += 2 * math.pi
        return beta - alpha + (turn - 1) * 2 * math.pi
    if alpha <= beta:
        alpha += 2 * math.pi
    return beta - alpha + (turn + 1) * 2 * math.pi


# -- moves ------------------------------------------------------------------------------------------
def _plane(interp: Interpreter) -> tuple[int, int]:
    plane = interp.state.plane
    if plane not in COMP_AXES:
        raise CompensationError("Cannot change the plane to one other than XY or XZ with cutter radius comp on")
    return COMP_AXES[plane]


def straight(interp: Interpreter, end: list[Number], code: int) -> None:
    """A G0/G1 under compensation (LinuxCNC's convert_straight_comp1 and comp2)."""
    s = interp.state
    name = "STRAIGHT_TRAVERSE" if code == 0 else "STRAIGHT_FEED"
    if s.cutter_radius == 0:
        interp.emit(name, *end)
        s.position = tuple(end)
        s.comp_programmed = tuple(end)
        return
    first, second = _plane(interp)
    radius = float(s.cutter_radius)
    side = _side(interp)
    cx, cy = float(s.position[first]), float(s.position[second])
    px, py = float(end[first]), float(end[second])
    if s.comp_first:
        distance = math.hypot(px - cx, py - cy)
        if distance <= radius:
            raise CompensationError("Length of cutter compensation entry move is not greater than the tool radius")
        alpha = math.atan2(py - cy, px - cx) + (math.pi / 2 if side == LEFT else -math.pi / 2)
        ex, ey = px + radius * math.cos(alpha), py + radius * math.sin(alpha)
        set_endpoint(interp, cx, cy)
        args = list(end)
        args[first], args[second] = ex, ey
        enqueue(interp, name, args, direction=(math.cos(alpha), math.sin(alpha)))
        s.comp_first = False
        s.position = tuple(args)
        s.comp_programmed = tuple(end)
        return
    ox, oy = float(s.comp_programmed[first]), float(s.comp_programmed[second])
    args = list(end)
    if px == ox and py == oy:  # no motion in the plane
        args[first], args[second] = s.position[first], s.position[second]
        enqueue(interp, name, args, direction=(0.0, 0.0))
    else:
        theta = math.atan2(cy - oy, cx - ox)
        alpha = math.atan2(py - oy, px - ox)
        if side == LEFT:
            if theta < alpha:
                theta += 2 * math.pi
            beta = theta - alpha - math.pi / 2
            gamma = math.pi / 2
        else:
            if alpha < theta:
                alpha += 2 * math.pi
            beta = alpha - theta - math.pi / 2
            gamma = -math.pi / 2
        ex, ey = px + radius * math.cos(alpha + gamma), py + radius * math.sin(alpha + gamma)
        mx, my = ox + radius * math.cos(alpha + gamma), oy + radius * math.sin(alpha + gamma)
        queue = interp.comp_queue
        front = queue.items[0] if queue.items else None
        concave = beta < -SMALL or beta > math.pi + SMALL or (
            beta > math.pi - SMALL and front is not None and front.name == "ARC_FEED"
            and ((side == RIGHT and front.args[4] > 0) or (side == LEFT and front.args[4] < 0)))
        if not concave and beta > SMALL:  # a convex corner: around it
            move_endpoint_and_flush(interp, cx, cy)
            corner = list(s.position)
            corner[first], corner[second] = mx, my
            if code == 10:
                arc = _arc_args(mx, my, ox, oy, -1 if side == LEFT else 1, float(s.position[3 - first - second]),
                                end)
                interp.emit("ARC_FEED", *arc)
            else:
                interp.emit("STRAIGHT_TRAVERSE", *corner)
            set_endpoint(interp, mx, my)
        elif concave:
            if front is None or front.name != "ARC_FEED":
                half = (beta + math.pi) / 2
                if half == 0:
                    raise CompensationError("Zero degree inside corner is invalid for cutter compensation")
                retreat = radius / math.tan(half)
                move_endpoint_and_flush(interp, cx + retreat * math.cos(theta + gamma),
                                        cy + retreat * math.sin(theta + gamma))
            else:
                _arc_to_line(interp, front, side, radius, ox, oy, px, py)
        else:
            dequeue(interp)
            set_endpoint(interp, cx, cy)
        args[first], args[second] = ex, ey
        dx, dy = px - ox, py - oy
        enqueue(interp, name, args, direction=(dx, dy))
    s.position = tuple(args)
    s.comp_programmed = tuple(end)


def _arc_args(e1: float, e2: float, c1: float, c2: float, turn: int, normal: float,
              end: list[Number]) -> list[object]:
    return [e1, e2, c1, c2, turn, normal, *end[3:]]


def _arc_to_line(interp: Interpreter, prev: _Item, side: int, radius: float, ox: float, oy: float, px: float,
                 py: float) -> None:
    c1, c2 = float(prev.args[2]), float(prev.args[3])
    turn = int(prev.args[4])
    old = math.hypot(c2 - float(prev.args[1]), c1 - float(prev.args[0]))
    base = math.atan2(py - oy, px - ox)
    theta = base + math.pi / 2 if turn > 0 else base - math.pi / 2
    phi = math.atan2(c2 - oy, c1 - ox)
    uncomp = old + radius if _inside(side, turn) else old - radius
    d = uncomp * math.cos(theta - phi)
    if _inside(side, turn):
        ratio = (d - radius) / old
        _fits(ratio, "Arc to straight motion makes a corner the compensated tool can't fit in without gouging")
        angle = (-math.acos(ratio) if turn > 0 else math.acos(ratio)) + theta + math.pi
    else:
        ratio = (d + radius) / old
        _fits(ratio, "Arc to straight motion makes a corner the compensated tool can't fit in without gouging")
        angle = (math.acos(ratio) if turn > 0 else -math.acos(ratio)) + theta + math.pi
    move_endpoint_and_flush(interp, c1 + old * math.cos(angle), c2 + old * math.sin(angle))


def _fits(ratio: float, message: str) -> None:
    if ratio > 1 or ratio < -1:
        raise CompensationError(message)


def arc(interp: Interpreter, end: list[Number], center: tuple[Number, Number], rotation: int, first: int,
        second: int, normal: int) -> None:
    """A G2/G3 under compensation; ``center`` is the programmed arc's (LinuxCNC's convert_arc_comp1 and comp2)."""
    s = interp.state
    if s.cutter_radius == 0:
        interp.emit("ARC_FEED", end[first], end[second], center[0], center[1], rotation, end[normal], *end[3:])
        s.position = tuple(end)
        s.comp_programmed = tuple(end)
        return
    if (first, second) != _plane(interp):
        raise CompensationError("cutter radius compensation in this plane is not supported")
    radius = float(s.cutter_radius)
    side = _side(interp)
    cx, cy = float(s.position[first]), float(s.position[second])
    ex, ey = float(end[first]), float(end[second])
    ccx, ccy = float(center[0]), float(center[1])
    arc_radius = math.hypot(ccx - ex, ccy - ey)
    if _inside(side, rotation) and arc_radius <= radius:
        raise CompensationError("Tool radius not less than arc radius with cutter radius comp")
    if s.comp_first:
        if math.hypot(ex - cx, ey - cy) <= radius:
            raise CompensationError("Radius of cutter compensation entry arc is not greater than the tool radius")
        gamma = math.atan2(ccy - ey, ccx - ex) if _inside(side, rotation) else math.atan2(ey - ccy, ex - ccx)
        nx, ny = ex + radius * math.cos(gamma), ey + radius * math.sin(gamma)
        half = math.hypot(cy - ny, cx - nx) / 2
        ab = math.atan2(ccy - ny, ccx - nx)
        a_ang = math.atan2(cy - ny, cx - nx) - ab
        if abs(math.cos(a_ang)) < 0.0001:
            raise CompensationError("Tool radius not less than arc radius with cutter radius comp")
        c_len = half / math.cos(a_ang)
        ncx, ncy = nx + c_len * math.cos(ab), ny + c_len * math.sin(ab)
        set_endpoint(interp, cx, cy)
        args = [nx, ny, ncx, ncy, rotation, end[normal], *end[3:]]
        enqueue(interp, "ARC_FEED", args, turns=find_turn(cx, cy, ncx, ncy, rotation, nx, ny))
        s.comp_first = False
    else:
        ox, oy = float(s.comp_programmed[first]), float(s.comp_programmed[second])
        theta = math.atan2(cy - oy, cx - ox)
        theta = theta - math.pi / 2 if side == LEFT else theta + math.pi / 2
        delta = math.atan2(ccy - oy, ccx - ox)
        alpha = delta - math.pi / 2 if rotation > 0 else delta + math.pi / 2
        beta = theta - alpha if side == LEFT else alpha - theta
        if beta > 1.5 * math.pi:
            beta -= 2 * math.pi
        elif beta < -math.pi / 2:
            beta += 2 * math.pi
        if _inside(side, rotation):
            gamma = math.atan2(ccy - ey, ccx - ex)
        else:
            gamma = math.atan2(ey - ccy, ex - ccx)
            delta += math.pi
        nx, ny = ex + radius * math.cos(gamma), ey + radius * math.sin(gamma)
        queue = interp.comp_queue
        front = queue.items[0] if queue.items else None
        if beta < -SMALL or beta > math.pi + SMALL or (abs(beta - math.pi) < SMALL and not _inside(side, rotation)):
            if front is None or front.name != "ARC_FEED":
                _line_to_arc(interp, side, rotation, radius, arc_radius, beta, theta, ccx, ccy)
            else:
                _arc_to_arc(interp, front, side, rotation, radius, arc_radius, ccx, ccy)
        elif beta > SMALL:  # convex: an arc around the corner first
            mx, my = ox + radius * math.cos(delta), oy + radius * math.sin(delta)
            dequeue(interp)
            interp.emit("ARC_FEED", mx, my, ox, oy, -1 if side == LEFT else 1, s.position[normal], *end[3:])
            set_endpoint(interp, mx, my)
        else:
            dequeue(interp)
            set_endpoint(interp, cx, cy)
        args = [nx, ny, ccx, ccy, rotation, end[normal], *end[3:]]
        enqueue(interp, "ARC_FEED", args, turns=find_turn(ox, oy, ccx, ccy, rotation, ex, ey))
    position = list(end)
    position[first], position[second] = nx, ny
    s.position = tuple(position)
    s.comp_programmed = tuple(end)


def _line_to_arc(interp: Interpreter, side: int, turn: int, radius: float, arc_radius: float, beta: float,
                 theta: float, ccx: float, ccy: float) -> None:
    cy = arc_radius * math.sin(beta - math.pi / 2)
    message = "Arc move in concave corner cannot be reached by the tool without gouging"
    if _inside(side, turn):
        distance = arc_radius - radius
        ratio = (cy + radius) / distance
        _fits(ratio, message)
        angle = theta + math.asin(ratio) if turn > 0 else theta - math.asin(ratio)
    else:
        distance = arc_radius + radius
        ratio = (cy - radius) / distance
        _fits(ratio, message)
        angle = theta + math.pi - math.asin(ratio) if turn > 0 else theta + math.pi + math.asin(ratio)
    move_endpoint_and_flush(interp, ccx + distance * math.cos(angle), ccy + distance * math.sin(angle))


def _arc_to_arc(interp: Interpreter, prev: _Item, side: int, turn: int, radius: float, arc_radius: float,
                ccx: float, ccy: float) -> None:
    p1, p2 = float(prev.args[2]), float(prev.args[3])
    old = math.hypot(p2 - float(prev.args[1]), p1 - float(prev.args[0]))
    new = arc_radius - radius if _inside(side, turn) else arc_radius + radius
    between = math.hypot(p2 - ccy, p1 - ccx)
    if old == 0 or between == 0:
        raise CompensationError("Arc to arc motion is invalid because the arcs have the same center")
    a = (old * old + between * between - new * new) / (2 * old * between)
    _fits(a, "Arc to arc motion makes a corner the compensated tool can't fit in without gouging")
    pullback = math.acos(a)
    direction = math.atan2(ccy - p2, ccx - p1)
    prev_turn = int(prev.args[4])
    if _inside(side, prev_turn):
        angle = direction + pullback if turn > 0 else direction - pullback
    else:
        angle = direction - pullback if turn > 0 else direction + pullback
    move_endpoint_and_flush(interp, p1 + old * math.cos(angle), p2 + old * math.sin(angle))
