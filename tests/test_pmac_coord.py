"""Coordinate system: Ix93 source, Ix94 slew limit and slip, moves advancing by the time base."""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

import pytest
from cycle_probe import record_each_cycle

from cosim import rigs
from cosim.controllers.pmac.ect import pmac_default_table
from cosim.controllers.pmac.machine import Pmac
from cosim.controllers.pmac.motion import Delay, Dwell, LinearMove, compile_items
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor
from cosim.timebase import Priority

MOVE = LinearMove(100_000, 64_000, 10)  # 64 units/ms with TA 10 ms: longer than every run below


def _profile(elapsed_units: int) -> Fraction:
    (segment,) = compile_items([MOVE], {"X": Fraction(0)})
    return segment.position(Fraction(elapsed_units, 2**23))


def test_ix94_at_max_with_smoothly_varying_master_gives_no_slip(sim: Simulation) -> None:
    """Master 32 -> 96 -> 40 counts/ms; Ix94 = 8,388,607: the slave command is the move profile
    evaluated at the master-derived time, exactly, every servo cycle.

        master speed   __/‾‾‾‾\\___
        Ix94 active    ___________   (never)
        slip           0 0 0 0 0 0
    """
    belt = IdealConveyor(sim, speed_counts_per_ms=32,
                            phases=[(20_000_000, Fraction(16, 5)), (20_000_000, Fraction(-14, 5))])
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, ix94=8_388_607)  # Ix94 at its maximum
    clock = rig.pmac.clock
    rig.cs.run_program([MOVE])
    rows = record_each_cycle(sim, clock, lambda k, t: (rig.motor.cmd, rig.pmac.table.entry_at(0x3501).position,  # type: ignore[union-attr]
                                                       belt.position(t)), cycles=150)
    rig.pmac.start()
    sim.run(until=clock.t(150))
    start32 = rows[0][1]
    for cmd, pos32, true_pos in rows[1:]:
        master_elapsed = 2 * 2048 * (pos32 - start32)  # 2^-23 ms: the master-derived time
        assert cmd == _profile(master_elapsed)
        assert abs(Fraction(pos32, 32) - true_pos) < Fraction(1, 16)  # 1/T tracks the true master
    assert rig.cs.limit_events == [] and rig.cs.slip_counts == 0
    assert rig.cs.ideal_position("X") == rig.cs.position("X")
    _t, v = sim.trace.edges("pmac.cs1.ix94_active")
    assert v.tolist() == [0]


def test_ix94_low_during_fast_master_acceleration_reports_slip(sim: Simulation) -> None:
    """Master 0 -> 64 counts/ms in 5 ms; Ix94 = 16384: the time base needs about I10/Ix94 = 227 cycles.

        source    _/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
        actual    _______/‾‾‾‾‾‾‾‾‾‾     slope Ix94 per cycle
        Ix94 act  __|‾‾‾‾|__________     cycles 2..219 (cycle 1 initialises actual = source)
        slip      0 ↗ 3.1k counts, then constant
    """
    belt = IdealConveyor(sim, phases=[(5_000_000, Fraction(64, 5))])
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, ix94=16_384)
    clock = rig.pmac.clock
    rig.cs.run_program([MOVE])
    rows = record_each_cycle(sim, clock, lambda k, t: (rig.cs.source_value, rig.cs.actual,
                                                       rig.pmac.table.entry_at(0x3501).position),  # type: ignore[union-attr]
                             cycles=400)
    rig.pmac.start()
    sim.run(until=clock.t(400))
    cs = rig.cs
    # the manual's rule, applied here to the recorded source values: the actual value moves toward the
    # source by at most Ix94 = 16384 per cycle; whatever it falls short is master travel lost (slip),
    # at 2 * SF = 4096 units per 1/32 count, i.e. 64 * 2048 per count
    actual, lost, limited = rows[1][0], 0, []
    for k, (source, recorded, _pos) in enumerate(rows[2:], 2):
        step = max(-16_384, min(16_384, source - actual))
        actual += step
        assert recorded == actual, k
        if source - actual:
            lost += source - actual
            limited.append(k)
    assert cs.slip_counts == Fraction(lost, 64 * 2048)
    assert cs.limit_cycles == limited == list(range(2, limited[-1] + 1))  # one stretch from cycle 2
    assert 210 <= limited[-1] <= 228  # about (I10 - first source value) / Ix94
    # accounting from independent registers: master travel (1/T entry) minus elapsed program time
    master_counts = Fraction(rows[-1][2] - rows[1][2], 32)
    program_counts = Fraction(sum(actual for _source, actual, _pos in rows[2:]), 64 * 2048)
    assert cs.slip_counts == master_counts - program_counts
    # rough physics: the area between a ramp of I10 / Ix94 cycles and the master's ~11-cycle ramp
    slip = cs.slip_counts
    assert slip is not None
    estimate = Fraction(3_713_707, 2) * (Fraction(3_713_707, 16_384) - 11) / (64 * 2048)
    assert abs(slip / estimate - 1) < Fraction(10, 100)
    assert cs.ideal_position("X") - cs.position("X") == pytest.approx(float(slip), abs=0.1)  # 1 count/count
    t, v = sim.trace.edges("pmac.cs1.ix94_active")
    assert t.tolist() == [0, clock.t(2), clock.t(limited[-1] + 1)]
    assert v.tolist() == [0, 1, 0]
    _ts, vs = sim.trace.edges("pmac.cs1.slip")
    assert vs[-1] == int(slip) == 2842  # counts (scenario pmac_ix94_slip: 2842.125)
    assert any("synchronization to the master is lost" in note for _, note in cs.notes)


def test_host_percent_slews_at_ix94_per_cycle(sim: Simulation) -> None:
    """%0 then %100 with the default Ix94 = 1644: +1644 per cycle, 100 % after 2259 cycles
    (about 1000 ms), no slip because the source is the % register, not an external time base.

        %cmd    0 |‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
        actual  0 |  /‾‾‾‾‾‾‾‾‾‾‾‾   1644 per cycle
    """
    pmac = Pmac(sim)
    cs = pmac.coordinate_system(1)
    assert cs.ix94 == 1644  # PSRM p.124: Ix94 default 1644
    pmac.command_percent(1, 0)
    rows = record_each_cycle(sim, pmac.clock, lambda k, t: cs.actual, cycles=2300)

    def host() -> Generator[Any, Any, None]:
        yield sim.at(pmac.clock.t(10) + 1, Priority.HOST)
        assert pmac.command_percent(1, 100) == 3_713_707

    sim.process(host())
    pmac.start()
    sim.run(until=pmac.clock.t(2300))
    assert rows[:11] == [0] * 11
    assert rows[11:14] == [1644, 3288, 4932]
    n = 2259  # ceil(3,713,707 / 1644) cycles
    assert rows[10 + n - 1] < 3_713_707 == rows[10 + n]
    assert cs.slip_counts is None and len(cs.limit_events) == n - 1
    assert cs.percent == 100


def test_percent_register_is_ignored_under_external_time_base(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=48)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, i10=2**21)
    rig.pmac.command_percent(1, 10)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(5) + 1)
    assert rig.cs.percent == 75  # follows the master at 3/4 of the real-time input frequency
    assert rig.cs.percent_register.value == 2**21 // 10


#: Non-finite and absurdly large numbers through the Python API (issue 22): our error, never a crash.
FINITE = r"\(allowed: a finite number\)"
NON_FINITE = [
    ("%n nan", lambda pmac: pmac.command_percent(1, float("nan")),
     rf"^%n \(feedrate override\) = nan is not allowed {FINITE}$"),
    ("%n inf", lambda pmac: pmac.command_percent(1, float("inf")),
     rf"^%n \(feedrate override\) = inf is not allowed {FINITE}$"),
    ("I10 inf", lambda pmac: pmac.set_ivar(10, float("inf")),
     r"^I10 \(servo interrupt time\) = inf is not allowed \(allowed: integers 1..8388607 \(2\^-23 ms\)\)$"),
    ("I10 1e5000", lambda pmac: pmac.set_ivar(10, 10**5000),
     r"^I10 \(servo interrupt time\) = 1e\+5000 is not allowed \(allowed: integers 1..8388607"),
    ("LINEAR nan", lambda pmac: LinearMove(float("nan"), 10), rf"^target = nan is not allowed {FINITE}$"),
    ("F inf", lambda pmac: LinearMove(10, float("inf")), rf"^F \(feedrate\) = inf is not allowed {FINITE}$"),
    ("DWELL nan", lambda pmac: Dwell(float("nan")), rf"^DWELL time = nan is not allowed {FINITE}$"),
    ("jog nan", lambda pmac: pmac.coordinate_system(1).jog(10, speed_per_ms=float("nan")),
     rf"^jog speed_per_ms \(Ixx22\) = nan is not allowed {FINITE}$"),
]


@pytest.mark.parametrize(("case", "call", "message"), NON_FINITE, ids=[c[0] for c in NON_FINITE])
def test_non_finite_and_huge_values_are_refused(sim: Simulation, case: str, call: Any, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        call(Pmac(sim))


def test_percent_saturates_at_largest_implementable_value(sim: Simulation) -> None:
    pmac = Pmac(sim)
    assert pmac.command_percent(1, 500) == 2**23 - 1
    assert pmac.coordinate_system(1).percent_register.max_percent() == pytest.approx(225.88, abs=0.01)
    with pytest.raises(ConfigurationError, match=r"%n \(feedrate override\) = -5"):
        pmac.command_percent(1, -5)


def test_linear_move_profile_trapezoid_and_short_move() -> None:
    """LINEAR X1000 F100 (0.1 units/ms) TA100: accel 100 ms, plateau, decel 100 ms, total 10.1 s;
    X10: shorter than TA at that speed, so move time = TA and the plateau speed drops."""
    (seg,) = compile_items([LinearMove(1000, 100, 100)], {"X": Fraction(0)})
    assert seg.duration_units == Fraction(10_100) * 2**23
    assert seg.position(Fraction(100)) == 5  # v * TA / 2
    assert seg.position(Fraction(5050)) == 500
    assert seg.position(Fraction(10_000)) == 1000 - 5
    assert seg.position(Fraction(20_000)) == 1000
    (short,) = compile_items([LinearMove(-10, 1000, 100)], {"X": Fraction(0)})
    assert short.move_ms == 100 and short.speed == Fraction(1, 10)
    assert short.position(Fraction(100)) == -5 and short.position(Fraction(200)) == -10


def test_delay_runs_with_time_base_but_dwell_in_real_time(sim: Simulation) -> None:
    """At %50: DELAY 10 ms takes 20 ms of real time, DWELL 10 ms takes 10 ms (ceil to cycles)."""
    pmac = Pmac(sim, i10=2**21)  # 250 us cycles
    cs = pmac.coordinate_system(1)
    pmac.command_percent(1, 50)
    cs.run_program([Delay(10), LinearMove(1, 1000, 0), Dwell(10), LinearMove(2, 1000, 0)])
    rows = record_each_cycle(sim, pmac.clock, lambda k, t: cs.position("X"), cycles=140)
    pmac.start()
    sim.run(until=pmac.clock.t(140))
    first_move = next(k for k, x in enumerate(rows) if x > 0)
    assert first_move == 81  # cycle 1 starts; 80 cycles of 125 us program time = 10 ms
    reached_1 = rows.index(Fraction(1))
    second_move = next(k for k, x in enumerate(rows) if x > 1)
    assert second_move - reached_1 == 40 + 1  # 40 real-time cycles of 250 us, then the move starts


def test_time_base_overrun_carries_into_the_next_segment(sim: Simulation) -> None:
    """DELAY 0.1 ms then a move at 1 unit/ms, 0.25 ms per cycle at 100 %: the move already gets
    the 0.15 ms left over in the cycle the delay ends (exact program time, no lost fractions).

        cycle       1      2      3
        program     0.25   0.50   0.75 ms
        X           0.15   0.40   0.65
    """
    pmac = Pmac(sim, i10=2**21)
    cs = pmac.coordinate_system(1)
    cs.run_program([Delay(Fraction(1, 10)), LinearMove(10, 1000, 0)])
    rows = record_each_cycle(sim, pmac.clock, lambda k, t: cs.position("X"), cycles=4)
    pmac.start()
    sim.run(until=pmac.clock.t(4))
    assert rows == [0, Fraction(3, 20), Fraction(2, 5), Fraction(13, 20)]


def test_dwell_under_external_time_base_is_reported(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048)
    rig.cs.run_program([Dwell(1), MOVE])
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(10))
    assert any("DWELL under external time base" in note for _, note in rig.cs.notes)


def test_jog_runs_under_the_time_base(sim: Simulation) -> None:
    pmac = Pmac(sim, i10=2**21)
    cs = pmac.coordinate_system(1)
    pmac.command_percent(1, 25)
    cs.jog(10, speed_per_ms=1, ta_ms=0)  # 10 ms at 100 %: 40 ms at 25 %
    pmac.start()
    sim.run(until=pmac.clock.t(80) + 1)
    assert cs.position("X") == 5  # cycles 1..80, 62.5 us of program time each, at 1 unit/ms
    sim.run(until=pmac.clock.t(200))
    assert cs.position("X") == 10 and cs.program_done


@pytest.mark.parametrize("ix94", [-1, 8_388_608, 1.5])
def test_bad_ix94(sim: Simulation, ix94: object) -> None:
    pmac = Pmac(sim)
    with pytest.raises(ConfigurationError, match=r"I194 \(Ix94.*\) = .* is not allowed \(allowed: integers 0..8388607"):
        pmac.set_ivar(194, ix94)  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match=r"I194 \(Ix94\) = .* is not allowed \(allowed: integers 0..8388607"):
        pmac.coordinate_system(1).set_ix94(ix94)


def test_ix93_1833_selects_the_default_pmac_table_time_base(sim: Simulation) -> None:
    """The manual's example: default (non-Turbo) table, time-base result at $0729, I193=1833."""
    belt = IdealConveyor(sim, speed_counts_per_ms=48)
    pmac = Pmac(sim, i10=2**21, table=pmac_default_table(0xC000, 2048))
    pmac.add_channel(0xC000, belt)
    pmac.set_ivar(193, 1833)
    pmac.set_ivar(194, 8_388_607)  # the largest Ix94 (PSRM p.124: range 0..8,388,607)
    cs = pmac.coordinate_system(1)
    assert cs.external and cs.describe_source() == "$0729 (external time base)"
    pmac.start()
    sim.run(until=pmac.clock.t(3) + 1)
    assert cs.percent == 75


def test_ix93_pointing_at_nothing(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048)
    with pytest.raises(ConfigurationError, match=r"I193 \(Ix93 of CS1\) = \$0729 \(1833\) is not allowed \(allowed: "
                                                 r"addresses of time-base registers: \$2000 \(CS1 % register\), "
                                                 r"\$3503 \(TimeBaseEntry result\)\)"):
        rig.pmac.set_ivar(193, 1833)
    with pytest.raises(ConfigurationError, match=r"I5193 \(Ix93 of CS1\) = \$3502"):
        rig.pmac.set_ivar(5193, 0x3502)  # the entry's first line is not a time-base value
    rig.pmac.set_ivar(193, 0x2000)  # back to the % register: fine
    assert not rig.cs.external
