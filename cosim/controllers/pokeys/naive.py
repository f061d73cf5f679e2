"""A naive reference model: the same engine, but one SimPy event per step pulse.

:class:`NaivePulseEngine` behaves exactly like :class:`~cosim.controllers.pokeys.engine.PulseEngine`
(same slots, switches, modes and pulse instants) but emits every pulse as its own kernel event
at its instant instead of one segment per slot. It exists to cross-check the segment placement
and as the baseline of ``bench/bench_pokeys.py``.
"""

from __future__ import annotations

from functools import partial

from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.limits import COUNT_MASK, DIRECTION_BIT, SLOT_NS
from cosim.controllers.pokeys.states import AxisState
from cosim.timebase import Priority


class NaivePulseEngine(PulseEngine):
    """:class:`PulseEngine` with one scheduled event per pulse (``PulseTrain.pulse`` at its instant)."""

    def _emit_entry(self, t: int, entry: bytes) -> None:
        for a in range(3):
            byte = entry[a]
            count = byte & COUNT_MASK
            self._emit_axis(a, t, count, byte >= DIRECTION_BIT)
            self._set_axis_state(a, AxisState.RUNNING if count else AxisState.READY)

    def _emit_axis(self, a: int, t: int, count: int, negative: bool) -> None:
        if negative != self._dir_bit[a]:
            self._dir_bit[a] = negative
            self.dirs[a].set(negative != self.config.axes[a].invert_direction)
        if not count:
            return
        train = self.steps[a]
        direction = 0 if negative else 1
        t0 = t + self._setup
        for k in range(count):
            t_k = t0 + (k * SLOT_NS) // count
            self.sim.call_at(t_k, Priority.SLOT, partial(train.pulse, t_k, direction))
        self._pos[a] += -count if negative else count
        self.positions[a].set(self._pos[a])
