"""Adapters between the PMAC model and the Conveyor and Servo plants (FMUs or test doubles).

The PMAC model reads encoders through :class:`~cosim.controllers.pmac.encoder.EncoderSource`
and drives its slave through the ``pmac.motorN.dac`` signal. This module connects those hooks
to plants that publish the encoder outputs of ``fmu_src/Conveyor`` and ``fmu_src/Servo``
(``encoder_count``, ``edge_direction``, ``t_last_edge``, ``t_prev_edge`` [s]):

* :class:`PlantEncoder` -- an ``EncoderSource`` over such a plant. It reads the outputs at the
  servo interrupt instant (reading advances the plant to now) and converts the edge instants
  to integer ns once, here, with :meth:`cosim.timebase.TimeBase.ticks_from_seconds_ceil` (the
  first tick at or after the edge: the tick from which the new count is visible).
* :func:`watch_mark` -- the registration sensor as the capture trigger: ``Plant.watch("mark")``
  on an FMI 3.0 build with early return, so the mark is published at the first tick at or
  after its exact instant.
* :func:`connect_servo` -- motor DAC -> ``u_cmd`` [V] and 1/T-extended encoder feedback.
* :func:`servo_motor_model` / :func:`full_model_margins` -- the PID design model of a Servo plant
  and the margins of a designed loop on the plant's full linear model.

Nothing here imports fmpy: a plant is anything with ``sim`` and ``read(variable)`` (and
``drive``/``watch`` where those are used), so a test double can stand in.

Examples
--------
>>> from cosim.plants.servo import ServoParameters
>>> model = servo_motor_model(ServoParameters())      # maxon RE 40 behind a +-10 V -> +-24 V amplifier
>>> round(model.gain_counts_per_s_per_bit, 3), round(model.tau_s * 1e3, 3)   # counts/s per bit, ms
(7.74, 4.668)
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Protocol

import control
import numpy as np

from cosim import validate
from cosim.controllers.pmac.encoder import ONE_OVER_T_BITS, EncoderSample, extend_one_over_t
from cosim.controllers.pmac.servo import DAC_MAX, MotorModel, PidDesign
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.pmac.motor import Motor
    from cosim.kernel import Simulation
    from cosim.plants.servo import ServoParameters
    from cosim.signals import Signal


__all__ = [
    "DAC_VOLTS_PER_BIT",
    "ENCODER_OUTPUTS",
    "EncoderPlant",
    "PlantEncoder",
    "connect_servo",
    "dac_volts",
    "full_model_margins",
    "full_scale_speed_counts_per_ms",
    "servo_motor_model",
    "watch_mark",
]

#: DAC output voltage per bit [V]: a 16-bit DAC whose 32768 bits are 10 V (+-32767 = +-9.9997 V).
DAC_VOLTS_PER_BIT = Fraction(10, 32768)
#: Encoder outputs every plant read by :class:`PlantEncoder` has.
ENCODER_OUTPUTS = ("encoder_count", "edge_direction", "t_last_edge", "t_prev_edge")


class EncoderPlant(Protocol):
    """A plant with the encoder outputs of the Conveyor and Servo FMUs (``cosim.master.Plant``)."""

    @property
    def sim(self) -> Simulation: ...

    def read(self, variable: str) -> Any:
        """Value of an output now (the plant is advanced to now first)."""
        ...


def dac_volts(dac_bits: float) -> float:
    """DAC bits to the command voltage [V] (``DAC_VOLTS_PER_BIT`` per bit)."""
    return float(dac_bits * DAC_VOLTS_PER_BIT)


class PlantEncoder:
    """An :class:`~cosim.controllers.pmac.encoder.EncoderSource` over a plant's encoder outputs.

    Parameters
    ----------
    plant : EncoderPlant
        A Conveyor or Servo plant (or a double with the same outputs).
    start_ns : int, optional
        The plant's start time [ns] (default: now; build the adapter right after loading the
        plant). The FMUs report the start time as edge instant before there were edges; such an
        instant is taken as "no edge yet", so the 1/T extension only uses real edges.

    Notes
    -----
    ``sample(t_ns)`` may only be called at ``t_ns == sim.now``: the plant is read at the instant
    the controller samples it (the servo interrupt, or a capture trigger).
    """

    def __init__(self, plant: EncoderPlant, *, start_ns: int | None = None) -> None:
        self.plant = plant
        self.sim = plant.sim
        self.start_ns = self.sim.now if start_ns is None else start_ns

    def _edge_ns(self, t_s: float) -> int | None:
        t_ns = self.sim.timebase.ticks_from_seconds_ceil(float(t_s))
        return t_ns if t_ns > self.start_ns else None

    def sample(self, t_ns: int) -> EncoderSample:
        """Count, last two edge instants [ns] and direction of the plant's encoder now."""
        if t_ns != self.sim.now:
            raise ConfigurationError.out_of_range("t_ns of PlantEncoder.sample", t_ns,
                                                  f"the current time {self.sim.now} (a plant is read now)")
        read = self.plant.read
        last = self._edge_ns(read("t_last_edge"))
        prev = self._edge_ns(read("t_prev_edge")) if last is not None else None
        direction = 1 if int(read("edge_direction")) >= 0 else -1
        return EncoderSample(int(read("encoder_count")), last, prev, direction)

    def position(self, *, fraction_bits: int = ONE_OVER_T_BITS) -> Fraction:
        """1/T-extended position now [counts], truncated to ``2^-fraction_bits`` count."""
        now = self.sim.now
        return Fraction(extend_one_over_t(self.sample(now), now, fraction_bits), 1 << fraction_bits)


def watch_mark(plant: Any, *, signal: str | None = None) -> Signal:
    """The conveyor's registration sensor as a bit signal changing at its exact (ns-ceiled) edges.

    Parameters
    ----------
    plant : cosim.master.Plant
        A Conveyor plant loaded from its FMI 3.0 build (early return locates the mark edges).
    signal : str, optional
        Signal name (default ``<plant>.mark``).

    Raises
    ------
    ConfigurationError
        If the plant's FMU is not FMI 3.0 with early return (FMI 2.0 would publish the mark only
        at the end of a step, up to a servo period late).
    """
    fmu = getattr(plant, "fmu", None)
    version = getattr(fmu, "fmi_version", None)
    if fmu is not None and not (version == 3 and getattr(fmu, "early_return", False)):
        raise ConfigurationError.out_of_range(f"FMI version of {plant.name} for the capture trigger", version,
                                              "3 (FMI 3.0 with early return, to locate mark edges exactly)")
    out: Signal = plant.watch("mark", signal=signal)
    return out


def connect_servo(motor: Motor, plant: Any, *, fraction_bits: int = ONE_OVER_T_BITS,
                  command: str = "u_cmd") -> PlantEncoder:
    """Close ``motor``'s loop around a Servo plant: DAC -> ``u_cmd`` [V], 1/T encoder -> feedback.

    Parameters
    ----------
    motor : Motor
        A PMAC motor with a position loop.
    plant : cosim.master.Plant
        The Servo plant (anything with ``drive``, ``read`` and ``sim``).
    fraction_bits : int
        Resolution of the feedback's 1/T extension (5 = 1/32 count, a standard 1/T table entry).
    command : str
        Plant input driven by the DAC.

    Returns
    -------
    PlantEncoder
        The servo's encoder (its feedback source).
    """
    validate.integer(fraction_bits, "fraction_bits", low=0, high=8)
    encoder = PlantEncoder(plant)
    plant.drive(command, motor.dac, convert=dac_volts)

    def feedback() -> float:
        return float(encoder.position(fraction_bits=fraction_bits))

    motor.feedback = feedback
    return encoder


def _mechanical(params: ServoParameters) -> tuple[float, float]:
    """Speed per command volt [rad/s per V] and mechanical time constant [s], inductance neglected."""
    p = params
    damping = p.resistance * p.viscous_friction + p.torque_constant * p.back_emf_constant
    return p.amplifier_gain * p.torque_constant / damping, p.resistance * p.inertia / damping


def servo_motor_model(params: ServoParameters, *, volts_per_bit: float | Fraction = DAC_VOLTS_PER_BIT) -> MotorModel:
    """The design model ``K / (s (tau s + 1))`` [counts per DAC bit] of a Servo plant.

    ``K = g Kt / (R B + Kt Ke) * counts_per_rev / (2 pi) * volts_per_bit`` and
    ``tau = R J / (R B + Kt Ke)``: the electrical pole (``R / L``, about 580 Hz for the maxon
    RE 40) and Coulomb friction are left out; :func:`full_model_margins` checks the design
    against the model with the inductance.
    """
    kv, tau = _mechanical(params)
    counts_per_rad = params.counts_per_rev / (2 * math.pi)
    return MotorModel(gain_counts_per_s_per_bit=kv * counts_per_rad * float(volts_per_bit), tau_s=tau)


def full_model_margins(design: PidDesign, params: ServoParameters, *,
                       volts_per_bit: float | Fraction = DAC_VOLTS_PER_BIT) -> tuple[float, float, float]:
    """Gain margin [dB], phase margin [deg] and largest closed-loop |z| on the full linear model.

    The plant is ``cosim.plants.servo.linear_model(params, output="angle")`` (with the
    inductance) in counts per DAC bit, sampled with a zero-order hold at the servo period and
    closed with the designed discrete controller.
    """
    from cosim.plants.servo import linear_model

    scale = params.counts_per_rev / (2 * math.pi) * float(volts_per_bit)
    plant_d = control.sample_system(linear_model(params, output="angle") * scale, design.period_s, method="zoh")
    controller = control.ss(np.array(design.a), np.array(design.b).reshape(-1, 1),
                            np.array(design.c).reshape(1, -1), np.array([[design.d]]), design.period_s)
    loop = plant_d * controller
    gm, pm, *_rest = control.stability_margins(loop, method="frd")
    radius = float(np.max(np.abs(control.poles(control.feedback(loop, 1)))))
    gm_db = float(20 * math.log10(gm)) if np.isfinite(gm) and gm > 0 else math.inf
    return gm_db, float(pm), radius


def full_scale_speed_counts_per_ms(params: ServoParameters, *,
                                   volts_per_bit: float | Fraction = DAC_VOLTS_PER_BIT) -> float:
    """Steady speed at full DAC output (+32767 bits) without friction [counts/ms], below saturation."""
    model = servo_motor_model(params, volts_per_bit=volts_per_bit)
    volts = min(DAC_MAX * float(volts_per_bit), params.supply_voltage / params.amplifier_gain)
    return model.gain_counts_per_s_per_bit * volts / float(volts_per_bit) / 1000

