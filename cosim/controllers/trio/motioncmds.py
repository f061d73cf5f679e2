"""The motion commands of the controller (a part of :class:`~.controller.TrioController`).

Moves go into the axes' buffers (:mod:`.buffer`: one running and one buffered per axis; a further
one makes its program wait) and run from the next servo tick. Every command first brings the
servo ticks up to date and makes the next tick explicit (:meth:`~.servo.ServoLoop.wake`).
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import TYPE_CHECKING

from simpy.events import Event

from cosim import validate
from cosim.controllers.trio.datum import SEQUENCES, DatumMove
from cosim.controllers.trio.linked import CamMove, LinkedMove
from cosim.controllers.trio.motion import Move
from cosim.controllers.trio.params import ATYPE_VIRTUAL
from cosim.controllers.trio.paths import ArcPath
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis
    from cosim.controllers.trio.buffer import MoveBuffers
    from cosim.controllers.trio.servo import ServoLoop
    from cosim.kernel import Simulation

#: Link options of MOVELINK and CAMBOX the model runs (others start at once, listed as not modelled).
LINK_OPTIONS = (0, 1, 2)


def check_count(command: str, values: Sequence[object], axes: Sequence[int]) -> None:
    if not values or len(values) > len(axes):
        raise ConfigurationError.out_of_range(f"number of {command} values", len(values),
                                              f"1..{len(axes)} (one per BASE axis)")


class MotionCommands:
    """MOVE, MOVEABS, MOVECIRC, MOVEMODIFY, FORWARD, REVERSE, CANCEL, RAPIDSTOP, DATUM, CONNECT, MOVELINK,
    CAMBOX, CAM, WAIT IDLE / LOADED."""

    sim: Simulation
    axes: dict[int, Axis]
    buffers: MoveBuffers
    servo: ServoLoop
    wired: set[int]
    device: str

    def axis(self, number: object, *, where: str = "") -> Axis:
        raise NotImplementedError  # pragma: no cover - provided by the controller

    def table_value(self, index: object) -> Fraction:
        raise NotImplementedError  # pragma: no cover - provided by the controller

    def defpos(self, axes: Sequence[int], positions: Sequence[object]) -> None:
        """``DEFPOS(p1, ...)`` for ``axes``: applied by the next servo cycle (see OFFPOS)."""
        self.servo.wake()
        check_count("DEFPOS", positions, axes)
        for a, p in zip(axes, positions, strict=False):
            self.axis(a).defpos(validate.exact(p, "DEFPOS position"))

    def move(self, axes: Sequence[int], values: Sequence[object], *, absolute: bool, origin: str = "") -> Event:
        """``MOVE`` / ``MOVEABS`` on ``axes`` (the first is the base axis): an event once it is buffered."""
        self.servo.wake()
        command = "MOVEABS" if absolute else "MOVE"
        check_count(command, values, axes)
        group = self._group(axes[:len(values)], command)
        move = Move(group, command, tuple(validate.exact(v, f"{command} value") for v in values), origin)
        return self.buffers.add(move)

    def movecirc(self, axes: Sequence[int], values: Sequence[object], *, origin: str = "") -> Event:
        """``MOVECIRC(end1, end2, centre1, centre2, direction)`` on the first two of ``axes``.

        End and centre are relative to the start [units]; direction 0 is anticlockwise, 1 clockwise.
        """
        self.servo.wake()
        if len(values) != 5:
            raise ConfigurationError.out_of_range("number of MOVECIRC values", len(values),
                                                  "5 (end1, end2, centre1, centre2, direction)")
        if len(axes) < 2:
            raise ConfigurationError.out_of_range("number of BASE axes for MOVECIRC", len(axes),
                                                  ">= 2 (the arc is in the plane of the first two)")
        group = self._group(axes[:2], "MOVECIRC")
        e1, e2, c1, c2 = (validate.exact(v, "MOVECIRC value") for v in values[:4])
        direction = int(validate.flag(values[4], "MOVECIRC direction", true=(1,), allowed="0 (anticlockwise) or "
                                      "1 (clockwise)"))
        path = ArcPath.plan((e1, e2), (c1, c2), clockwise=direction == 1, tolerance=1 / self.axes[group[0]].units)
        return self.buffers.add(Move(group, "MOVECIRC", (e1, e2, c1, c2, Fraction(direction)), origin, path=path))

    def forward(self, axis: int, *, reverse: bool = False, origin: str = "") -> Event:
        """``FORWARD`` / ``REVERSE``: a continuous move of ``axis`` at its SPEED until ``CANCEL``."""
        self.servo.wake()
        command = "REVERSE" if reverse else "FORWARD"
        return self.buffers.add(Move(self._group((axis,), command), command, (), origin))

    def movemodify(self, axis: int, position: object, *, origin: str = "") -> Event:
        """``MOVEMODIFY(position)``: the running linear move of ``axis`` ends at ``position`` [units] instead,
        re-planned at the next servo tick from where it is then (coming back if it is past it; of several
        MOVEMODIFYs before that tick the last counts); without one, a ``MOVEABS``."""
        self.servo.wake()
        target = validate.exact(position, "MOVEMODIFY position")
        ax = self.axis(axis)
        move = ax.current
        if move is None or move.kind not in ("MOVE", "MOVEABS") or len(move.axes) != 1 or move.done:
            return self.move((ax.number,), (target,), absolute=True, origin=origin)
        assert move.path is not None
        start_units = (move.start_counts[0] - ax.origin) / ax.units
        delta = move.path.deltas[0]  # type: ignore[union-attr]
        sign = 1 if delta >= 0 else -1
        move.modify_to = (target - start_units) * sign
        done = self.sim.env.event()
        done.succeed()
        return done

    def _group(self, axes: Sequence[int], command: str) -> tuple[int, ...]:
        group = tuple(self.axis(a).number for a in axes)
        base = self.axes[group[0]]
        validate.positive(base.params["SPEED"], f"SPEED of axis {base.number} for {command}")
        for a in group:
            if a in self.wired and self.axes[a].params["ATYPE"] == ATYPE_VIRTUAL:
                raise ConfigurationError(
                    f"{command} on axis {a}: its step/direction output drives a plant, but ATYPE = 0 (virtual) "
                    "gives no step pulses (allowed: ATYPE = 1 or 35 before moving the axis)")
        return group

    def cancel(self, axes: Sequence[int], *, buffered: bool = False) -> None:
        """``CANCEL``: the running moves of ``axes`` decelerate at DECEL from the next servo tick;
        ``CANCEL(1)``: the buffered (next) moves are dropped instead."""
        self.servo.wake()
        group = tuple(self.axis(a).number for a in axes)
        if buffered:
            self.buffers.drop_buffered(group)
        else:
            self.buffers.cancel(group)

    def rapidstop(self) -> None:
        """``RAPIDSTOP``: every axis' buffered move is dropped and its running move cancelled."""
        self.servo.wake()
        every = tuple(self.axes)
        self.buffers.drop_buffered(every)
        self.buffers.cancel(every)

    def wait_idle(self, axes: Sequence[int]) -> Event:
        """An event that succeeds at the servo tick where every axis in ``axes`` is idle."""
        self.servo.sync()
        group = tuple(self.axis(a).number for a in axes)
        return self.buffers.wait(lambda: self.buffers.idle(group))

    def wait_loaded(self, axes: Sequence[int]) -> Event:
        """An event that succeeds at the servo tick where no move waits behind the running one on ``axes``."""
        self.servo.sync()
        group = tuple(self.axis(a).number for a in axes)
        return self.buffers.wait(lambda: self.buffers.loaded(group))

    # -- homing and linked moves ------------------------------------------------------------------
    def datum(self, axis: int, sequence: object, *, origin: str = "") -> Event | None:
        """``DATUM(sequence)`` on ``axis`` (see :mod:`.datum`); ``DATUM(0)`` clears the motion error bits."""
        self.servo.wake()
        ax = self.axis(axis)
        number = validate.integer(sequence, "DATUM sequence", low=0, high=6, whole=True,
                                  allowed="0..6 (0 clears the motion error)")
        if number == 0:
            for a in self.axes.values():
                a.fe_exceeded = False
            return None
        needs_switch = SEQUENCES[number][1] == "set"
        channel = ax.params["DATUM_IN"]
        if needs_switch and channel < 0:
            raise ConfigurationError(f"DATUM({number}) on axis {ax.number} needs the datum switch: DATUM_IN = -1 "
                                     "(allowed: the input the switch is wired to, 0..31)")
        read = self.read_input  # type: ignore[attr-defined]
        group = self._group((ax.number,), "DATUM")
        move = DatumMove(group, number, origin, switch=lambda: needs_switch and not read(channel))
        if not needs_switch:
            ax.ensure_z_mark()
        return self.buffers.add(move)

    def connect(self, axis: int, ratio: object, driving: object, *, origin: str = "") -> Event:
        """``CONNECT(ratio, driving axis)``: ``axis`` follows the driving axis' measured position."""
        self.servo.wake()
        link = self.axis(driving, where="CONNECT driving axis")
        group = self._group((axis,), "CONNECT")
        if link.number == group[0]:
            raise ConfigurationError(f"CONNECT: axis {link.number} cannot drive itself (allowed: another axis)")
        move = LinkedMove(group, "CONNECT", (validate.exact(ratio, "CONNECT ratio"),), origin, link=link.number)
        move.link_axis = link
        return self.buffers.add(move)

    def movelink(self, axis: int, *values: object, origin: str = "") -> Event:
        """``MOVELINK(distance, link dist, link acc, link dec, link axis[, option[, link pos]])``."""
        self.servo.wake()
        distance, link_dist, link_acc, link_dec = (validate.exact(v, f"MOVELINK {n}") for v, n in
                                                   zip(values[:4], ("distance", "link dist", "link acc", "link dec"),
                                                       strict=True))
        validate.positive(link_dist, "MOVELINK link dist", unit="units of the link axis")
        for value, name in ((link_acc, "link acc"), (link_dec, "link dec")):
            validate.in_range(value, f"MOVELINK {name}", low=0, high=link_dist, unit="units of the link axis")
        if link_acc + link_dec > link_dist:
            scale = link_dist / (link_acc + link_dec)  # the blends share the link distance (TRM: reduced)
            link_acc, link_dec = link_acc * scale, link_dec * scale
        return self._linked(axis, "MOVELINK", (distance, link_dist, link_acc, link_dec), values[4:], origin)

    def cambox(self, axis: int, *values: object, origin: str = "") -> Event:
        """``CAMBOX(start, end, table multiplier, link distance, link axis[, option[, link pos]])``."""
        self.servo.wake()
        start, end = (Fraction(validate.integer(v, f"CAMBOX {n}", low=0, whole=True)) for v, n in
                      zip(values[:2], ("start", "end"), strict=True))
        self.table_value(start), self.table_value(end)
        multiplier = validate.exact(values[2], "CAMBOX table multiplier")
        link_dist = validate.positive(values[3], "CAMBOX link distance", unit="units of the link axis")
        return self._linked(axis, "CAMBOX", (start, end, multiplier, link_dist), values[4:], origin)

    def cam(self, axis: int, *values: object, origin: str = "") -> Event:
        """``CAM(start, end, table multiplier, distance)``: the TABLE over ``distance / SPEED`` seconds."""
        self.servo.wake()
        start, end = (Fraction(validate.integer(v, f"CAM {n}", low=0, whole=True)) for v, n in
                      zip(values[:2], ("start", "end"), strict=True))
        self.table_value(start), self.table_value(end)
        multiplier = validate.exact(values[2], "CAM table multiplier")
        distance = validate.positive(values[3], "CAM distance", unit="units")
        group = self._group((axis,), "CAM")
        speed = validate.positive(self.axes[group[0]].params["SPEED"], "SPEED for CAM")
        return self.buffers.add(CamMove(group, (start, end, multiplier, distance), origin,
                                        table=self.table_value, speed=Fraction(speed)))

    def _linked(self, axis: int, kind: str, numbers: tuple[Fraction, ...], rest: Sequence[object],
                origin: str) -> Event:
        link = self.axis(rest[0], where=f"{kind} link axis")
        option = validate.integer(rest[1], f"{kind} link option", low=0, whole=True) if len(rest) > 1 else 0
        link_pos = validate.exact(rest[2], f"{kind} link pos") if len(rest) > 2 else Fraction(0)
        if option not in LINK_OPTIONS:
            self.sim.notes.not_modelled(self.device, f"{kind} link option", option, where=origin)
            option = 0
        group = self._group((axis,), kind)
        if link.number == group[0]:
            raise ConfigurationError(f"{kind}: axis {link.number} cannot be its own link axis")
        move = LinkedMove(group, kind, numbers, origin, link=link.number, option=option, link_pos=link_pos,
                          table=self.table_value)
        move.link_axis = link
        return self.buffers.add(move)

    def regist(self, axis: int, mode: object, *extra: object, origin: str = "") -> None:
        """``REGIST(mode)``: arm the registration of ``axis`` (see :meth:`Axis.arm_registration`)."""
        self.servo.wake()
        ax = self.axis(axis)
        number = validate.integer(mode, "REGIST mode", low=0, whole=True)
        if number not in (1, 2, 3, 4) or extra:
            self.sim.notes.not_modelled(self.device, f"REGIST({number}{', ...' if extra else ''}) axis {ax.number}",
                                        number, where=origin)
            return
        ax.arm_registration(number, self.read_input_signal)  # type: ignore[attr-defined]
