"""Trio interpolated groups: MOVE and MOVECIRC on BASE(0,1), VP_SPEED as the path speed through lines and arcs,
the speed link following it, FORWARD/REVERSE/CANCEL, and move errors that name the program line."""

from __future__ import annotations

import itertools
import math
from collections.abc import Generator
from fractions import Fraction
from typing import Any

import pytest

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000
T = Fraction(1, 1000)  # SERVO_PERIOD 1 ms

SETUP = """BASE(0, 1)
ATYPE = 1
ATYPE AXIS(1) = 1
UNITS = 100
UNITS AXIS(1) = 100
SPEED = 50
ACCEL = 500
DECEL = 500
"""


def watch(trio: TrioController, axes: tuple[int, ...] = (0, 1), *, mark_axis: int | None = None
          ) -> list[tuple[int, list[Fraction], Fraction, int]]:
    """(tick, exact DPOS of ``axes``, VP_SPEED of the first, PWM mark of ``mark_axis``) at every servo tick."""
    log: list[tuple[int, list[Fraction], Fraction, int]] = []

    def sample() -> Generator[Any, Any, None]:
        k = 0
        while True:
            yield trio.sim.at(k * MS, Priority.SAMPLE)
            mark = trio.pwm(mark_axis).mark if mark_axis is not None else 0
            log.append((k * MS, [trio.axes[a].dpos for a in axes], trio.axes[axes[0]].vp_speed, mark))
            k += 1

    trio.sim.process(sample())
    return log


def test_vp_speed_is_the_path_speed_of_every_cycle_through_a_line_an_arc_and_a_line_and_the_link_follows_it() -> None:
    """BASE(0,1): MOVE(20,0), MOVECIRC(10,10,0,10,0) (a quarter circle of radius 10 around (20,10),
    anticlockwise), MOVE(0,20). PWM axis 3 is speed-linked to axis 0 (the path's base axis), whose VP_SPEED
    is the path speed: mark = VP_SPEED * 1000000 / 100000 + 20, at most 450 clocks.

        y
        30 |                  . end (30, 30)
           |                  |
        10 |            .--'  (30, 10)
           |          /
         0 +---------+ (20, 0)
    """
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    program = SETUP + """PWM_CYCLE AXIS(3) = 1000
PWM_CONTROL(2, 1000000, 20, 450, 0) AXIS(3)
MOVE(20, 0)
MOVECIRC(10, 10, 0, 10, 0)
MOVE(0, 20)
WAIT IDLE
"""
    BasicProgram.parse(program, name="xy.bas").start(trio)
    log = watch(trio, mark_axis=3)
    sim.run(until=2000 * MS)
    assert (trio.axes[0].dpos, trio.axes[1].dpos) == (30, 30)
    on_arc = on_line = 0
    for (_, p0, _, _), (_, p1, vp, mark) in itertools.pairwise(log):
        assert mark == min(450, math.floor(vp * 1_000_000 / 100_000 + 20))
        if p0 == p1:
            assert vp == 0
            continue
        x0, y0, x1, y1 = (float(v) for v in (*p0, *p1))
        if x0 >= 20 and x1 <= 30 and y0 >= 0 and y1 <= 10 and (x0, y0) != (30, 10):  # the arc around (20, 10)
            r0, r1 = math.hypot(x0 - 20, y0 - 10), math.hypot(x1 - 20, y1 - 10)
            assert r0 == pytest.approx(10, abs=1e-12) and r1 == pytest.approx(10, abs=1e-12)
            turned = math.atan2(y1 - 10, x1 - 20) - math.atan2(y0 - 10, x0 - 20)
            assert float(vp) * 0.001 == pytest.approx(10 * turned, rel=1e-9)  # arc length of the cycle / T
            on_arc += 1
        else:
            assert vp * T == Fraction(math.hypot(x1 - x0, y1 - y0)) or float(vp * T) == pytest.approx(
                math.hypot(x1 - x0, y1 - y0), rel=1e-12)
            on_line += 1
    assert on_arc > 300 and on_line > 800  # 15.7 units of arc and 40 of line at 50 units/s
    assert max(vp for *_, vp, _ in log) == 50


def test_arc_cycles_follow_the_trapezoid_over_the_arc_length() -> None:
    """A half circle of radius 5 (length 5 pi) at SPEED 50, ACCEL = DECEL = 500: cycle k's VP_SPEED is
    (s((k+1)T) - s(kT)) / T of the closed-form trapezoid over 5 pi."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(SETUP + "MOVECIRC(0, 10, 0, 5, 1)\nWAIT IDLE\n").start(trio)
    log = watch(trio)
    sim.run(until=800 * MS)
    length, v, a = 5 * math.pi, 50.0, 500.0
    t_a, t_c = v / a, (length - v * v / a) / v

    def s(t: float) -> float:
        if t <= t_a:
            return a * t * t / 2
        if t <= t_a + t_c:
            return v * t_a / 2 + v * (t - t_a)
        return length - a * max(2 * t_a + t_c - t, 0) ** 2 / 2

    speeds = [float(vp) for t, _, vp, _ in log if t >= MS and vp > 0]
    expected = [(s((k + 1) / 1000) - s(k / 1000)) * 1000 for k in range(len(speeds))]
    assert speeds == pytest.approx(expected, rel=1e-9, abs=1e-9)
    assert (trio.axes[0].dpos, trio.axes[1].dpos) == (0, 10)  # ends exactly on the programmed end
    assert all(float(p[0]) <= 0 for _, p, _, _ in log)  # clockwise from below the centre: through x < 0


@pytest.mark.parametrize(("direction", "sign_of_x"), [(0, 1), (1, -1)])
def test_movecirc_direction_0_is_anticlockwise_and_1_clockwise(direction: int, sign_of_x: int) -> None:
    """From (0,0) around (0,10) to (10,10): anticlockwise is a quarter through x > 0, clockwise three quarters
    through x < 0."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(SETUP + f"MOVECIRC(10, 10, 0, 10, {direction})\nWAIT IDLE\n").start(trio)
    log = watch(trio)
    sim.run(until=2000 * MS)
    xs = [p[0] for _, p, _, _ in log]
    assert (trio.axes[0].dpos, trio.axes[1].dpos) == (10, 10)
    assert (min(xs) < -9) == (sign_of_x < 0) and max(xs) == 10


def test_a_full_circle_when_the_end_is_the_start() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(SETUP + "MOVECIRC(0, 0, 4, 0, 0)\nWAIT IDLE\n").start(trio)
    log = watch(trio)
    sim.run(until=2000 * MS)
    xs = [float(p[0]) for _, p, _, _ in log]
    assert max(xs) == pytest.approx(8, abs=1e-3) and (trio.axes[0].dpos, trio.axes[1].dpos) == (0, 0)


@pytest.mark.parametrize(("arc", "message"), [
    ("MOVECIRC(10, 0, 0, 10, 0)", r"xy.bas line 9: MOVECIRC end point is not on the circle: radius 10 at the "
                                  r"start, 14.1421 at the end \(allowed: the same within 0.01 units, one step\)"),
    ("MOVECIRC(1, 1, 0, 0, 0)", r"xy.bas line 9: MOVECIRC centre is the start point"),
    ("MOVECIRC(0, 0, 4, 0, 2)", r"xy.bas line 9: MOVECIRC direction = 2 is not allowed \(allowed: 0 "
                                r"\(anticlockwise\) or 1 \(clockwise\)\)"),
])
def test_bad_arcs_are_refused_at_their_line(arc: str, message: str) -> None:
    sim = Simulation(seed=1)
    BasicProgram.parse(SETUP + arc + "\n", name="xy.bas").start(TrioController(sim))
    with pytest.raises(ConfigurationError, match=message):
        sim.run(until=10 * MS)


def test_forward_runs_at_speed_until_cancel_then_stops_at_decel() -> None:
    """FORWARD from t = 0 (loaded at 1 ms; SPEED 100 after 0.1 s at ACCEL 1000); CANCEL at 300 ms acts at the
    301 ms tick, after 300 cycles: at 25 units and 100 units/s, it stops 100**2 / (2 * 500) = 10 units on."""
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse("ATYPE = 1\nUNITS = 10\nSPEED = 100\nACCEL = 1000\nDECEL = 500\nFORWARD\nWA(300)\n"
                       "CANCEL\nWAIT IDLE\nVR(0) = DPOS\nREVERSE\nWA(50)\nCANCEL\nWAIT IDLE\n").start(trio)
    log = watch(trio, (0,))
    sim.run(until=2000 * MS)
    assert trio.vr(0) == 35 and trio.axes[0].steps < 350
    at = {t: (p[0], vp) for t, p, vp, _ in log}
    assert at[300 * MS] == (25, 100) and at[501 * MS] == (35, 0)
    assert at[500 * MS][1] > 0  # the last cycle of the stop runs at the 500 ms tick
    back = 50 * Fraction(1, 1000) * 50 * Fraction(1, 1000) * 1000 / 2  # 50 cycles of ACCEL from rest
    assert trio.axes[0].dpos == 35 - back - (50 * 1000 * T) ** 2 / (2 * 500)


def test_cancel_stops_a_move_short_along_its_path() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    BasicProgram.parse(SETUP + "MOVE(30, 40)\nWA(100)\nCANCEL\nWAIT IDLE\n").start(trio)
    sim.run(until=2000 * MS)
    x, y = trio.axes[0].dpos, trio.axes[1].dpos
    assert 4 * x == 3 * y and 0 < x < 30  # on the line, short of the end


def test_a_move_on_an_axis_that_drives_a_plant_but_gives_no_pulses_is_an_error_at_its_line() -> None:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    trio.step_dir(0)  # a machine coupled a stepper to axis 0
    BasicProgram.parse("BASE(0)\nUNITS = 10\nMOVE(5)\n", name="m.bas").start(trio)
    with pytest.raises(ConfigurationError, match=r"m.bas line 3: MOVE on axis 0: its step/direction output drives "
                                                 r"a plant, but ATYPE = 0 \(virtual\) gives no step pulses"):
        sim.run(until=10 * MS)


def test_an_error_the_servo_cycle_finds_in_a_move_names_the_program_line_that_issued_it() -> None:
    """10000 pulses in one 1 ms cycle leave 100 ns between pulses, less than two 100 ns pulse widths."""
    sim = Simulation(seed=1)
    BasicProgram.parse("ATYPE = 1\nUNITS = 1000\nSPEED = 10000\nACCEL = 10000000\nDECEL = 10000000\nWA(5)\n"
                       "MOVE(100)\n", name="fast.bas").start(TrioController(sim))
    with pytest.raises(TimingViolation, match=r"^fast.bas line 7: trio.axis0: 10000 step pulses in one servo cycle"):
        sim.run(until=100 * MS)


def test_a_following_error_names_the_program_line_of_the_move() -> None:
    sim = Simulation(seed=1)
    BasicProgram.parse("BASE(3)\nATYPE = 35\nSERVO = ON\nUNITS = 1\nFE_LIMIT = 0.5\nSPEED = 100\nMOVE(10)\n",
                       name="fe.bas").start(TrioController(sim, encoder_at_atype=0))
    with pytest.raises(TimingViolation, match=r"^fe.bas line 7: trio.axis3: following error .* exceeds FE_LIMIT = 0.5"):
        sim.run(until=100 * MS)
