"""The narrow interface between the protocol handlers and a pulse engine.

The command handlers (:mod:`.commands_v1`, :mod:`.commands_v2`) speak only to an
:class:`EngineAdapter`: status, fill (returning the accepted count), clear, free space, state
changes, positions, moves, homing, configuration. Two implementations:

* :class:`PulseEngineAdapter`: the project's PoKeys engine model
  (:class:`cosim.controllers.pokeys.PulseEngine`), SimPy process, trace and all. Time moves only
  when the owner runs the simulation (the real-time pacer of :mod:`.realtime`, or a test);
* :class:`FakeEngine`: a few lines of bookkeeping for protocol unit tests that need what the
  engine model does not do (8 axes, more than 127 pulses per slot in 16-bit fills), advanced
  by :meth:`FakeEngine.tick`.

Engine states are the v1 codes of :class:`~cosim.controllers.pokeys.EngineState` (0 stopped,
1 internal, 2 buffer, 10 jogging, 20 home, 21 homing, 100 limit stop, 101 emergency stop); the
v2 handler maps them to its own codes.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Protocol

from cosim.controllers.pokeys import EngineConfig, EngineState, PulseEngine
from cosim.controllers.pokeys.limits import MAX_PULSES_PER_SLOT, MAX_RATE_HZ
from cosim.errors import ConfigurationError
from cosim.pokeys_device.common import log


@dataclass(frozen=True)
class AxisSettings:
    """Motion parameters and switch configuration of one axis, as the host set them.

    Parameters
    ----------
    max_speed_hz : int
        Maximum speed [pulses/s], 1..25000.
    accel, decel : int
        [pulses/s^2], > 0.
    limit_pos_enabled, limit_neg_enabled, home_enabled : bool
    invert_direction, invert_homing : bool
    """

    max_speed_hz: int = MAX_RATE_HZ
    accel: int = 100_000
    decel: int = 100_000
    limit_pos_enabled: bool = False
    limit_neg_enabled: bool = False
    home_enabled: bool = False
    invert_direction: bool = False
    invert_homing: bool = False


@dataclass(frozen=True)
class EngineSettings:
    """Everything the host configures that the engine acts on.

    Parameters
    ----------
    axes : tuple of AxisSettings
        One per engine axis (extra ones are ignored).
    homing_speed_pct, homing_return_pct : int
        Homing search and back-off speeds [% of the maximum speed], 1..100.
    emergency_polarity : {0, 1}
        0: a high input means emergency.
    """

    axes: tuple[AxisSettings, ...] = (AxisSettings(), AxisSettings(), AxisSettings())
    homing_speed_pct: int = 10
    homing_return_pct: int = 1
    emergency_polarity: int = 0


@dataclass(frozen=True)
class EngineStatus:
    """The engine as a status reply reports it.

    Attributes
    ----------
    positions : tuple of int
        Position counters [pulses], one per engine axis.
    state : int
        Engine state (v1 codes).
    limit_pos, limit_neg, home : int
        Switch bitmaps read at the last slot start (bit 0 = axis 0).
    axis_states : tuple of int
        The engine's own axis states.
    queued_slots, free_slots : int
        Slot buffer level and free space.
    """

    positions: tuple[int, ...]
    state: int
    limit_pos: int
    limit_neg: int
    home: int
    axis_states: tuple[int, ...]
    queued_slots: int
    free_slots: int


class EngineAdapter(Protocol):
    """What the protocol handlers need from a pulse engine.

    Attributes
    ----------
    axes : int
        Axes the engine drives (index 0..axes-1).
    depth_slots : int
        Slot buffer depth.
    max_count : int or None
        Largest pulse count one slot entry may carry (None: any).
    enabled : bool
        Pulse output allowed (v1 "engine enabled"); while False nothing moves in any state.
    """

    axes: int
    depth_slots: int
    max_count: int | None
    enabled: bool

    def status(self) -> EngineStatus:
        """Status now."""
        ...

    def fill(self, slots: Sequence[Sequence[int]]) -> int:
        """Queue as many slots of signed counts (one per axis) as fit, in order; return how many."""
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

    def configure(self, settings: EngineSettings) -> None:
        """Apply the host's motion parameters and switch configuration."""
        ...

    def settings(self) -> EngineSettings:
        """The motion parameters and switch configuration in force."""
        ...


HOST_STATES = frozenset((EngineState.STOPPED, EngineState.INTERNAL, EngineState.BUFFER, EngineState.JOGGING))


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
    * Slot entries carry 7-bit counts (``max_count`` = 127). Counts above the generator's 25 per
      slot are queued as given (the protocol notes' convention: positions integrate exactly what
      was sent); the recorded pulses then fail the 25-per-slot check, which is the point.
    * "Disabled" keeps the engine stopped and remembers the state the host asked for; enabling
      applies it.
    """

    max_count: int | None = 127

    def __init__(self, engine: PulseEngine, *, enabled: bool = True) -> None:
        self.engine = engine
        self.axes = len(engine.config.axes)
        self.depth_slots = engine.buffer.depth_slots
        self.enabled = enabled
        self._requested = EngineState.STOPPED

    def status(self) -> EngineStatus:
        s = self.engine.status()
        state = s.engine_state if self.enabled else self._requested
        return EngineStatus(tuple(s.positions), int(state), s.limit_pos, s.limit_neg, s.home,
                            tuple(int(a) for a in s.axis_states), self.depth_slots - s.free_slots, s.free_slots)

    def fill(self, slots: Sequence[Sequence[int]]) -> int:
        entries = [bytes(abs(c) | (0x80 if c < 0 else 0) for c in slot) for slot in slots]
        if all(max(abs(c) for c in slot) <= MAX_PULSES_PER_SLOT for slot in slots):
            return self.engine.fill_buffer(entries).accepted
        log.info("fill with more than %d pulses in a slot: queued as given", MAX_PULSES_PER_SLOT)
        accepted = self.engine.buffer.fill(entries)
        self.engine.buffer_level.set(self.engine.buffer.level)
        return accepted

    def clear_buffer(self) -> None:
        self.engine.clear_buffer()

    def set_state(self, state: int) -> None:
        try:
            new = EngineState(state)
        except ValueError:
            new = None
        if new not in HOST_STATES:
            raise ConfigurationError.out_of_range("engine state", state, "0 stopped, 1 internal, 2 buffer, 10 jogging")
        assert new is not None
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
        speeds = [None if v is None else max(-MAX_RATE_HZ, min(MAX_RATE_HZ, v)) for v in speeds_hz[:self.axes]]
        self.engine.run_at(speeds)

    def start_homing(self, axes: Sequence[int]) -> None:
        self._require_enabled("start_homing")
        self.engine.start_homing(list(axes))

    def _require_enabled(self, what: str) -> None:
        if not self.enabled:
            raise ConfigurationError.out_of_range(f"pulse engine enabled for {what}", False, "True (enable it first)")

    def configure(self, settings: EngineSettings) -> None:
        cfg = self.engine.config
        axes = tuple(replace(old, max_speed_hz=new.max_speed_hz, accel=new.accel, decel=new.decel,
                             limit_pos_enabled=new.limit_pos_enabled, limit_neg_enabled=new.limit_neg_enabled,
                             home_enabled=new.home_enabled, invert_direction=new.invert_direction,
                             invert_homing=new.invert_homing)
                     for old, new in zip(cfg.axes, settings.axes, strict=False))
        new_config = replace(cfg, axes=axes, homing_speed_pct=settings.homing_speed_pct,
                             homing_return_pct=settings.homing_return_pct,
                             emergency_polarity=settings.emergency_polarity)
        if new_config != cfg:
            reconfigure(self.engine, new_config)

    def settings(self) -> EngineSettings:
        cfg = self.engine.config
        axes = tuple(AxisSettings(int(a.max_speed_hz), int(a.accel), int(a.decel), a.limit_pos_enabled,
                                  a.limit_neg_enabled, a.home_enabled, a.invert_direction, a.invert_homing)
                     for a in cfg.axes)
        return EngineSettings(axes, cfg.homing_speed_pct, cfg.homing_return_pct, cfg.emergency_polarity)


def reconfigure(engine: PulseEngine, config: EngineConfig) -> None:
    """Give a running engine a new configuration (the host changed parameters or switch wiring).

    Uses ``engine.reconfigure`` when the engine model offers it; until then it replaces the
    configuration the engine and its switch inputs read, and rebuilds the internal controller's
    limits from it (the axes' motion restarts from rest, as after a state change).
    """
    method = getattr(engine, "reconfigure", None)
    if callable(method):
        method(config)
        return
    from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits

    engine.config = config
    engine.switches.config = config
    positions = engine.status().positions
    limits = [SlotLimits.exact(a.max_speed_per_slot, a.accel_per_slot2, a.decel_per_slot2) for a in config.axes]
    engine._limits = limits
    engine._motions = [AxisMotion(lim, position=p) for lim, p in zip(limits, positions, strict=True)]


class FakeEngine:
    """In-memory bookkeeping engine for protocol unit tests (not a model: no pulses, no switches).

    Each :meth:`tick` is one slot: while enabled and in state 1 or 2 it pops one slot and adds its
    counts to the positions, without any limit on the counts. Homing completes at once.

    Parameters
    ----------
    axes : int
        Number of axes (8 like the 57 series by default).
    depth_slots : int
        Buffer depth (128).
    """

    max_count: int | None = None

    def __init__(self, *, axes: int = 8, depth_slots: int = 128, enabled: bool = True) -> None:
        self.axes = axes
        self.depth_slots = depth_slots
        self.enabled = enabled
        self.state = int(EngineState.STOPPED)
        self.positions = [0] * axes
        self.buffer: deque[tuple[int, ...]] = deque()
        self._settings = EngineSettings(tuple(AxisSettings() for _ in range(axes)))
        self.calls: list[tuple[str, object]] = []

    def tick(self, slots: int = 1) -> None:
        """Run ``slots`` slots."""
        for _ in range(slots):
            if self.enabled and self.state in (EngineState.INTERNAL, EngineState.BUFFER) and self.buffer:
                for a, count in enumerate(self.buffer.popleft()):
                    self.positions[a] += count

    def status(self) -> EngineStatus:
        moving = int(bool(self.buffer)) + 1
        return EngineStatus(tuple(self.positions), self.state, 0, 0, 0, (moving,) * self.axes, len(self.buffer),
                            self.depth_slots - len(self.buffer))

    def fill(self, slots: Sequence[Sequence[int]]) -> int:
        accepted = min(len(slots), self.depth_slots - len(self.buffer))
        self.buffer.extend(tuple(slot) for slot in slots[:accepted])
        return accepted

    def clear_buffer(self) -> None:
        self.buffer.clear()

    def set_state(self, state: int) -> None:
        if state not in HOST_STATES:
            raise ConfigurationError.out_of_range("engine state", state, "0 stopped, 1 internal, 2 buffer, 10 jogging")
        self.state = int(state)

    def set_enabled(self, enabled: bool) -> None:
        self.enabled = enabled

    def set_position(self, axis: int, position: int) -> None:
        self.positions[axis] = position

    def move_to(self, targets: Sequence[int | None]) -> None:
        self.calls.append(("move_to", tuple(targets)))
        self.state = int(EngineState.INTERNAL)

    def run_at(self, speeds_hz: Sequence[int | None]) -> None:
        self.calls.append(("run_at", tuple(speeds_hz)))
        self.state = int(EngineState.INTERNAL)

    def start_homing(self, axes: Sequence[int]) -> None:
        self.calls.append(("start_homing", tuple(axes)))
        for a in axes:
            self.positions[a] = 0
        self.state = int(EngineState.HOME)

    def configure(self, settings: EngineSettings) -> None:
        self._settings = settings

    def settings(self) -> EngineSettings:
        return self._settings
