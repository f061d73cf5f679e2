"""The PWM generator of a EURO205X PWM axis (TN20-81), and the PWM output in closed form.

The generator counts a 20 MHz clock (50 ns). ``PWM_CYCLE`` is the mark+space period and
``PWM_MARK`` the on-time, both in clocks (0..65535): ``PWM_CYCLE=1000`` is 20 kHz, ``200`` is
100 kHz. ``PWM_MARK >= PWM_CYCLE`` is continuously on; ``PWM_MARK = 0`` is off.

Where the mark comes from (``PWM_CONTROL`` modes 0 to 2):

* mode 0 (:attr:`PwmMode.OFF`): output off (the laser gets ``pwm_mark = 0``);
* mode 1 (:attr:`PwmMode.FIXED`): the ``PWM_MARK`` axis parameter;
* mode 2 (:attr:`PwmMode.LINKED`): every servo cycle ``PWM_MARK`` is loaded with
  ``VP_SPEED(link axis) * multiplier / 100000 + offset``, and with ``limit`` if that exceeds it
  (:func:`linked_mark`).

The outputs the Laser FMU takes: ``trio.axisN.pwm_cycle`` (its ``pwm_period``),
``trio.axisN.pwm_mark`` (``pwm_on``), ``trio.axisN.pwm_phase`` (``pwm_phase``: the clock count
at which the carrier's periods start; a new ``PWM_CYCLE`` restarts the carrier at the next clock
edge), ``trio.axisN.gate`` and ``trio.wdog`` (``enable``). :func:`output_waveform` computes the
resulting output edges exactly from a trace (the pure-Python reference for the PWM tests).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from fractions import Fraction
from itertools import pairwise
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from cosim import validate
from cosim.controllers.trio.outputs import SettledSignal
from cosim.controllers.trio.params import PWM_CLOCK_HZ, PWM_CLOCK_NS, PWM_REGISTER_MAX, SPEED_LINK_DIVISOR
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation
    from cosim.trace import Trace

IntArray = npt.NDArray[np.int64]


class PwmMode(IntEnum):
    """Where the PWM mark comes from (``PWM_CONTROL`` modes 0, 1 and 2)."""

    OFF = 0
    FIXED = 1
    LINKED = 2


@dataclass(frozen=True)
class SpeedLink:
    """The arguments of ``PWM_CONTROL(2, multiplier, offset, limit value, link axis)``.

    Parameters
    ----------
    multiplier : Fraction
        Scale of VP_SPEED [clocks per (units/s) * 100000].
    offset : Fraction
        Added to the scaled speed [clocks].
    limit : int
        Largest mark loaded [clocks], 0..65535.
    link_axis : int
        Axis whose VP_SPEED is used.
    """

    multiplier: Fraction
    offset: Fraction
    limit: int
    link_axis: int


def linked_mark(vp_speed: Fraction, link: SpeedLink) -> int:
    """The mark loaded by the speed link for one servo cycle [clocks].

    ``VP_SPEED * multiplier / 100000 + offset``, the limit value if it exceeds it, rounded down to
    a whole clock (the register is an integer) and never below 0.

    Examples
    --------
    >>> link = SpeedLink(Fraction(1000), Fraction(50), 400, 3)
    >>> linked_mark(Fraction(0), link), linked_mark(Fraction(12345), link), linked_mark(Fraction(50000), link)
    (50, 173, 400)
    """
    value = vp_speed * link.multiplier / SPEED_LINK_DIVISOR + link.offset
    if value > link.limit:
        return link.limit
    return max(0, math.floor(value))


def pwm_frequency_hz(cycle_clocks: int) -> Fraction:
    """Carrier frequency of ``PWM_CYCLE = cycle_clocks`` [Hz], exact (20 MHz / cycle).

    Examples
    --------
    >>> pwm_frequency_hz(1000), pwm_frequency_hz(200)
    (Fraction(20000, 1), Fraction(100000, 1))
    """
    cycle = validate.integer(cycle_clocks, "PWM_CYCLE", low=1, high=PWM_REGISTER_MAX,
                             allowed=f"1..{PWM_REGISTER_MAX} for a frequency")
    return Fraction(PWM_CLOCK_HZ, cycle)


class PwmGenerator:
    """The PWM generator of one axis: PWM_CYCLE, PWM_MARK and the mark source.

    Parameters
    ----------
    sim : Simulation
    prefix : str
        Trace prefix of the axis, e.g. ``trio.axis3``.
    """

    def __init__(self, sim: Simulation, prefix: str) -> None:
        self.sim = sim
        self.clock_ticks = sim.ticks(PWM_CLOCK_NS, "ns", name="PWM clock period (50 ns)")
        self.mode = PwmMode.OFF
        self.cycle = 0
        self.mark = 0
        self.link: SpeedLink | None = None
        self._link_terms: tuple[object, int, int, int] = (None, 0, 0, 1)  # the link and its integer terms
        self.cycle_out = SettledSignal(sim, f"{prefix}.pwm_cycle", kind="int", unit="clocks",
                                       description="PWM_CYCLE: mark+space period [20 MHz clocks]")
        self.mark_out = SettledSignal(sim, f"{prefix}.pwm_mark", kind="int", unit="clocks",
                                      description="PWM mark the laser gets [20 MHz clocks] (0 while PWM is off)")
        self.phase_out = Signal(sim, f"{prefix}.pwm_phase", kind="int", unit="clocks",
                                description="20 MHz clock count at which the carrier periods start")

    @property
    def on(self) -> bool:
        """True unless the output is switched off (``PWM_CONTROL(0)``)."""
        return self.mode != PwmMode.OFF

    def set_cycle(self, cycle: int) -> None:
        """Write ``PWM_CYCLE`` [clocks] (checked by the caller); the carrier restarts at the next clock."""
        if cycle != self.cycle:
            self.cycle = cycle
            self.phase_out.set(-(-self.sim.now // self.clock_ticks))
        self.cycle_out.request(cycle)

    def set_mark(self, mark: int) -> None:
        """Write ``PWM_MARK`` [clocks] (overwritten every servo cycle while the speed link runs)."""
        self.mark = mark
        self._publish()

    def switch(self, mode: PwmMode, link: SpeedLink | None = None) -> None:
        """``PWM_CONTROL(0)``, ``(1)`` or ``(2, ...)``: choose the source of the mark."""
        self.mode = mode
        self.link = link if mode == PwmMode.LINKED else None
        self._publish()

    def servo_update_ratio(self, v_num: int, v_den: int) -> None:
        """:meth:`servo_update` with ``vp_speed = v_num / v_den`` given as integers (the servo cycle's form)."""
        link = self.link
        if self.mode == PwmMode.LINKED and link is not None:
            mark = self.linked_mark(link, v_num, v_den)
            if mark != self.mark or self.mark_out._wanted != (mark if self.mode != PwmMode.OFF else 0):
                self.set_mark(mark)

    def linked_mark(self, link: SpeedLink, v_num: int, v_den: int) -> int:
        """The mark [clocks] ``link`` gives for ``VP_SPEED = v_num / v_den`` (:func:`linked_mark`, in integers)."""
        if self._link_terms[0] is not link:
            m, o = link.multiplier, link.offset
            self._link_terms = (link, m.numerator * o.denominator, o.numerator * m.denominator * SPEED_LINK_DIVISOR,
                                m.denominator * SPEED_LINK_DIVISOR * o.denominator)
        _, a, b, c = self._link_terms
        num = v_num * a + b * v_den  # VP_SPEED * multiplier / divisor + offset = num / den, exactly
        den = v_den * c
        if den < 0:
            num, den = -num, -den
        return link.limit if num > link.limit * den else max(0, num // den)

    def servo_update(self, vp_speed: Fraction) -> None:
        """Servo-cycle update of the speed link (``vp_speed`` of the link axis) [units/s]."""
        if self.mode == PwmMode.LINKED and self.link is not None:
            self.set_mark(linked_mark(vp_speed, self.link))

    def _publish(self) -> None:
        self.mark_out.request(self.mark if self.on else 0)


# -- the output in closed form -----------------------------------------------------------------
def carrier_edges(t0: int, t1: int, *, cycle: int, mark: int, clock_ticks: int, phase: int = 0,
                  enabled: bool = True) -> tuple[IntArray, IntArray]:
    """Exact edges of the PWM output over ``[t0, t1)`` with constant settings.

    Parameters
    ----------
    t0, t1 : int
        Interval [ticks].
    cycle, mark : int
        PWM_CYCLE and the mark [20 MHz clocks].
    clock_ticks : int
        Length of a PWM clock [ticks] (50 ns: 50 at the default resolution).
    phase : int
        Clock count at which a carrier period starts.
    enabled : bool
        WDOG on, gate open and PWM on; False gives a constant low output.

    Returns
    -------
    (t, level) : arrays of int
        The level at ``t0`` first, then each change inside the interval.

    Examples
    --------
    >>> t, v = carrier_edges(0, 100_000, cycle=1000, mark=400, clock_ticks=50)
    >>> t.tolist(), v.tolist()
    ([0, 20000, 50000, 70000], [1, 0, 1, 0])
    """
    if not enabled or mark <= 0:
        return np.array([t0], dtype=np.int64), np.array([0], dtype=np.int64)
    if mark >= cycle:
        return np.array([t0], dtype=np.int64), np.array([1], dtype=np.int64)
    period, on, start = cycle * clock_ticks, mark * clock_ticks, phase * clock_ticks
    k0 = (t0 - start) // period
    k1 = -(-(t1 - start) // period)
    rise = start + np.arange(k0, k1 + 1, dtype=np.int64) * period
    t = np.stack([rise, rise + on], axis=1).ravel()
    v = np.tile(np.array([1, 0], dtype=np.int64), rise.size)
    level_at_t0 = int(v[np.searchsorted(t, t0, side="right") - 1])
    inside = (t > t0) & (t < t1)
    return (np.concatenate([[t0], t[inside]]).astype(np.int64),
            np.concatenate([[level_at_t0], v[inside]]).astype(np.int64))


def output_waveform(trace: Trace, axis: int, t0: int, t1: int, *,
                    device: str = "trio") -> tuple[IntArray, IntArray]:
    """Exact edges of an axis' PWM output over ``[t0, t1)`` [ticks], from the trace alone.

    The output is high when WDOG is on, the gate is open, and the carrier of ``pwm_cycle``,
    ``pwm_mark`` and ``pwm_phase`` is in its mark. Returns ``(t, level)``: the level at
    ``t0`` first, then every change.
    """
    prefix = f"{device}.axis{axis}"
    names = (f"{device}.wdog", f"{prefix}.gate", f"{prefix}.pwm_cycle", f"{prefix}.pwm_mark",
             f"{prefix}.pwm_phase")
    clock_ticks = trace.timebase.ticks(PWM_CLOCK_NS, "ns", name="PWM clock period (50 ns)")
    cuts = {t0}
    for name in names:
        t, _ = trace.edges(name)
        cuts.update(int(x) for x in t[(t > t0) & (t < t1)])
    bounds = [*sorted(cuts), t1]
    ts: list[IntArray] = []
    vs: list[IntArray] = []
    for a, b in pairwise(bounds):
        wdog, gate, cycle, mark, phase = (trace.value_at(n, a) for n in names)
        t, v = carrier_edges(a, b, cycle=int(cycle), mark=int(mark), clock_ticks=clock_ticks, phase=int(phase),
                             enabled=bool(wdog) and bool(gate))
        ts.append(t)
        vs.append(v)
    t_all, v_all = np.concatenate(ts), np.concatenate(vs)
    keep = np.concatenate([[True], v_all[1:] != v_all[:-1]])
    return t_all[keep], v_all[keep]


def rising_edges(t: IntArray, level: IntArray) -> IntArray:
    """Instants where a waveform from :func:`output_waveform` goes high (not its first sample)."""
    up = np.flatnonzero((level[1:] == 1) & (level[:-1] == 0)) + 1
    return t[up]
