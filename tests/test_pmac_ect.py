"""Encoder conversion table: time-base values in register units, exactly as the formula says.

% = 100 * SCALE_FACTOR * f[counts/ms] / 2^17, i.e. a time-base value of % * I10 / 100 per
servo cycle (untriggered entry: 2 * SF * delta in 1/32 count = 64 * SF per count).
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from cycle_probe import record_each_cycle

from cosim import rigs
from cosim.controllers.pmac.ect import (
    ARMED,
    FROZEN,
    RUNNING,
    ConversionTable,
    OneOverTEntry,
    TimeBaseEntry,
    TriggeredTimeBaseEntry,
    pmac_default_table,
)
from cosim.controllers.pmac.encoder import EncoderChannel
from cosim.controllers.pmac.units import I10_DEFAULT, ServoClock, formula_percent
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor

I10_250US = 2**21  # 250 us = 15625 ns * 16: whole counts per cycle at the speeds below


@pytest.mark.parametrize(
    ("freq_counts_per_ms", "scale_factor", "expected_pct"),
    [
        (64, 2048, 100),  # the manual's example: RTIF 64 counts/ms -> SF 2048
        (48, 2048, 75),  # 3/4 of the real-time input frequency
        (128, 2048, 200),
        (32, 4096, 100),
        (256, 512, 100),
        (100, 1024, Fraction(625, 8)),  # 78.125 %
        (16, 2048, 25),
    ],
)
def test_time_base_value_equals_formula_in_register_units(
        sim: Simulation, freq_counts_per_ms: int, scale_factor: int, expected_pct: Fraction) -> None:
    """Every cycle after the first, the entry's result is exactly % * I10 / 100.

        servo k     0      1      2      3   ...
        result      0     tb     tb     tb        tb = 2 * SF * 32 * f * 0.25 ms
    """
    assert formula_percent(scale_factor, freq_counts_per_ms) == expected_pct
    belt = IdealConveyor(sim, speed_counts_per_ms=freq_counts_per_ms)
    rig = rigs.external_time_base(sim, belt, scale_factor=scale_factor, i10=I10_250US)
    values = record_each_cycle(sim, rig.pmac.clock, lambda k, t: rig.entry.result, cycles=20)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(20))
    register = Fraction(expected_pct) * I10_250US / 100
    assert register.denominator == 1
    assert values == [0] + [int(register)] * 19
    assert rig.cs.percent == expected_pct


def test_default_i10_time_base_averages_exactly_and_jitters_by_one_lsb(sim: Simulation) -> None:
    """With I10 = 3,713,707 a cycle holds 28.33 counts: each value is within 2*SF (one 1/32 count)
    of the formula, and their sum is exactly 2 * SF * (1/T travel in 1/32 count)."""
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048)
    clock = rig.pmac.clock
    rows = record_each_cycle(sim, clock, lambda k, t: (rig.entry.result, rig.entry.position), cycles=200)
    rig.pmac.start()
    sim.run(until=clock.t(200))
    ideal = formula_percent(2048, 64) * I10_DEFAULT / 100
    assert ideal == I10_DEFAULT
    assert all(abs(value - ideal) < 2 * 2048 for value, _ in rows[1:])
    assert {value for value, _ in rows[1:]} == {3_710_976, 3_715_072}  # 906 or 907 /32 counts, times 4096
    assert sum(v for v, _ in rows) == 2 * 2048 * (rows[-1][1] - rows[0][1])
    exact_travel = belt.position(clock.t(199)) - belt.position(0)
    assert abs(Fraction(rows[-1][1] - rows[0][1], 32) - exact_travel) < Fraction(1, 32)


def test_triggered_entry_running_gives_the_same_percent_with_one_eighth_sf(sim: Simulation) -> None:
    """Turbo triggered entry: 1/256 count, SF = 16384 / RTIF: 256 counts/ms with SF 64 is 100 %."""
    belt = IdealConveyor(sim, speed_counts_per_ms=256)
    rig = rigs.triggered_time_base(sim, belt, belt.mark, scale_factor=64, method=RUNNING, i10=I10_250US)
    values = record_each_cycle(sim, rig.pmac.clock, lambda k, t: rig.entry.result, cycles=10)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(10))
    assert values == [0] + [I10_250US] * 9
    assert formula_percent(64, 256, triggered=True) == 100


def test_result_saturates_at_24_bits(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=1024)
    rig = rigs.external_time_base(sim, belt, scale_factor=8192, i10=I10_250US)  # 4096 %: too big
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(3) + 1)
    assert rig.entry.result == 2**23 - 1
    assert rig.entry.saturated_cycles == [1, 2, 3]


def test_table_runs_top_to_bottom_so_a_later_source_is_one_cycle_old(sim: Simulation) -> None:
    """A time-base entry above its 1/T source differentiates last cycle's positions."""
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    channels = {0x078000: EncoderChannel(sim, 0x078000, belt)}
    table = ConversionTable()
    early = table.add(TimeBaseEntry(0x3503, 2048), at=0x3501)  # reads $3503, which runs after it
    table.add(OneOverTEntry(0x078000), at=0x3503)
    late = table.add(TimeBaseEntry(0x3503, 2048), at=0x3504)
    table.bind(channels)
    clock = ServoClock(I10_250US)
    results = []
    for k in range(4):
        table.run(clock.t(k), k)
        results.append((table.x_word(early.result_address), table.x_word(late.result_address)))
    tb = 2 * 2048 * 16 * 32
    assert results == [(0, 0), (0, tb), (tb, tb), (tb, tb)]


def test_pmac_default_table_result_is_at_0729(sim: Simulation) -> None:
    table = pmac_default_table(0xC000, 2048)
    assert [e.address for e in table.entries] == [0x0720, 0x0728]
    assert table.time_base_entries()[0].result_address == 0x0729 == 1833


def test_triggered_states_frozen_and_armed_output_zero(sim: Simulation) -> None:
    """Frozen ($9) and armed ($B): result 0, master position still tracked in 1/256 count."""
    belt = IdealConveyor(sim, speed_counts_per_ms=256)
    rig = rigs.triggered_time_base(sim, belt, belt.mark, scale_factor=64, method=FROZEN, i10=I10_250US)
    rows = record_each_cycle(sim, rig.pmac.clock, lambda k, t: (rig.entry.result, rig.entry.position), cycles=6)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(3) + 1)
    rig.entry.set_method(ARMED)
    sim.run(until=rig.pmac.clock.t(6))
    assert rows == [(0, 256 * 64 * k) for k in range(6)]
    assert rig.entry.state == "armed" and rig.entry.starts == []


@pytest.mark.parametrize("scale_factor", [Fraction(131072, 60), 2184.53, 0, -3, 2**23, True])
def test_bad_scale_factor_names_value_and_range(scale_factor: object) -> None:
    with pytest.raises(ConfigurationError, match=r"SCALE_FACTOR = .* is not allowed \(allowed: integers 1..8388607\)"):
        TimeBaseEntry(0x3501, scale_factor)  # type: ignore[arg-type]
    with pytest.raises(ConfigurationError, match=r"SCALE_FACTOR = .* \(allowed: integers 1..8388607\)"):
        TriggeredTimeBaseEntry(0x078008, scale_factor)  # type: ignore[arg-type]


def test_non_integer_scale_factor_is_shown_as_written() -> None:
    with pytest.raises(ConfigurationError, match=r"SCALE_FACTOR = 2184.53 is not allowed"):
        TimeBaseEntry(0x3501, 2184.53)  # type: ignore[arg-type]


@pytest.mark.parametrize("method", [0x0, 0x4, 0x8, 0xC, 0xF])
def test_triggered_method_digit_other_than_9_a_b(method: int) -> None:
    with pytest.raises(ConfigurationError, match=r"method digit .* = \$[0-9A-F] is not allowed "
                                                 r"\(allowed: \$9 \(frozen\), \$A \(running\), \$B \(armed\)\)"):
        TriggeredTimeBaseEntry(0x078008, 64, method=method)
    entry = TriggeredTimeBaseEntry(0x078008, 64, origin="I8010")
    with pytest.raises(ConfigurationError, match=rf"I8010 \(method digit \${method:X}\) = \${method:X}78008"):
        entry.write_first_line((method << 20) | 0x78008)
    assert entry.method == FROZEN


def test_sources_pointing_at_nothing(sim: Simulation) -> None:
    table = ConversionTable()
    table.add(TimeBaseEntry(0x3510, 2048))
    with pytest.raises(ConfigurationError, match=r"source address of the TimeBaseEntry at \$3501 = \$3510 \(13584\)"
                                                 r" is not allowed \(allowed: position registers of the table: none\)"):
        table.bind({})
    table = ConversionTable()
    table.add(OneOverTEntry(0x078000))
    with pytest.raises(ConfigurationError, match=r"channel address .* = \$78000 .* encoder channels: none added"):
        table.bind({})
    with pytest.raises(ConfigurationError, match=r"\$3501 is taken by the OneOverTEntry"):
        table.add(OneOverTEntry(0x078000), at=0x3501)


def test_24_bit_position_wrap_does_not_disturb_the_time_base(sim: Simulation) -> None:
    """The 1/32-count register wraps every 2^19 counts; the 24-bit difference hides the wrap.

        position   524,188 ... 524,288 (= 2^19, register back to 0) ... 524,388
        result     tb tb tb tb tb tb tb                                      (unchanged)
    """
    belt = IdealConveyor(sim, speed_counts_per_ms=64, position_counts=2**19 - 100)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, i10=I10_250US)
    rows = record_each_cycle(sim, rig.pmac.clock, lambda k, t: (rig.entry.result, rig.entry.position), cycles=20)
    rig.pmac.start()
    sim.run(until=rig.pmac.clock.t(20))
    assert rows[0][1] > rows[-1][1]  # the source register wrapped
    assert [r for r, _ in rows] == [0] + [I10_250US] * 19
