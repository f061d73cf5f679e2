"""A controller's PWM outputs to a laser plant (the Laser FMU, or any plant with the same roles).

Every change of the port's signals sets the plant's input at that tick (the master advances the
plant to it first), so the laser sees the exact instants of gate edges, mark changes and WDOG.

Roles (with the Laser FMU's inputs as defaults): ``enable`` (bit), ``gate`` (bit),
``period_clocks`` (``pwm_period``), ``mark_clocks`` (``pwm_on``), ``phase_clocks``
(``pwm_phase``), and, optional, ``clock_hz`` (the parameter ``clock_frequency``): when the plant
has it, its value must equal the controller's PWM clock, or the carrier would be wrong.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction

from cosim.couplings.roles import required, resolve
from cosim.errors import ConfigurationError
from cosim.master import PlantLike
from cosim.signals import PwmPort

ROLES: dict[str, str | None] = {"enable": "enable", "gate": "gate", "period_clocks": "pwm_period",
                                "mark_clocks": "pwm_on", "phase_clocks": "pwm_phase", "clock_hz": "clock_frequency"}
"""Roles of the laser coupling and the Laser FMU's variables that play them."""


def couple_laser(port: PwmPort, plant: PlantLike, *, variables: Mapping[str, str | None] | None = None) -> None:
    """Drive a laser ``plant`` from a controller's PWM ``port`` (e.g. ``trio.pwm_port(3)``).

    Parameters
    ----------
    port : PwmPort
    plant : PlantLike
        The Laser FMU (or a plant with the roles of :data:`ROLES`).
    variables : mapping role -> variable, optional
        The plant's names for the roles, where they differ from the Laser FMU's.

    Raises
    ------
    ConfigurationError
        A role the plant lacks, or a plant clock that differs from the port's PWM clock.
    """
    names = resolve(plant, "laser", ROLES, variables, optional=("clock_hz",))
    clock = names["clock_hz"]
    if clock is not None:
        value = Fraction(str(plant.read(clock)))
        if value != port.clock_hz:
            raise ConfigurationError.out_of_range(f"{plant.name}.{clock}", float(value),
                                                  f"{float(port.clock_hz):g} Hz (the controller's PWM clock)")
    plant.drive(required(names, "enable"), port.enable, convert=bool)
    plant.drive(required(names, "gate"), port.gate, convert=bool)
    plant.drive(required(names, "period_clocks"), port.period_clocks, convert=int)
    plant.drive(required(names, "mark_clocks"), port.mark_clocks, convert=int)
    plant.drive(required(names, "phase_clocks"), port.phase_clocks, convert=int)
