"""Traces: exact edge lists, pulse segments, exports that other tools read back."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import vcdvcd

from cosim.errors import ConfigurationError
from cosim.export import read_trace, write_trace
from cosim.kernel import Simulation
from cosim.signals import PulseTrain, Signal
from cosim.timebase import TimeBase
from cosim.trace import Trace


def _scenario(sim: Simulation) -> None:
    """A gate, a register, a real value and a step train.

    t [ns]:   0     1000   1500    2000       3000
    gate      0_____1‾‾‾‾‾‾‾‾‾‾‾‾‾‾0__________
    count     0     7              9
    step            | | |          (3 pulses in [1000, 2000), dir 1)  | | (2 in [2000, 3000), dir 0)
    """
    gate = Signal(sim, "dev.axis1.gate")
    count = Signal(sim, "dev.axis1.count", kind="int")
    power = Signal(sim, "dev.power", kind="real", unit="W")
    step = PulseTrain(sim, "dev.axis1.step", pulse_width=100)

    def run() -> object:
        yield sim.at(1000)
        gate.set(1)
        count.set(7)
        power.set(12.5)
        step.emit(1000, 1000, 3, 1)
        yield sim.at(2000)
        gate.set(0)
        count.set(9)
        step.emit(2000, 1000, 2, 0)

    sim.process(run())  # type: ignore[arg-type]
    sim.run(until=3000)


def test_edges_and_pulses_are_exact(sim: Simulation) -> None:
    _scenario(sim)
    t, v = sim.trace.edges("dev.axis1.gate")
    assert t.tolist() == [0, 1000, 2000] and v.tolist() == [0, 1, 0]
    pt, pd_ = sim.trace.pulses("dev.axis1.step")
    assert pt.tolist() == [1000, 1333, 1666, 2000, 2500]
    assert pd_.tolist() == [1, 1, 1, 0, 0]
    assert sim.trace.value_at("dev.axis1.count", 1999) == 7


def test_values_and_positions_at_instants_follow_the_diagram(sim: Simulation) -> None:
    _scenario(sim)
    ticks = [0, 999, 1000, 1333, 1999, 2000, 2499, 2500, 2999]
    assert sim.trace.values_at("dev.axis1.count", ticks).tolist() == [0, 0, 7, 7, 7, 9, 9, 9, 9]
    # up 1000, 1333, 1666; down 2000, 2500: a pulse counts from its own instant on
    assert sim.trace.positions_at("dev.axis1.step", ticks).tolist() == [0, 0, 1, 2, 3, 2, 2, 1, 1]
    assert np.isnan(sim.trace.values_at("dev.power", [-1])[0])  # before its first record


def test_pulses_per_window_counts_each_window_whatever_the_direction(sim: Simulation) -> None:
    _scenario(sim)
    starts, counts = sim.trace.pulses_per_window("dev.axis1.step", 500)
    assert starts.tolist() == [0, 500, 1000, 1500, 2000, 2500]  # to the trace's end at 3000
    assert counts.tolist() == [0, 0, 2, 1, 1, 1]
    starts, counts = sim.trace.pulses_per_window("dev.axis1.step", 1000, start=1000, end=2000)
    assert starts.tolist() == [1000] and counts.tolist() == [3]
    starts, counts = sim.trace.pulses_per_window("dev.axis1.step", 1000, start=1000, end=2300)
    assert starts.tolist() == [1000, 2000] and counts.tolist() == [3, 1]  # the last window ends at 2300: not 2500
    with pytest.raises(ConfigurationError, match="window"):
        sim.trace.pulses_per_window("dev.axis1.step", 0)


def test_materialised_pulses_are_kept_read_only_until_the_train_grows(sim: Simulation) -> None:
    step = PulseTrain(sim, "dev.x.step")
    step.emit(0, 1000, 2, 1)
    t, _ = sim.trace.pulses("dev.x.step")
    assert sim.trace.pulses("dev.x.step")[0] is t  # kept
    with pytest.raises(ValueError, match="read-only"):
        t[0] = 5
    step.emit(1000, 1000, 1, 0)
    assert sim.trace.pulses("dev.x.step")[0].tolist() == [0, 500, 1000]  # a new segment: materialised again
    step.pulse(3000, 1)
    assert sim.trace.pulses("dev.x.step")[0].tolist() == [0, 500, 1000, 3000]  # a single pulse too
    kept = sim.trace.pulses("dev.x.step")[0]
    sim.trace.drop_pulse_cache()
    assert sim.trace.pulses("dev.x.step")[0] is not kept


def test_setting_the_same_value_records_nothing(sim: Simulation) -> None:
    gate = Signal(sim, "dev.gate")
    assert not gate.set(0)
    assert gate.set(1)
    assert sim.trace.edges("dev.gate")[0].tolist() == [0, 0]


def test_bad_names_and_unknown_signals(sim: Simulation) -> None:
    with pytest.raises(ConfigurationError, match="scheme"):
        Signal(sim, "Dev Gate")
    Signal(sim, "dev.axis1.gate")
    with pytest.raises(KeyError, match=r"did you mean dev\.axis1\.gate"):
        sim.trace.edges("dev.axis1.gat")


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_tables_round_trip(sim: Simulation, tmp_path: Path, fmt: str) -> None:
    _scenario(sim)
    write_trace(sim.trace, tmp_path, formats=(fmt,))
    back = read_trace(tmp_path)
    for name in sim.trace.names():
        if sim.trace.info[name].kind == "pulse":
            for a, b in zip(back.pulses(name), sim.trace.pulses(name), strict=True):
                np.testing.assert_array_equal(a, b)
        else:
            for a, b in zip(back.edges(name), sim.trace.edges(name), strict=True):
                np.testing.assert_array_equal(a, b)
    assert back.info == sim.trace.info and back.end_t == 3000


def test_vcd_reads_back_with_an_independent_parser(sim: Simulation, tmp_path: Path) -> None:
    _scenario(sim)
    write_trace(sim.trace, tmp_path, formats=("vcd",))
    vcd = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    assert vcd.timescale["unit"] == "ns" and vcd.timescale["magnitude"] == 1
    # scopes from the dotted path, the signal named by its whole path
    gate = vcd["dev.axis1.dev_axis1_gate"]
    assert [(t, v) for t, v in gate.tv] == [(0, "0"), (1000, "1"), (2000, "0")]
    count = vcd["dev.axis1.dev_axis1_count"]
    assert [(t, int(v, 2)) for t, v in count.tv] == [(0, 0), (1000, 7), (2000, 9)]
    step = vcd["dev.axis1.dev_axis1_step"]
    rises = [t for t, v in step.tv if v == "1"]
    falls = [t for t, v in step.tv if v == "0" and t > 0]
    assert rises == [1000, 1333, 1666, 2000, 2500]
    assert falls == [1100, 1433, 1766, 2100, 2600]
    assert float(vcd["dev.dev_power"].tv[-1][1]) == 12.5
    assert vcd.endtime == 3000  # the run's end, not the last change (2600)


def test_same_scenario_twice_gives_bit_identical_exports(tmp_path: Path) -> None:
    digests = []
    for run in range(2):
        with Simulation(seed=3) as sim:
            _scenario(sim)
            out = write_trace(sim.trace, tmp_path / str(run), formats=("vcd", "csv"))
        digests.append({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    assert digests[0] == digests[1]


def test_a_train_with_a_varying_width_keeps_each_segments_width_through_spills(tmp_path: Path) -> None:
    """A PWM-like train: 3 pulses 400 wide every 1000 ticks, then one cut to 17, then 2 pulses 250 wide; kept
    two rows at a time in memory, read whole, in chunks of 2 pulses and back from Parquet."""
    from cosim.trace import Trace

    trace = Trace(spill_rows=2, chunk_pulses=2, spool=tmp_path / "spool")
    trace.declare("dev.axis1.pwm", "pulse", varying_width=True)
    for row in ((0, 3000, 3, 1, 400), (3000, 17, 1, 1, 17), (5000, 2000, 2, 1, 250)):
        trace.record_segment("dev.axis1.pwm", *row[:4], width=row[4])
    trace.end_t = 8000
    expected = ([0, 1000, 2000, 3000, 5000, 6000], [400, 400, 400, 17, 250, 250])
    t, width = trace.pulse_widths("dev.axis1.pwm")
    assert (t.tolist(), width.tolist()) == expected
    chunks = list(trace.pulse_width_chunks("dev.axis1.pwm"))
    assert max(c[0].size for c in chunks) <= 2 and trace.spilled_rows() == 2
    assert trace.segments("dev.axis1.pwm")["width"].tolist() == [400, 17, 250]
    write_trace(trace, tmp_path / "out", formats=("parquet",))
    back = read_trace(tmp_path / "out")
    assert back.info["dev.axis1.pwm"].varying_width
    assert tuple(a.tolist() for a in back.pulse_widths("dev.axis1.pwm")) == expected


def test_widths_are_required_where_they_vary_and_refused_elsewhere(sim: Simulation) -> None:
    _scenario(sim)
    assert sim.trace.segments("dev.axis1.step")["width"].tolist() == [100, 100]  # the declared pulse_width
    assert sim.trace.pulse_widths("dev.axis1.step")[1].tolist() == [100] * 5
    with pytest.raises(ConfigurationError, match="takes no width"):
        sim.trace.record_segment("dev.axis1.step", 4000, 100, 1, 1, width=30)
    sim.trace.declare("dev.axis1.pwm", "pulse", varying_width=True)
    with pytest.raises(ConfigurationError, match="takes a width"):
        sim.trace.record_segment("dev.axis1.pwm", 4000, 100, 1, 1)
    with pytest.raises(ConfigurationError, match="need a width"):
        sim.trace.extend_segments("dev.axis1.pwm", [0], [10], [1], [1])
    with pytest.raises(ConfigurationError, match="only a pulse train has a varying width"):
        sim.trace.declare("dev.axis1.level", "bit", varying_width=True)


def _long_train(chunk_pulses: int) -> Trace:
    """A train of 5 segments x 7 pulses (35 pulses), read in chunks of ``chunk_pulses``."""
    trace = Trace(TimeBase(), chunk_pulses=chunk_pulses)
    trace.declare("dev.step", "pulse")
    for k in range(5):
        trace.record_segment("dev.step", 1000 * k, 1000, 7, k % 2)
    return trace


def test_a_train_in_memory_is_materialised_once_for_several_readers(monkeypatch: pytest.MonkeyPatch) -> None:
    import cosim.trace
    import cosim.tracestore

    calls: list[int] = []
    original = cosim.tracestore.materialize_pulses

    def counting(*args: Any, **kwargs: Any) -> np.ndarray:
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(cosim.tracestore, "materialize_pulses", counting)
    monkeypatch.setattr(cosim.trace, "materialize_pulses", counting)
    trace = _long_train(chunk_pulses=10)
    first = [(t.tolist(), d.tolist()) for t, d in trace.pulse_chunks("dev.step")]
    made = len(calls)
    second = [(t.tolist(), d.tolist()) for t, d in trace.pulse_chunks("dev.step")]
    assert first == second and [len(t) for t, _ in first] == [10, 10, 10, 5]
    assert first[0][0][:8] == [0, 142, 285, 428, 571, 714, 857, 1000] and first[0][1][:8] == [0] * 7 + [1]
    assert made > 0 and len(calls) == made  # the second reader got the kept arrays


def test_trains_read_longest_ago_are_forgotten_beyond_the_kept_pulses(monkeypatch: pytest.MonkeyPatch) -> None:
    import cosim.trace

    monkeypatch.setattr(cosim.trace, "KEPT_PULSES", 40)
    trace = _long_train(chunk_pulses=10)
    trace.declare("dev.other", "pulse")
    trace.record_segment("dev.other", 0, 1000, 20, 1)
    trace.pulses("dev.step")
    trace.pulses("dev.other")  # 35 + 20 > 40: dev.step is forgotten
    assert list(trace._pulse_cache) == ["dev.other"]
    trace.pulses("dev.step")
    assert list(trace._pulse_cache) == ["dev.step"]
