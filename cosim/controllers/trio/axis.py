"""One axis of the controller: parameters, demand and step counters, the step/direction output, DPOS/MPOS.

Positions are exact and kept in integers on the servo cycle's path:

* the **demand** in counts (step pulses) is ``dnum / dden`` (two Python ints, the denominator
  fixed for the duration of a move; see :mod:`.piecewise`);
* the **step counter** and MPOS of a stepper are whole counts (``int``);
* ``DPOS``, ``MPOS`` and ``VP_SPEED`` in user units are ``(counts - origin) / UNITS``: read as exact
  :class:`~fractions.Fraction` by a program (rarely), and recorded every servo cycle as the float of
  that exact value, computed as one integer division (``int / int`` in Python is correctly rounded,
  as ``float(Fraction)`` is: the same bits).

**Step output** (ATYPE 1 or 35). The change of the step counter over a cycle is one pulse segment
spread evenly over the cycle: pulse ``j`` of ``n`` starts (its *leading* edge) at
``t_s + k*T + dir_setup + floor(j*T/n)`` (the rule of :mod:`cosim.pulses`). Each pulse lasts
``step_pulse_width``; its *trailing* edge is the **active edge** (TRM 8-165: the falling edge by
default; ``INVERT_STEP=ON`` inverts the output so that the same edge is a rising one). The step
is counted there: MPOS, PWM_ENCODER and the gate see each pulse ``step_pulse_width`` after its
leading edge. The direction output changes at the servo tick, ``dir_setup`` before the leading
edge of the first pulse it concerns.

The step counter only moves by whole steps that the demand has covered in the direction of motion
(``floor`` moving up, ``ceil`` moving down); the fraction is carried to the next cycle, so no step
is ever lost or invented and the counter ends exactly on an integer target.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.controllers.trio.counter import StepCounter
from cosim.controllers.trio.gate import GateFifo
from cosim.controllers.trio.params import ATYPE_STEPPER, ATYPE_STEPPER_PWM, AXIS_PARAMS, STEPPER_ATYPES, Number
from cosim.controllers.trio.pwm import PwmGenerator
from cosim.errors import TimingViolation
from cosim.signals import PulseTrain, Signal

if TYPE_CHECKING:
    from cosim.controllers.trio.motion import Move
    from cosim.kernel import Simulation


class Axis:
    """One axis: parameters, demand and step counters, moves, step/direction, and (axes 2, 3) PWM and gate.

    Parameters
    ----------
    sim : Simulation
    number : int
        Axis number.
    pwm : bool
        The axis has the PWM / gating feature.
    device : str
        Trace device name.
    pulse_width : int
        Step pulse width [ticks]: from the leading edge to the active edge.
    dir_setup : int
        Direction set-up before the leading edge of a pulse [ticks].
    """

    def __init__(self, sim: Simulation, number: int, *, pwm: bool, device: str = "trio", pulse_width: int = 100,
                 dir_setup: int = 0) -> None:
        self.sim = sim
        self.number = number
        self.has_pwm = pwm
        self.prefix = f"{device}.axis{number}"
        self.pulse_width = pulse_width
        self.dir_setup = dir_setup
        self.params: dict[str, Any] = {s.name: s.default for s in AXIS_PARAMS.values() if pwm or not s.pwm_only}
        #: Demand position [counts] = dnum / dden (exact).
        self.dnum, self.dden = 0, 1
        #: Counts at DPOS = 0 (moved by DEFPOS and REP_DIST).
        self.origin = Fraction(0)
        self.pending_shift = Fraction(0)
        self.steps_raw = 0
        self.feedback = StepCounter(0)
        #: VP_SPEED [units/s] = vnum / vden.
        self.vnum, self.vden = 0, 1
        #: MPOS latched at the servo tick [counts] = mnum / mden.
        self.mnum, self.mden = 0, 1
        self.current: Move | None = None
        self.queued: Move | None = None
        #: Limits or jog inputs are configured: the servo cycle watches them (see :mod:`.supervise`).
        self.supervised = False
        #: Sign of the demand's change in the last cycle (+1, -1, 0).
        self.moving = 0
        #: The following error exceeded FE_LIMIT (AXISSTATUS 256, until DATUM(0)).
        self.fe_exceeded = False
        #: Registration: the armed mode (0: none), MARK, the position latched [counts].
        self.regist_mode = 0
        self.mark = False
        self.reg_pos_counts = Fraction(0)
        sim.trace.may_declare(f"{self.prefix}.reg_pos")
        self.z_seen = False
        self.z_mark: Signal | None = None
        #: Nothing of the axis changes at the next servo tick unless a command or a move changes it (set False
        #: by every change; the servo cycle then runs the axis until it is at rest and recorded).
        self.quiet = False
        self.dpos_out = Signal(sim, f"{self.prefix}.dpos", kind="real", unit="units", description="DPOS")
        self.mpos_out = Signal(sim, f"{self.prefix}.mpos", kind="real", unit="units", description="MPOS")
        self.vp_out = Signal(sim, f"{self.prefix}.vp_speed", kind="real", unit="units/s",
                             description="VP_SPEED: path speed of the move being executed")
        self.step: PulseTrain | None = None
        #: The servo tick whose cycle emitted the last pulse segment (the controller announces the end of a run
        #: of segments at the next tick without pulses: :meth:`PulseTrain.end_run`).
        self.emitted_at: int | None = None
        self.dir: Signal | None = None
        self.invert_out: Signal | None = None
        self.pwm: PwmGenerator | None = None
        self.gate: GateFifo | None = None
        self._scale_key: tuple[object, object] = (None, None)
        self._scale = (1, 0, 1)
        self._vp_scale = 1
        if pwm:
            self.pwm = PwmGenerator(sim, self.prefix)
            self.gate = GateFifo(sim, self.prefix)
            self.ensure_outputs()

    def ensure_outputs(self) -> tuple[PulseTrain, Signal]:
        """The step and direction outputs, created on first use (axes 2 and 3 have them from the start;
        another axis when it becomes a stepper or a plant is coupled to it), so a trace holds only used ones."""
        if self.step is None or self.dir is None:
            self.step = PulseTrain(self.sim, f"{self.prefix}.step", pulse_width=self.pulse_width,
                                   description="step output (ATYPE 1 or 35): each pulse drawn from its leading "
                                               "edge; the step counts at its trailing (active) edge, pulse_width "
                                               "later", announces_ends=True)
            self.dir = Signal(self.sim, f"{self.prefix}.dir", kind="bit",
                              description="direction output (1 = positive)")
            self.step.pull = lambda: self.sync()  # a stepper coupling brings the servo ticks up to date first
        return self.step, self.dir

    # -- positions ----------------------------------------------------------------------------
    #: Brings the servo ticks before now up to date (set by the controller; see :mod:`.servo`).
    sync: Any = staticmethod(lambda: None)

    @property
    def steps(self) -> int:
        """The step counter [counts] (step pulses emitted so far, signed)."""
        self.sync()
        return self.steps_raw

    @property
    def feeds_gate(self) -> bool:
        """The step pulses count on the gate's PWM_ENCODER (ATYPE 35 with SERVO ON, TN20-81)."""
        return self.gate is not None and self.params["ATYPE"] == ATYPE_STEPPER_PWM and bool(self.params["SERVO"])

    @property
    def units(self) -> Fraction:
        return Fraction(self.params["UNITS"])

    @property
    def stepper(self) -> bool:
        """ATYPE 1 (stepper) or 35 (stepper output with PWM): the axis emits step pulses."""
        return self.params["ATYPE"] in (ATYPE_STEPPER, ATYPE_STEPPER_PWM)

    @property
    def counts_steps(self) -> bool:
        """MPOS follows the counted step pulses (ATYPE 1; ATYPE 35 only while SERVO=ON, TN20-81)."""
        atype = self.params["ATYPE"]
        return atype == ATYPE_STEPPER or (atype == ATYPE_STEPPER_PWM and bool(self.params["SERVO"]))

    @property
    def demand(self) -> Fraction:
        """The demand position [counts], exact."""
        self.sync()
        return Fraction(self.dnum, self.dden)

    def set_demand(self, counts: Fraction) -> None:
        """Set the demand [counts] directly (a servo cycle sets it through :meth:`output_cycle`)."""
        self.dnum, self.dden = counts.numerator, counts.denominator

    @property
    def dpos(self) -> Fraction:
        """DPOS [units]."""
        return (self.demand - self.origin) / self.units

    @property
    def vp_speed(self) -> Fraction:
        """VP_SPEED [units/s] (the path speed of the cycle just run)."""
        self.sync()
        return Fraction(self.vnum, self.vden)

    @vp_speed.setter
    def vp_speed(self, value: Fraction | int) -> None:
        self.vnum, self.vden = value.numerator, value.denominator

    @property
    def mpos_sampled(self) -> Fraction:
        """MPOS latched at the last servo tick [units]."""
        return (Fraction(self.mnum, self.mden) - self.origin) / self.units

    def mpos_at(self, t: int) -> Fraction:
        """MPOS [units] at tick ``t``: counted step pulses on a stepper axis, else DPOS."""
        self.sync()
        if not self.stepper:
            return self.dpos
        return (self.feedback.value(t) - self.origin) / self.units

    @property
    def idle(self) -> bool:
        """No move running or buffered."""
        return self.current is None and self.queued is None

    def defpos(self, position: Fraction) -> None:
        """DEFPOS: request DPOS = MPOS = ``position``; the next servo cycle shifts both by OFFPOS.

        The shift is fixed now (``position - DPOS``), as the controller's OFFPOS register is.
        """
        self.pending_shift = position * self.units - (self.demand - self.origin)
        self.quiet = False

    @property
    def offpos(self) -> Fraction:
        """OFFPOS: the shift a pending DEFPOS will apply [units] (0 when none)."""
        return self.pending_shift / self.units

    def apply_offset(self) -> None:
        """Servo cycle: apply a pending DEFPOS (shifts the origin; step counters and PWM_ENCODER keep counting)."""
        if self.pending_shift:
            self.origin -= self.pending_shift
            self.pending_shift = Fraction(0)

    def became_stepper(self) -> None:
        """ATYPE was set to 1 or 35: the step and feedback counters start at the demand position."""
        self.steps_raw = self.dnum // self.dden
        self.feedback.set_value(self.sim.now, self.steps_raw)
        self.quiet = False
        self.ensure_outputs()

    def shift(self, offset: Fraction) -> None:
        """``OFFPOS = offset``: DPOS and MPOS move by ``offset`` [units] at the next servo tick (the demand
        does not move)."""
        self.pending_shift += -offset * self.units
        self.quiet = False

    def direction(self) -> int:
        """Where the axis is going: the sign of its last demand change, or the running move's heading."""
        if self.moving:
            return self.moving
        move = self.current
        return 0 if move is None else move.heading(self.number)

    def datum_found(self, counts: Fraction) -> None:
        """A DATUM sequence ends at demand ``counts``: DPOS (and MPOS) are 0 there."""
        self.origin = Fraction(counts)
        self.pending_shift = Fraction(0)
        self.quiet = False

    def ensure_z_mark(self) -> Signal:
        """The Z marker input ``<axis>.z_mark`` (a bit a stimulus or a plant drives); its rising edges are seen
        by DATUM and REGIST."""
        if self.z_mark is None:
            self.z_mark = Signal(self.sim, f"{self.prefix}.z_mark", kind="bit",
                                 description="Z marker input of the axis (its rising edge is the marker)")
            self.z_mark.subscribe(self._z_changed)
        return self.z_mark

    def _z_changed(self, signal: Signal) -> None:
        if signal.value:
            self.z_seen = True
        if self.regist_mode in (3, 4) and bool(signal.value) == (self.regist_mode == 3):
            self._capture()

    def arm_registration(self, mode: int, input_signal: Any) -> None:
        """``REGIST(mode)``: MARK goes FALSE; at the next edge (1 rising, 2 falling edge of the registration
        input; 3 rising, 4 falling edge of the Z marker) REG_POS latches the position and MARK goes TRUE."""
        self.regist_mode, self.mark = mode, False
        if f"{self.prefix}.reg_pos" not in self.sim.trace.info:
            self.sim.trace.declare(f"{self.prefix}.reg_pos", "real", unit="units",
                                   description="REG_POS latched at each registration edge (REGIST)")
        if mode in (1, 2):
            signal = input_signal(self.number)
            if not getattr(signal, "_regist_subscribed", False):
                signal.subscribe(lambda s: self._registration_edge(s))
                signal._regist_subscribed = True
        else:
            self.ensure_z_mark()

    def _registration_edge(self, signal: Signal) -> None:
        if self.regist_mode in (1, 2) and bool(signal.value) == (self.regist_mode == 1):
            self._capture()

    def _capture(self) -> None:
        self.sync()
        if self.stepper:
            self.reg_pos_counts = Fraction(self.feedback.value(self.sim.now))
        else:
            self.reg_pos_counts = Fraction(self.mnum, self.mden)
        self.mark, self.regist_mode = True, 0
        self.sim.trace.record(f"{self.prefix}.reg_pos", self.sim.now, float(self.reg_pos))

    @property
    def reg_pos(self) -> Fraction:
        """REG_POS [units]: the position latched at the registration edge."""
        return (self.reg_pos_counts - self.origin) / self.units

    def set_invert_step(self, on: int) -> None:
        """INVERT_STEP: the step wire idles high and pulses low; the active edge (still the trailing one,
        at the same instant) is then rising. Shown as ``<axis>.invert_step`` from the first write on."""
        if self.invert_out is None:
            self.invert_out = Signal(self.sim, f"{self.prefix}.invert_step", kind="bit",
                                     description="INVERT_STEP: 1 = the step wire is inverted (its trailing, active "
                                                 "edge rises); the trace draws pulses high whatever it is")
        self.invert_out.set(on)

    # -- servo cycle --------------------------------------------------------------------------
    def output_cycle(self, t0: int, period: int, num: int, den: int, origin: str = "") -> None:
        """Set the demand ``num / den`` [counts] for the end of the cycle starting at ``t0``; emit its pulses."""
        change = num * self.dden - self.dnum * den
        self.moving = (change > 0) - (change < 0)
        self.dnum, self.dden = num, den
        params = self.params
        atype = params["ATYPE"]
        if atype != ATYPE_STEPPER and atype != ATYPE_STEPPER_PWM:  # not self.stepper
            return
        steps = self.steps_raw
        target = num // den if num >= steps * den else -(-num // den)
        delta = target - steps
        if delta == 0:
            return
        count = delta if delta > 0 else -delta
        if period // count < 2 * self.pulse_width:
            raise TimingViolation(
                f"{origin + ': ' if origin else ''}{self.prefix}: {count} step pulses in one servo cycle of "
                f"{period} ticks leave less than two pulse widths ({2 * self.pulse_width} ticks) between pulses; "
                "lower SPEED or UNITS")
        direction = 1 if delta > 0 else 0
        dir_out = self.dir
        assert self.step is not None and dir_out is not None  # a stepper has its outputs (became_stepper)
        if dir_out.value != direction:
            dir_out.set(direction)
        leading = t0 + self.dir_setup
        self.step.emit(leading, period, count, direction)
        self.emitted_at = t0
        self.steps_raw = target
        sign = 1 if delta > 0 else -1
        active = leading + self.pulse_width
        if atype == ATYPE_STEPPER or params["SERVO"]:  # self.counts_steps
            self.feedback.feed(active, period, count, sign)
            if self.gate is not None and atype == ATYPE_STEPPER_PWM:  # self.feeds_gate
                self.gate.feed(active, period, count, sign)

    def sample_mpos(self, now: int) -> None:
        """Servo tick, before the cycle's pulses: latch MPOS (the pulses counted so far)."""
        if self.params["ATYPE"] in STEPPER_ATYPES:
            self.mnum, self.mden = self.feedback.value(now), 1
        else:
            self.mnum, self.mden = self.dnum, self.dden

    def settle(self, now: int) -> None:
        """End of a servo tick: the axis is :attr:`quiet` if nothing of it can change by itself any more."""
        feedback = self.feedback
        self.quiet = (self.current is None and self.queued is None and not self.pending_shift and not self.vnum
                      and (feedback.count == 0 or feedback.value(now) == feedback.end_value))

    def following_error_exceeds(self) -> bool:
        """``|DPOS - MPOS| > FE_LIMIT`` with MPOS latched at this tick (exact, in integers)."""
        units, limit = self.params["UNITS"], self.params["FE_LIMIT"]
        error = self.dnum * self.mden - self.mnum * self.dden  # (demand - mpos) * dden * mden [counts]
        if error < 0:
            error = -error
        return error * units.denominator * limit.denominator > (limit.numerator * units.numerator
                                                                 * self.dden * self.mden)

    def _scales(self) -> tuple[int, int, int]:
        """``(A, B, C)`` with ``position [units] = (counts_num * A - B * counts_den) / (counts_den * C)``."""
        units, origin = self.params["UNITS"], self.origin
        if self._scale_key[0] is not units or self._scale_key[1] is not origin:
            od, on = origin.denominator, origin.numerator
            ud, un = units.denominator, units.numerator
            self._scale = (od * ud, on * ud, od * un)
            self._scale_key = (units, origin)
        return self._scale

    def record(self) -> None:
        """Record DPOS (demand for the end of the cycle), the latched MPOS and VP_SPEED (float of the exact value)."""
        a, b, c = self._scales()
        dden = self.dden
        dpos = (self.dnum * a - b * dden) / (dden * c)
        if dpos != self.dpos_out.value:
            self.dpos_out.set(dpos)
        mden = self.mden
        mpos = (self.mnum * a - b * mden) / (mden * c)
        if mpos != self.mpos_out.value:
            self.mpos_out.set(mpos)
        vp = self.vnum / self.vden
        if vp != self.vp_out.value:
            self.vp_out.set(vp)


def number_parts(value: Number) -> tuple[int, int]:
    """``(numerator, denominator)`` of an int or a Fraction."""
    return value.numerator, value.denominator
