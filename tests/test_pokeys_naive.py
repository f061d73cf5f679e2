"""The naive per-pulse reference model places every pulse exactly where the segment engine does."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cosim.controllers.pokeys import EngineConfig, EngineState, PulseEngine, uniform_axes
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.kernel import Simulation
from cosim.testing.pokeys_naive import naive_pulse_engine

MS = 1_000_000


def _run(kind: Callable[..., PulseEngine]) -> tuple[Simulation, PulseEngine]:
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
    naive_sim, naive = _run(naive_pulse_engine)
    for axis in "xyz":
        t_fast, d_fast = fast_sim.trace.pulses(f"pokeys.{axis}.step")
        t_naive, d_naive = naive_sim.trace.pulses(f"pokeys.{axis}.step")
        assert np.array_equal(t_fast, t_naive) and np.array_equal(d_fast, d_naive)
        dir_name = f"pokeys.{axis}.dir"
        assert np.array_equal(fast_sim.trace.edges(dir_name)[0], naive_sim.trace.edges(dir_name)[0])
    assert fast.status() == naive.status()
    assert naive_sim.trace.segments("pokeys.x.step")["count"].size == 0  # really one pulse at a time
    assert naive_sim.trace.pulses("pokeys.x.step")[0].size == 1000


def test_slots_run_without_kernel_events_give_the_same_trace_as_one_event_per_slot() -> None:
    """The engine skips slot events while nothing else is due; a 0.3 ms ticker forbids every skip."""
    traces = []
    for ticker in (False, True):
        sim = Simulation(seed=1)
        config = EngineConfig(axes=uniform_axes(accel=2_000_000, decel=2_000_000))
        engine = PulseEngine(sim, config)
        engine.fill_buffer(to_entries(plan([Move((500, -300, 13)), Move((0, 0, 0))], config.axes)))
        engine.set_state(EngineState.BUFFER)
        if ticker:
            def tick(sim: Simulation = sim) -> object:
                k = 0
                while True:
                    yield sim.at(k * 300_000 + 1)
                    k += 1
            sim.process(tick())  # type: ignore[arg-type]
        steps_before = sim.env._steps
        sim.run(until=130 * MS)
        traces.append((sim, sim.env._steps - steps_before))
    (plain, plain_steps), (ticked, ticked_steps) = traces
    for name in plain.trace.names():
        if plain.trace.info[name].kind == "pulse":
            assert np.array_equal(plain.trace.pulses(name)[0], ticked.trace.pulses(name)[0]), name
        else:
            for a, b in zip(plain.trace.edges(name), ticked.trace.edges(name), strict=True):
                assert np.array_equal(a, b), name
    assert plain_steps <= 3  # the first slot's event and the run's end: 129 slots skipped
    assert ticked_steps >= 130 + 434  # every slot its own event, beside the ticker's 434
