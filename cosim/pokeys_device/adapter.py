"""The narrow interface between the protocol handlers and a pulse engine.

The command handlers (:mod:`.commands_v1`, :mod:`.commands_v2`) speak only to an
:class:`EngineAdapter`: status, fill (returning the accepted count), clear, free space, state
changes, positions, moves, homing, configuration. Status and configuration are the engine's own
public records (:class:`~cosim.controllers.pokeys.Status`, :class:`~cosim.controllers.pokeys.EngineConfig`),
not copies. :class:`PulseEngineAdapter` puts the project's engine model behind it (SimPy process,
trace and all; time moves only when the owner runs the simulation: the real-time pacer of
:mod:`.realtime`, or a test). Protocol unit tests use a bookkeeping fake with the same interface
(``tests/pokeys_fake_engine.py``).

Engine states are the v1 codes of :class:`~cosim.controllers.pokeys.EngineState` (0 stopped,
1 internal, 2 buffer, 10 jogging, 20 home, 21 homing, 100 limit stop, 101 emergency stop); the
v2 handler maps them to its own codes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Protocol

from cosim.controllers.pokeys import EngineConfig, EngineState, PulseEngine, Status
from cosim.controllers.pokeys.engine import HOST_SETTABLE, host_state
from cosim.errors import ConfigurationError

HOST_STATES = frozenset(HOST_SETTABLE)


class EngineAdapter(Protocol):
    """What the protocol handlers need from a pulse engine.

    Attributes
    ----------
    axes : int
        Axes the engine drives (index 0..axes-1).
    depth_slots : int
        Slot buffer depth [slots].
    enabled : bool
        Pulse output allowed (v1 "engine enabled"); while False nothing moves in any state.
    """

    axes: int
    depth_slots: int
    enabled: bool

    def status(self) -> Status:
        """Status now (the engine's record)."""
        ...

    def fill(self, slots: Sequence[bytes | Sequence[int]]) -> int:
        """Queue as many slots as fit, in order; return how many.

        A slot is one byte per axis (7-bit count, direction MSB) or one signed count per axis.
        Raises ConfigurationError (nothing queued) for a slot the device model cannot emit.
        """
        ...

    def clear_buffer(self) -> None:
        """Drop every queued slot."""
        ...

    def set_state(self, state: int) -> None:
        """Set the engine state (0, 1, 2, 10); raises ConfigurationError for others."""
        ...

    def set_enabled(self, enabled: bool) -> None:
        """Allow (True) or stop (False) pulse output."""
        ...

    def set_position(self, axis: int, position: int) -> None:
        """Set one position counter [pulses]."""
        ...

    def move_to(self, targets: Sequence[int | None]) -> None:
        """Internal position control towards ``targets`` [pulses] (None: leave the axis)."""
        ...

    def run_at(self, speeds_hz: Sequence[int | None]) -> None:
        """Internal speed control at signed ``speeds_hz`` [pulses/s] (None: leave the axis)."""
        ...

    def start_homing(self, axes: Sequence[int]) -> None:
        """Home the given axes."""
        ...

    def configure(self, config: EngineConfig) -> None:
        """Apply the host's motion parameters and switch configuration (raises ConfigurationError if invalid)."""
        ...

    def settings(self) -> EngineConfig:
        """The configuration in force."""
        ...


class PulseEngineAdapter:
    """:class:`EngineAdapter` over the project's PoKeys engine model.

    Parameters
    ----------
    engine : PulseEngine
        The engine (its simulation is advanced by the owner).
    enabled : bool
        Pulse output allowed at power-on.

    Notes
    -----
    * Fills go to :meth:`PulseEngine.fill_buffer`: a slot over the model's per-slot limit (25 on a
      56E or 57E, 125 on a 57CNC) or the v1 reserved x byte 0xFF refuses the whole fill, as the
      engine's Python API does; the handlers answer it with 0 accepted.
    * "Disabled" keeps the engine stopped and remembers the state the host asked for; enabling
      applies it.
    """

    def __init__(self, engine: PulseEngine, *, enabled: bool = True) -> None:
        self.engine = engine
        self.axes = len(engine.axis_names)
        self.depth_slots = engine.buffer.depth_slots
        self.enabled = enabled
        self._requested = EngineState.STOPPED

    def status(self) -> Status:
        status = self.engine.status()
        return status if self.enabled else replace(status, engine_state=self._requested)

    def fill(self, slots: Sequence[bytes | Sequence[int]]) -> int:
        return self.engine.fill_buffer(slots).accepted

    def clear_buffer(self) -> None:
        self.engine.clear_buffer()

    def set_state(self, state: int) -> None:
        new = host_state(state)
        self._requested = new
        if self.enabled or new == EngineState.STOPPED:
            self.engine.set_state(new)

    def set_enabled(self, enabled: bool) -> None:
        if enabled == self.enabled:
            return
        if not enabled:
            state = self.engine.state
            self._requested = state if state in HOST_STATES else EngineState.STOPPED
            self.engine.set_state(EngineState.STOPPED)
        self.enabled = enabled
        if enabled and self._requested != EngineState.STOPPED:
            self.engine.set_state(self._requested)

    def set_position(self, axis: int, position: int) -> None:
        self.engine.set_position(axis, position)

    def move_to(self, targets: Sequence[int | None]) -> None:
        self._require_enabled("move_to")
        self.engine.move_to(list(targets[:self.axes]))

    def run_at(self, speeds_hz: Sequence[int | None]) -> None:
        self._require_enabled("run_at")
        top = self.engine.device.max_rate_hz
        speeds = [None if v is None else max(-top, min(top, v)) for v in speeds_hz[:self.axes]]
        self.engine.run_at(speeds)

    def start_homing(self, axes: Sequence[int]) -> None:
        self._require_enabled("start_homing")
        self.engine.start_homing(list(axes))

    def _require_enabled(self, what: str) -> None:
        if not self.enabled:
            raise ConfigurationError.out_of_range(f"pulse engine enabled for {what}", False, "True (enable it first)")

    def configure(self, config: EngineConfig) -> None:
        if config != self.engine.config:
            self.engine.reconfigure(config)

    def settings(self) -> EngineConfig:
        return self.engine.config
