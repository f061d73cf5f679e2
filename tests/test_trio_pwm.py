"""Trio PWM output: 20 MHz clock, PWM_CYCLE/PWM_MARK, PWM_CONTROL modes 0-2, speed link, WDOG."""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from trio_rigs import laser_axis

from cosim.controllers.trio import OFF, ON, TrioController, TrioProcess
from cosim.controllers.trio.pwm import SpeedLink, carrier_edges, linked_mark
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000


@pytest.mark.parametrize(("cycle", "frequency_hz", "period_ns"), [(1000, 20_000, 50_000), (200, 100_000, 10_000)])
def test_pwm_cycle_sets_the_frequency_of_the_20mhz_generator(sim: Simulation, cycle: int, frequency_hz: int,
                                                             period_ns: int) -> None:
    """PWM_CYCLE=1000 -> 20 kHz, PWM_CYCLE=200 -> 100 kHz (the note's two examples).

    out  _|‾‾‾‾|______|‾‾‾‾|______   rising edges every cycle * 50 ns, high for mark * 50 ns
    """
    laser_axis(sim, cycle=cycle, mark=cycle // 4)
    sim.run(until=1 * MS)
    rises, highs = sim.trace.pulse_widths("trio.axis3.pwm_out")  # the recorded output pin
    assert np.diff(rises).tolist() == [period_ns] * (rises.size - 1) and 10**9 // period_ns == frequency_hz
    assert rises.size == 1 * MS // period_ns  # the first period starts high at t = 0
    assert set(highs.tolist()) == {cycle // 4 * 50}


@pytest.mark.parametrize(("cycle", "mark"), [(1000, 1000), (1000, 1001), (200, 65535), (0, 5)])
def test_mark_at_or_above_cycle_is_continuously_on(sim: Simulation, cycle: int, mark: int) -> None:
    laser_axis(sim, cycle=cycle, mark=mark)
    sim.run(until=1 * MS)
    rises, highs = sim.trace.pulse_widths("trio.axis3.pwm_out")
    assert rises.tolist() == [0] and highs.tolist() == [1 * MS]  # one pulse, high to the end of the run


def test_mark_zero_is_off(sim: Simulation) -> None:
    laser_axis(sim, cycle=1000, mark=0)
    sim.run(until=1 * MS)
    assert sim.trace.pulse_widths("trio.axis3.pwm_out")[0].size == 0  # the pin never rises


def test_wdog_off_stops_the_output_at_once(sim: Simulation) -> None:
    """WDOG=OFF at 0.3 ms + 17 ns, in the middle of a mark: the output falls at that very tick.

    out   |‾‾|__|‾‾|__|‾|________________
    wdog  ‾‾‾‾‾‾‾‾‾‾‾‾‾‾|_______________  t_off = 300_017 ns
    """
    _trio, p = laser_axis(sim, cycle=1000, mark=400)
    t_off = 300_017
    sim.call_at(t_off, Priority.HOST, lambda: p.set("WDOG", OFF))
    sim.run(until=1 * MS)
    rises, highs = sim.trace.pulse_widths("trio.axis3.pwm_out")
    assert rises[-1] + highs[-1] == t_off  # the pulse that rose at 300 us falls at t_off, 17 ns later
    assert (rises[-2:].tolist(), highs[-2:].tolist()) == ([250_000, 300_000], [20_000, 17])
    assert sim.trace.edges("trio.wdog")[0].tolist() == [0, 0, t_off]


def test_pwm_control_0_switches_off_and_1_takes_pwm_mark(sim: Simulation) -> None:
    """pwm_mark (what the laser gets) is 0 in mode 0 and PWM_MARK in mode 1, settled per instant."""
    trio, p = laser_axis(sim, cycle=1000, mark=400)
    def mark_250_and_on() -> None:
        p.set("PWM_MARK", 250)
        p.pwm_control(1)

    def off() -> None:
        p.pwm_control(0)

    sim.call_at(1 * MS, Priority.HOST, off)
    sim.call_at(2 * MS, Priority.HOST, mark_250_and_on)
    sim.run(until=3 * MS)
    t, v = sim.trace.edges("trio.axis3.pwm_mark")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (0, 400), (1 * MS, 0), (2 * MS, 250)]
    assert trio.get_param("PWM_MARK", axis=3) == 250


def test_new_pwm_cycle_restarts_the_carrier_at_the_next_clock_edge(sim: Simulation) -> None:
    _trio, p = laser_axis(sim, cycle=1000, mark=100)
    sim.call_at(123_456, Priority.HOST, lambda: p.set("PWM_CYCLE", 200))
    sim.run(until=200_000)
    assert sim.trace.value_at("trio.axis3.pwm_phase", 150_000) == 2470  # ceil(123456 / 50)
    rises, _ = sim.trace.pulse_widths("trio.axis3.pwm_out")
    assert rises[:5].tolist() == [0, 50_000, 100_000, 123_500, 133_500]  # 1000 clocks, then 200 from 123.5 us


def test_linked_mark_formula_and_limit() -> None:
    link = SpeedLink(Fraction(2000), Fraction(10), 300, 3)
    assert linked_mark(Fraction(0), link) == 10
    assert linked_mark(Fraction(12345, 10), link) == 34  # 1234.5 * 2000 / 100000 + 10 = 34.69
    assert linked_mark(Fraction(10**6), link) == 300  # 20010 exceeds the limit value
    assert linked_mark(Fraction(100), SpeedLink(Fraction(1000), Fraction(-50), 300, 3)) == 0  # never below 0


def test_speed_link_follows_vp_speed_every_servo_cycle_and_never_exceeds_the_limit(sim: Simulation) -> None:
    """PWM_CONTROL(2, 25000, 20, 120, 2) on axis 3 while BASE(2,3) draws an 80 x 60 diagonal and back.

    Vectorised over every servo tick of the move: mark = min(floor(VP_SPEED*25000/100000 + 20), 120).
    """
    trio = TrioController(sim, encoder_at_atype=0)
    p = TrioProcess(trio, base=(2, 3))
    for axis in (2, 3):
        for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", 10), ("SPEED", 500), ("ACCEL", 2500),
                            ("DECEL", 5000)):
            p.set(name, value, axis=axis)
    p.set("PWM_CYCLE", 1000, axis=3)
    p.pwm_control(2, 25000, 20, 120, 2, axis=3)
    p.set("WDOG", ON)

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield p.move(80, 60)
        yield p.move(-80, -60)

    sim.process(job())
    sim.run(until=800 * MS)
    ticks = np.arange(1, 800) * MS
    vp = np.array([sim.trace.value_at("trio.axis2.vp_speed", int(t)) for t in ticks])
    mark = np.array([sim.trace.value_at("trio.axis3.pwm_mark", int(t)) for t in ticks])
    expected = np.minimum(np.floor(vp * 25000 / 100000 + 20), 120)
    assert (mark == expected).all()
    assert mark.max() == 120 and (mark < 120).sum() > 50 and mark[-1] == 20
    assert (vp > 0).sum() > 100 and vp.max() == 500


def test_speed_link_arguments_are_checked(sim: Simulation) -> None:
    _trio, p = laser_axis(sim, cycle=1000, mark=0)
    with pytest.raises(ConfigurationError, match=r"PWM_CONTROL\(2\) limit value = 70000 is not allowed "
                                                 r"\(allowed: 0..65535\)"):
        p.pwm_control(2, 1000, 0, 70000, 3)
    with pytest.raises(ConfigurationError, match=r"axis = 9 is not allowed \(allowed: 0..3\)"):
        p.pwm_control(2, 1000, 0, 400, 9)
    with pytest.raises(ConfigurationError, match=r"PWM_CONTROL\(2\) takes 4 arguments after the mode"):
        p.pwm_control(2, 1000)


@pytest.mark.parametrize(("name", "value", "allowed"), [
    ("PWM_CYCLE", 65536, "integer 0..65535"), ("PWM_CYCLE", -1, "integer 0..65535"),
    ("PWM_MARK", 70000, "integer 0..65535"), ("PWM_MARK", 1.5, "integer 0..65535"),
])
def test_pwm_registers_are_16_bit(sim: Simulation, name: str, value: object, allowed: str) -> None:
    _trio, p = laser_axis(sim, cycle=1000, mark=0)
    with pytest.raises(ConfigurationError, match=rf"^{name} = {value} is not allowed \(allowed: {allowed}\)$"):
        p.set(name, value)


def test_carrier_edges_closed_form() -> None:
    t, v = carrier_edges(10_000, 130_000, cycle=1000, mark=400, clock_ticks=50, phase=0)
    assert t.tolist() == [10_000, 20_000, 50_000, 70_000, 100_000, 120_000]
    assert v.tolist() == [1, 0, 1, 0, 1, 0]
    assert carrier_edges(0, 10, cycle=1000, mark=400, clock_ticks=50, enabled=False)[1].tolist() == [0]
