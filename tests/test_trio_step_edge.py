"""Trio step output (issue 20): the active step edge, the pulse width, the direction set-up, and register limits
the note gives as numbers (PWM_CYCLE and PWM_MARK at most 65535; the speed link reads the *link axis*).

TRM 8-165: "the FALLING edge of the step output is the active edge"; INVERT_STEP=ON makes it a rising edge.
A step pulse is drawn from its leading edge for its width; the trailing edge is the falling one.
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import vcdvcd

from cosim.checks import DirectionSetup
from cosim.controllers.trio import ON, TrioController, TrioProcess
from cosim.controllers.trio.basic import BasicProgram, example
from cosim.errors import ConfigurationError
from cosim.export import write_trace
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000


def test_note_example_gate_edges_sit_on_the_falling_edge_of_the_counted_pulse_in_the_vcd(tmp_path: Path) -> None:
    """tn20_81.bas with the default polarity (INVERT_STEP=OFF): in the VCD every gate edge is at a falling
    edge of the step output (0 ns apart), and that edge is the 1761st, 1841st, ... (forward, GT) and the
    4800 + (4800 - 3519)th, ... (reverse, LT) falling edge."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    example("tn20_81").start(trio)
    sim.run(until=2 * 3200 * MS)
    write_trace(sim.trace, tmp_path, formats=("vcd",))
    vcd = vcdvcd.VCDVCD(str(tmp_path / "trace.vcd"))
    falls = np.array([t for t, v in vcd["trio.axis3.trio_axis3_step"].tv if v == "0" and t > 0])
    rises = np.array([t for t, v in vcd["trio.axis3.trio_axis3_step"].tv if v == "1"])
    gate = [(t, int(v)) for t, v in vcd["trio.axis3.trio_axis3_gate"].tv if t > 0]
    assert (falls - rises == 100).all()  # 100 ns pulses, the model's default width
    counts = [int(np.searchsorted(falls, t, side="right")) for t, _ in gate[:8]]
    assert counts == [1761, 1841, 3121, 3521, 9600 - 3519, 9600 - 3119, 9600 - 1839, 9600 - 1759]
    assert all(t in set(falls.tolist()) for t, _ in gate[:8])  # each gate edge is on a falling edge, 0 ns apart
    assert [v for _, v in gate[:8]] == [1, 0, 1, 0, 1, 0, 1, 0]


def stepper(sim: Simulation, **kwargs: Any) -> tuple[TrioController, TrioProcess]:
    trio = TrioController(sim, encoder_at_atype=0, **kwargs)
    p = TrioProcess(trio, base=(3,))
    for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", 1), ("SPEED", 1000), ("ACCEL", 10**6),
                        ("DECEL", 10**6)):
        p.set(name, value)
    return trio, p


@pytest.mark.parametrize(("width_ns", "invert"), [(100, 0), (250, 0), (250, 1)])
def test_pwm_encoder_counts_each_pulse_at_its_trailing_edge_whatever_the_polarity(width_ns: int,
                                                                                 invert: int) -> None:
    """MOVE(1): one pulse, at a servo tick; PWM_ENCODER reads 0 until its leading edge + width, then 1.
    INVERT_STEP=ON inverts the wire (the trailing edge rises): the same instant counts."""
    sim = Simulation(seed=1)
    trio, p = stepper(sim, step_pulse_width_ns=width_ns)
    p.set("INVERT_STEP", invert)

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield p.move(1)

    sim.process(job())
    sim.run(until=5 * MS)
    (leading,), _ = sim.trace.pulses("trio.axis3.step")
    assert leading % MS == 0
    assert [trio.gate(3).encoder_value(t) for t in (leading + width_ns - 1, leading + width_ns)] == [0, 1]
    assert sim.trace.info["trio.axis3.step"].pulse_width == width_ns
    assert sim.trace.value_at("trio.axis3.invert_step", 5 * MS) == invert


def test_the_step_pulse_width_must_leave_room_between_pulses() -> None:
    with pytest.raises(ConfigurationError, match=r"step_pulse_width_ns = 0 is not allowed \(allowed: 1..1000000 ns\)"):
        TrioController(Simulation(), step_pulse_width_ns=0)


def reversal(sim: Simulation, **kwargs: Any) -> TrioController:
    """MOVE(5) and MOVE(-5) back to back: the reverse move's first cycle follows the forward move's last one."""
    trio, p = stepper(sim, **kwargs)

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield p.move(5)
        yield p.move(-5)

    sim.process(job())
    sim.run(until=20 * MS)
    return trio


def test_direction_changes_a_pulse_width_before_the_active_edge_of_the_first_reverse_pulse() -> None:
    """Default: the direction changes with the leading edge of the first reverse pulse, 100 ns before its
    active edge (it used to change at the very instant the step was counted: 0 ns)."""
    sim = Simulation(seed=1)
    trio = reversal(sim)
    t_dir, level = sim.trace.edges("trio.axis3.dir")
    t_p, d = sim.trace.pulses("trio.axis3.step")
    first_back = int(t_p[np.flatnonzero(d == 0)[0]])
    assert (int(t_dir[-1]), level[-1]) == (first_back, 0)
    assert trio.setup_ticks == 100
    found = DirectionSetup("trio.axis3.step", "trio.axis3.dir", 100, active_delay=100).evaluate(sim.trace)
    assert found.passed and found.measured["min_setup_ns"] == 100
    tighter = DirectionSetup("trio.axis3.step", "trio.axis3.dir", 101, active_delay=100).evaluate(sim.trace)
    assert tighter.n_violations == 2  # the first forward pulse and the first reverse pulse


def test_a_direction_set_up_parameter_delays_the_pulses_behind_the_direction_output() -> None:
    """dir_setup_ns = 2000: the direction changes at the servo tick, every pulse of a cycle starts 2 us later;
    the set-up before the active edge is 2100 ns."""
    sim = Simulation(seed=1)
    trio = reversal(sim, dir_setup_ns=2000)
    t_dir, _ = sim.trace.edges("trio.axis3.dir")
    t_p, d = sim.trace.pulses("trio.axis3.step")
    assert int(t_p[0]) % MS == 2000 and int(t_dir[1]) == int(t_p[0]) - 2000
    first_back = int(t_p[np.flatnonzero(d == 0)[0]])
    assert int(t_dir[-1]) == first_back - 2000 and first_back % MS == 2000
    assert trio.setup_ticks == 2100
    found = DirectionSetup("trio.axis3.step", "trio.axis3.dir", 2100, active_delay=100).evaluate(sim.trace)
    assert found.passed and found.measured["min_setup_ns"] == 2100


@pytest.mark.parametrize(("name", "value", "accepted"), [
    ("PWM_CYCLE", 65535, True), ("PWM_CYCLE", 65536, False),  # TN20-81: "Maximum value 65535"
    ("PWM_MARK", 65535, True), ("PWM_MARK", 65536, False),
])
def test_pwm_registers_take_at_most_65535_clocks(name: str, value: int, accepted: bool) -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    program = BasicProgram.parse(f"BASE(3)\n{name} = {value}\nWDOG = ON\n", name="p.bas")
    program.start(trio)
    if accepted:
        sim.run(until=MS)
        assert trio.get_param(name, axis=3) == 65535 and sim.trace.value_at("trio.wdog", 0) == 1
    else:
        with pytest.raises(ConfigurationError, match=rf"^p.bas line 2: {name} = 65536 is not allowed \(allowed: "
                                                     r"integer 0..65535\)$"):
            sim.run(until=MS)


@pytest.mark.parametrize(("limit", "accepted"), [(65535, True), (65536, False)])
def test_the_speed_link_limit_is_a_65535_clock_register(limit: int, accepted: bool) -> None:
    p = TrioProcess(TrioController(Simulation()), base=(3,))
    if accepted:
        p.pwm_control(2, 1000, 0, limit, 3)
    else:
        with pytest.raises(ConfigurationError, match=r"PWM_CONTROL\(2\) limit value = 65536 is not allowed"):
            p.pwm_control(2, 1000, 0, limit, 3)


@pytest.mark.parametrize("link_axis", [2, 3])
def test_the_speed_link_reads_vp_speed_of_the_link_axis_not_of_the_pwm_axis(link_axis: int) -> None:
    """Axis 2 moves 100 units at SPEED 100; axis 3 (the PWM axis) stands still. Linked to axis 2 the mark follows
    its VP_SPEED (mark = VP_SPEED * 100000 / 100000 + 5); linked to axis 3 it stays at the offset, 5."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    p = TrioProcess(trio, base=(2,))
    for name, value in (("UNITS", 1), ("SPEED", 100), ("ACCEL", 1000), ("DECEL", 1000)):
        p.set(name, value)
    p.set("PWM_CYCLE", 1000, axis=3)
    p.pwm_control(2, 100_000, 5, 1000, link_axis, axis=3)
    marks: list[tuple[Fraction, int]] = []

    def job() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield p.move(100)

    def watch() -> Generator[Any, Any, None]:
        for k in range(1, 1200):
            yield sim.at(k * MS, Priority.SAMPLE)
            marks.append((trio.axes[2].vp_speed, trio.pwm(3).mark))

    sim.process(job())
    sim.process(watch())
    sim.run(until=1200 * MS)
    assert trio.axes[3].vp_speed == 0 and max(v for v, _ in marks) == 100
    if link_axis == 2:
        assert all(mark == int(v) + 5 for v, mark in marks) and max(m for _, m in marks) == 105
    else:
        assert {mark for _, mark in marks} == {5}
