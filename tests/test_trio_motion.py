"""Trio motion: servo cycle, trapezoidal moves, base-group interpolation, stepper pulses per servo cycle."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Generator
from fractions import Fraction
from math import ceil, floor
from typing import Any

import numpy as np
import pytest

from cosim.controllers.trio import ON, TrioController, TrioProcess
from cosim.controllers.trio.basic import BasicProgram
from cosim.controllers.trio.profile import Trapezoid
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import Simulation
from cosim.timebase import Priority

MS = 1_000_000


def stepper(sim: Simulation, *, axes: tuple[int, ...] = (3,), units: int = 16, speed: int = 100,
            accel: int = 1000, decel: int = 1000, servo_period_us: int = 1000) -> tuple[TrioController, TrioProcess]:
    """A controller whose ``axes`` are ATYPE=35 steppers with SERVO=ON and the given parameters."""
    trio = TrioController(sim, servo_period_us=servo_period_us, encoder_at_atype=0)
    p = TrioProcess(trio, base=axes)
    for axis in axes:
        for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", units), ("SPEED", speed), ("ACCEL", accel),
                            ("DECEL", decel)):
            p.set(name, value, axis=axis)
    return trio, p


def host(sim: Simulation, body: Callable[[], Generator[Any, Any, None]]) -> None:
    """Run ``body`` as a program starting at t = 0 with HOST priority (after the servo tick at 0)."""
    def program() -> Generator[Any, Any, None]:
        yield sim.at(0, Priority.HOST)
        yield from body()

    sim.process(program())


def test_move_is_loaded_at_the_next_servo_tick_and_ends_exactly_on_target(sim: Simulation) -> None:
    """MOVE(10) issued at t = 0 (after the servo tick at 0) starts at the 1 ms tick.

    servo   |0        |1 ms     |2 ms ...          |t_s + N*T
    move              [cycle 0  ][cycle 1 ]...[N-1 ] idle
    """
    trio, p = stepper(sim, units=16, speed=100, accel=1000, decel=1000)
    host(sim, lambda: (yield p.move(10)))
    sim.run(until=300 * MS)
    seg = sim.trace.segments("trio.axis3.step")
    profile = Trapezoid.plan(Fraction(10), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000))
    cycles = ceil(profile.t_end / Fraction(1, 1000))
    t_vp, vp = sim.trace.edges("trio.axis3.vp_speed")
    assert t_vp[vp > 0][0] == 1 * MS and t_vp[-1] == (1 + cycles) * MS and vp[-1] == 0
    assert int(seg["count"].sum()) == 160 and set(seg["dir"].tolist()) == {1}
    assert int(seg["t0"][-1]) == cycles * MS  # the last cycle [cycles ms, cycles+1 ms) has pulses
    assert trio.axes[3].dpos == 10 and trio.axes[3].steps == 160 and trio.axes[3].idle


def test_each_cycle_emits_the_step_counter_change_spread_evenly_over_the_cycle(sim: Simulation) -> None:
    """Cycle k: pulses = floor(16 s((k+1)T)) - floor(16 s(kT)); pulse j of n at t_k + floor(j*T/n)."""
    trio, p = stepper(sim, units=16, speed=100, accel=1000, decel=1000)
    host(sim, lambda: (yield p.move(10)))
    sim.run(until=300 * MS)
    profile = Trapezoid.plan(Fraction(10), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000))
    period = Fraction(1, 1000)
    n_cycles = ceil(profile.t_end / period)
    steps = [floor(16 * profile.position(k * period)) for k in range(n_cycles + 1)]
    counts = np.diff(steps)
    t0 = MS + MS * np.arange(n_cycles)
    expected = np.concatenate([t0[k] + (np.arange(c) * MS) // c for k, c in enumerate(counts) if c])
    t_pulses, _ = sim.trace.pulses("trio.axis3.step")
    assert t_pulses.tolist() == expected.tolist()
    assert trio.axes[3].steps == 160


def test_fractional_steps_are_carried_forward_and_back(sim: Simulation) -> None:
    """0.7 counts per cycle: the counter is floor(demand) moving up and ceil(demand) moving down.

    demand  0 0.7 1.4 2.1 ...   counter 0 0 1 2 ...   (never ahead of the demand)
    """
    trio, p = stepper(sim, units=1, speed=700, accel=10**9, decel=10**9)
    log: list[tuple[Fraction, int]] = []

    def watch() -> Generator[Any, Any, None]:
        k = 0
        while True:
            yield sim.at(k * MS, Priority.SAMPLE)
            log.append((trio.axes[3].demand, trio.axes[3].steps))
            k += 1

    def body() -> Generator[Any, Any, None]:
        yield p.move(Fraction(37, 10))
        yield p.wait_idle()
        yield p.move(Fraction(-37, 10))

    host(sim, body)
    sim.process(watch())
    sim.run(until=20 * MS)
    assert all(abs(d - s) < 1 for d, s in log)
    # the counter only moves once the demand has covered a whole step beyond it
    assert all(s1 == s0 or abs(d1 - s0) >= 1 for (_, s0), (d1, s1) in itertools.pairwise(log))
    assert [s for _, s in log[:15]] == [0, 0, 1, 2, 2, 3, 3, 3, 3, 3, 2, 1, 1, 0, 0]
    assert trio.axes[3].steps == 0 and trio.axes[3].demand == 0
    assert sim.trace.segments("trio.axis3.step")["count"].max() == 1


def test_base_group_moves_with_linear_interpolation_and_path_speed(sim: Simulation) -> None:
    """BASE(2,3) MOVE(30,40): a 50-unit path; every cycle axis 2 : axis 3 = 3 : 4 and VP_SPEED <= SPEED."""
    trio, p = stepper(sim, axes=(2, 3), units=4, speed=200, accel=2000, decel=1000)
    samples: list[tuple[Fraction, Fraction, Fraction, Fraction]] = []

    def watch() -> Generator[Any, Any, None]:
        k = 1
        while True:
            yield sim.at(k * MS, Priority.SAMPLE)
            a2, a3 = trio.axes[2], trio.axes[3]
            samples.append((a2.dpos, a3.dpos, a2.vp_speed, a3.vp_speed))
            k += 1

    host(sim, lambda: (yield p.move(30, 40)))
    sim.process(watch())
    sim.run(until=500 * MS)
    assert all(4 * d2 == 3 * d3 for d2, d3, _, _ in samples)
    assert all(v2 == v3 <= 200 for _, _, v2, v3 in samples)
    assert max(v for *_, v in samples) == 200
    assert (trio.axes[2].dpos, trio.axes[3].dpos) == (30, 40)
    assert (trio.axes[2].steps, trio.axes[3].steps) == (120, 160)
    profile = Trapezoid.plan(Fraction(50), speed=Fraction(200), accel=Fraction(2000), decel=Fraction(1000))
    moved = [5 * d3 / 4 for _, d3, _, _ in samples]  # path position from axis 3
    assert moved[:5] == [profile.position(Fraction(k, 1000)) for k in range(1, 6)]


def test_vp_speed_is_the_path_speed_executed_in_the_cycle(sim: Simulation) -> None:
    _trio, p = stepper(sim, speed=100, accel=1000, decel=1000)
    host(sim, lambda: (yield p.move(20)))
    sim.run(until=400 * MS)
    _t, v = sim.trace.edges("trio.axis3.vp_speed")
    profile = Trapezoid.plan(Fraction(20), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000))
    # cycle k of the move (tick (k+1) ms): (s((k+1)T) - s(kT)) / T
    k = np.arange(5)
    s = profile.position
    expected = [float((s(Fraction(int(j) + 1, 1000)) - s(Fraction(int(j), 1000))) * 1000) for j in k]
    assert [sim.trace.value_at("trio.axis3.vp_speed", int(j + 1) * MS) for j in k] == expected
    assert v.max() == 100 and v[-1] == 0


def test_wait_idle_returns_at_the_tick_after_the_last_cycle_and_buffer_holds_one_move(sim: Simulation) -> None:
    """One move may wait in the buffer (NTYPE) while one runs; a further move waits for the buffer.

    servo    0  1ms ........ s1 ........ s2 ........ s2+N
    move 1   q  [== run ===]
    move 2      q (accepted at 1 ms, when move 1 leaves the buffer)
                             [== run ===]            (starts at the tick where move 1 is over)
    move 3                   q (accepted at s1)      [== run ===]
    WAIT IDLE                                                    returns at s2 + N
    """
    trio, p = stepper(sim, speed=100, accel=1000, decel=1000)
    log: list[tuple[str, int]] = []

    def body() -> Generator[Any, Any, None]:
        for k in range(3):
            yield p.move(5)
            log.append((f"move {k + 1} accepted", sim.now))
        yield p.wait_idle()
        log.append(("idle", sim.now))

    host(sim, body)
    sim.run(until=1000 * MS)
    profile = Trapezoid.plan(Fraction(5), speed=Fraction(100), accel=Fraction(1000), decel=Fraction(1000))
    cycles = ceil(profile.t_end * 1000)
    start = [MS + k * cycles * MS for k in range(3)]
    assert log == [("move 1 accepted", 0), ("move 2 accepted", start[0]), ("move 3 accepted", start[1]),
                   ("idle", start[2] + cycles * MS)]
    t_vp, vp = sim.trace.edges("trio.axis3.vp_speed")
    assert [float(vp[t_vp == s][0]) for s in start] == [0.5, 0.5, 0.5]  # first cycle of each move: A*T/2
    assert trio.axes[3].dpos == 15


def test_defpos_applies_at_next_tick_after_moves_are_loaded(sim: Simulation) -> None:
    """DEFPOS(100) then MOVEABS(110) at once: the move is loaded with the old position (TRM 8-30).

    With WAIT UNTIL OFFPOS=0 between them the move is 10 units, as the manual recommends.
    """
    text = "BASE(3)\nATYPE=35\nSERVO=ON\nDEFPOS(100)\n{wait}MOVEABS(110)\nWAIT IDLE\n"
    ends = []
    for wait in ("", "WAIT UNTIL OFFPOS=0\n"):
        s = Simulation(seed=1)
        trio = TrioController(s, encoder_at_atype=0)
        BasicProgram.parse(text.format(wait=wait)).start(trio)
        s.run(until=3000 * MS)
        ends.append((trio.axes[3].dpos, trio.axes[3].steps))
    assert ends[0] == (210, 110)  # moved 110 units in the old frame, then shifted by +100
    assert ends[1] == (110, 10)


def test_mpos_counts_pulses_only_with_servo_on(sim: Simulation) -> None:
    trio, p = stepper(sim, units=2, speed=100, accel=1000, decel=1000)

    def body() -> Generator[Any, Any, None]:
        yield p.move(10)
        yield p.wait_idle()
        p.set("SERVO", 0)
        yield p.move(5)
        yield p.wait_idle()

    host(sim, body)
    sim.run(until=1000 * MS)
    assert trio.axes[3].steps == 30
    assert trio.get_param("MPOS", axis=3) == 10 and trio.get_param("DPOS", axis=3) == 15
    assert trio.gate(3).encoder_value() == 20


def test_following_error_beyond_fe_limit_stops_with_a_motion_error(sim: Simulation) -> None:
    _trio, p = stepper(sim, units=1, speed=100, accel=1000, decel=1000)
    p.set("FE_LIMIT", Fraction(1, 2))
    host(sim, lambda: (yield p.move(10)))
    with pytest.raises(TimingViolation, match=r"trio.axis3: following error .* exceeds FE_LIMIT = 0.5"):
        sim.run(until=100 * MS)


@pytest.mark.parametrize("period_us", [250, 500, 1000, 2000])
def test_servo_ticks_are_k_times_the_servo_period(sim: Simulation, period_us: int) -> None:
    trio, p = stepper(sim, servo_period_us=period_us, speed=1000, accel=10**6, decel=10**6, units=1)
    host(sim, lambda: (yield p.move(50)))
    sim.run(until=100 * MS)
    t0 = sim.trace.segments("trio.axis3.step")["t0"]
    t_vp, _vp = sim.trace.edges("trio.axis3.vp_speed")
    assert (t0 % (period_us * 1000) == 0).all() and (t_vp % (period_us * 1000) == 0).all()
    assert int(t_vp[1]) == period_us * 1000  # loaded at the first tick after t = 0
    assert trio.get_param("SERVO_PERIOD") == period_us


@pytest.mark.parametrize("period_us", [100, 300, 1500])
def test_unsupported_servo_period_is_refused(sim: Simulation, period_us: int) -> None:
    with pytest.raises(ConfigurationError, match=rf"SERVO_PERIOD = {period_us} is not allowed "
                                                 r"\(allowed: 250, 500, 1000, 2000 us\)"):
        TrioController(sim, servo_period_us=period_us)


def test_move_needs_a_positive_speed(sim: Simulation) -> None:
    _trio, p = stepper(sim)
    p.set("SPEED", 0)
    with pytest.raises(ConfigurationError, match=r"SPEED of axis 3 for MOVE = 0 is not allowed \(allowed: > 0\)"):
        p.move(1)
