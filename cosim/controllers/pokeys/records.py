"""What the engine reports: its status, fill replies, underruns, and its recorded registers."""

from __future__ import annotations

from dataclasses import dataclass

from cosim.controllers.pokeys.limits import SLOT_NS
from cosim.controllers.pokeys.states import AxisState, EngineState
from cosim.kernel import Simulation


class Register:
    """An integer register of the engine, recorded in the trace at every change (read it, do not drive it).

    Lighter than a :class:`~cosim.signals.Signal` (no subscribers): the position counters and the
    buffer level change every slot.
    """

    __slots__ = ("_record", "_sim", "name", "value")

    def __init__(self, sim: Simulation, name: str, *, unit: str, description: str) -> None:
        self._sim = sim
        self.name = name
        self.value = 0
        sim.trace.declare(name, "int", unit=unit, description=description)
        self._record = sim.trace.recorder(name)
        self._record(sim.now, 0)

    def set(self, value: int, t: int | None = None) -> None:
        """Record ``value`` at ``t`` (default: now) if it changed."""
        if value != self.value:
            self.value = value
            self._record(self._sim.now if t is None else t, value)


@dataclass(frozen=True)
class Status:
    """What the status command and every fill-buffer reply report.

    Attributes
    ----------
    positions : tuple of int
        Position counters x, y, z [pulses].
    engine_state : EngineState
    limit_pos, limit_neg, home : int
        Tripped switch bitmaps as read at the last slot start (bit 0 = x).
    emergency : bool
        Emergency input active at the last slot start.
    axis_states : tuple of AxisState
    free_slots : int
        Free space in the slot buffer.
    """

    positions: tuple[int, ...]
    engine_state: EngineState
    limit_pos: int
    limit_neg: int
    home: int
    emergency: bool
    axis_states: tuple[AxisState, ...]
    free_slots: int


@dataclass(frozen=True)
class FillReply:
    """Reply to a fill-buffer command: slots accepted, and the status at that moment."""

    accepted: int
    status: Status


@dataclass(frozen=True)
class Underrun:
    """Consecutive slots of buffer mode with an empty buffer while the job was not finished."""

    t_start_ns: int
    length_ns: int

    @property
    def slots(self) -> int:
        """Length in slots."""
        return self.length_ns // SLOT_NS
