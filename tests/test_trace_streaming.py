"""Traces kept on disk in chunks: bounded memory, and every reader gives what it gives in memory.

A trace made with ``spill_rows=3`` keeps at most three rows of each table in memory and writes the
rest to disk; one made with ``chunk_pulses=4`` materialises at most four pulses at a time. Every
reading (the Trace API, every check, every export) must give exactly what the same records give
held in memory in one piece. The random traces cover the seams: segments of 0..40 pulses, a train
whose segments are out of order, single pulses in and out of order, several records at one tick,
NaN samples.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cosim.checks import (
    Bound,
    DirectionSetup,
    Duration,
    EdgeAtPosition,
    EdgeRef,
    IntervalsAbove,
    IntervalsBelow,
    MaxPulseRate,
    MinPulseSpacing,
    NoUnderrun,
    PulseRef,
    PulsesPerWindow,
    ValueAt,
)
from cosim.checks.base import Check
from cosim.controllers.pokeys import PulseEngine, uniform_axes
from cosim.controllers.pokeys.config import EngineConfig
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.export import write_trace
from cosim.kernel import Simulation
from cosim.trace import Trace
from cosim.tracestore import merge_sorted

S, D, G, L, P = "dev.x.step", "dev.x.dir", "dev.x.gate", "dev.level", "dev.power"
SMALL = {"spill_rows": 3, "chunk_pulses": 4}


def _records(seed: int) -> tuple[list[tuple[str, tuple[object, ...]]], int]:
    """A random trace as a list of recording calls, and its end."""
    rng = np.random.default_rng(seed)
    calls: list[tuple[str, tuple[object, ...]]] = []
    t = 0
    segments = []
    for _ in range(int(rng.integers(0, 120))):
        duration, count = int(rng.integers(1, 60)), int(rng.integers(0, 6))
        if rng.random() < 0.05:
            count = int(rng.integers(6, 40))
        segments.append((t, duration, count, int(rng.integers(0, 2))))
        t += duration + int(rng.integers(0, 3)) * int(rng.integers(0, 20))
    if seed % 7 == 3 and segments:  # segments out of time order
        segments.insert(0, segments.pop(len(segments) // 2))
    calls += [("record_segment", (S, *seg)) for seg in segments]
    singles = rng.integers(0, max(t, 1), int(rng.integers(0, 12)))
    calls += [("record_pulse", (S, int(x), int(rng.integers(0, 2))))
              for x in (singles if seed % 5 == 2 else np.sort(singles))]
    for name, low, high in ((D, 0, 2), (G, 0, 2), (L, -3, 5)):
        times = np.sort(rng.integers(0, t + 50, int(rng.integers(0, 80))))
        calls += [("record", (name, int(x), int(rng.integers(low, high)))) for x in times]
    for x in np.sort(rng.integers(0, t + 50, int(rng.integers(0, 60)))):
        calls.append(("record", (P, int(x), float(rng.normal()) if rng.random() > 0.05 else float("nan"))))
    return calls, t + int(rng.integers(0, 100))


def _trace(seed: int, **options: int) -> Trace:
    trace = Trace(**options)  # type: ignore[arg-type]
    for name, kind in ((S, "pulse"), (D, "bit"), (G, "bit"), (L, "int"), (P, "real")):
        trace.declare(name, kind, pulse_width=7)
    calls, end = _records(seed)
    for method, args in calls:
        getattr(trace, method)(*args)
    trace.end_t = end
    return trace


def _checks(seed: int) -> list[Check]:
    rng = np.random.default_rng(1000 + seed)

    def ri(a: int, b: int) -> int:
        return int(rng.integers(a, b))

    expected = [(ri(-10, 30), ri(0, 2)) for _ in range(ri(0, 8))]
    return [
        MinPulseSpacing(S, ri(1, 30)), MaxPulseRate(S, ri(1, 10) * 10**7),
        MaxPulseRate(S, ri(1, 10) * 10**7, window=ri(1, 200)), PulsesPerWindow(S, ri(0, 6), ri(1, 100), ri(-50, 50)),
        DirectionSetup(S, D, ri(0, 40), positive_level=ri(0, 2)),
        Duration(EdgeRef(D, 1), PulseRef(S, "last"), max=ri(0, 500)),
        Duration(EdgeRef(D), PulseRef(S, "first"), min=ri(0, 50), max=ri(50, 500)),
        Duration(EdgeRef(D, 1), EdgeRef(G, 0, which="last"), equals=ri(0, 100), tol=ri(0, 30)),
        Duration(PulseRef(S, "each"), EdgeRef(G, 1), max=ri(0, 100)),
        Duration(PulseRef(S, "first"), PulseRef(S, "last"), max=ri(0, 5000)),
        Duration(EdgeRef(G, None, which="last"), PulseRef(S, "first"), min=ri(0, 300)),
        EdgeAtPosition(G, S, expected, ri(0, 3)), EdgeAtPosition(G, L, expected, ri(0, 3)),
        Bound(L, lower=ri(-3, 1), upper=ri(1, 4)), Bound(P, upper=1.0),
        IntervalsBelow(L, ri(-2, 3), max_duration=ri(0, 200), start=ri(0, 100), until=ri(200, 4000),
                       allow_final=seed % 2 == 0),
        IntervalsBelow(L, ri(-2, 3)), IntervalsAbove(P, 0.5, max_duration=ri(0, 100)), NoUnderrun(L, 1),
        ValueAt(S, None, ri(-5, 5)), ValueAt(S, ri(0, 3000), ri(-5, 5)), ValueAt(L, None, 1),
        ValueAt(P, ri(0, 3000), 0.0, tol=0.5),
    ]


def _same(a: object, b: object) -> bool:
    return json.dumps(a, default=str) == json.dumps(b, default=str)  # NaN equals NaN here


@pytest.mark.parametrize("seed", range(40))
def test_every_check_finds_the_same_whatever_the_chunks(seed: int) -> None:
    whole, chunked = _trace(seed), _trace(seed, **SMALL)
    assert chunked.spilled_rows() > 0 or whole.memory_rows() <= 3 * 6
    for check in _checks(seed):
        assert _same(check.evaluate(chunked).to_dict(), check.evaluate(whole).to_dict()), check.label


@pytest.mark.parametrize("seed", range(40))
def test_trace_readers_give_the_same_whatever_the_chunks(seed: int) -> None:
    whole, chunked = _trace(seed), _trace(seed, **SMALL)
    rng = np.random.default_rng(seed)
    ticks = rng.integers(-5, whole.end_t + 50, 40)
    for a, b in zip(chunked.pulses(S), whole.pulses(S), strict=True):
        np.testing.assert_array_equal(a, b)
    assert np.concatenate([t for t, _ in chunked.pulse_chunks(S)] or [np.empty(0)]).tolist() == \
        whole.pulses(S)[0].tolist()
    # about a chunk of segment pulses (4) and one of single pulses (3) at a time, however long the train
    # (pulses at one tick come together: the random segments pack up to 40 pulses into a few ticks)
    same_tick = int(np.unique(whole.pulses(S)[0], return_counts=True)[1].max(initial=0))
    assert max((t.size for t, _ in chunked.pulse_chunks(S)), default=0) <= 2 * (4 + 3) + same_tick
    for key, column in chunked.segments(S).items():
        np.testing.assert_array_equal(column, whole.segments(S)[key])
    np.testing.assert_array_equal(chunked.positions_at(S, ticks), whole.positions_at(S, ticks))
    for name in (D, L, P):
        for a, b in zip(chunked.edges(name), whole.edges(name), strict=True):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(chunked.values_at(name, ticks), whole.values_at(name, ticks))
    for window in (1, 17, 500):
        for a, b in zip(chunked.pulses_per_window(S, window, start=-20),
                        whole.pulses_per_window(S, window, start=-20), strict=True):
            np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("seed", [0, 3, 9, 12, 21])
def test_exports_are_the_same_bytes_whatever_the_chunks(seed: int, tmp_path: Path) -> None:
    folders = []
    for k, options in enumerate(({}, SMALL)):
        trace = _trace(seed, **options)  # type: ignore[arg-type]
        folders.append(write_trace(trace, tmp_path / str(k), formats=("vcd", "csv")))
    files = sorted(p.name for p in folders[0].iterdir())
    assert files == ["edges.csv", "pulses.csv", "segments.csv", "trace.gtkw", "trace.vcd", "trace_digital.vcd",
                     "trace_meta.json", "trace_wide.csv", "values.csv"]
    for name in files:
        assert (folders[0] / name).read_bytes() == (folders[1] / name).read_bytes(), name


def test_a_table_keeps_at_most_spill_rows_in_memory_and_the_rest_on_disk(tmp_path: Path) -> None:
    trace = Trace(spill_rows=100)
    trace.spool_dir = tmp_path
    trace.declare("dev.count", "int")
    record = trace.recorder("dev.count")
    for t in range(1050):
        record(t, t % 7)
    assert trace.memory_rows() == 50 and trace.spilled_rows() == 1000
    spool = list(tmp_path.iterdir())
    assert len(spool) == 1 and spool[0].name.startswith("cosim-trace-")
    t, v = trace.edges("dev.count")
    assert t.tolist() == list(range(1050)) and v.tolist() == [k % 7 for k in range(1050)]
    trace.discard_spill()
    assert list(tmp_path.iterdir()) == []


def test_a_long_runs_memory_stays_flat_in_simulated_time() -> None:
    """PoKeys engine and host on a 20 s 3-axis job, the trace spilling every 2,000 rows.

    After 5 s and after 20 s of simulated time the same bound holds for what is held in memory:
    2,000 rows per table and 1,000 fill records, while what is on disk grows with the run.
    """
    with Simulation() as sim:
        sim.trace = Trace(sim.timebase, spill_rows=2_000)
        config = EngineConfig(axes=uniform_axes(max_speed_hz=24_000, accel=400_000, decel=400_000))
        engine = PulseEngine(sim, config)
        targets = [(240_000, -180_000, 120_000), (0, 0, 0)]
        host = HostApp(sim, engine, to_entries(plan([Move(t) for t in targets], config.axes)))
        tables = len(sim.trace.names()) + len(sim.trace.names("pulse"))  # a pulse train has two tables
        held, spilled, fills = [], [], []
        for seconds in (5, 20):
            sim.run(until=seconds * 1_000_000_000)
            held.append(sim.trace.memory_rows())
            spilled.append(sim.trace.spilled_rows())
            fills.append((len(host.fills.kept), len(host.fills)))
    assert all(rows <= 2_000 * tables for rows in held)
    assert spilled[1] >= 4 * spilled[0] > 0  # 20 s of slots: about four times the rows of 5 s on disk
    assert fills[0][0] == fills[1][0] == 1_000 and fills[1][1] > fills[0][1] > 1_000


def test_merge_keeps_the_stream_order_at_one_instant() -> None:
    a = [(np.array([1, 3, 3]), np.array([10, 11, 12])), (np.array([3, 8]), np.array([13, 14]))]
    b = [(np.array([], dtype=np.int64), np.array([], dtype=np.int64)), (np.array([0, 3, 9]), np.array([20, 21, 22]))]
    merged = list(merge_sorted([a, b]))
    t = np.concatenate([m[0] for m in merged]).tolist()
    v = np.concatenate([m[1] for m in merged]).tolist()
    assert t == [0, 1, 3, 3, 3, 3, 8, 9] and v == [20, 10, 11, 12, 13, 21, 14, 22]
