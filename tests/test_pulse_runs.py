"""Runs of slots: a PoKeys engine hands the slots between host events to its trains as runs.

    slot starts   |k        |k+1      |k+2      |k+3       (no event in between: one run of 3 slots)
    host events        ^ fill                        ^ reply
    train         emit_run(t0 = slot k + setup, 1 ms, [c_k, c_k+1, c_k+2])  ==  3 x emit(...)

A run must leave the trace, the counters and every listener exactly as one segment per slot at
its own instant does: the tests compare runs against the same job with runs switched off (a
listener that takes single segments only), signal by signal.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from cosim.controllers.pokeys import AXES, AxisConfig, EngineConfig, PulseEngine
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.stepper import couple_stepper
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.presets import load_preset
from cosim.signals import PulseTrain
from cosim.trace import Trace

MS = 1_000_000
PRESET = "nema17_17hs16_2004s1"


def digests(trace: Trace) -> dict[str, str]:
    """SHA-256 per signal over its pulses or changes (instants and values), as the run-digest tests take them."""
    out = {}
    for name in trace.names():
        t, v = trace.pulses(name) if trace.info[name].kind == "pulse" else trace.edges(name)
        out[name] = hashlib.sha256(np.asarray(t, "<i8").tobytes() + np.asarray(v, "<f8").tobytes()).hexdigest()
    return out


def job(*, runs: bool, steppers: bool) -> tuple[Simulation, PulseEngine, dict[str, int]]:
    """Out and back on three axes near 25 kHz, streamed over USB with a 10 ms host loop (events between slots)."""
    sim = Simulation(seed=3)
    config = EngineConfig(axes=tuple(AxisConfig(max_speed_hz=25_000, accel=500_000, decel=500_000) for _ in AXES))
    engine = PulseEngine(sim, config)
    counts = plan([Move((6_000, -4_500, 3_000)), Move((0, 0, 0)), Move((1_200, 0, -700))], config.axes)
    HostApp(sim, engine, to_entries(counts), link="usb", prefill_slots=100, period_ns=10 * MS)
    if not runs:  # a listener that takes single segments: every slot is emitted on its own
        for train in engine.steps:
            train.subscribe(lambda *segment: None)
    plants = []
    if steppers:
        plants = [Plant.load(sim, "Stepper", name=f"stepper_{a}", parameters=load_preset(PRESET)) for a in AXES]
        for i, plant in enumerate(plants):
            couple_stepper(engine.step_dir(i), plant)
    stats = {"events": 0, "slots_in_runs": 0}
    run_slots = engine._run_slots

    def counted(t: int, most: int) -> int:
        done = run_slots(t, most)
        stats["slots_in_runs"] += done
        return done

    engine._run_slots = counted  # type: ignore[method-assign]
    sim.run(until=len(counts) * MS + 200 * MS)
    stats["events"] = sim.env._steps
    stats.update({f"steps_{p.name}": p.steps for p in plants})
    return sim, engine, stats


def test_runs_leave_the_same_trace_and_counters_as_one_segment_per_slot() -> None:
    with_runs, engine, stats = job(runs=True, steppers=False)
    single, engine_single, _ = job(runs=False, steppers=False)
    assert all(train.takes_runs for train in engine.steps)
    assert stats["slots_in_runs"] > 0.6 * engine.slot_index  # most slots went in runs (not: idle, direction changes)
    assert not any(train.takes_runs for train in engine_single.steps)
    assert digests(with_runs.trace) == digests(single.trace)
    assert [r.value for r in engine.positions] == [r.value for r in engine_single.positions] == [1_200, 0, -700]
    assert engine.slot_index == engine_single.slot_index
    assert len(with_runs.trace.segments("pokeys.x.step")["count"]) == \
        len(single.trace.segments("pokeys.x.step")["count"])


@pytest.mark.fmu
def test_steppers_fed_by_runs_step_at_the_same_instants_and_record_the_same_outputs() -> None:
    with_runs, _, stats = job(runs=True, steppers=True)
    single, _, stats_single = job(runs=False, steppers=True)
    assert digests(with_runs.trace) == digests(single.trace)  # commanded_steps at every stop included
    # the same plant steps (rows full, stops): runs changed no FMU step, only how segments reach the coupling
    assert {k: v for k, v in stats.items() if k.startswith("steps")} == \
        {k: v for k, v in stats_single.items() if k.startswith("steps")}
    # fewer kernel events: a run goes past the host's quiet cycles (bookkeeping that sees nothing of it)
    assert stats["events"] < stats_single["events"]


def test_a_run_is_the_segments_emit_would_record_one_by_one(sim: Simulation) -> None:
    runs: list[tuple[int, int, list[int], int, int]] = []
    train = PulseTrain(sim, "dev.x.step")
    train.subscribe(lambda *segment: None, runs=lambda _train, *run: runs.append(run))
    other = PulseTrain(sim, "dev.y.step")
    train.emit_run(5_000, 1_000_000, [3, 25, 1], 0, 5_000)
    for k, count in enumerate([3, 25, 1]):
        other.emit(5_000 + k * 1_000_000, 1_000_000, count, 0)
    assert runs == [(5_000, 1_000_000, [3, 25, 1], 0, 5_000)]
    assert train.position == other.position == -29
    for a, b in zip(sim.trace.pulses("dev.x.step"), sim.trace.pulses("dev.y.step"), strict=True):
        assert a.tolist() == b.tolist()


def test_a_train_with_a_single_segment_listener_refuses_runs(sim: Simulation) -> None:
    train = PulseTrain(sim, "dev.x.step")
    train.subscribe(lambda *segment: None)
    assert not train.takes_runs
    with pytest.raises(ConfigurationError, match="single segments only"):
        train.emit_run(0, 1_000, [1], 1, 0)


def test_a_train_that_announces_ends_tells_the_listeners_that_asked(sim: Simulation) -> None:
    ended: list[str] = []
    train = PulseTrain(sim, "dev.x.step", announces_ends=True)
    train.subscribe(lambda *segment: None, ends=lambda t: ended.append(t.name))
    train.subscribe(lambda *segment: None)
    train.end_run()
    assert train.announces_ends and ended == ["dev.x.step"]


def test_free_until_is_the_next_event_and_skip_to_counts_the_passes_it_stands_for(sim: Simulation) -> None:
    reports: list[int] = []
    sim.env.on_progress = reports.append
    sim.call_at(10_000, 20, lambda: None)
    assert sim.free_until() == 10_000
    assert sim.skip_to(9_999, passes=5_000)  # crosses a multiple of 4096 passes: one progress report
    assert sim.now == 9_999 and reports == [9_999]
    assert not sim.skip_to(10_000)  # the event is due at 10_000
    sim.add_look_ahead(lambda t: None)
    assert sim.free_until() == sim.now  # a plant could announce an event at any instant
