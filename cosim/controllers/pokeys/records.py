"""What the engine reports: its status, fill replies, refusals, underruns, and its recorded registers.

Every time in these records is in ticks of the simulation's resolution (``t``, ``t_start``,
``length``); the names carry no ``_ns`` because they do not hold nanoseconds at other resolutions.
"""

from __future__ import annotations

from dataclasses import dataclass

from cosim.controllers.pokeys.states import AxisState, EngineState
from cosim.kernel import Simulation


class Register:
    """An integer register of the engine, recorded in the trace at every change (read it, do not drive it).

    Lighter than a :class:`~cosim.signals.Signal` (no subscribers): the position counters and the
    buffer level change every slot.
    """

    __slots__ = ("_record", "_sim", "name", "value")

    def __init__(self, sim: Simulation, name: str, *, unit: str, description: str, kind: str = "int") -> None:
        self._sim = sim
        self.name = name
        self.value = 0
        sim.trace.declare(name, kind, unit=unit, description=description)
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
        Position counters, one per axis (x, y, z, ...) [pulses].
    engine_state : EngineState
    limit_pos, limit_neg, home : int
        Tripped switch bitmaps as read at the last slot start (bit 0 = x, one bit per axis).
    emergency : bool
        Emergency input active at the last slot start.
    axis_states : tuple of AxisState
    free_slots : int
        Free space in the slot buffer [slots].
    queued_slots : int
        Slots in the buffer [slots].
    refused_fills : int
        Fill commands refused so far for an entry the model cannot emit (see :class:`Refusal`).
    """

    positions: tuple[int, ...]
    engine_state: EngineState
    limit_pos: int
    limit_neg: int
    home: int
    emergency: bool
    axis_states: tuple[AxisState, ...]
    free_slots: int
    queued_slots: int = 0
    refused_fills: int = 0


@dataclass(frozen=True)
class Refusal:
    """A fill command refused as a whole because one entry holds what the device model cannot emit.

    Attributes
    ----------
    t : int
        When [ticks].
    slot : int
        Index of the offending entry in the fill command.
    axis : int
        Its axis.
    count : int
        The entry's signed count [pulses].
    limit : int
        The model's most pulses per slot [pulses].
    reason : str
        The message the Python API raises with.
    """

    t: int
    slot: int
    axis: int
    count: int
    limit: int
    reason: str


@dataclass(frozen=True)
class FillReply:
    """Reply to a fill-buffer command: slots accepted, and the status at that moment."""

    accepted: int
    status: Status


@dataclass(frozen=True)
class Underrun:
    """Slots of buffer mode that found the buffer empty between two slots that had data.

    The rule (the engine's, for scenarios and the virtual device alike): in buffer mode, once a
    slot has taken data, slot starts that find the buffer empty begin a stretch; the stretch is an
    underrun when a later slot start in buffer mode takes data again. A stretch that ends with
    a state change, a stop or the end of the run is the end of a job, not an underrun.

    Attributes
    ----------
    t_start : int
        Start of the first empty slot [ticks].
    t_end : int
        Start of the slot that took data again [ticks].
    slots : int
        Empty slots in a row.
    """

    t_start: int
    t_end: int
    slots: int

    @property
    def length(self) -> int:
        """Duration [ticks]."""
        return self.t_end - self.t_start
