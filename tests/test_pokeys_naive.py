"""The naive per-pulse reference model places every pulse exactly where the segment engine does."""

from __future__ import annotations

import numpy as np

from cosim.controllers.pokeys import EngineConfig, EngineState, PulseEngine, uniform_axes
from cosim.controllers.pokeys.naive import NaivePulseEngine
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.kernel import Simulation

MS = 1_000_000


def _run(kind: type[PulseEngine]) -> tuple[Simulation, PulseEngine]:
    sim = Simulation(seed=1)
    config = EngineConfig(axes=uniform_axes(accel=2_000_000, decel=2_000_000), dir_setup_ns=3_000)
    engine = kind(sim, config)
    entries = to_entries(plan([Move((500, -300, 13)), Move((0, 0, 0))], config.axes))
    assert engine.fill_buffer(entries).accepted == len(entries)
    engine.set_state(EngineState.BUFFER)
    sim.run(until=130 * MS)
    return sim, engine


def test_naive_model_gives_the_same_pulses_one_event_each() -> None:
    fast_sim, fast = _run(PulseEngine)
    naive_sim, naive = _run(NaivePulseEngine)
    for axis in "xyz":
        t_fast, d_fast = fast_sim.trace.pulses(f"pokeys.{axis}.step")
        t_naive, d_naive = naive_sim.trace.pulses(f"pokeys.{axis}.step")
        assert np.array_equal(t_fast, t_naive) and np.array_equal(d_fast, d_naive)
        dir_name = f"pokeys.{axis}.dir"
        assert np.array_equal(fast_sim.trace.edges(dir_name)[0], naive_sim.trace.edges(dir_name)[0])
    assert fast.status() == naive.status()
    assert naive_sim.trace.segments("pokeys.x.step")["count"].size == 0  # really one pulse at a time
    assert naive_sim.trace.pulses("pokeys.x.step")[0].size == 1000
