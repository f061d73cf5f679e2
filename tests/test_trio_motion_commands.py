"""Motion beyond the basic moves (issue 28, item 4), as timing diagrams.

DATUM(0..6) on the datum switch (DATUM_IN, active low) and the Z marker, CONNECT, MOVELINK, CAMBOX and
CAM from TABLE data, MOVEMODIFY, MERGE, SRAMP, AXISSTATUS bits, REGIST (the position latched at the
input edge) and TRIGGER. Axes are virtual (UNITS = 1) unless said; SERVO_PERIOD is 1 ms; a move issued
at 0 is loaded at the tick at 1 ms.
"""

from __future__ import annotations

import itertools
from fractions import Fraction

from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import BasicProgram
from cosim.kernel import Simulation

MS = 1_000_000


def run(text: str, *, until_ms: int, inputs: dict[str, list[tuple[int, int]]] | None = None) -> TrioController:
    sim = Simulation(seed=1)
    trio = TrioController(sim)
    for name, changes in (inputs or {}).items():
        signal = trio.axes[int(name[4:])].ensure_z_mark() if name.startswith("zmk") else trio.input(int(name))
        if not name.startswith("zmk"):
            signal.set(1)
        for t_ms, level in changes:
            sim.call_at(t_ms * MS, 1, lambda signal=signal, level=level: signal.set(level))
    BasicProgram.parse(text, name="t.bas").start(trio, job=True)
    sim.run(until=until_ms * MS)
    return trio


def dpos_at(trio: TrioController, axis: int, t_ms: int) -> float:
    return trio.sim.trace.value_at(f"trio.axis{axis}.dpos", t_ms * MS)


def test_datum_3_forward_to_the_switch_then_back_at_creep_until_it_resets() -> None:
    """DATUM_IN = 2 (active low). The switch is set (input OFF) from 300 ms to 600 ms.

        t [ms]     1 ......... 300 ... ~400 .............. 600
        motion     forward at SPEED 100 | decelerate | back at CREEP 10 | DPOS = 0, stop
        AXISSTATUS 64 ..................................................| 0

    At 600 ms the position becomes 0, then the axis decelerates at DECEL 1000 from CREEP: 10^2/2000 =
    0.05 units further back: DPOS ends at -0.05."""
    trio = run("BASE(0)\nSPEED = 100\nCREEP = 10\nDATUM_IN = 2\nDATUM(3)\nWA(100)\nVR(0) = AXISSTATUS\n"
               "VR(1) = MTYPE\nWAIT IDLE\nVR(2) = DPOS\nVR(3) = AXISSTATUS\nVR(4) = TICKS\n",
               until_ms=800, inputs={"2": [(300, 0), (600, 1)]})
    assert (trio.vr(0), trio.vr(1), trio.vr(2), trio.vr(3)) == (64, 12, Fraction(-1, 20), 0)
    assert trio.vr(4) == -610  # at rest 0.01 s after 600 ms (10 units/s at 1000 units/s^2): idle from that tick


def test_datum_4_reverse_to_the_switch_when_already_on_it_only_creeps() -> None:
    """On the switch from the start: DATUM(4) skips the fast search and creeps forward until it resets."""
    trio = run("BASE(0)\nCREEP = 10\nDATUM_IN = 2\nDATUM(4)\nWAIT IDLE\nVR(0) = DPOS\nVR(1) = TICKS\n",
               until_ms=500, inputs={"2": [(0, 0), (200, 1)]})
    assert (trio.vr(0), trio.vr(1)) == (Fraction(1, 20), -210)


def test_datum_1_creeps_to_the_z_marker() -> None:
    """DATUM(1): forward at CREEP until the Z marker's rising edge (at 50 ms), 0 there, then rest."""
    trio = run("BASE(1)\nCREEP = 10\nDATUM(1)\nWAIT IDLE\nVR(0) = DPOS\n", until_ms=300,
               inputs={"zmk_1": [(50, 1), (51, 0)]})
    assert trio.vr(0) == Fraction(1, 20)


def test_datum_needs_its_switch_and_datum_0_moves_nothing() -> None:
    trio = run("BASE(0)\nDATUM(0)\nVR(0) = IDLE\n", until_ms=5)
    assert trio.vr(0) == -1
    sim = Simulation(seed=1)
    BasicProgram.parse("DATUM(3)\n", name="t.bas").start(TrioController(sim))
    try:
        sim.run(until=5 * MS)
    except Exception as exc:
        assert "DATUM(3) on axis 0 needs the datum switch: DATUM_IN = -1" in str(exc)
    else:  # pragma: no cover
        raise AssertionError("DATUM(3) without DATUM_IN ran")


def test_connect_follows_the_driving_axis_measured_position_a_tick_later() -> None:
    """CONNECT(2, 0) on axis 1: each tick axis 1's demand is 2 x the change of axis 0's MPOS, which is latched
    at the tick (the demand of the tick before on a virtual axis). Axis 0 moves 10: axis 1 ends at 20."""
    trio = run("BASE(1)\nCONNECT(2, 0)\nBASE(0)\nSPEED = 100\nMOVE(10)\nWAIT IDLE\nWA(5)\nVR(0) = DPOS AXIS(1)\n"
               "CANCEL AXIS(1)\n", until_ms=400)
    assert trio.vr(0) == 20
    for t_ms in (50, 100, 150):
        assert dpos_at(trio, 1, t_ms) == 2 * dpos_at(trio, 0, t_ms - 1)


def test_movelink_moves_its_distance_over_the_link_travel_with_blends() -> None:
    """MOVELINK(10, 20, 5, 5, 0): axis 1 moves 10 while axis 0 travels 20, speeding up over the first 5 and
    slowing down over the last 5 of it; ratio in the middle 10 / (20 - 2.5 - 2.5) = 2/3: when axis 0 has
    travelled 10, axis 1 is at 2/3 x (10 - 2.5) = 5. (Axis 0: 20 units/s reached in 2 ms at 10000 units/s^2,
    so it is at 0.02 k - 0.02 after cycle k: at 10 after the cycle of the tick at 501 ms.)"""
    trio = run("BASE(1)\nMOVELINK(10, 20, 5, 5, 0)\nBASE(0)\nSPEED = 20\nACCEL = 10000\nDECEL = 10000\n"
               "MOVE(30)\nWAIT IDLE\nVR(0) = DPOS AXIS(1)\nVR(1) = IDLE AXIS(1)\n", until_ms=2000)
    assert (trio.vr(0), trio.vr(1)) == (10, -1)
    t, v = trio.sim.trace.edges("trio.axis0.dpos")
    at_ten = int(t[list(v).index(10.0)])  # the tick where axis 0 has travelled 10
    assert trio.sim.trace.value_at("trio.axis1.dpos", at_ten + MS) == 5


def test_cambox_follows_the_table_as_the_link_axis_moves() -> None:
    """TABLE(0, 0, 100, 400, 900), CAMBOX(0, 3, 0.1, 30, 0): the TABLE values times 0.1 are counts; axis 1
    follows them linearly between the points as axis 0 moves 30: 10 per point. At 25 of travel it is at
    (400 + 0.5 x 500) x 0.1 = 65; at the end at 90. (Axis 0 at 10 units/s after 2 ms at 5000 units/s^2.)"""
    trio = run("TABLE(0, 0, 100, 400, 900)\nBASE(1)\nCAMBOX(0, 3, 0.1, 30, 0)\nBASE(0)\nSPEED = 10\n"
               "ACCEL = 5000\nDECEL = 5000\nMOVE(40)\nWAIT IDLE\nVR(0) = DPOS AXIS(1)\n", until_ms=5000)
    assert trio.vr(0) == 90
    t, v = trio.sim.trace.edges("trio.axis0.dpos")
    at_25 = int(t[list(v).index(25.0)])
    assert trio.sim.trace.value_at("trio.axis1.dpos", at_25 + MS) == 65


def test_cam_runs_through_the_table_over_distance_over_speed() -> None:
    """CAM(0, 3, 1, 100) at SPEED 100: one second for the table 0, 100, 400, 900 [counts]; 1/3 s per point.
    At 0.5 s (k = 500 cycles, 1.5 points) it is at 100 + 0.5 x 300 = 250; it ends at 900."""
    trio = run("TABLE(0, 0, 100, 400, 900)\nBASE(0)\nSPEED = 100\nCAM(0, 3, 1, 100)\nWAIT IDLE\nVR(0) = DPOS\n",
               until_ms=1500)
    assert trio.vr(0) == 900
    assert dpos_at(trio, 0, 500) == 250  # the cycle of the tick at 500 ms ends 500 ms after the load at 1 ms


def test_movemodify_shortens_the_move_and_comes_back_when_passed() -> None:
    """MOVE(100) at SPEED 100 from 1 ms. MOVEMODIFY(50) at 200 ms: the move now ends at 50. A second run:
    MOVEMODIFY(10) at 300 ms, when the axis is at 25 (300 cycles run: 100 x 0.3 - 5): it decelerates (5 units
    further, to 30) and comes back to 10."""
    trio = run("BASE(0)\nSPEED = 100\nMOVE(100)\nWA(200)\nMOVEMODIFY(50)\nWAIT IDLE\nVR(0) = DPOS\n", until_ms=1500)
    assert trio.vr(0) == 50
    trio = run("BASE(0)\nSPEED = 100\nMOVE(100)\nWA(300)\nMOVEMODIFY(10)\nWAIT IDLE\nVR(0) = DPOS\n", until_ms=2000)
    assert trio.vr(0) == 10
    assert max(trio.sim.trace.edges("trio.axis0.dpos")[1]) == 30


def test_movemodify_to_the_end_the_move_already_has_changes_nothing() -> None:
    """MOVE(100) at SPEED 100 from 1 ms (ramps of 0.1 s at 1000 units/s^2: 1.1 s, idle at the tick at 1101 ms).
    A loop that gives MOVEMODIFY(100) 20000 times at 200 ms (all within one servo period) re-plans nothing:
    the move still ends at 1101 ms."""
    trio = run("BASE(0)\nSPEED = 100\nMOVE(100)\nWAIT IDLE\nVR(0) = -TICKS\n", until_ms=1500)
    assert trio.vr(0) == 1101
    trio = run("BASE(0)\nSPEED = 100\nMOVE(100)\nWA(200)\nFOR k = 1 TO 20000\n  MOVEMODIFY(100)\nNEXT k\n"
               "WAIT IDLE\nVR(0) = -TICKS\n", until_ms=1500)
    assert trio.vr(0) == 1101


def test_merge_runs_two_moves_without_stopping_between() -> None:
    """MERGE = ON, MOVE(10) twice at SPEED 100, ACCEL = DECEL = 1000: one path of 20, so 0.3 s (0.1 up, 0.1 at
    100, 0.1 down) instead of two triangles of 0.2 s each; VP_SPEED never drops to 0 in between."""
    trio = run("BASE(0)\nSPEED = 100\nMERGE = ON\nMOVE(10)\nMOVE(10)\nWAIT IDLE\nVR(0) = DPOS\nVR(1) = TICKS\n",
               until_ms=800)
    assert (trio.vr(0), trio.vr(1)) == (20, -301)
    _, v = trio.sim.trace.edges("trio.axis0.vp_speed")
    assert [float(x) for x in v[1:-1]].count(0.0) == 0 and max(v) == 100


def test_sramp_smooths_the_acceleration_and_adds_its_time() -> None:
    """SRAMP = 100 (ms): MOVE(10) at SPEED 100, ACCEL = DECEL = 1000 takes 0.2 s without and 0.3 s with it
    (the speed averaged over the S-ramp time); the acceleration ramps: the speed change per cycle grows."""
    trio = run("BASE(0)\nSPEED = 100\nSRAMP = 100\nMOVE(10)\nWAIT IDLE\nVR(0) = DPOS\nVR(1) = TICKS\n", until_ms=600)
    assert (trio.vr(0), trio.vr(1)) == (10, -301)
    _, v = trio.sim.trace.edges("trio.axis0.vp_speed")
    steps = [b - a for a, b in itertools.pairwise(v[1:13])]
    assert all(b > a for a, b in itertools.pairwise(steps))


def test_axisstatus_shows_cancelling() -> None:
    """CANCEL at 50 ms: bit 11 (2048) while the move decelerates."""
    trio = run("BASE(0)\nSPEED = 100\nMOVE(100)\nWA(50)\nCANCEL\nWA(10)\nVR(0) = AXISSTATUS\nWAIT IDLE\n"
               "VR(1) = AXISSTATUS\n", until_ms=300)
    assert (trio.vr(0), trio.vr(1)) == (2048, 0)


def test_regist_latches_the_position_at_the_input_edge() -> None:
    """A stepper (ATYPE 1, UNITS 10) moving at 100 units/s (1000 steps/s: one step each 1 ms from the tick);
    the registration input (input 0 for axis 0) rises at 500.5 ms: REG_POS is the step count there / 10;
    MARK is TRUE; REGIST again makes MARK FALSE."""
    trio = run("BASE(0)\nATYPE = 1\nUNITS = 10\nSPEED = 100\nACCEL = 100000\nDECEL = 100000\nREGIST(1)\n"
               "FORWARD\nWAIT UNTIL MARK\nVR(0) = REG_POS\nVR(1) = MARK\nREGIST(1)\nVR(2) = MARK\nCANCEL\n",
               until_ms=800, inputs={"0": [(0, 0), (500, 1)]})
    steps = int(trio.sim.trace.positions_at("trio.axis0.step", [500 * MS - 100])[0])
    assert (trio.vr(0), trio.vr(1), trio.vr(2)) == (Fraction(steps, 10), -1, 0)


def test_trigger_is_a_marker_in_the_trace() -> None:
    trio = run("TRIGGER\nWA(3)\nTRIGGER\n", until_ms=5)
    t, v = trio.sim.trace.edges("trio.trigger")
    assert list(zip(t.tolist(), v.tolist(), strict=True)) == [(0, 0), (0, 1), (3 * MS, 2)]
