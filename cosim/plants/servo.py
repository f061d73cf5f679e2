"""Servo plant: the DC motor's linear model, its steady state and the encoder's 1/T position.

The Servo FMU (``fmu_src/Servo``) integrates a brushed DC motor behind a voltage amplifier::

    u = clamp(amplifier_gain * u_cmd, -supply_voltage, +supply_voltage)
    L di/dt = u - R i - Ke w
    J dw/dt = Kt i - B w - Tc sgn(w) - T_load,        dtheta/dt = w

Without Coulomb friction and below saturation it is linear: :func:`linear_model` gives its
transfer functions (python-control), and the tests compare the FMU's step response with them.
:func:`steady_state_speed` includes Coulomb friction and the load torque.

The encoder reports the instants of its last two edges, so a controller can extend the count
between edges as 1/T hardware does (:func:`cosim.encoders.extend_one_over_t`).

Examples
--------
>>> motor = ServoParameters()                 # the Servo FMU's defaults (a maxon RE 40, 24 V)
>>> round(steady_state_speed(motor, u_cmd_v=10.0), 1)   # 24 V on the motor [rad/s]
796.8
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.plants.params import from_mapping

#: FMU parameters that only steer the FMU's solver or start state, not the motor.
_FMU_ONLY = frozenset({"angle_start", "max_step"})


@dataclass(frozen=True)
class ServoParameters:
    """The motor and amplifier of the Servo FMU, named as its parameters (SI units).

    Defaults are the FMU's defaults: a maxon RE 40 (24 V winding, order no. 148867) behind an
    amplifier that maps +-10 V to +-24 V (see ``models/presets/servo_maxon_re40_24v.toml``).

    Parameters
    ----------
    resistance : float
        Terminal resistance R [Ohm], > 0.
    inductance : float
        Terminal inductance L [H], > 0.
    torque_constant : float
        Kt [N.m/A], > 0.
    back_emf_constant : float
        Ke [V.s/rad], > 0.
    inertia : float
        Rotor plus load inertia J [kg.m2], > 0.
    viscous_friction : float
        B [N.m.s/rad], >= 0.
    coulomb_friction : float
        Tc [N.m], >= 0.
    amplifier_gain : float
        Motor voltage per command volt [V/V], > 0.
    supply_voltage : float
        Saturation of the motor voltage [V], > 0.
    counts_per_rev : int
        Encoder quadrature counts per revolution, a positive multiple of 4.
    """

    resistance: float = 0.299
    inductance: float = 0.082e-3
    torque_constant: float = 30.2e-3
    back_emf_constant: float = 30.12e-3
    inertia: float = 142e-7
    viscous_friction: float = 0.0
    coulomb_friction: float = 0.0
    amplifier_gain: float = 2.4
    supply_voltage: float = 24.0
    counts_per_rev: int = 2000

    def __post_init__(self) -> None:
        where = "ServoParameters"
        positive = ("resistance", "inductance", "torque_constant", "back_emf_constant", "inertia",
                    "amplifier_gain", "supply_voltage")
        for name in positive:
            validate.positive(getattr(self, name), name, where=where)
        for name in ("viscous_friction", "coulomb_friction"):
            validate.positive(getattr(self, name), name, zero=True, where=where)
        multiple = "a positive multiple of 4"
        counts = validate.integer(self.counts_per_rev, "counts_per_rev", low=4, allowed=multiple, where=where,
                                  whole=True)
        if counts % 4:
            raise ConfigurationError.out_of_range("counts_per_rev", self.counts_per_rev, multiple, where=where)

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> ServoParameters:
        """From FMU parameter values (e.g. a preset); solver-only parameters are ignored.

        Raises
        ------
        ConfigurationError
            For a name that is not a Servo parameter.
        """
        return from_mapping(cls, values, model="Servo", solver_only=_FMU_ONLY)

    def as_fmu_parameters(self) -> dict[str, float | int]:
        """The values as FMU start values (``Plant.load(..., parameters=...)``)."""
        return asdict(self)


def linear_model(params: ServoParameters, *, output: str = "speed") -> Any:
    """Transfer function from the command ``u_cmd`` [V] to ``output`` (python-control).

    ``speed`` [rad/s]: ``g Kt / ((L s + R)(J s + B) + Kt Ke)``; ``angle`` [rad]: that over ``s``;
    ``current`` [A]: ``g (J s + B) / ((L s + R)(J s + B) + Kt Ke)``, with ``g`` the amplifier gain.
    Valid without Coulomb friction and while the amplifier does not saturate.
    """
    import control

    p = params
    den = [p.inductance * p.inertia,
           p.inductance * p.viscous_friction + p.resistance * p.inertia,
           p.resistance * p.viscous_friction + p.torque_constant * p.back_emf_constant]
    gain = p.amplifier_gain
    if output == "speed":
        return control.tf([gain * p.torque_constant], den)
    if output == "angle":
        return control.tf([gain * p.torque_constant], [*den, 0.0])
    if output == "current":
        return control.tf([gain * p.inertia, gain * p.viscous_friction], den)
    raise ConfigurationError.out_of_range("output", output, "'speed', 'angle' or 'current'")


def motor_voltage(params: ServoParameters, u_cmd_v: float) -> float:
    """Voltage the amplifier applies [V]: ``amplifier_gain * u_cmd`` within +-``supply_voltage``."""
    return max(-params.supply_voltage, min(params.supply_voltage, params.amplifier_gain * u_cmd_v))


def steady_state_speed(params: ServoParameters, *, u_cmd_v: float, load_torque_nm: float = 0.0) -> float:
    """Speed [rad/s] the motor settles at for a constant command and load torque.

    Zero while the stall torque ``Kt u / R - T_load`` stays within the Coulomb friction (the rotor
    is held), else ``(Kt u / R - T_load - Tc sgn) / (B + Kt Ke / R)``.
    """
    p = params
    stall = p.torque_constant * motor_voltage(p, u_cmd_v) / p.resistance - load_torque_nm
    if abs(stall) <= p.coulomb_friction:
        return 0.0
    friction = math.copysign(p.coulomb_friction, stall)
    return (stall - friction) / (p.viscous_friction + p.torque_constant * p.back_emf_constant / p.resistance)


