"""DATUM sequences (homing on the datum switch and the Z marker) and jogging on inputs.

``DATUM(n)`` on the base axis [?: the sequences as the TRM describes them, the details below are
the model's]:

======  ===========================================================================================
0       clears the axis' motion error bits (AXISSTATUS 256); no motion
1       forward at CREEP until the Z marker; position 0 there
2       reverse at CREEP until the Z marker; position 0 there
3       forward at SPEED until the datum switch is set, then back at CREEP until it is reset; 0 there
4       reverse at SPEED until the datum switch is set, then forward at CREEP until it is reset; 0 there
5       forward at SPEED until the datum switch is set, then back at CREEP until the Z marker; 0 there
6       reverse at SPEED until the datum switch is set, then forward at CREEP until the Z marker; 0 there
======  ===========================================================================================

The datum switch is the input ``DATUM_IN`` and is active low (set while the input is OFF: the
fail-safe wiring of a normally closed switch); the Z marker is the axis' ``trio.axisN.z_mark``
input (its rising edges). Inputs are seen at servo ticks: the switch is read at each tick, a Z
edge between two ticks is seen at the next one. At the switch the fast search decelerates at DECEL
to rest, then the creep phase accelerates at ACCEL to CREEP; when the creep phase sees its event its
position there becomes 0 (DPOS and MPOS, as DEFPOS(0) at
that tick) and the axis decelerates at DECEL to rest (a little beyond: CREEP^2 / (2 DECEL)).
AXISSTATUS bit 64 is set while the sequence runs.

``FWD_JOG`` / ``REV_JOG`` (inputs, active low): while the axis has no move and the input is set,
it jogs at JOGSPEED (at SPEED while the ``FAST_JOG`` input is set) and decelerates at DECEL when the
input is reset.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.linked import GenericMove
from cosim.controllers.trio.piecewise import Piecewise
from cosim.controllers.trio.profile import Ramp, Stop
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis

#: (direction of the search, what ends it, direction of the creep, what ends the creep), by sequence.
SEQUENCES: dict[int, tuple[int, str, int, str]] = {
    1: (0, "", 1, "z"), 2: (0, "", -1, "z"),
    3: (1, "set", -1, "reset"), 4: (-1, "set", 1, "reset"),
    5: (1, "set", -1, "z"), 6: (-1, "set", 1, "z"),
}


class DatumMove(GenericMove):
    """One DATUM sequence of the base axis (see the module doc).

    Parameters
    ----------
    sequence : int
        1..6.
    switch : callable
        ``switch()`` -> True while the datum switch is set (read at a servo tick).
    """

    def __init__(self, axes: tuple[int, ...], sequence: int, origin: str = "", *, switch: Any) -> None:
        super().__init__(axes, "DATUM", (Fraction(sequence),), origin)
        self.sequence = sequence
        self.switch = switch
        self.phase = ""
        self.profile_now: Piecewise | None = None
        self.phase_start = 0  # cycles at the start of the phase
        self.sign = 1
        self.base_count = Fraction(0)
        self.z_seen = False

    def begin(self) -> None:
        search, _event, _creep, _end = SEQUENCES[self.sequence]
        self.base_count = self.start_count
        axis = self.axis_list[0]
        axis.z_seen = False
        if search and not self.switch():
            self._phase("search", search, Ramp(Fraction(axis.params["SPEED"]), Fraction(axis.params["ACCEL"])))
        else:
            self._creep()

    def _phase(self, name: str, sign: int, profile: Ramp | Stop) -> None:
        self.phase, self.sign = name, sign
        self.profile_now = profile.pieces()
        self.phase_start = self.cycles
        self.base_count = self.last

    def _creep(self) -> None:
        axis = self.axis_list[0]
        _search, _event, creep, _end = SEQUENCES[self.sequence]
        speed = Fraction(axis.params["CREEP"])
        if speed <= 0:
            raise ConfigurationError(f"DATUM({self.sequence}) on axis {axis.number}: CREEP = 0 (allowed: > 0, the "
                                     "speed of the slow phase)")
        axis.z_seen = False
        self._phase("creep", creep, Ramp(speed, Fraction(axis.params["ACCEL"])))

    def _local(self) -> Fraction:
        return (self.cycles - self.phase_start) * self.period_s

    def target(self) -> Fraction:
        axis = self.axis_list[0]
        _search, _event, _creep, end = SEQUENCES[self.sequence]
        if self.phase == "search" and self.switch():  # seen at this tick: decelerate to rest
            t = self._local() - self.period_s
            assert self.profile_now is not None
            stop = Stop(t, self.profile_now.position(t), self.profile_now.speed(t), Fraction(axis.params["DECEL"]))
            self.profile_now = stop.pieces()
            self.phase = "stopping"
        elif self.phase == "stopping" and self._local() - self.period_s >= self._stop_end():
            self._creep()
        elif self.phase == "creep" and ((end == "reset" and not self.switch()) or (end == "z" and axis.z_seen)):
            axis.datum_found(self.last)  # DPOS = 0 where the event was seen; then the axis comes to rest
            t = self._local() - self.period_s
            assert self.profile_now is not None
            stop = Stop(t, self.profile_now.position(t), self.profile_now.speed(t), Fraction(axis.params["DECEL"]))
            self.profile_now = stop.pieces()
            self.phase = "found"
        elif self.phase == "found" and self._local() >= self._stop_end():
            self.done = True
        assert self.profile_now is not None
        s = self.profile_now.position(self._local())
        return self.base_count + self.sign * s * axis.units

    def _stop_end(self) -> Fraction:
        assert self.profile_now is not None and self.profile_now.t_end is not None
        return self.profile_now.t_end

    def stop(self, period_s: Fraction, decel: Fraction) -> None:
        """CANCEL: the sequence stops (decelerating from the speed it has), without a datum."""
        self.cancel_requested = False
        self.cancelling = True
        t = self._local()
        assert self.profile_now is not None
        stop = Stop(t, self.profile_now.position(t), self.profile_now.speed(t), decel)
        self.profile_now = stop.pieces()
        self.phase = "cancelled"
        end = stop.t_end
        target = self.target

        def stopping() -> Fraction:
            value = target()
            if self._local() >= end:
                self.done = True
            return value
        self.target = stopping  # type: ignore[method-assign]


class JogMove(GenericMove):
    """A jog on the FWD_JOG / REV_JOG inputs: a ramp at JOGSPEED until the input is reset."""

    def __init__(self, axes: tuple[int, ...], sign: int, speed: Fraction) -> None:
        super().__init__(axes, "FWD_JOG" if sign > 0 else "REV_JOG", (speed,))
        self.sign = sign
        self.profile_now: Piecewise | None = None
        self.phase_start = 0

    def begin(self) -> None:
        axis = self.axis_list[0]
        self.profile_now = Ramp(self.values[0], Fraction(axis.params["ACCEL"])).pieces()

    def target(self) -> Fraction:
        assert self.profile_now is not None
        s = self.profile_now.position((self.cycles - self.phase_start) * self.period_s)
        if self.profile_now.t_end is not None and (self.cycles - self.phase_start) * self.period_s >= \
                self.profile_now.t_end:
            self.done = True
        return self.start_count + self.sign * s * self.axis_list[0].units

    def heading(self, axis: int) -> int:
        return self.sign

    def stop(self, period_s: Fraction, decel: Fraction) -> None:
        """The jog input is reset (or CANCEL): decelerate to rest."""
        self.cancel_requested = False
        self.cancelling = True
        assert self.profile_now is not None
        t = (self.cycles - self.phase_start) * period_s
        self.profile_now = Stop(t, self.profile_now.position(t), self.profile_now.speed(t), decel).pieces()


def jog_direction(axis: Axis, read: Any) -> int:
    """+1 / -1 while the forward / reverse jog input of ``axis`` is set (active low), else 0."""
    fwd, rev = axis.params["FWD_JOG"], axis.params["REV_JOG"]
    if fwd >= 0 and not read(fwd):
        return 1
    if rev >= 0 and not read(rev):
        return -1
    return 0
