"""Axes and moves: the servo-cycle motion generator and the stepper pulse output.

Servo cycle ``k`` of a move loaded at tick ``t_s`` runs at ``t_s + k*T`` (``T`` = SERVO_PERIOD).
It evaluates the move's exact trapezoid (:mod:`~cosim.controllers.trio.profile`) at the *end* of
the cycle, ``(k+1)*T``, so every axis of the move gets its demand position for ``t_s + (k+1)*T``::

    demand_i = start_i + delta_i * s((k+1)T) / L          [counts, exact Fraction]

and ``VP_SPEED`` is the path speed the cycle executes, ``(s((k+1)T) - s(kT)) / T``. The move is
over at the first cycle that reaches its end; the axis is idle from the next servo tick on.

A stepper axis (ATYPE=35) outputs the change of its step counter over the cycle as one pulse
segment spread evenly over ``[t_s + k*T, t_s + (k+1)*T)``: pulse ``j`` of ``n`` is at
``t_s + k*T + floor(j*T/n)`` (the rule of :mod:`cosim.pulses`), so the first pulse of a cycle is
on the servo tick. The step counter only moves by whole steps that the demand has covered in the
direction of motion (``floor`` moving up, ``ceil`` moving down); the fraction is carried to the
next cycle, so no step is ever lost or invented and the counter ends exactly on an integer
target. While SERVO=ON the pulses are also counted back (``MPOS`` and ``PWM_ENCODER``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from math import ceil, floor
from typing import TYPE_CHECKING

from cosim.controllers.trio.counter import StepCounter
from cosim.controllers.trio.gate import GateFifo
from cosim.controllers.trio.params import ATYPE_STEPPER_PWM, AXIS_PARAMS, Number
from cosim.controllers.trio.profile import Trapezoid, sqrt_down
from cosim.controllers.trio.pwm import PwmGenerator
from cosim.errors import TimingViolation
from cosim.signals import PulseTrain, Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation

#: Width of a drawn step pulse [ns] (display only; checks use the pulse instants).
STEP_PULSE_WIDTH_NS = 100


@dataclass
class Move:
    """A MOVE (relative) or MOVEABS (absolute) of one axis or an interpolated base group.

    Parameters
    ----------
    axes : tuple of int
        The axes that move; the first is the base axis whose SPEED, ACCEL and DECEL are used.
    values : tuple of Fraction
        Distances (MOVE) or end positions (MOVEABS) [units of each axis].
    absolute : bool
        MOVEABS when True.
    """

    axes: tuple[int, ...]
    values: tuple[Fraction, ...]
    absolute: bool
    t_start: int = -1
    profile: Trapezoid | None = None
    start_counts: tuple[Fraction, ...] = ()
    delta_counts: tuple[Fraction, ...] = ()
    cycles: int = 0
    done: bool = False
    travelled: Fraction = field(default=Fraction(0))

    def load(self, axes: dict[int, Axis], t: int) -> None:
        """Plan the move at servo tick ``t`` from the axes' current demand positions."""
        base = axes[self.axes[0]]
        deltas = [value - axes[a].dpos if self.absolute else value for a, value in zip(self.axes, self.values,
                                                                                         strict=True)]
        length = abs(deltas[0]) if len(deltas) == 1 else sqrt_down(sum((d * d for d in deltas), Fraction(0)))
        self.profile = Trapezoid.plan(length, speed=Fraction(base.params["SPEED"]),
                                      accel=Fraction(base.params["ACCEL"]), decel=Fraction(base.params["DECEL"]))
        self.start_counts = tuple(axes[a].demand for a in self.axes)
        self.delta_counts = tuple(d * axes[a].units for a, d in zip(self.axes, deltas, strict=True))
        self.t_start = t

    def advance(self, period_s: Fraction) -> tuple[list[Fraction], Fraction]:
        """One servo cycle: demand positions [counts] at the end of the cycle and the path speed [units/s]."""
        assert self.profile is not None
        self.cycles += 1
        t_end_of_cycle = self.cycles * period_s
        s = self.profile.position(t_end_of_cycle)
        speed = (s - self.travelled) / period_s
        self.travelled = s
        self.done = t_end_of_cycle >= self.profile.t_end
        share = s / self.profile.length if self.profile.length else Fraction(1)
        demands = [start + delta * share for start, delta in zip(self.start_counts, self.delta_counts, strict=True)]
        return demands, speed


class Axis:
    """One axis: parameters, demand and step counters, moves, and (axes 2 and 3) PWM and gate.

    Parameters
    ----------
    sim : Simulation
    number : int
        Axis number.
    pwm : bool
        The axis has the PWM / gating feature.
    device : str
        Trace device name.
    """

    def __init__(self, sim: Simulation, number: int, *, pwm: bool, device: str = "trio") -> None:
        self.sim = sim
        self.number = number
        self.has_pwm = pwm
        self.prefix = f"{device}.axis{number}"
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
        self.pwm: PwmGenerator | None = None
        self.gate: GateFifo | None = None
        if pwm:
            self.step = PulseTrain(sim, f"{self.prefix}.step", pulse_width=STEP_PULSE_WIDTH_NS,
                                   description="step output (ATYPE=35)")
            self.dir = Signal(sim, f"{self.prefix}.dir", kind="bit", description="direction output (1 = positive)")
            self.pwm = PwmGenerator(sim, self.prefix)
            self.gate = GateFifo(sim, self.prefix)

    # -- positions ----------------------------------------------------------------------------
    @property
    def units(self) -> Fraction:
        return Fraction(self.params["UNITS"])

    @property
    def stepper(self) -> bool:
        """ATYPE=35: stepper output with PWM."""
        return self.params["ATYPE"] == ATYPE_STEPPER_PWM

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
        """ATYPE was set to 35: the step and feedback counters start at the demand position."""
        self.steps = floor(self.demand)
        self.feedback.set_value(self.sim.now, self.steps)

    # -- servo cycle --------------------------------------------------------------------------
    def output_cycle(self, t0: int, period: int, demand: Fraction) -> None:
        """Set the demand for the end of the cycle starting at ``t0`` and emit its step pulses."""
        self.demand = demand
        if not self.stepper:
            return
        target = floor(demand) if demand >= self.steps else ceil(demand)
        delta = target - self.steps
        if delta == 0:
            return
        count = abs(delta)
        if count > period:
            raise TimingViolation(
                f"{self.prefix}: {count} step pulses in one servo cycle of {period} ticks is more than one "
                "pulse per tick; lower SPEED or raise UNITS resolution")
        direction = 1 if delta > 0 else 0
        assert self.step is not None and self.dir is not None
        self.dir.set(direction)
        self.step.emit(t0, period, count, direction)
        self.steps = target
        if self.params["SERVO"]:
            sign = 1 if delta > 0 else -1
            self.feedback.feed(t0, period, count, sign)
            if self.gate is not None:
                self.gate.feed(t0, period, count, sign)

    def sample_mpos(self) -> None:
        """Servo tick, before the cycle's pulses: latch MPOS (the pulses counted so far)."""
        self.mpos_sampled = self.mpos_at(self.sim.now)

    def record(self) -> None:
        """Record DPOS (demand for the end of the cycle), the latched MPOS and VP_SPEED."""
        self.dpos_out.set(float(self.dpos))
        self.mpos_out.set(float(self.mpos_sampled))
        self.vp_out.set(float(self.vp_speed))
