"""Outputs that settle at the end of an instant.

A program may switch an output several times at one instant (the note's example switches the
PWM on, then gating on, at t = 0). The hardware shows only the final level, so the outputs that
drive the laser (``gate``, ``pwm_cycle``, ``pwm_mark``, ``wdog``) are *settled*: a change is
committed once per instant, at priority ``Priority.SETTLE`` (after the servo cycle and the host
program, before recording samples). The trace and the plant see one value per instant, at the
exact tick.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cosim.signals import Signal
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.kernel import Simulation

class SettledSignal:
    """A :class:`~cosim.signals.Signal` whose changes are committed at the end of the instant.

    Parameters
    ----------
    sim : Simulation
    name : str
        Trace name.
    kind : {'bit', 'int', 'real'}
    initial : int
        Value at power-up.
    unit, description : str
    """

    def __init__(self, sim: Simulation, name: str, *, kind: str, initial: int = 0, unit: str = "",
                 description: str = "") -> None:
        self.sim = sim
        self.signal = Signal(sim, name, kind=kind, initial=initial, unit=unit, description=description)
        self._wanted: float = self.signal.value
        self._pending_t: int | None = None

    @property
    def value(self) -> float:
        """The value requested last (what the output will be at the end of this instant)."""
        return self._wanted

    def request(self, value: float) -> None:
        """Ask for ``value``; committed once, at the end of the current instant."""
        self._wanted = value
        if self._pending_t != self.sim.now and value != self.signal.value:
            self._pending_t = self.sim.now
            self.sim.call_at(self.sim.now, Priority.SETTLE, self._commit)

    def _commit(self) -> None:
        self._pending_t = None
        self.signal.set(self._wanted)
