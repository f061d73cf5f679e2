"""A motion controller's servo loop around a servo plant: DAC command out, encoder feedback in.

:func:`connect_servo` closes a PMAC motor's position loop around a plant (the Servo FMU): the
motor's DAC [bits] drives the plant's command input [V] (:data:`DAC_VOLTS_PER_BIT` per bit) and
the plant's encoder, 1/T-extended (:class:`~cosim.couplings.encoder.PlantEncoder`), is the
feedback. The design helpers turn the plant's parameters into the controller's design model:
:func:`servo_motor_model` (``K / (s (tau s + 1))`` in counts per DAC bit) and
:func:`full_model_margins` (the designed loop on the plant's full linear model).

Roles: ``command`` (``u_cmd``) and the encoder roles of :mod:`cosim.couplings.encoder`.

Examples
--------
>>> from cosim.plants.servo import ServoParameters
>>> model = servo_motor_model(ServoParameters())      # maxon RE 40 behind a +-10 V -> +-24 V amplifier
>>> round(model.gain_counts_per_s_per_bit, 3), round(model.tau_s * 1e3, 3)   # counts/s per bit, ms
(7.74, 4.668)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np

from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.servo import DAC_MAX, DAC_VOLTS_PER_BIT, MotorModel, PidDesign, cached_design
from cosim.couplings.encoder import ROLES as ENCODER_ROLES
from cosim.couplings.encoder import PlantEncoder
from cosim.couplings.roles import required, resolve
from cosim.errors import ConfigurationError
from cosim.master import PlantLike
from cosim.plants.servo import ServoParameters, linear_model
from cosim.validate import integer

if TYPE_CHECKING:
    from cosim.controllers.pmac.ports import ServoPort

_DAC_NUM, _DAC_DEN = DAC_VOLTS_PER_BIT.numerator, DAC_VOLTS_PER_BIT.denominator
ROLES: dict[str, str | None] = {"command": "u_cmd", **ENCODER_ROLES}
"""Roles of the servo coupling and the Servo FMU's variables that play them."""


def dac_volts(dac_bits: float) -> float:
    """DAC bits to the command voltage [V] (``DAC_VOLTS_PER_BIT`` per bit).

    For whole bits (what the DAC gives) in integers: ``bits * 10 / 32768`` is the correctly rounded
    float of the exact product, as ``float(bits * DAC_VOLTS_PER_BIT)``.
    """
    if type(dac_bits) is int:
        return dac_bits * _DAC_NUM / _DAC_DEN
    return float(dac_bits * DAC_VOLTS_PER_BIT)


def connect_servo(motor: Motor, plant: PlantLike, *, fraction_bits: int = 5,
                  variables: Mapping[str, str | None] | None = None) -> PlantEncoder:
    """Close ``motor``'s loop around a servo plant: DAC -> command [V], 1/T encoder -> feedback.

    Parameters
    ----------
    motor : Motor
        A PMAC motor with a position loop.
    plant : PlantLike
        The Servo plant (or any plant with the roles of :data:`ROLES`).
    fraction_bits : int
        Resolution of the feedback's 1/T extension (5 = 1/32 count, a standard 1/T table entry).
    variables : mapping role -> variable, optional
        The plant's names for the roles, where they differ from the Servo FMU's.

    Returns
    -------
    PlantEncoder
        The servo's encoder (its feedback source).
    """
    integer(fraction_bits, "fraction_bits", low=0, high=8)
    names = resolve(plant, "servo", ROLES, variables)
    encoder = PlantEncoder(plant, variables={role: names[role] for role in ENCODER_ROLES})
    plant.drive(required(names, "command"), motor.dac, convert=dac_volts)

    extended, sim, scale = encoder.extended, encoder.sim, 1 << fraction_bits

    def feedback() -> float:
        return extended(sim.now, fraction_bits) / scale  # = float(encoder.position(...)): exact

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
    closed with the designed discrete controller. Kept on disk by its inputs, as the design is
    (:func:`cosim.controllers.pmac.servo.cached_design`).
    """
    inputs = {"design": dataclasses.asdict(design), "params": dataclasses.asdict(params),
              "volts_per_bit": float(volts_per_bit)}
    value = cached_design("margins", inputs, lambda: _margins(design, params, volts_per_bit))
    return value["gain_margin_db"], value["phase_margin_deg"], value["radius"]


def _margins(design: PidDesign, params: ServoParameters, volts_per_bit: float | Fraction) -> dict[str, float]:
    import control  # python-control only where a loop is checked (see cosim.controllers.pmac.servo)

    scale = params.counts_per_rev / (2 * math.pi) * float(volts_per_bit)
    plant_d = control.sample_system(linear_model(params, output="angle") * scale, design.period_s, method="zoh")
    controller = control.ss(np.array(design.a), np.array(design.b).reshape(-1, 1),
                            np.array(design.c).reshape(1, -1), np.array([[design.d]]), design.period_s)
    loop = plant_d * controller
    gm, pm, *_rest = control.stability_margins(loop, method="frd")
    radius = float(np.max(np.abs(control.poles(control.feedback(loop, 1)))))
    gm_db = float(20 * math.log10(gm)) if np.isfinite(gm) and gm > 0 else math.inf
    return {"gain_margin_db": gm_db, "phase_margin_deg": float(pm), "radius": radius}


def full_scale_speed_counts_per_ms(params: ServoParameters, *,
                                   volts_per_bit: float | Fraction = DAC_VOLTS_PER_BIT) -> float:
    """Steady speed at full DAC output (+32767 bits) without friction [counts/ms], below saturation."""
    model = servo_motor_model(params, volts_per_bit=volts_per_bit)
    volts = min(DAC_MAX * float(volts_per_bit), params.supply_voltage / params.amplifier_gain)
    return model.gain_counts_per_s_per_bit * volts / float(volts_per_bit) / 1000


def servo_parameters(plant: PlantLike) -> ServoParameters:
    """The motor and amplifier parameters of a Servo plant, read from the plant itself."""
    names = [f.name for f in dataclasses.fields(ServoParameters)]
    missing = [n for n in names if n not in plant.variable_names()]
    if missing:
        raise ConfigurationError(f"servo coupling of {plant.name}: the plant has no parameter {missing[0]!r}, so the "
                                 "PID's design model cannot be derived from it; give the model in the coupling "
                                 "(gain_counts_per_s_per_bit and tau_s)")
    values = {n: plant.read(n) for n in names}
    values["counts_per_rev"] = int(values["counts_per_rev"])
    return ServoParameters(**values)  # type: ignore[arg-type]


def couple_servo(port: ServoPort, plant: PlantLike, *,
                 variables: Mapping[str, str | None] | None = None) -> PidDesign:
    """Close a PMAC motor's loop around a servo plant with a PID designed for the port's bandwidth.

    The design model is the port's own (a user's FMU), or :func:`servo_motor_model` of the plant's
    parameters (the Servo FMU); then :func:`connect_servo` joins DAC -> command and encoder ->
    feedback. Returns the design (bandwidth, margins).
    """
    model = port.model or servo_motor_model(servo_parameters(plant))
    design = port.close_loop(model)
    connect_servo(port.motor, plant, variables=variables)
    return design
