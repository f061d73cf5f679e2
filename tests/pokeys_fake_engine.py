"""A bookkeeping engine for the PoKeys protocol unit tests (not a model: no pulses, no switches, no limits).

Why here (``tests/``) and not in ``cosim.testing``: only the protocol tests use it. It implements
:class:`cosim.pokeys_device.adapter.EngineAdapter` with the engine's own public records
(:class:`~cosim.controllers.pokeys.Status`, :class:`~cosim.controllers.pokeys.EngineConfig`) and
covers what the engine model does not: more axes than a model drives, and counts above every
model's per-slot limit (the 16-bit fills of the protocol notes' test vectors).

Each :meth:`FakeEngine.tick` is one slot: while enabled and in state 1 or 2 it pops one slot and
adds its counts to the positions. Homing completes at once.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

from cosim.controllers.pokeys import AxisState, EngineConfig, EngineState, Status, signed_count
from cosim.errors import ConfigurationError

HOST_STATES = (EngineState.STOPPED, EngineState.INTERNAL, EngineState.BUFFER, EngineState.JOGGING)


class FakeEngine:
    """In-memory engine for protocol unit tests.

    Parameters
    ----------
    axes : int
        Number of axes (8, like the 57 series' status block, by default).
    depth_slots : int
        Buffer depth [slots].
    """

    def __init__(self, *, axes: int = 8, depth_slots: int = 128, enabled: bool = True) -> None:
        self.axes = axes
        self.depth_slots = depth_slots
        self.enabled = enabled
        self.state = EngineState.STOPPED
        self.positions = [0] * axes
        self.buffer: deque[tuple[int, ...]] = deque()
        self._config = EngineConfig.for_model("57CNC") if axes == 8 else EngineConfig()
        self.calls: list[tuple[str, object]] = []

    def tick(self, slots: int = 1) -> None:
        """Run ``slots`` slots."""
        for _ in range(slots):
            if self.enabled and self.state in (EngineState.INTERNAL, EngineState.BUFFER) and self.buffer:
                for a, count in enumerate(self.buffer.popleft()):
                    self.positions[a] += count

    def status(self) -> Status:
        moving = AxisState.RUNNING if self.buffer else AxisState.READY
        return Status(tuple(self.positions), self.state, 0, 0, 0, False, (moving,) * self.axes,
                      self.depth_slots - len(self.buffer), len(self.buffer))

    def fill(self, slots: Sequence[bytes | Sequence[int]]) -> int:
        accepted = min(len(slots), self.depth_slots - len(self.buffer))
        for slot in slots[:accepted]:
            counts = tuple(signed_count(b) for b in slot) if isinstance(slot, bytes) else tuple(slot)
            self.buffer.append(counts + (0,) * (self.axes - len(counts)))
        return accepted

    def clear_buffer(self) -> None:
        self.buffer.clear()

    def set_state(self, state: int) -> None:
        if state not in HOST_STATES:
            raise ConfigurationError.out_of_range("engine state", state, "0 stopped, 1 internal, 2 buffer, 10 jogging")
        self.state = EngineState(state)

    def set_enabled(self, enabled: bool) -> None:
        self.enabled = enabled

    def set_position(self, axis: int, position: int) -> None:
        self.positions[axis] = position

    def move_to(self, targets: Sequence[int | None]) -> None:
        self.calls.append(("move_to", tuple(targets)))
        self.state = EngineState.INTERNAL

    def run_at(self, speeds_hz: Sequence[int | None]) -> None:
        self.calls.append(("run_at", tuple(speeds_hz)))
        self.state = EngineState.INTERNAL

    def start_homing(self, axes: Sequence[int]) -> None:
        self.calls.append(("start_homing", tuple(axes)))
        for a in axes:
            self.positions[a] = 0
        self.state = EngineState.HOME

    def configure(self, config: EngineConfig) -> None:
        self._config = config

    def settings(self) -> EngineConfig:
        return self._config
