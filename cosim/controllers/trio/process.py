"""A Trio program's view of the controller: the BASIC vocabulary for Python scenario scripts.

Each Trio program (process) has its own BASE group; parameters and commands act on the BASE axis
(or the whole BASE group for moves), or on the axis given by an ``AXIS(n)`` modifier (``axis=n``
here). Commands that can make a program wait return a SimPy event to ``yield``; it has already
succeeded when there was nothing to wait for::

    p = TrioProcess(trio)
    p.base(3)
    p.set("UNITS", 16)
    p.table(1000, 110, 115, 195, 220)
    def job():
        yield p.pwm_control(3, 1, ON, 1000, 1003)   # waits while the FIFO is full
        yield p.moveabs(300)                        # waits while the move buffer is full
        yield p.wait_idle()
    sim.process(job())

The BASIC interpreter (:mod:`.basic`) runs programs through this same class.
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

from simpy.events import Event

from cosim import validate
from cosim.controllers.trio.controller import TrioController
from cosim.errors import ConfigurationError
from cosim.timebase import Priority


class TrioProcess:
    """One program's state (its BASE group) and the commands of the modelled BASIC subset.

    Parameters
    ----------
    controller : TrioController
    base : tuple of int
        Initial BASE group (axis 0 by default, as on the controller).
    """

    def __init__(self, controller: TrioController, base: tuple[int, ...] = (0,)) -> None:
        self.controller = controller
        self.sim = controller.sim
        self.base_axes: tuple[int, ...] = ()
        self.base(*base)
        #: Where the next command comes from (``job.bas line 12``), for errors raised later by its move.
        self.origin = ""
        self._ticks_value = 0
        self._ticks_set_at = controller.sim.now

    def _done(self) -> Event:
        event = self.sim.env.event()
        event.succeed()
        return event

    def _axes(self, axis: object | None) -> tuple[int, ...]:
        return self.base_axes if axis is None else (self.controller.axis(axis).number,)

    def base(self, *axes: object) -> None:
        """``BASE(a, b, ...)``: the axes later commands act on (first = base axis)."""
        if not axes:
            raise ConfigurationError.out_of_range("number of BASE axes", 0, f"1..{len(self.controller.axes)}")
        group = tuple(self.controller.axis(a).number for a in axes)
        if len(set(group)) != len(group):
            raise ConfigurationError(f"BASE{group} names an axis twice")
        self.base_axes = group

    def set(self, name: str, value: object, *, axis: object | None = None) -> None:
        """``NAME = value`` (``NAME AXIS(n) = value`` with ``axis``): write a parameter."""
        self.controller.set_param(name, value, axis=self._axes(axis)[0], where=_where(self.origin))

    def get(self, name: str, *, axis: object | None = None) -> Fraction:
        """Read parameter ``NAME`` of the base axis (or ``axis``) now."""
        return self.controller.get_param(name, axis=self._axes(axis)[0])

    def table(self, start: object, *values: object) -> None:
        """``TABLE(start, v1, ...)``: write TABLE memory."""
        self.controller.table(start, *values)

    def table_value(self, index: object) -> Fraction:
        """``TABLE(n)``: read TABLE memory."""
        return self.controller.table_value(index)

    def defpos(self, *positions: object, axis: object | None = None) -> None:
        """``DEFPOS(p1, ...)``: define positions of the BASE axes (applied at the next servo cycle)."""
        self.controller.defpos(self._axes(axis), positions)

    def move(self, *distances: object, axis: object | None = None) -> Event:
        """``MOVE(d1, ...)``: relative move of the BASE axes, interpolated."""
        return self.controller.move(self._axes(axis), distances, absolute=False, origin=self.origin)

    def moveabs(self, *positions: object, axis: object | None = None) -> Event:
        """``MOVEABS(p1, ...)``: absolute move of the BASE axes, interpolated."""
        return self.controller.move(self._axes(axis), positions, absolute=True, origin=self.origin)

    def movecirc(self, end1: object, end2: object, centre1: object, centre2: object, direction: object, *,
                 axis: object | None = None) -> Event:
        """``MOVECIRC(end1, end2, centre1, centre2, direction)``: an arc of the first two BASE axes.

        End and centre relative to the start [units]; direction 0 anticlockwise, 1 clockwise.
        ``VP_SPEED`` of the base axis is the speed along the arc.
        """
        return self.controller.movecirc(self._axes(axis), (end1, end2, centre1, centre2, direction),
                                        origin=self.origin)

    def forward(self, *, axis: object | None = None) -> Event:
        """``FORWARD``: move the base axis (or ``axis``) forward at SPEED until ``CANCEL``."""
        return self.controller.forward(self._axes(axis)[0], origin=self.origin)

    def reverse(self, *, axis: object | None = None) -> Event:
        """``REVERSE``: move the base axis (or ``axis``) in reverse at SPEED until ``CANCEL``."""
        return self.controller.forward(self._axes(axis)[0], reverse=True, origin=self.origin)

    def cancel(self, *, axis: object | None = None, buffered: bool = False) -> None:
        """``CANCEL``: the running move of the base axis (or ``axis``) decelerates to rest at DECEL;
        ``CANCEL(1)`` (``buffered``): its buffered move is dropped instead."""
        self.controller.cancel(self._axes(axis)[:1], buffered=buffered)

    def movemodify(self, position: object, *, axis: object | None = None) -> Event:
        """``MOVEMODIFY(position)``: the running linear move of the base axis ends at ``position`` instead."""
        return self.controller.movemodify(self._axes(axis)[0], position, origin=self.origin)

    def datum(self, sequence: object, *, axis: object | None = None) -> Event:
        """``DATUM(n)``: a homing sequence of the base axis (see :mod:`.datum`); DATUM(0) clears motion errors."""
        event = self.controller.datum(self._axes(axis)[0], sequence, origin=self.origin)
        return event if event is not None else self._done()

    def connect(self, ratio: object, driving: object, *, axis: object | None = None) -> Event:
        """``CONNECT(ratio, driving axis)``: the base axis follows the driving axis (see :mod:`.linked`)."""
        return self.controller.connect(self._axes(axis)[0], ratio, driving, origin=self.origin)

    def movelink(self, *values: object, axis: object | None = None) -> Event:
        """``MOVELINK(distance, link dist, link acc, link dec, link axis[, option[, link pos]])``."""
        return self.controller.movelink(self._axes(axis)[0], *values, origin=self.origin)

    def cambox(self, *values: object, axis: object | None = None) -> Event:
        """``CAMBOX(start, end, table multiplier, link distance, link axis[, option[, link pos]])``."""
        return self.controller.cambox(self._axes(axis)[0], *values, origin=self.origin)

    def cam(self, *values: object, axis: object | None = None) -> Event:
        """``CAM(start, end, table multiplier, distance)``."""
        return self.controller.cam(self._axes(axis)[0], *values, origin=self.origin)

    def regist(self, mode: object, *extra: object, axis: object | None = None) -> None:
        """``REGIST(mode)``: arm the registration of the base axis."""
        self.controller.regist(self._axes(axis)[0], mode, *extra, origin=self.origin)

    def wait_idle(self, *, axis: object | None = None) -> Event:
        """``WAIT IDLE``: until every BASE axis has finished its moves."""
        return self.controller.wait_idle(self._axes(axis))

    def wait_loaded(self, *, axis: object | None = None) -> Event:
        """``WAIT LOADED``: until no move waits behind the running one on the BASE axes."""
        return self.controller.wait_loaded(self._axes(axis))

    def op(self, channel: object, state: object) -> None:
        """``OP(n, ON/OFF)``: set a digital output."""
        self.controller.io.write_output(channel, state)

    def read_op(self, channel: object) -> int:
        """``READ_OP(n)``: the state last written to output ``n`` (1 ON, 0 OFF)."""
        return self.controller.io.read_output(channel)

    def input(self, channel: object) -> int:
        """``IN(n)``: the state of digital input ``n`` (1 ON, 0 OFF)."""
        return self.controller.io.read_input(channel)

    @property
    def ticks(self) -> int:
        """``TICKS``: this process' counter, decremented at every servo tick since it was last written.

        A 32-bit signed register (it wraps); 0 when the process starts.
        """
        period = self.controller.period_ticks
        elapsed = self.sim.now // period - self._ticks_set_at // period
        return (self._ticks_value - elapsed + (1 << 31)) % (1 << 32) - (1 << 31)

    @ticks.setter
    def ticks(self, value: object) -> None:
        self._ticks_value = validate.integer(value, "TICKS", low=-(1 << 31), high=(1 << 31) - 1, whole=True)
        self._ticks_set_at = self.sim.now

    def pwm_control(self, mode: object, *args: object, axis: object | None = None) -> Event:
        """``PWM_CONTROL(mode, ...)`` on the base axis (or ``axis``); mode 3 may wait for FIFO space."""
        loaded = self.controller.pwm_control(self._axes(axis)[0], mode, *args)
        return loaded if loaded is not None else self._done()

    def wa(self, ms: object, *, priority: int = Priority.HOST) -> Event:
        """``WA(ms)``: wait ``ms`` milliseconds (a whole number of ticks); the program goes on at HOST priority,
        after a servo tick at that instant, like every program wake-up."""
        value = validate.positive(ms, "WA time", unit="ms", zero=True)
        return self.sim.after(self.sim.timebase.ticks(value, "ms", name="WA time"), priority)

    def wait_until(self, condition: Any) -> Generator[Event, Any, None]:
        """``WAIT UNTIL cond``: check ``condition()`` now, then at every servo tick until it holds."""
        period = self.controller.period_ticks
        while not condition():
            yield self.sim.at((self.sim.now // period + 1) * period, Priority.HOST)



def _where(origin: str) -> str:
    """``job.bas line 12`` as the notes write a place: ``job.bas:12``."""
    name, _, line = origin.rpartition(" line ")
    return f"{name}:{line}" if name else origin
