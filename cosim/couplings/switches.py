"""A plant's switch outputs to a controller's switch inputs.

The plant publishes each switch as a signal that changes at its own events (exactly located on
an FMI 3.0 FMU with early return); the coupling copies the level (1 = tripped) to the
controller's input, which sees it the way its hardware does (a PoKeys engine at its next slot
start).

Roles (with the Stepper FMU's outputs as defaults): ``limit_pos``, ``limit_neg``, ``home``; each
optional (a port without that input, or a role mapped to None, is not wired).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial

from cosim.couplings.roles import resolve
from cosim.master import PlantLike
from cosim.signals import Signal, SwitchPort

ROLES: dict[str, str | None] = {"limit_pos": "limit_pos", "limit_neg": "limit_neg", "home": "home"}
"""Roles of the switch coupling and the Stepper FMU's outputs that play them."""


def couple_switches(plant: PlantLike, port: SwitchPort, *,
                    variables: Mapping[str, str | None] | None = None) -> list[Signal]:
    """Feed the switch inputs of ``port`` from the plant's switch outputs.

    Parameters
    ----------
    plant : PlantLike
        A plant with boolean switch outputs (true = tripped), e.g. the Stepper FMU.
    port : SwitchPort
        The controller's inputs of one axis, e.g. ``engine.switch_port(0)``.
    variables : mapping role -> variable or None, optional
        The plant's names for ``limit_pos``, ``limit_neg``, ``home``; None leaves one unwired.

    Returns
    -------
    list of Signal
        The watched plant outputs (``<plant>.<output>``), in the order limit_pos, limit_neg, home.
    """
    names = resolve(plant, "switch", ROLES, variables, optional=ROLES)
    watched = []
    for role, target in (("limit_pos", port.limit_pos), ("limit_neg", port.limit_neg), ("home", port.home)):
        variable = names[role]
        if target is None or variable is None:
            continue
        source = plant.watch(variable)
        target.set(int(bool(source.value)))
        source.subscribe(partial(_copy_level, target))
        watched.append(source)
    return watched


def _copy_level(target: Signal, source: Signal) -> None:
    target.set(int(bool(source.value)))
