"""The host planner for G-code: exact end points in steps, never over the engine's 25 pulses per slot.

    program ──read_program──> Toolpath ──plan_toolpath──> per-slot counts (x, y, z)
                                          │ exact stop: every segment ends at rest
                                          │ blend: corners at the junction-deviation speed
                                          └ a feed the axes cannot run is slowed, with a note
"""

from __future__ import annotations

import doctest
import math
from fractions import Fraction
from itertools import accumulate, pairwise

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim.controllers.pokeys import PulseEngine, pathplan, planner, profile
from cosim.controllers.pokeys.config import uniform_axes
from cosim.controllers.pokeys.gcode import read_program
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.pathplan import HostAxis, PathSettings, plan_toolpath
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.controllers.pokeys.trajectory import Segment, profile_chain
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation

AXES = [HostAxis(400, 100, 1000, name=a) for a in "xyz"]  # 400 steps/mm, 100 mm/s (above 25 kHz), 1000 mm/s^2
MODES = ("exact_stop", "blend")


def _plan(text: str, mode: str = "exact_stop", axes: list[HostAxis] = AXES, **kw: object):  # type: ignore[no-untyped-def]
    return plan_toolpath(read_program(text), axes, settings=PathSettings(mode=mode, **kw))  # type: ignore[arg-type]


def _ends(counts: list[tuple[int, ...]]) -> tuple[int, ...]:
    return tuple(sum(c[a] for c in counts) for a in range(3))


PROGRAMS = {
    # absolute, arcs in both forms and directions, ends away from the origin: X12.3456 Y-7.891 Z-1.25
    "absolute": ("G21 G90 G0 Z2\nG0 X5 Y5\nG1 Z-1.25 F300\nG1 X20.0013 F900\nG3 X30.0013 Y15 I0 J10\n"
                 "G2 X40.0013 Y5 R-10\nG2 X40.0013 Y5 I-5 J0\nG1 X12.3456 Y-7.891 F1500\nM2\n", (4938, -3156, -500)),
    # incremental: three half circles to the right, a helix down and back (G91 arcs), then up
    "incremental": ("G21 G91 G1 X1 F1200\nG2 X10 Y0 I5 J0\nG2 X10 Y0 I5 J0\nG3 X10 Y0 I5 J0\n"
                    "G2 X0 Y0 Z-2 I-3 J0\nG1 Z0.5\nM30\n", (12400, 0, -600)),
    # inches on a mm machine and a G92 offset: the end is 10 mm + X1.2345 in = 41.3563 mm, 10 mm + Y-0.5 in = -2.7 mm
    "inch_g92": ("G21 G0 X10 Y10\nG92 X0 Y0\nG20 G90 G1 X1 Y0.5 F20\nG2 X1.2345 Y-0.5 R0.8\nM2\n",
                 (16543, -1080, 0)),
}


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_final_step_positions_equal_the_program_end_point(name: str, mode: str) -> None:
    text, end = PROGRAMS[name]
    job = _plan(text, mode)
    assert job.end_steps == end
    assert _ends(job.counts) == end
    assert max(abs(c) for slot in job.counts for c in slot) <= 25


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_the_engine_counters_end_on_the_program_end_point(name: str, mode: str) -> None:
    """The same programs streamed over USB into a 56E: the position counters end on the end point."""
    text, end = PROGRAMS[name]
    job = _plan(text, mode)
    with Simulation(seed=3) as sim:
        engine = PulseEngine(sim)
        host = HostApp(sim, engine, to_entries(job.counts), link="usb", prefill_slots=64)
        sim.run(until=(len(job.counts) + 200) * 1_000_000)
        assert host.finished and engine.underruns == [] and engine.status().positions == end


def test_incremental_moves_accumulate_exact_positions_not_rounded_steps() -> None:
    """1000 moves of X+0.0013 Y-0.0021 mm at 400 steps/mm end at X1.3 Y-2.1 = 520, -840 steps.

    Rounding each move to steps would give 1000 x round(0.52) = 1000 and 1000 x round(-0.84) = -1000.
    """
    job = _plan("G21 G91 F600\n" + "G1 X0.0013 Y-0.0021\n" * 1000)
    assert job.end_steps == (520, -840, 0) and _ends(job.counts) == (520, -840, 0)


def test_a_feed_the_engine_cannot_emit_is_slowed_to_25_pulses_per_slot_and_said_so() -> None:
    job = _plan("G1 X100 F6000\n", axes=[HostAxis(400, 200, 1000, name=a) for a in "xyz"])
    assert job.notes == ("program.nc:1: feed 6000 mm/min needs 40000 pulses/s on x, more than the engine's 25 "
                         "pulses per slot: slowed to 3750 mm/min",)
    assert max(c[0] for c in job.counts) == 25 and _ends(job.counts) == (40_000, 0, 0)
    slow = _plan("G1 X100 F6000\n", axes=[HostAxis(400, 50, 1000, name=a) for a in "xyz"])
    assert slow.notes == ("program.nc:1: feed 6000 mm/min needs 40000 pulses/s on x, more than its max_velocity "
                          "50 mm/s: slowed to 3000 mm/min",)
    assert max(c[0] for c in slow.counts) == 20  # 50 mm/s x 400 steps/mm = 20 pulses per slot


def test_feed_override_and_a_lower_max_velocity_change_the_time_as_expected() -> None:
    """100 mm at F1200 (20 mm/s) and 1000 mm/s^2: 5000 slots of cruise + 20 of ramps; at half the feed 10000 + 10."""
    full = _plan("G1 X100 F1200\n")
    half = plan_toolpath(read_program("G1 X100 F1200\n"), AXES, settings=PathSettings(feed_override=Fraction(1, 2)))
    assert abs(len(full.counts) - 5020) <= 2 and abs(len(half.counts) - 10_010) <= 2
    fast = _plan("G0 X100\n", axes=[HostAxis(400, 50, 1000, name=a) for a in "xyz"])  # rapids: not overridden
    slow = _plan("G0 X100\n", axes=[HostAxis(400, 25, 1000, name=a) for a in "xyz"])
    assert abs(len(fast.counts) - 2050) <= 2 and abs(len(slow.counts) - 4025) <= 2


def test_exact_stop_ends_each_side_of_a_square_at_rest_and_blending_passes_the_corner() -> None:
    """Corner speed of blending: a = 1000 mm/s^2, tolerance 0.05 mm, 90 deg: v^2 = a * 0.05 * s/(1-s),
    s = sin 45 deg, v = 10.99 mm/s = 4.4 pulses per slot."""
    square = "G1 X10 F1200\nY10\nX0\nY0\n"
    exact, blend = _plan(square, "exact_stop"), _plan(square, "blend", tolerance=Fraction(5, 100))
    assert _ends(exact.counts) == _ends(blend.counts) == (0, 0, 0)
    # exact stop: no slot moves x and y together (the path lands on each corner at a slot end)
    assert not any(c[0] and c[1] for c in exact.counts)
    # blending: the slot that passes the first corner moves both, and the path never stops there
    first_y = next(i for i, c in enumerate(blend.counts) if c[1])
    assert blend.counts[first_y][0] > 0
    around = blend.counts[first_y - 3:first_y + 3]
    assert all(4 <= abs(c[0]) + abs(c[1]) <= 6 for c in around)
    assert len(blend.counts) < len(exact.counts)
    # the blended corner is slower than the 8-pulse feed (20 mm/s) but not a stop
    assert max(abs(c[0]) + abs(c[1]) for c in blend.counts) == 8


def test_arcs_are_chords_within_the_tolerance() -> None:
    """R = 10 mm, tolerance 0.01 mm: chords of at most 2 acos(1 - 0.001) = 0.0894 rad: 18 per quarter, 71 per turn."""
    quarter = _plan("G0 X10\nG3 X0 Y10 I-10 J0 F600\n", arc_tolerance=Fraction(1, 100))
    full = _plan("G0 X10\nG3 I-10 F600\n", arc_tolerance=Fraction(1, 100))
    assert (quarter.segments, full.segments) == (1 + 18, 1 + 71)
    x = list(accumulate(c[0] for c in full.counts))
    y = list(accumulate(c[1] for c in full.counts))
    start = next(i for i, c in enumerate(full.counts) if c[1])  # the circle starts with the first y step
    radii = [math.hypot(xs, ys) / 400 for xs, ys in zip(x[start:], y[start:], strict=True)]
    assert all(abs(r - 10) <= 0.01 + 1.5 / 400 for r in radii)


def test_dwell_and_spindle_changes_stop_the_path_and_mark_their_slot() -> None:
    job = _plan("M3 S1000\nG1 X1 F600\nG4 P0.25\nM5\nG1 X0\nS200\n")
    (on_at, on), (off_at, off), (speed_at, speed) = job.outputs
    assert (on_at, on.on, on.speed) == (0, True, 1000)
    moving = [i for i, c in enumerate(job.counts) if any(c)]
    first_move_end = max(i for i in moving if i < off_at) + 1
    assert off_at == first_move_end + 250 and not any(any(c) for c in job.counts[first_move_end:off_at])
    assert not off.on and speed_at == len(job.counts) and speed.speed == 200


@pytest.mark.parametrize("module", [pathplan, profile, planner])
def test_the_docstring_examples_hold(module: object) -> None:
    failures, tried = doctest.testmod(module)  # type: ignore[arg-type]
    assert failures == 0 and tried > 0


def test_bad_planner_settings_are_refused() -> None:
    with pytest.raises(ConfigurationError, match=r"mode = 'round' is not allowed \(allowed: exact_stop, blend\)"):
        PathSettings(mode="round")
    with pytest.raises(ConfigurationError, match=r"feed_override = 0 is not allowed"):
        PathSettings(feed_override=0)
    with pytest.raises(ConfigurationError, match=r"axis z: steps_per_unit = -1 is not allowed"):
        HostAxis(-1, 10, 10, name="z")


def test_one_planner_moves_in_pulses_use_the_same_rule() -> None:
    """plan() of straight moves is the one-segment chain of the tool-path planner."""
    axes = uniform_axes(max_speed_hz=24_000, accel=400_000, decel=400_000)
    counts = plan([Move((5_000, -3_000, 1_000))], axes)
    from cosim.controllers.pokeys.profile import SlotLimits

    limits = SlotLimits.exact(Fraction(24), Fraction(2, 5), Fraction(2, 5))
    chain = profile_chain([Segment((0, 0, 0), (5_000, -3_000, 1_000), 5_000 * limits.scale, limits.vmax,
                                   limits.accel, limits.decel)])
    assert counts == chain and _ends(counts) == (5_000, -3_000, 1_000)


# -- any program the planner accepts ------------------------------------------------------------
_coord = st.decimals(min_value=-40, max_value=40, places=3)


@st.composite
def programs(draw: st.DrawFn) -> str:
    lines = ["G21 G90"]
    x = y = Fraction(0)
    for _ in range(draw(st.integers(1, 5))):
        feed = draw(st.integers(60, 20_000))  # from 1 mm/min a 60 mm arc is 3.7 million slots: slow, not harder
        kind = draw(st.sampled_from(["G0", "G1", "G2", "G3"]))
        nx, ny, nz = (Fraction(draw(_coord)) for _ in range(3))
        if kind in ("G2", "G3"):  # centre offsets; the end goes on the circle through the start
            i, j = Fraction(draw(_coord)) / 4, Fraction(draw(_coord)) / 4
            if i == j == 0:
                i = Fraction(1)
            radius = math.hypot(i, j)
            angle = draw(st.floats(0, 2 * math.pi))
            cx, cy = x + i, y + j
            nx = cx + Fraction(round(radius * math.cos(angle), 6)).limit_denominator(10**6)
            ny = cy + Fraction(round(radius * math.sin(angle), 6)).limit_denominator(10**6)
            lines.append(f"{kind} X{float(nx):.6f} Y{float(ny):.6f} Z{float(nz)} I{float(i)} J{float(j)} F{feed}")
            nx, ny = Fraction(f"{float(nx):.6f}"), Fraction(f"{float(ny):.6f}")
        else:
            lines.append(f"{kind} X{float(nx)} Y{float(ny)} Z{float(nz)} F{feed}")
        x, y = nx, ny
    return "\n".join(lines) + "\n"


@settings(max_examples=50, deadline=None, database=None, derandomize=True,  # the same 50 programs every run
          suppress_health_check=[HealthCheck.too_slow])
@given(text=programs(), mode=st.sampled_from(MODES), spu=st.sampled_from([80, 200, 320, 400, 1600]),
       velocity=st.integers(5, 200), accel=st.integers(50, 5000))
def test_no_slot_exceeds_the_engine_limit_and_every_program_ends_exactly(text: str, mode: str, spu: int,
                                                                       velocity: int, accel: int) -> None:
    axes = [HostAxis(spu, velocity, accel, name=a) for a in "xyz"]
    toolpath = read_program(text)
    job = plan_toolpath(toolpath, axes, settings=PathSettings(mode=mode))
    per_slot = min(Fraction(spu * velocity, 1000), Fraction(25))
    assert all(abs(c) <= math.ceil(per_slot) for slot in job.counts for c in slot[:3])  # a fraction: its ceiling
    assert max((abs(c) for slot in job.counts for c in slot), default=0) <= 25
    assert _ends(job.counts) == job.end_steps == tuple(a.steps(p) for a, p in zip(axes, toolpath.end, strict=True))
    if mode == "exact_stop":  # within the acceleration limit on every axis, up to the rounding of two slots
        step = math.ceil(Fraction(spu * accel, 10**6)) + 1
        for axis in range(3):
            counts = [slot[axis] for slot in job.counts]
            # a reversal at an exact stop: the last slot of one segment (<= decel) meets the first of the next
            assert all(abs(b - a) <= (step if a * b >= 0 else 2 * step) for a, b in pairwise(counts))


@pytest.mark.parametrize("mode", MODES)
def test_a_job_longer_than_4_hours_of_slots_is_refused_with_its_length_not_planned_into_the_memory(mode: str) -> None:
    """G1 X1000 F1 takes 1000 min = 16.7 h (60,000,000 slots of 1 ms): refused before its slots are made; the
    fuzzed arc that met this (I-18513 at F33, 58 h) filled 24 GB and was killed."""
    with pytest.raises(ConfigurationError, match=r"more than 14,400,000 slots \(4 hours of 1 ms slots\)"):
        _plan("G1 X1000 F1\n", mode)
    with pytest.raises(ConfigurationError, match=r"more than 14,400,000 slots"):
        _plan("G1 X-30.7 F33\nG3 X-28.091 Y-31.169 I-18513 J16.782\n", mode)
