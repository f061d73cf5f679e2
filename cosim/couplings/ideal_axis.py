"""A switch on an ideal axis: step pulses counted as the position, a switch input driven from it.

For machines without a plant model on an axis (the Stepper FMU is coupled by
:mod:`cosim.couplings.stepper`): the axis is taken to follow its step pulses exactly. The
coupling subscribes to a step pulse train (one call per segment, as the stepper coupling does)
and sets a switch signal at the exact pulse instant at which the position enters or leaves a
region, with priority PLANT_EVENT. A PoKeys engine sees the change at its next slot start.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from cosim.kernel import Simulation
from cosim.signals import PulseTrain, Signal
from cosim.timebase import Priority


class PositionSwitch:
    """Drive ``switch`` with ``tripped(position)`` after every pulse of ``train``.

    Parameters
    ----------
    sim : Simulation
    train : PulseTrain
        The axis' step output (``pokeys.x.step``); its ``dir`` 1 counts up.
    switch : Signal
        The switch input to drive (1 = tripped).
    tripped : callable
        ``tripped(position_pulses) -> bool``.
    position : int
        Position of the axis before the first pulse [pulses].

    Examples
    --------
    A home switch covering ``x <= -20``::

        PositionSwitch(sim, engine.steps[0], engine.switches.home[0], lambda p: p <= -20)
    """

    def __init__(self, sim: Simulation, train: PulseTrain, switch: Signal, tripped: Callable[[int], bool], *,
                 position: int = 0) -> None:
        self.sim = sim
        self.switch = switch
        self.tripped = tripped
        self.position = position
        self._level = bool(tripped(position))
        switch.set(int(self._level))
        train.subscribe(self._on_segment)

    def _on_segment(self, train: PulseTrain, t0: int, duration: int, count: int, direction: int) -> None:
        step = 1 if direction else -1
        for k in range(count):
            self.position += step
            level = bool(self.tripped(self.position))
            if level != self._level:
                self._level = level
                t_k = t0 + (k * duration) // count
                self.sim.call_at(t_k, Priority.PLANT_EVENT, partial(self._set, int(level)))

    def _set(self, level: int) -> None:
        self.switch.set(level)
