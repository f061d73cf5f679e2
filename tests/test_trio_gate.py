"""Trio gating FIFO: GT/LT compare per count against the 29-bit PWM_ENCODER, loads, waits, late entries."""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

import numpy as np
import pytest

from cosim.controllers.trio import OFF, ON, TrioController, TrioProcess
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
#: TRM 8-165: a step pulse's falling edge is the active one; with the model's default pulse width it comes 100 ns
#: after the leading edge that the trace records. PWM_ENCODER and the gate count there.
ACTIVE = 100


def gated_axis(sim: Simulation, *, units: int = 16, speed: int = 100, encoder_at_atype: int | None = 0,
               clear: bool = True) -> tuple[TrioController, TrioProcess]:
    """Axis 3: stepper with SERVO=ON, PWM on at 20 kHz, FIFO emptied, gating on, WDOG on."""
    trio = TrioController(sim, encoder_at_atype=encoder_at_atype)
    p = TrioProcess(trio, base=(3,))
    for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", units), ("SPEED", speed), ("ACCEL", 1000),
                        ("DECEL", 1000), ("PWM_CYCLE", 1000), ("PWM_MARK", 400)):
        p.set(name, value)
    p.pwm_control(1)
    if clear:
        p.pwm_control(6)
    p.pwm_control(4)
    p.pwm_control(5)
    p.set("WDOG", ON)
    return trio, p


def run_job(sim: Simulation, job: Generator[Any, Any, None], until_ms: int) -> None:
    def program() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield from job

    sim.process(program())
    sim.run(until=until_ms * MS)


def gate_edges(sim: Simulation) -> list[tuple[int, int, int]]:
    """(t, level, count) of each gate edge; count = signed step pulses at or before t."""
    t, v = sim.trace.edges("trio.axis3.gate")
    tp, dp = sim.trace.pulses("trio.axis3.step")
    count = np.concatenate([[0], np.cumsum(dp.astype(np.int64) * 2 - 1)])
    at = np.searchsorted(tp, t[1:], side="right")
    return [(int(a), int(b), int(count[i])) for a, b, i in zip(t[1:], v[1:], at, strict=True)]


def pulse_time(sim: Simulation, n: int) -> int:
    """Active (falling) edge of the n-th step pulse (1-based) of the run."""
    return int(sim.trace.pulses("trio.axis3.step")[0][n - 1]) + ACTIVE


def test_gt_fires_at_the_exact_pulse_of_the_first_count_above_position_times_units(sim: Simulation) -> None:
    """GT at 110.03 (1760.48 counts), 110.0625 (exactly 1761) and 115 (1840): counts 1761, 1762, 1841.

    count   ... 1760 | 1761 | 1762 ... 1840 | 1841
    gate    ________|‾‾‾‾‾‾|__________________|‾‾‾‾   (ON, OFF, ON)
    """
    _trio, p = gated_axis(sim, speed=1000)
    p.table(10, Fraction(11003, 100), Fraction(1761, 16), 115)

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, ON, 10, 12)
        yield p.moveabs(200)

    run_job(sim, job(), 2500)
    assert gate_edges(sim) == [(pulse_time(sim, 1761), 1, 1761), (pulse_time(sim, 1762), 0, 1762),
                               (pulse_time(sim, 1841), 1, 1841)]
    assert any(t % MS for t, _, _ in gate_edges(sim))  # edges are not snapped to servo-cycle boundaries


def test_lt_fires_at_the_first_count_below(sim: Simulation) -> None:
    """From 200 back to 0, LT at 110.03 (ceil 1761 -> 1760), 110 (1760 -> 1759), 50 (800 -> 799)."""
    _trio, p = gated_axis(sim)
    p.table(0, Fraction(11003, 100), 110, 50)

    def job() -> Generator[Any, Any, None]:
        yield p.moveabs(200)
        yield p.wait_idle()
        yield p.pwm_control(3, 0, ON, 0, 2)
        yield p.moveabs(0)

    run_job(sim, job(), 5000)
    t_p, _ = sim.trace.pulses("trio.axis3.step")
    back = {3200 - k: int(t) + ACTIVE for k, t in enumerate(t_p[3200:], start=1)}  # count reached, reverse pulses
    assert gate_edges(sim) == [(back[1760], 1, 1760), (back[1759], 0, 1759), (back[799], 1, 799)]


def test_on_off_state_toggles_entry_by_entry_from_the_given_state(sim: Simulation) -> None:
    _trio, p = gated_axis(sim, units=1)
    p.table(0, 10, 20, 30, 40)

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, OFF, 0, 1)  # 10 OFF, 20 ON
        yield p.pwm_control(3, 1, OFF, 2, 3)  # 30 OFF, 40 ON: each load starts from its own state
        yield p.moveabs(50)

    run_job(sim, job(), 2000)
    assert [(level, count) for _, level, count in gate_edges(sim)] == [(1, 21), (0, 31), (1, 41)]


def test_two_positions_within_one_count_fire_at_the_same_pulse(sim: Simulation) -> None:
    """ON at 110.01 and OFF at 110.02 both need count 1761: the FIFO drops both at that pulse, the gate
    shows no edge (outputs settle once per instant)."""
    _trio, p = gated_axis(sim)
    p.table(0, Fraction(11001, 100), Fraction(11002, 100), 115)

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, ON, 0, 2)
        yield p.moveabs(120)

    run_job(sim, job(), 2000)
    t_level, level = sim.trace.edges("trio.axis3.fifo_level")
    assert (int(t_level[-2]), level[-2]) == (pulse_time(sim, 1761), 1)
    assert gate_edges(sim) == [(pulse_time(sim, 1841), 1, 1841)]


def test_fifo_holds_256_positions_and_a_load_that_does_not_fit_waits(sim: Simulation) -> None:
    """256 GT positions at 1, 2, ... 256 counts fill the FIFO; a 4-position load waits (fifo_waiting = 4)
    until four have fired, and goes in at the next servo tick; the program waits with it.

    fifo_level   256 ------\\___ 252 (at the 4th pulse)  ->  256 at the next servo tick
    fifo_waiting   4 ________________________________ 0
    """
    _trio, p = gated_axis(sim, units=1, speed=1000)
    p.table(0, *range(260))  # TN20-81: "The FIFO is up to 256 positions deep": 256 + 4 positions
    log: list[int] = []

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, ON, 0, 255)  # TABLE(0..255): 256 positions, a full FIFO
        log.append(sim.now)
        waiting = p.pwm_control(3, 1, ON, 256, 259)  # 4 more: they wait
        yield p.move(300)
        assert not waiting.triggered
        yield waiting
        log.append(sim.now)

    run_job(sim, job(), 1000)
    t_fire4 = pulse_time(sim, 4)
    t_loaded = (t_fire4 // MS + 1) * MS
    assert log == [0, t_loaded]
    t_w, v_w = sim.trace.edges("trio.axis3.fifo_waiting")
    assert list(zip(t_w.tolist(), v_w.tolist(), strict=True)) == [(0, 0), (0, 4), (t_loaded, 0)]
    assert sim.trace.value_at("trio.axis3.fifo_level", t_fire4) == 252
    assert sim.trace.value_at("trio.axis3.fifo_level", t_loaded) == 256
    assert len(gate_edges(sim)) == 260


def test_empty_fifo_closes_the_gate_and_gating_off_opens_it_while_pwm_is_on(sim: Simulation) -> None:
    trio, p = gated_axis(sim, units=1)
    p.table(0, 5, 500)

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, ON, 0, 1)
        yield p.moveabs(20)
        yield p.wait_idle()
        t_empty = sim.now
        p.pwm_control(4)
        assert trio.gate(3).entries == type(trio.gate(3).entries)() and trio.gate(3).latch == 0
        yield sim.after(MS)
        p.pwm_control(0)  # PWM off, gating off: gate closed
        yield sim.after(MS)
        p.pwm_control(1)  # PWM on without gating: gate open
        log.extend([t_empty, sim.now])

    log: list[int] = []
    run_job(sim, job(), 1000)
    t_empty, t_on = log
    edges = gate_edges(sim)
    assert [(t, level) for t, level, _ in edges[-2:]] == [(t_empty, 0), (t_on, 1)]
    assert edges[0][2] == 6


def test_pwm_encoder_counts_step_pulses_and_ignores_defpos_until_cleared(sim: Simulation) -> None:
    trio, p = gated_axis(sim, units=4)

    def job() -> Generator[Any, Any, None]:
        yield p.move(25)
        yield p.wait_idle()
        p.defpos(0)
        yield sim.at(sim.now + MS, Priority.HOST)  # after the servo tick that applies DEFPOS
        log.append((trio.get_param("PWM_ENCODER", axis=3), trio.get_param("DPOS", axis=3)))
        p.pwm_control(6)
        log.append((trio.get_param("PWM_ENCODER", axis=3), trio.get_param("MPOS", axis=3)))

    log: list[tuple[Fraction, Fraction]] = []
    run_job(sim, job(), 1000)
    assert log == [(100, 0), (0, 0)]


#: TN20-81: "A dedicated 29 bit encoder hardware register": values 0 .. 2**29 - 1 = 536870911.
ENCODER_WRAP = 536_870_912


def test_pwm_encoder_is_29_bit_and_the_compare_works_across_its_wrap(sim: Simulation) -> None:
    """ATYPE=35 left PWM_ENCODER at 536870872 (2**29 - 40, not cleared); GT 1 fires when it reads 2 (42 pulses
    on), and on the way back LT -20 fires when it reads 536870891 (2**29 - 21, 19 pulses from the start)."""
    trio, p = gated_axis(sim, units=1, encoder_at_atype=536_870_872, clear=False)
    p.table(0, 1, -20)
    assert trio.get_param("PWM_ENCODER", axis=3) == 536_870_872
    readings: list[Fraction] = []

    def job() -> Generator[Any, Any, None]:
        yield p.pwm_control(3, 1, ON, 0, 0)
        yield p.pwm_control(3, 0, OFF, 1, 1)
        yield p.move(50)
        yield p.wait_idle()
        readings.append(trio.get_param("PWM_ENCODER", axis=3))
        yield p.move(-50)

    run_job(sim, job(), 1500)
    assert readings == [10]  # 536870872 + 50 wraps past 536870911 to 0: 536870922 - 536870912 = 10
    assert trio.get_param("PWM_ENCODER", axis=3) == 536_870_872
    edges = gate_edges(sim)
    assert [(level, count) for _, level, count in edges] == [(1, 42), (0, 19)]  # LT -20: reads 536870891
    assert edges[0][0] == pulse_time(sim, 42)


@pytest.mark.parametrize(("start", "moved", "reads"), [
    (536_870_911, 1, 0),            # the largest 29-bit value, one pulse on: 0
    (536_870_911, -1, 536_870_910),
    (0, -1, 536_870_911),           # below 0: the largest value (a 28-bit register would read 268435455)
    (268_435_455, 1, 268_435_456),  # 2**28 - 1 + 1 fits 29 bits (a 28-bit register would wrap to 0)
])
def test_pwm_encoder_wraps_at_2_to_the_29(sim: Simulation, start: int, moved: int, reads: int) -> None:
    trio, p = gated_axis(sim, units=1, encoder_at_atype=start, clear=False)

    def job() -> Generator[Any, Any, None]:
        yield p.move(moved)

    run_job(sim, job(), 100)
    assert trio.get_param("PWM_ENCODER", axis=3) == reads


@pytest.mark.parametrize(("value", "accepted"), [(536_870_911, True), (536_870_912, False)])
def test_the_power_up_encoder_value_must_fit_29_bits(value: int, accepted: bool) -> None:
    if accepted:
        assert TrioController(Simulation(), encoder_at_atype=value).encoder_at_atype == 536_870_911
    else:
        with pytest.raises(ConfigurationError, match=r"encoder_at_atype = 536870912 is not allowed \(allowed: "
                                                     r"0..536870911"):
            TrioController(Simulation(), encoder_at_atype=value)


def test_positions_passed_before_they_were_loaded_fire_at_the_load_and_are_reported(sim: Simulation) -> None:
    """The FIFO ran empty: at the load the axis is already past 110 and 115; both fire at once (late),
    195 and 220 fire at their counts.

    load     ................^ (t_load, position ~150)
    gate_late                 110, 115
    gate     ________________________________|‾‾‾‾‾‾|___  (195 ON, 220 OFF)
    """
    trio, p = gated_axis(sim)
    p.table(1000, 110, 115, 195, 220)
    t_load = 1600 * MS

    def job() -> Generator[Any, Any, None]:
        yield p.moveabs(300)
        yield sim.at(t_load, Priority.HOST)
        yield p.pwm_control(3, 1, ON, 1000, 1003)

    run_job(sim, job(), 4000)
    t_late, position = sim.trace.edges("trio.axis3.gate_late")
    assert t_late.tolist() == [t_load, t_load] and position.tolist() == [110, 115]
    assert trio.gate(3).late == [(t_load, 110), (t_load, 115)]
    assert [(level, count) for _, level, count in gate_edges(sim)] == [(1, 3121), (0, 3521)]


def test_atype_35_leaves_an_arbitrary_encoder_value_drawn_from_the_seeded_rng() -> None:
    values = []
    for seed in (1, 1, 2):
        s = Simulation(seed=seed)
        trio = TrioController(s)
        trio.set_param("ATYPE", 35, axis=2)
        values.append(int(trio.get_param("PWM_ENCODER", axis=2)))
    assert values[0] == values[1] != values[2]
    assert all(0 <= v < ENCODER_WRAP for v in values)  # TN20-81: a 29-bit register


@pytest.mark.parametrize(("args", "message"), [
    ((2, ON, 0, 3), r"PWM_CONTROL\(3\) GT/LT flag = 2 is not allowed \(allowed: 1 \(GT\) or 0 \(LT\)\)"),
    ((1, ON, 10, 3), r"PWM_CONTROL\(3\) table end = 3 is not allowed \(allowed: >= table start 10\)"),
    ((1, ON, 15990, 16000), r"PWM_CONTROL\(3\) table end = 16000 is not allowed \(allowed: 0..15999"),
    ((1, ON, -1, 3), r"PWM_CONTROL\(3\) table start = -1 is not allowed \(allowed: 0..15999"),
    ((1, ON, 0, 256), r"PWM_CONTROL\(3\) positions in one load = 257 is not allowed \(allowed: 1..256"),
    ((1, 2, 0, 3), r"PWM_CONTROL\(3\) ON/OFF = 2 is not allowed"),
    ((1, ON, 0), r"PWM_CONTROL\(3\) takes 4 arguments after the mode \(GT/LT, ON/OFF, table start, table end\)"),
])
def test_bad_fifo_loads_are_refused(sim: Simulation, args: tuple[object, ...], message: str) -> None:
    _trio, p = gated_axis(sim)
    with pytest.raises(ConfigurationError, match=message):
        p.pwm_control(3, *args)
