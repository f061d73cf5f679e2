"""Moves and axes: the servo-cycle motion generator and the step/direction output.

Servo cycle ``k`` of a move loaded at tick ``t_s`` runs at ``t_s + k*T`` (``T`` = SERVO_PERIOD).
It evaluates the move's exact profile (:mod:`~cosim.controllers.trio.profile`) at the *end* of
the cycle, ``(k+1)*T``, and its path (:mod:`~cosim.controllers.trio.paths`) at that distance, so
every axis of the move gets its demand position for ``t_s + (k+1)*T``::

    demand_i = start_i + offset_i(s((k+1)T)) * UNITS_i          [counts, exact Fraction]

and ``VP_SPEED`` is the path speed the cycle executes, ``(s((k+1)T) - s(kT)) / T``: for a line
and for an arc alike. The move is over at the first cycle that reaches its end; the axes are idle
from the next servo tick on. ``CANCEL`` makes the move decelerate at DECEL from the next tick, along
its own path, and end where it comes to rest.

**Step output** (ATYPE 1 or 35). The change of the step counter over a cycle is one pulse segment
spread evenly over the cycle: pulse ``j`` of ``n`` starts (its *leading* edge) at
``t_s + k*T + dir_setup + floor(j*T/n)`` (the rule of :mod:`cosim.pulses`). Each pulse lasts
``step_pulse_width``; its *trailing* edge is the **active edge** (TRM 8-165: the falling edge by
default; ``INVERT_STEP=ON`` inverts the output so that the same edge is a rising one). The step
is counted there: MPOS, PWM_ENCODER and the gate see each pulse ``step_pulse_width`` after its
leading edge, which is where a drive that matches INVERT_STEP counts it. The direction output
changes at the servo tick, ``dir_setup`` before the leading edge of the first pulse it concerns,
so a drive has ``dir_setup + step_pulse_width`` of set-up before the active edge.

The step counter only moves by whole steps that the demand has covered in the direction of motion
(``floor`` moving up, ``ceil`` moving down); the fraction is carried to the next cycle, so no step
is ever lost or invented and the counter ends exactly on an integer target.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from math import ceil, floor
from typing import TYPE_CHECKING

from cosim import validate
from cosim.controllers.trio.counter import StepCounter
from cosim.controllers.trio.gate import GateFifo
from cosim.controllers.trio.params import ATYPE_STEPPER, ATYPE_STEPPER_PWM, AXIS_PARAMS, Number
from cosim.controllers.trio.paths import ArcPath, LinearPath, RayPath
from cosim.controllers.trio.profile import Ramp, Stop, Trapezoid
from cosim.controllers.trio.pwm import PwmGenerator
from cosim.errors import TimingViolation
from cosim.signals import PulseTrain, Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation

Path = LinearPath | ArcPath | RayPath
Profile = Trapezoid | Ramp | Stop


@dataclass
class Move:
    """A move of one axis or an interpolated base group.

    Parameters
    ----------
    axes : tuple of int
        The axes that move; the first is the base axis whose SPEED, ACCEL and DECEL are used.
    kind : str
        ``MOVE`` (values are distances), ``MOVEABS`` (end positions), ``MOVECIRC`` (end1, end2,
        centre1, centre2 relative to the start, direction; its :class:`ArcPath` given as ``path``),
        ``FORWARD`` or ``REVERSE``.
    values : tuple of Fraction
        The command's arguments [units].
    origin : str
        Where the move was issued (``job.bas line 12``), for error messages.
    """

    axes: tuple[int, ...]
    kind: str
    values: tuple[Fraction, ...]
    origin: str = ""
    t_start: int = -1
    path: Path | None = None
    profile: Profile | None = None
    start_counts: tuple[Fraction, ...] = ()
    units: tuple[Fraction, ...] = ()
    cycles: int = 0
    done: bool = False
    cancel_requested: bool = False
    travelled: Fraction = field(default=Fraction(0))

    def load(self, axes: dict[int, Axis], t: int) -> None:
        """Plan the move at servo tick ``t`` from the axes' current demand positions."""
        base = axes[self.axes[0]]
        speed = validate.positive(base.params["SPEED"], f"SPEED of axis {base.number} when the {self.kind} starts")
        accel, decel = Fraction(base.params["ACCEL"]), Fraction(base.params["DECEL"])
        if self.kind in ("FORWARD", "REVERSE"):
            self.path = RayPath(1 if self.kind == "FORWARD" else -1)
            self.profile = Ramp(speed, accel)
        else:
            if self.path is None:  # an arc is planned when it is issued: its geometry is relative to the start
                self.path = LinearPath(tuple(value - axes[a].dpos if self.kind == "MOVEABS" else value
                                             for a, value in zip(self.axes, self.values, strict=True)))
            assert not isinstance(self.path, RayPath)
            self.profile = Trapezoid.plan(self.path.length, speed=speed, accel=accel, decel=decel)
        self.start_counts = tuple(axes[a].demand for a in self.axes)
        self.units = tuple(axes[a].units for a in self.axes)
        self.t_start = t

    def stop(self, period_s: Fraction, decel: Fraction) -> None:
        """CANCEL takes effect at this cycle: decelerate at ``decel`` [units/s^2] from the state now."""
        assert self.profile is not None
        self.cancel_requested = False
        t_now = self.cycles * period_s
        speed = self.profile.speed(t_now)
        stop = Stop(t_now, self.profile.position(t_now), speed, decel)
        length = self.path.length if self.path is not None else None
        if length is not None and stop.length > length:  # DECEL lowered since the move was planned
            stop = Stop(t_now, stop.start, speed, speed * speed / (2 * (length - stop.start))) \
                if length > stop.start else Stop(t_now, length, Fraction(0), decel)
        self.profile = stop

    def advance(self, period_s: Fraction) -> tuple[list[Fraction], Fraction]:
        """One servo cycle: demand positions [counts] at the end of the cycle and the path speed [units/s]."""
        assert self.profile is not None and self.path is not None
        self.cycles += 1
        t_end_of_cycle = self.cycles * period_s
        s = self.profile.position(t_end_of_cycle)
        speed = (s - self.travelled) / period_s
        self.travelled = s
        t_end = self.profile.t_end
        self.done = t_end is not None and t_end_of_cycle >= t_end
        offsets = self.path.offset(s)
        demands = [start + offset * units for start, offset, units in
                   zip(self.start_counts, offsets, self.units, strict=False)]
        demands += list(self.start_counts[len(demands):])  # axes of the group an arc does not move
        return demands, speed


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
        self.params: dict[str, Number] = {s.name: s.default for s in AXIS_PARAMS.values() if pwm or not s.pwm_only}
        self.demand = Fraction(0)
        self.origin = Fraction(0)
        self.pending_shift = Fraction(0)
        self.steps = 0
        self.feedback = StepCounter(0)
        self.vp_speed = Fraction(0)
        self.mpos_sampled = Fraction(0)
        self.current: Move | None = None
        self.queued: Move | None = None
        self.dpos_out = Signal(sim, f"{self.prefix}.dpos", kind="real", unit="units", description="DPOS")
        self.mpos_out = Signal(sim, f"{self.prefix}.mpos", kind="real", unit="units", description="MPOS")
        self.vp_out = Signal(sim, f"{self.prefix}.vp_speed", kind="real", unit="units/s",
                             description="VP_SPEED: path speed of the move being executed")
        self.step: PulseTrain | None = None
        self.dir: Signal | None = None
        self.invert_out: Signal | None = None
        self.pwm: PwmGenerator | None = None
        self.gate: GateFifo | None = None
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
                                               "later")
            self.dir = Signal(self.sim, f"{self.prefix}.dir", kind="bit",
                              description="direction output (1 = positive)")
        return self.step, self.dir

    # -- positions ----------------------------------------------------------------------------
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
    def dpos(self) -> Fraction:
        """DPOS [units]."""
        return (self.demand - self.origin) / self.units

    def mpos_at(self, t: int) -> Fraction:
        """MPOS [units] at tick ``t``: counted step pulses on a stepper axis, else DPOS."""
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
        self.steps = floor(self.demand)
        self.feedback.set_value(self.sim.now, self.steps)
        self.ensure_outputs()

    def set_invert_step(self, on: int) -> None:
        """INVERT_STEP: the step wire idles high and pulses low; the active edge (still the trailing one,
        at the same instant) is then rising. Shown as ``<axis>.invert_step`` from the first write on."""
        if self.invert_out is None:
            self.invert_out = Signal(self.sim, f"{self.prefix}.invert_step", kind="bit",
                                     description="INVERT_STEP: 1 = the step wire is inverted (its trailing, active "
                                                 "edge rises); the trace draws pulses high whatever it is")
        self.invert_out.set(on)

    # -- servo cycle --------------------------------------------------------------------------
    def output_cycle(self, t0: int, period: int, demand: Fraction, origin: str = "") -> None:
        """Set the demand for the end of the cycle starting at ``t0`` and emit its step pulses."""
        self.demand = demand
        if not self.stepper:
            return
        target = floor(demand) if demand >= self.steps else ceil(demand)
        delta = target - self.steps
        if delta == 0:
            return
        count = abs(delta)
        if period // count < 2 * self.pulse_width:
            raise TimingViolation(
                f"{origin + ': ' if origin else ''}{self.prefix}: {count} step pulses in one servo cycle of "
                f"{period} ticks leave less than two pulse widths ({2 * self.pulse_width} ticks) between pulses; "
                "lower SPEED or UNITS")
        direction = 1 if delta > 0 else 0
        assert self.step is not None and self.dir is not None  # a stepper has its outputs (became_stepper)
        self.dir.set(direction)
        leading = t0 + self.dir_setup
        self.step.emit(leading, period, count, direction)
        self.steps = target
        sign = 1 if delta > 0 else -1
        active = leading + self.pulse_width
        if self.counts_steps:
            self.feedback.feed(active, period, count, sign)
        if self.gate is not None and self.params["ATYPE"] == ATYPE_STEPPER_PWM and self.params["SERVO"]:
            self.gate.feed(active, period, count, sign)

    def sample_mpos(self) -> None:
        """Servo tick, before the cycle's pulses: latch MPOS (the pulses counted so far)."""
        self.mpos_sampled = self.mpos_at(self.sim.now)

    def record(self) -> None:
        """Record DPOS (demand for the end of the cycle), the latched MPOS and VP_SPEED."""
        self.dpos_out.set(float(self.dpos))
        self.mpos_out.set(float(self.mpos_sampled))
        self.vp_out.set(float(self.vp_speed))
