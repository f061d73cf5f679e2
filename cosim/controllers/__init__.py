"""Controller timing models: SimPy processes that drive and read signals, never FMUs.

Every controller offers the small :class:`Controller` protocol: the signals it drives (its
outputs) and the signals it reads (its inputs), so a machine can be wired, listed and checked
without knowing the controller family. Connectors that belong together are offered as ports
(:mod:`cosim.signals`: ``step_dir``, ``pwm_port``, ``switch_port``); couplings
(:mod:`cosim.couplings`) join those to plants. A controller imports only the kernel, signals,
the time base, the errors and :mod:`cosim.validate`: it never names a plant variable.
"""

from __future__ import annotations

from typing import Protocol

from cosim.signals import PulseTrain, Signal


class Controller(Protocol):
    """What every controller offers a machine (PoKeys ``PulseEngine``, ``TrioController``, ``Pmac``)."""

    def outputs(self) -> list[Signal | PulseTrain]:
        """Every signal the controller drives (step trains, direction, gate, DAC, ...)."""
        ...

    def inputs(self) -> list[Signal]:
        """Every signal the controller reads (switches, capture triggers, digital inputs)."""
        ...
