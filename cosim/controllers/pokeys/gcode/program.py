"""The canonical program as a tool path in machine coordinates and units: what the host planner runs.

:func:`toolpath` follows the canonical calls as LinuxCNC's motion side does: program coordinates
plus the G92/G52 offset, rotated by the coordinate system's XY rotation, plus the G5x origin, plus
the tool length offset, in the machine's units (rotary axes A, B, C in degrees, as the program
gives them); feeds in machine units per second along the move's feed axes (XYZ, else UVW, else
ABC in degrees per second: :func:`~cosim.controllers.pokeys.toolpath.feed_axes`; G93 inverse
time and G95 per revolution are already per minute in the canonical calls, G95 times the spindle
speed). The points have the axes of :attr:`HostSetup.axes`: x, y, z and the other axes the
machine drives. What the host does between moves becomes records the planner puts between slots:

* spindle (``M3 M4 M5 S``): :class:`~cosim.controllers.pokeys.toolpath.Spindle`;
* coolant, tool, pauses, digital and analog outputs: :class:`~cosim.controllers.pokeys.toolpath.Output`;
* a tool change (``M6``): a rapid to the machine file's tool change position (if it gives one),
  ``tool_changing`` = 1 for ``tool_change_time``, the new ``tool``;
* ``M0`` (and ``M1`` with ``optional_stop``, ``M60``): ``paused`` = 1 for ``pause_time``, or with
  ``cycle_start`` until the operator's cycle start (a :class:`~cosim.controllers.pokeys.toolpath.Wait`
  for a rise of the engine's ``cycle_start`` input);
* ``M66`` with the machine's inputs (``inputs``): a :class:`~cosim.controllers.pokeys.toolpath.Wait`
  on ``din<n>`` / ``ain<n>`` (``waiting`` = 1 while it waits, L1-L4);
* path control (``G61``, ``G61.1``, ``G64 P``): :class:`~cosim.controllers.pokeys.toolpath.PathControl`;
* ``G5``/``G5.1`` splines: chords within the arc tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from itertools import pairwise

from cosim.controllers.pokeys.gcode.canon import CanonProgram, Number
from cosim.controllers.pokeys.gcode.state import MM_PER_INCH
from cosim.controllers.pokeys.toolpath import (
    Arc,
    Line,
    Message,
    Output,
    PathControl,
    Pause,
    Point,
    Spindle,
    Step,
    Toolpath,
    Wait,
    feed_axes,
)
from cosim.errors import ConfigurationError

PLANES = {"XY": ((0, 1), 2, "xy"), "XZ": ((2, 0), 1, "zx"), "YZ": ((1, 2), 0, "yz")}
CANON_AXES = "xyzabcuvw"
"""The coordinates of a canonical call's point, in order."""
LINEAR = frozenset("xyzuvw")
MODES = {"EXACT_STOP": "exact_stop", "EXACT_PATH": "exact_path", "CONTINUOUS": "blend"}
SPINDLE_CALLS = frozenset({"SET_SPINDLE_SPEED", "START_SPINDLE_CLOCKWISE", "START_SPINDLE_COUNTERCLOCKWISE",
                           "STOP_SPINDLE_TURNING"})


@dataclass(frozen=True)
class HostSetup:
    """What the host machine does between moves (from the machine file's ``[host]``).

    Parameters
    ----------
    units : {'mm', 'inch'}
        Machine units.
    tool_change_time : Fraction
        Seconds a tool change (M6) takes.
    tool_change_position : tuple of Fraction, optional
        Where the machine goes for a tool change (machine coordinates x, y, z) [units].
    pause_time : Fraction
        Seconds an M0 / M60 (and M1 with ``optional_stop``) pause lasts before the operator resumes.
    optional_stop : bool
        The optional stop switch is on: M1 pauses.
    arc_tolerance : Fraction
        Largest chord error of spline chords [units].
    axes : str
        The axes the host plans: ``"xyz"``, then the machine's other axes among a, b, c, u, v, w
        (``"xyzab"``); the tool path's points have these coordinates.
    cycle_start : bool
        A pause (M0, M60, M1 with ``optional_stop``) lasts until the operator's cycle start (a rise
        of the ``cycle_start`` input) instead of ``pause_time``.
    inputs : bool
        M66 waits on the machine's inputs (a ``Wait``); without them it ends at once (noted).
    """

    units: str = "mm"
    tool_change_time: Fraction = Fraction(0)
    tool_change_position: Point | None = None
    pause_time: Fraction = Fraction(0)
    optional_stop: bool = False
    arc_tolerance: Fraction = Fraction(1, 100)
    axes: str = "xyz"
    cycle_start: bool = False
    inputs: bool = False

    def __post_init__(self) -> None:
        extra = self.axes[3:]
        if self.axes[:3] != "xyz" or any(a not in CANON_AXES[3:] for a in extra) or len(set(extra)) != len(extra):
            raise ConfigurationError.out_of_range("host axes", self.axes, "xyz then some of a, b, c, u, v, w")


def _exact(value: Number) -> Fraction:
    return value if isinstance(value, Fraction) else Fraction(value)


class _Follower:
    def __init__(self, program: CanonProgram, setup: HostSetup) -> None:
        self.program = program
        self.setup = setup
        self.units = setup.units
        self.g5x: tuple[Number, ...] = (0,) * 9
        self.g92: tuple[Number, ...] = (0,) * 9
        self.tlo: tuple[Number, ...] = (0,) * 9
        self.rotation: Number = 0
        self.feed: Number = 0
        self.feed_mode = 0
        self.plane = "XY"
        self.spindle = Spindle(False, False, Fraction(0), 0)
        self.pending: Spindle | None = None
        self.outputs: dict[str, float] = {}
        self.steps: list[Step] = []
        self.notes: list[str] = list(program.notes)
        self.axes = setup.axes
        self.extra = [(CANON_AXES.index(a), a in LINEAR) for a in setup.axes[3:]]
        self.position: Point = (Fraction(0),) * len(setup.axes)
        self.start = self.position
        self.done = 0  # calls followed
        self.unplanned = [i for i in range(3, 9) if CANON_AXES[i] not in setup.axes]
        self.rest: tuple[Number, ...] = (0,) * len(self.unplanned)

    # -- coordinates -------------------------------------------------------------------------------
    def _program_scale(self) -> Fraction:
        """Machine units per program unit."""
        if self.units == self.setup.units:
            return Fraction(1)
        return 1 / MM_PER_INCH if self.units == "mm" else MM_PER_INCH

    def machine(self, p: tuple[Number, ...]) -> Point:
        """Machine coordinates of program point ``p`` (the offsets are kept in machine units)."""
        k = self._program_scale()
        x, y, z = p[0] * k + self.g92[0], p[1] * k + self.g92[1], p[2] * k + self.g92[2]
        if self.rotation:
            c, s = math.cos(math.radians(self.rotation)), math.sin(math.radians(self.rotation))
            x, y = x * c - y * s, x * s + y * c
        xyz = (_exact(x + self.g5x[0] + self.tlo[0]), _exact(y + self.g5x[1] + self.tlo[1]),
               _exact(z + self.g5x[2] + self.tlo[2]))
        if not self.extra:
            return xyz
        return (*xyz, *(_exact((p[i] * k if linear else p[i]) + self.g92[i] + self.g5x[i] + self.tlo[i])
                        for i, linear in self.extra))

    def _in_machine_units(self, values: tuple[Number, ...]) -> tuple[Number, ...]:
        k = self._program_scale()
        return tuple(v * k if i in (0, 1, 2, 6, 7, 8) else v for i, v in enumerate(values))

    def feed_per_s(self, axes: str = "xyz") -> Fraction:
        """The feed [units/s] of a move along ``axes`` (its :func:`feed_axes`: a pure rotary move's is in deg/s)."""
        f = _exact(self.feed)
        if self.feed_mode == 2:
            f = f * _exact(self.spindle.speed)
        return f / 60 if axes == "abc" else f * self._program_scale() / 60

    # -- calls --------------------------------------------------------------------------------------
    def run(self) -> Toolpath:
        self.advance()
        return Toolpath(tuple(self.steps), source=self.program.source, start=self.start,
                        skipped=tuple(self.program.skipped), notes=tuple(self.notes), ending=self.program.end,
                        axes=self.axes)

    def advance(self) -> list[Step]:
        """Follow the calls the program has gained since the last time; the steps they make."""
        first = len(self.steps)
        calls = self.program.calls
        for call in calls[self.done:]:
            name, args = call.name, call.args
            if self.pending is not None and (name not in SPINDLE_CALLS or call.line != self.pending.line):
                self._flush_spindle()
            handler = getattr(self, f"_{name.lower()}", None)
            if handler is not None:
                handler(call.line, *args)
        self.done = len(calls)
        self._flush_spindle()
        return self.steps[first:]

    def _flush_spindle(self) -> None:
        if self.pending is not None:
            if (self.pending.on, self.pending.ccw, self.pending.speed) != \
                    (self.spindle.on, self.spindle.ccw, self.spindle.speed):
                self.steps.append(self.pending)
                self.spindle = self.pending
            self.pending = None

    def _spin(self, line: int, *, on: bool | None = None, ccw: bool | None = None,
              rpm: Number | None = None) -> None:
        base = self.pending or self.spindle
        self.pending = Spindle(base.on if on is None else on, base.ccw if ccw is None else ccw,
                               base.speed if rpm is None else _exact(rpm), line)

    def _set_spindle_speed(self, line: int, _spindle: int, speed: Number) -> None:
        self._spin(line, rpm=speed)

    def _start_spindle_clockwise(self, line: int, *_: object) -> None:
        self._spin(line, on=True, ccw=False)

    def _start_spindle_counterclockwise(self, line: int, *_: object) -> None:
        self._spin(line, on=True, ccw=True)

    def _stop_spindle_turning(self, line: int, *_: object) -> None:
        self._spin(line, on=False, ccw=False)

    def _use_length_units(self, line: int, units: str) -> None:
        self.units = "mm" if units == "MM" else "inch"

    def _set_g5x_offset(self, line: int, _n: int, *offset: Number) -> None:
        self.g5x = self._in_machine_units(offset)

    def _set_g92_offset(self, line: int, *offset: Number) -> None:
        self.g92 = self._in_machine_units(offset)

    def _set_xy_rotation(self, line: int, degrees: Number) -> None:
        self.rotation = degrees

    def _use_tool_length_offset(self, line: int, *offset: Number) -> None:
        self.tlo = self._in_machine_units(offset)

    def _set_feed_rate(self, line: int, feed: Number) -> None:
        self.feed = feed

    def _set_feed_mode(self, line: int, _spindle: int, mode: int) -> None:
        self.feed_mode = mode

    def _select_plane(self, line: int, plane: str) -> None:
        self.plane = plane

    def _straight_traverse(self, line: int, *p: Number) -> None:
        self._line(p, None, line)

    def _straight_feed(self, line: int, *p: Number) -> None:
        self._line(p, True, line)

    def _straight_probe(self, line: int, *p: Number) -> None:
        self._line(p, True, line)

    def _line(self, p: tuple[Number, ...], feed: bool | None, line: int) -> None:
        self._check_rest(p, line)
        end = self.machine(p)
        speed = self.feed_per_s(feed_axes(self.position, end, self.axes)) if feed else None
        self.steps.append(Line(end, speed, line))
        self.position = end

    def _check_rest(self, p: tuple[Number, ...], line: int) -> None:
        rest = tuple(p[i] for i in self.unplanned)
        if rest != self.rest:
            moved = [CANON_AXES[i].upper() for i, old, new in zip(self.unplanned, self.rest, rest, strict=True)
                     if old != new]
            self.rest = rest
            if moved:
                text = (f"{self.program.source}:{line}: {', '.join(moved)} moves: the host planner drives "
                        f"{', '.join(self.axes)}; the other axes' moves are not modelled")
                if text not in self.notes:
                    self.notes.append(text)

    def _arc_feed(self, line: int, e1: Number, e2: Number, c1: Number, c2: Number, rotation: int,
                  normal_end: Number, *rest: Number) -> None:
        (i1, i2), normal, name = PLANES[self.plane]
        p: list[Number] = [0] * 9
        p[i1], p[i2], p[normal] = e1, e2, normal_end
        p[3:] = rest
        self._check_rest(tuple(p), line)
        end = self.machine(tuple(p))
        # the centre through the same transformation (a point on the plane at the centre)
        q: list[Number] = list(p)
        q[i1], q[i2] = c1, c2
        centre = self.machine(tuple(q))
        self.steps.append(Arc(end, (centre[i1], centre[i2]), rotation < 0, self.feed_per_s(), line, plane=name,
                              turns=abs(rotation)))
        self.position = end

    def _spline_feed(self, line: int, order: int, points: tuple[Number, ...], *end: Number) -> None:
        x0, y0 = self._program_xy()
        ctrl = [(float(x0), float(y0))] + [(float(points[i]), float(points[i + 1])) for i in range(0, len(points), 2)]
        z0 = float(self._program_z())
        z1 = float(end[2])
        second = max((math.hypot(ctrl[i + 2][0] - 2 * ctrl[i + 1][0] + ctrl[i][0],
                                 ctrl[i + 2][1] - 2 * ctrl[i + 1][1] + ctrl[i][1]) for i in range(len(ctrl) - 2)),
                     default=0.0)
        degree = len(ctrl) - 1
        tolerance = float(self.setup.arc_tolerance) / float(self._program_scale())
        n = max(1, math.ceil(math.sqrt(degree * (degree - 1) * second / (8 * tolerance)))) if second else 1
        n = min(n, 10_000)
        for k in range(1, n + 1):
            t = k / n
            x, y = _bezier(ctrl, t)
            p = list(end)
            if k < n:
                p[0], p[1], p[2] = x, y, z0 + (z1 - z0) * t
            self._line(tuple(p), True, line)

    def _program_xy(self) -> tuple[Number, Number]:
        return self._last_program[0], self._last_program[1]

    def _program_z(self) -> Number:
        return self._last_program[2]

    @property
    def _last_program(self) -> tuple[Number, ...]:
        # the program coordinates of the current point: invert the transformation of the last step's end
        x, y, z = self.position[:3]
        k = self._program_scale()
        px, py, pz = x - self.g5x[0] - self.tlo[0], y - self.g5x[1] - self.tlo[1], z - self.g5x[2] - self.tlo[2]
        if self.rotation:
            c, s = math.cos(math.radians(-self.rotation)), math.sin(math.radians(-self.rotation))
            px, py = px * c - py * s, px * s + py * c
        return ((px - self.g92[0]) / k, (py - self.g92[1]) / k, (pz - self.g92[2]) / k)

    def _dwell(self, line: int, seconds: Number) -> None:
        self.steps.append(Pause(_exact(seconds), line))

    def _output(self, name: str, value: float, line: int) -> None:
        if self.outputs.get(name) != value:
            self.outputs[name] = value
            self.steps.append(Output(name, value, line))

    def _flood_on(self, line: int) -> None:
        self._output("coolant_flood", 1, line)

    def _flood_off(self, line: int) -> None:
        self._output("coolant_flood", 0, line)

    def _mist_on(self, line: int) -> None:
        self._output("coolant_mist", 1, line)

    def _mist_off(self, line: int) -> None:
        self._output("coolant_mist", 0, line)

    def _change_tool(self, line: int, tool: int) -> None:
        if self.setup.tool_change_position is not None:
            here = (*self.setup.tool_change_position[:3], *self.position[3:])  # the other axes stay
            self.steps.append(Line(here, None, line))
            self.position = here
        self._output("tool_changing", 1, line)
        if self.setup.tool_change_time:
            self.steps.append(Pause(self.setup.tool_change_time, line))
        self._output("tool", tool, line)
        self._output("tool_changing", 0, line)

    def _change_tool_number(self, line: int, tool: int) -> None:
        self._output("tool", tool, line)

    def _program_stop(self, line: int) -> None:
        self._output("paused", 1, line)
        if self.setup.cycle_start:
            self.steps.append(Wait("cycle_start", 1, None, line, reads=False))
        elif self.setup.pause_time:
            self.steps.append(Pause(self.setup.pause_time, line))
        self._output("paused", 0, line)

    def _optional_program_stop(self, line: int) -> None:
        if self.setup.optional_stop:
            self._program_stop(line)
        else:
            note = (f"{self.program.source}:{line}: M1 does not stop: the optional stop switch is off "
                    "(host.optional_stop)")
            if note not in self.notes:
                self.notes.append(note)

    def _set_motion_output_bit(self, line: int, n: int) -> None:
        self._output(f"dout{n}", 1, line)

    _set_aux_output_bit = _set_motion_output_bit

    def _clear_motion_output_bit(self, line: int, n: int) -> None:
        self._output(f"dout{n}", 0, line)

    _clear_aux_output_bit = _clear_motion_output_bit

    def _set_motion_output_value(self, line: int, n: int, value: Number) -> None:
        self._output(f"aout{n}", float(value), line)

    _set_aux_output_value = _set_motion_output_value

    def _wait(self, line: int, index: int, digital: int, mode: int, timeout: Number) -> None:
        if self.setup.inputs:
            if mode:
                self._output("waiting", 1, line)
            self.steps.append(Wait(f"{'din' if digital else 'ain'}{index}", mode, _exact(timeout) if mode else None,
                                   line))
            if mode:
                self._output("waiting", 0, line)
            return
        if mode:
            note = (f"{self.program.source}:{line}: M66 waits on {'digital' if digital else 'analog'} input {index}: "
                    "inputs are not modelled, the wait ends at once")
            if note not in self.notes:
                self.notes.append(note)

    def _set_motion_control_mode(self, line: int, mode: str, tolerance: Number = 0) -> None:
        value = _exact(tolerance) * self._program_scale() if tolerance else None
        self.steps.append(PathControl(MODES[mode], value if mode == "CONTINUOUS" else None, line))

    def _message(self, line: int, text: str) -> None:
        self.steps.append(Message("MSG", str(text).strip(), line))

    def _print(self, line: int, text: str) -> None:
        self.steps.append(Message("PRINT", str(text).strip(), line))


def _bezier(ctrl: list[tuple[float, float]], t: float) -> tuple[float, float]:
    points = list(ctrl)
    while len(points) > 1:
        points = [((1 - t) * a[0] + t * b[0], (1 - t) * a[1] + t * b[1]) for a, b in pairwise(points)]
    return points[0]


def toolpath(program: CanonProgram, setup: HostSetup | None = None) -> Toolpath:
    """The tool path of a canonical program, in machine coordinates and ``setup.units``."""
    return _Follower(program, setup or HostSetup()).run()


def follower(program: CanonProgram, setup: HostSetup) -> _Follower:
    """A follower of a program that is still growing (a live interpreter's): :meth:`_Follower.advance` gives the
    steps of the calls added since its last call; ``notes`` are its notes so far."""
    return _Follower(program, setup)
