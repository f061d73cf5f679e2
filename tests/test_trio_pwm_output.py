"""The Trio PWM output pin in the trace (``trio.axis3.pwm_out``): carrier AND gate AND WDOG as pulse segments.

TN20-81: a 20 MHz clock (50 ns); PWM_CYCLE=1000 is 20 kHz (a 50 us period = 1000 clocks); PWM_MARK is the
on-time in clocks (400 -> 20 us); the output is gated by the position FIFO and off while WDOG is off. Every
number below is written from the note (periods, marks in ns) or from the instant the test chose.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import vcdvcd
from trio_rigs import laser_axis

from cosim.controllers.trio import OFF, ON, TrioController
from cosim.controllers.trio.basic import example
from cosim.export import read_trace, write_trace
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
PIN = "trio.axis3.pwm_out"


def pulses(sim_or_trace: object, name: str = PIN) -> list[tuple[int, int]]:
    """(rise, fall) of every pulse of the pin, from the trace's segments and widths."""
    trace = getattr(sim_or_trace, "trace", sim_or_trace)
    t, width = trace.pulse_widths(name)  # type: ignore[attr-defined]
    return [(a, a + w) for a, w in zip(t.tolist(), width.tolist(), strict=True)]


def test_20_khz_carrier_is_one_segment_of_50_us_pulses_20_us_wide(sim: Simulation) -> None:
    """PWM_CYCLE=1000, PWM_MARK=400 for 1 ms: 20 pulses rising every 50_000 ns, each high 20_000 ns, one row."""
    laser_axis(sim)
    sim.run(until=1 * MS)
    seg = sim.trace.segments(PIN)
    assert {k: v.tolist() for k, v in seg.items()} == {
        "t0": [0], "duration": [1 * MS], "count": [20], "dir": [1], "width": [20_000]}
    assert pulses(sim) == [(k * 50_000, k * 50_000 + 20_000) for k in range(20)]
    assert sim.trace.info[PIN].varying_width and sim.trace.info[PIN].description


@pytest.mark.parametrize(("cycle", "mark", "period_ns", "high_ns"), [(1000, 250, 50_000, 12_500),
                                                                     (200, 150, 10_000, 7_500)])
def test_the_mark_is_the_pulse_width_on_the_50_ns_clock(sim: Simulation, cycle: int, mark: int, period_ns: int,
                                                        high_ns: int) -> None:
    laser_axis(sim, cycle=cycle, mark=mark)
    sim.run(until=100_000)
    rises = [a for a, _ in pulses(sim)]
    assert np.diff(rises).tolist() == [period_ns] * (len(rises) - 1)
    assert {b - a for a, b in pulses(sim)} == {high_ns}


def test_a_new_mark_changes_the_width_from_the_next_pulse_or_the_one_in_progress(sim: Simulation) -> None:
    """PWM_MARK 400 -> 600 at 1_010_000 ns (in the mark of the pulse that rose at 1 ms): that pulse goes on to
    1_030_000 (one pulse, not two); 600 -> 100 at 2_010_000 (past a 5 us mark): the pulse falls at that tick;
    then 5_000 ns pulses from 2_050_000.

    pin  |‾‾|__|‾‾‾|_|‾‾‾|_ ... |‾|___|‾|___
         1 ms     2 ms          ^ 2_010_000
    """
    _, p = laser_axis(sim)
    sim.call_at(1_010_000, Priority.HOST, lambda: p.set("PWM_MARK", 600))
    sim.call_at(2_010_000, Priority.HOST, lambda: p.set("PWM_MARK", 100))
    sim.run(until=2_200_000)
    got = pulses(sim)
    assert got[19:22] == [(950_000, 970_000), (1_000_000, 1_030_000), (1_050_000, 1_080_000)]
    assert got[39:43] == [(1_950_000, 1_980_000), (2_000_000, 2_010_000), (2_050_000, 2_055_000),
                          (2_100_000, 2_105_000)]
    assert sim.trace.segments(PIN)["count"].size <= 5  # a row per stretch and per cut pulse, not per pulse


def test_closing_the_gate_cuts_the_pulse_at_its_tick_and_opening_it_in_a_mark_starts_one(sim: Simulation) -> None:
    """PWM_CONTROL(0) at 1_010_017 ns closes the gate inside a mark: the pin falls at that tick. PWM_CONTROL(1)
    at 2_030_000 (in a space): nothing until the carrier's rise at 2_050_000; closed at 3 ms, opened again at
    4_007_000 (in a mark): a pulse from 4_007_000 to 4_020_000."""
    _, p = laser_axis(sim)
    sim.call_at(1_010_017, Priority.HOST, lambda: p.pwm_control(0))
    sim.call_at(2_030_000, Priority.HOST, lambda: p.pwm_control(1))
    sim.call_at(3 * MS, Priority.HOST, lambda: p.pwm_control(0))
    sim.call_at(4_007_000, Priority.HOST, lambda: p.pwm_control(1))
    sim.run(until=4_100_000)
    got = pulses(sim)
    assert got[19:21] == [(950_000, 970_000), (1_000_000, 1_010_017)]
    assert got[21] == (2_050_000, 2_070_000)
    assert got[-3:] == [(2_950_000, 2_970_000), (4_007_000, 4_020_000), (4_050_000, 4_070_000)]
    assert len(got) == 20 + 1 + 19 + 2  # 0..1 ms, the cut pulse, 2.05..2.95 ms, 4.007 and 4.05 ms


def test_wdog_off_holds_the_pin_low_and_on_again_resumes_in_the_mark(sim: Simulation) -> None:
    """WDOG=OFF at 300_017 ns cuts the pulse that rose at 300_000; nothing while it is off; WDOG=ON at
    507_000 (7 us into a mark) raises the pin there until 520_000."""
    _, p = laser_axis(sim)
    sim.call_at(300_017, Priority.HOST, lambda: p.set("WDOG", OFF))
    sim.call_at(507_000, Priority.HOST, lambda: p.set("WDOG", ON))
    sim.run(until=600_000)
    got = pulses(sim)
    assert got[5:] == [(250_000, 270_000), (300_000, 300_017), (507_000, 520_000), (550_000, 570_000)]


@pytest.mark.parametrize(("cycle", "mark"), [(1000, 1000), (1000, 5000)])
def test_a_mark_at_or_above_the_cycle_is_one_long_pulse(sim: Simulation, cycle: int, mark: int) -> None:
    _, p = laser_axis(sim, cycle=cycle, mark=mark)
    sim.call_at(700_000, Priority.HOST, lambda: p.set("WDOG", OFF))
    sim.run(until=1 * MS)
    assert pulses(sim) == [(0, 700_000)]


def test_mark_zero_records_nothing(sim: Simulation) -> None:
    laser_axis(sim, mark=0)
    sim.run(until=1 * MS)
    assert pulses(sim) == []


def test_a_pulse_high_when_the_run_stops_ends_there_and_the_vcd_shows_no_edge_where_the_run_resumed(
        sim: Simulation, tmp_path: Path) -> None:
    """The run stops at 110_000 ns (10 us into a mark): the pulse is recorded up to there, the rest from there on;
    the VCD shows one pulse 100_000 -> 120_000."""
    laser_axis(sim)
    sim.run(until=110_000)
    assert pulses(sim)[-1] == (100_000, 110_000)
    sim.run(until=200_000)
    assert pulses(sim)[2:] == [(100_000, 110_000), (110_000, 120_000), (150_000, 170_000)]
    write_trace(sim.trace, tmp_path, formats=("vcd",))
    tv = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))["trio.axis3.trio_axis3_pwm_out"].tv
    assert [(t, int(v)) for t, v in tv] == [(0, 1), (20_000, 0), (50_000, 1), (70_000, 0), (100_000, 1),
                                            (120_000, 0), (150_000, 1), (170_000, 0)]


def test_the_vcds_and_the_tables_carry_every_edge_at_its_exact_ns(sim: Simulation, tmp_path: Path) -> None:
    """20 kHz / 400 clocks, PWM_MARK 100 (5 us) from 200_000 ns, WDOG off at 310_017: in trace.vcd and
    trace_digital.vcd the pin rises every 50_000 ns and falls 20_000 (then 5_000) ns later, and at 310_017;
    the Parquet and CSV tables read back give the same segments, widths included."""
    _, p = laser_axis(sim)
    sim.call_at(200_000, Priority.HOST, lambda: p.set("PWM_MARK", 100))
    sim.call_at(310_017, Priority.HOST, lambda: p.set("WDOG", OFF))
    sim.run(until=400_000)
    expected = [(0, 1)]
    for k in range(4):
        expected += [(k * 50_000 + 20_000, 0), ((k + 1) * 50_000, 1)]
    expected += [(205_000, 0), (250_000, 1), (255_000, 0), (300_000, 1), (305_000, 0)]
    write_trace(sim.trace, tmp_path / "parquet", formats=("vcd", "parquet"))
    for vcd_file in ("trace.vcd", "trace_digital.vcd"):
        tv = vcdvcd.VCDVCD(str(tmp_path / "parquet" / vcd_file))["trio.axis3.trio_axis3_pwm_out"].tv
        assert [(t, int(v)) for t, v in tv] == expected, vcd_file
    write_trace(sim.trace, tmp_path / "csv", formats=("csv",))
    for fmt in ("parquet", "csv"):
        back = read_trace(tmp_path / fmt)
        assert back.info[PIN].varying_width
        assert pulses(back) == pulses(sim)
        for key, column in sim.trace.segments(PIN).items():
            assert back.segments(PIN)[key].tolist() == column.tolist(), (fmt, key)


def test_the_note_example_pin_is_cut_at_every_gate_edge_and_stays_segments() -> None:
    """tn20_81.bas, one forward pass: the pin is high only inside the gate windows; in each window it rises at
    the gate edge if that falls in a mark (else at the next 50 us carrier rise), pulses every 50_000 ns for
    20_000 ns, and its last pulse ends at the closing edge if that falls in a mark. A few rows, not a row per pulse."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    for name, value in (("SPEED", 1000), ("ACCEL", 100_000), ("DECEL", 100_000)):
        trio.set_param(name, value, axis=3)
    example("tn20_81").start(trio)
    sim.run(until=300 * MS)  # the forward pass: gate windows 110..115 and 195..220 units at 1000 units/s
    gate_t, gate_v = sim.trace.edges("trio.axis3.gate")
    edges = [int(t) for t, v in zip(gate_t.tolist(), gate_v.tolist(), strict=True) if t > 0]
    windows = list(zip(edges[0::2], edges[1::2], strict=False))
    assert len(windows) == 2 and [int(v) for v in gate_v[1:5]] == [1, 0, 1, 0]
    got = pulses(sim)
    for opened, closed in windows:
        inside = [(a, b) for a, b in got if opened <= a < closed]
        first = opened if opened % 50_000 < 20_000 else (opened // 50_000 + 1) * 50_000
        last_rise = (closed - 1) // 50_000 * 50_000
        assert inside[0][0] == first
        assert inside[-1] == (last_rise, min(last_rise + 20_000, closed))
        assert all(b - a == 20_000 for a, b in inside[1:-1]) and all(a % 50_000 == 0 for a, _ in inside[1:])
    assert len(got) == sum(len([1 for a, _ in got if o <= a < c]) for o, c in windows)  # nothing outside
    assert len(got) > 600 and sim.trace.segments(PIN)["count"].size <= 3 * len(windows)


@pytest.mark.fmu
def test_the_laser_power_of_the_note_example_is_sampled_at_each_gate_edge(tmp_path: Path) -> None:
    """trio_example (1 pass, Laser FMU sampled every 1 ms): the gate opens at 470_125_100 ns, 0.875 ms before the
    next 1 ms sample; the laser power has a sample at that tick (0 W: the laser was off) and at every other gate
    edge, so its rise is drawn from the gate edge, not from the next millisecond."""
    from cosim.runner import run_scenario
    from cosim.scenario import load

    result = run_scenario(load("trio_example"), overrides={"passes": "1"}, out=tmp_path / "run", formats=("parquet",))
    trace = read_trace(result.out if result.out is not None else tmp_path / "run")
    gate_t, gate_v = trace.edges("trio.axis3.gate")
    edges = gate_t[1:].tolist()
    assert len(edges) == 8 and edges[0] == 470_125_100 and gate_v[1] == 1
    t, power = trace.edges("laser.power")
    samples = dict(zip(t.tolist(), power.tolist(), strict=True))
    assert all(edge in samples for edge in edges)
    assert samples[470_125_100] == 0.0 and samples[471_000_000] > 0.0
    assert set(t.tolist()) - set(edges) <= {k * MS for k in range(t[-1] // MS + 1)}  # otherwise the 1 ms grid
