"""A naive reference for the PoKeys engine: the same engine, but one SimPy event per step pulse.

:func:`naive_pulse_engine` builds a :class:`~cosim.controllers.pokeys.PulseEngine` whose step outputs
are :class:`PerPulseTrain`: every segment the engine announces is turned into ``count`` kernel
events, pulse k at its instant ``t0 + (k * duration) // count`` (the rule of :mod:`cosim.pulses`),
each recorded as a single pulse. It cross-checks the segment placement (the tests compare the two
traces pulse by pulse) and is the baseline of ``bench/bench_pokeys.py``.

Why here and not in ``tests/``: the benchmark, which is not a test, runs it too.
"""

from __future__ import annotations

from functools import partial
from typing import Any

from cosim.controllers.pokeys import EngineConfig, PulseEngine
from cosim.kernel import Simulation
from cosim.signals import PulseTrain
from cosim.timebase import Priority


class PerPulseTrain(PulseTrain):
    """A pulse train that schedules each pulse of a segment as its own event (:meth:`PulseTrain.pulse`)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.takes_runs = False  # one segment at a time, each into single pulses

    def emit(self, t0: int, duration: int, count: int, direction: int) -> None:
        """``count`` single pulses at ``t0 + (k * duration) // count`` [ticks], one kernel event each."""
        for k in range(count):
            t_k = t0 + (k * duration) // count
            self.sim.call_at(t_k, Priority.SLOT, partial(self.pulse, t_k, direction))


def naive_pulse_engine(sim: Simulation, config: EngineConfig | None = None, **options: Any) -> PulseEngine:
    """A :class:`PulseEngine` with one scheduled event per pulse (``options`` as for the engine)."""
    return PulseEngine(sim, config, pulse_train=PerPulseTrain, **options)
