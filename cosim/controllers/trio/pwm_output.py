"""The PWM output pin of a EURO205X PWM axis in the trace: carrier AND gate AND WDOG, as pulse segments.

``trio.axisN.pwm_out`` is the level of the pin that the laser sees (TN20-81: the 20 MHz PWM
generator, gated by the position FIFO, switched off while WDOG is off), recorded as a pulse train
whose segments each carry their own pulse width (a train declared with ``varying_width``, see
:mod:`cosim.trace`)::

    settings   | cycle 1000, mark 400 ............................| mark 600 ......| gate closed
    pin        _|‾‾|___|‾‾|___|‾‾|___|‾‾|___|‾‾|___|‾‾|___|‾‾|___|‾‾‾|__|‾‾‾|__|‾|_______
    segments    one: t0 = first rise, count n, duration n * period, width = mark * 50 ns
                (pulse k rises at t0 + k * period); a pulse cut by a change is a segment of one

The output is a function of the axis' ``pwm_cycle``, ``pwm_mark`` and ``pwm_phase``, its ``gate``
and ``trio.wdog`` (the :class:`~cosim.signals.PwmPort` the laser coupling takes), exactly as
:func:`~cosim.controllers.trio.pwm.output_waveform` computes it from the trace: in a stretch of
constant settings the pin is high from ``phase * 50 ns + k * cycle * 50 ns`` for ``mark * 50 ns``
while WDOG and the gate are on, continuously high for ``mark >= cycle``, low for ``mark = 0``. The
settings are committed once per instant, so a stretch ends at the first tick with a different
final setting and every edge falls on its exact tick. A pulse that a change cuts (the gate closing
in a mark, a shorter mark) ends there; one that a change leaves high (a longer mark) goes on into
the next stretch, so each recorded pulse is one rise and one fall of the pin.

Rows: at most two per stretch (the pulse in progress at its start, the evenly spaced ones), none
while the output is held off, so a 4.4 s run at 20 kHz (88,000 pulses) is a few rows per gate
window. The open stretch is written up to the instant each ``Simulation.run`` stops; a pulse high
at that instant is recorded as ending there (a run resumed mid-pulse records the rest as a new
pulse from that instant; the VCD shows no edge there, as a fall and a rise at one tick keep the
line high).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cosim.signals import PwmPort, Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation

Settings = tuple[bool, int, int, int]  # enabled (WDOG and gate), period, mark, phase start [ticks]


class PwmOutput:
    """Records the PWM output pin of one axis as a pulse train with a width per segment.

    Parameters
    ----------
    sim : Simulation
    name : str
        Trace name of the pin, e.g. ``trio.axis3.pwm_out``.
    port : PwmPort
        The axis' PWM signals (WDOG, gate, PWM_CYCLE, mark, phase), as the laser coupling gets them.
    clock_ticks : int
        One PWM clock [ticks] (50 ns).
    """

    def __init__(self, sim: Simulation, name: str, port: PwmPort, *, clock_ticks: int) -> None:
        self.sim = sim
        self.name = name
        self.clock_ticks = clock_ticks
        self._inputs = (port.enable, port.gate, port.period_clocks, port.mark_clocks, port.phase_clocks)
        sim.trace.declare(name, "pulse", varying_width=True,
                          description="PWM output pin: carrier (PWM_CYCLE, mark, phase) AND gate AND WDOG; "
                                      "each pulse from its rising edge, high for its segment's width")
        self.start = sim.now
        self.settings = self._read()
        self.rise: int | None = None  # where the pulse in progress rose (the pin is high at `start`)
        for signal in self._inputs:
            signal.subscribe(self._changed)
        sim.on_stop(self.flush)

    def _read(self) -> Settings:
        enable, gate, period, mark, phase = (int(s.value) for s in self._inputs)
        clock = self.clock_ticks
        return bool(enable and gate), period * clock, mark * clock, phase * clock

    def _changed(self, _signal: Signal) -> None:
        now = self.sim.now
        if now > self.start:
            self._close(now)
        self.settings = self._read()  # the last change at an instant wins

    def flush(self, t: int) -> None:
        """Write everything up to ``t`` (a pulse high at ``t`` ends there); the stretch goes on from ``t``."""
        if t > self.start:
            self._close(t)
        if self.rise is not None and t > self.rise:
            self._pulse(self.rise, t - self.rise)
            self.rise = None

    def _pulse(self, t0: int, width: int) -> None:
        self.sim.trace.record_segment(self.name, t0, width, 1, 1, width=width)

    def _close(self, end: int) -> None:
        """Record the pulses of the stretch ``[start, end)``; keep the one still high at ``end - 1``."""
        a, (enabled, period, mark, phase) = self.start, self.settings
        self.start = end
        if not enabled or mark <= 0:  # held low
            if self.rise is not None:
                self._pulse(self.rise, a - self.rise)
                self.rise = None
            return
        if mark >= period:  # continuously on
            if self.rise is None:
                self.rise = a
            return
        this_rise = a - (a - phase) % period
        first = this_rise + period  # the first rise after a
        if a - this_rise < mark:  # high at a: the pulse in progress (or one rising at a)
            rise = a if self.rise is None else self.rise
            if rise == this_rise:  # it rose with the carrier: a regular pulse
                first = this_rise
            elif this_rise + mark >= end:
                self.rise = rise
                return
            else:
                self._pulse(rise, this_rise + mark - rise)
        elif self.rise is not None:  # the new settings put a in a space: the pin falls at a
            self._pulse(self.rise, a - self.rise)
        self.rise = None
        if first >= end:
            return
        rises = (end - 1 - first) // period + 1
        last = first + (rises - 1) * period
        if last + mark >= end:  # still high at the end of the stretch
            self.rise = last
            rises -= 1
        if rises:
            self.sim.trace.record_segment(self.name, first, rises * period, rises, 1, width=mark)
