"""More axes (issue 26, item 7): A, B, C (degrees) and U, V on the PoKeys models that drive them.

    [controller] model = "57CNC"   x, y, z, a, b, c, u, v   (the 56E, 56U, 57E: x, y, z)
    [controller.axis.a] steps_per_unit / max_velocity / max_accel  ->  A words plan and stream like X

The numbers are LinuxCNC's. Its reference ("Feed Rate"): "If any of XYZ are moving, F is in units per
minute in the XYZ cartesian system, and all other axes (ABCUVW) move so as to start and stop in
coordinated fashion. Otherwise, if any of UVW are moving, F is in units per minute in the UVW cartesian
system ... Otherwise, the move is pure rotary motion and the F word is in rotary units in the ABC
pseudo-cartesian system"; ("Units") "The positions of rotational axes are measured in degrees",
G20/G21 change the units of X, Y, Z (and U, V, W) only. rs274 2.9 for ``G20 / G1 X1 A90 F10 / G92 A10 /
G1 A0 F600 / G2 X0 Y1 I-0.5 J0.5 A45 F10``: ``STRAIGHT_FEED(1, 0, 0, 90, 0, 0)``,
``SET_G92_OFFSET(0, 0, 0, 80, 0, 0)`` (degrees: not scaled by G20), ``STRAIGHT_FEED(1, 0, 0, 0, 0, 0)``,
``ARC_FEED(0, 1, 0.5, 0.5, -1, 0, 45, 0, 0)``.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest
from gcode_machines import ROUTER_AXES

from cosim.controllers.pokeys.gcode import HostSetup, canonical, read_program, read_text
from cosim.controllers.pokeys.pathplan import HostAxis, plan_toolpath
from cosim.controllers.pokeys.toolpath import Arc, Line, feed_axes
from cosim.errors import ConfigurationError
from cosim.machine import load_machine
from cosim.machine.check import check_machine
from cosim.runner import run_scenario

F = Fraction
MACHINE = f"""
[machine]
until = "12 s"

[controller]
family = "pokeys"
model = "57CNC"
{ROUTER_AXES}[controller.axis.a]
steps_per_unit = 100        # steps per degree
max_velocity = 360          # degrees/s
max_accel = 3600            # degrees/s^2
[controller.axis.u]
steps_per_unit = 200
max_velocity = 50
max_accel = 1000

[host]
link = "ethernet"

[[program]]
file = "job.nc"
"""


@pytest.fixture
def machine(tmp_path: Path) -> Path:
    path = tmp_path / "job.toml"
    path.write_text(MACHINE)
    return path


def figures(machine: Path, program: str) -> dict[str, float]:
    (machine.parent / "job.nc").write_text(program)
    result = run_scenario(load_machine(machine))
    assert result.verdict == "PASS", result.table()
    return {name: figure["value"] for name, figure in result.figures.items()}


def test_the_feed_axes_are_xyz_else_uvw_else_abc_as_the_reference_says() -> None:
    zero = (F(0),) * 5
    assert feed_axes(zero, (F(1), F(0), F(0), F(90), F(0)), "xyzau") == "xyz"
    assert feed_axes(zero, (F(0), F(0), F(0), F(90), F(3)), "xyzau") == "uvw"
    assert feed_axes(zero, (F(0), F(0), F(0), F(90), F(0)), "xyzau") == "abc"
    assert feed_axes(zero, zero, "xyzau") == ""


def test_rotary_moves_are_in_degrees_and_a_pure_rotary_feed_is_in_degrees_per_minute() -> None:
    """G20 on a mm machine: X1 is 25.4 mm at 10 in/min (XYZ moves: F along XYZ); A stays in degrees, G92 A10 at A90
    is an offset of 80 degrees (rs274), G1 A0 F600 turns from 90 to 80 degrees at 600 degrees/min = 10 deg/s (not
    scaled by G20), and the arc's A45 ends at 125 degrees, reached linearly with the angle."""
    path = read_program("G20\nG1 X1 A90 F10\nG92 A10\nG1 A0 F600\nG2 X0 Y1 I-0.5 J0.5 A45 F10\nM2\n", axes="xyza",
                        host=HostSetup(units="mm", axes="xyza"))
    moves = [s for s in path.steps if isinstance(s, Line | Arc)]
    assert path.axes == "xyza" and path.notes == ()
    assert (moves[0].end, moves[0].feed) == ((F(254, 10), 0, 0, 90), F(254, 10) * 10 / 60)  # mm/s along X
    assert (moves[1].end, moves[1].feed) == ((F(254, 10), 0, 0, 80), F(600, 60))  # deg/s: pure rotary
    arc = moves[2]
    assert isinstance(arc, Arc) and arc.end == (0, F(254, 10), 0, 125) and arc.feed == F(254, 10) * 10 / 60


def test_a_rotary_axis_moves_with_x_and_f_is_along_x(machine: Path) -> None:
    """G1 X10 A90 F600: 10 mm at 600 mm/min = 1 s, A turns its 90 degrees in the same second: x at 10 mm/s x 400 =
    4000 Hz, a at 90 deg/s x 100 steps/deg = 9000 Hz. The path accelerates at 3600 deg/s^2 x 10 mm / 90 deg =
    400 mm/s^2 (a's limit, below x's 1000), so the job is 1 s + 10 / 400 s = 1.025 s."""
    f = figures(machine, "G21 G1 X10 A90 F600\nM2\n")
    assert (f["x_peak_hz"], f["a_peak_hz"], f["u_peak_hz"]) == (4000, 9000, 0)
    assert f["job_duration_s"] == pytest.approx(1.025, abs=0.002)


def test_a_pure_rotary_move_runs_at_f_degrees_per_minute_in_g20_and_g21(machine: Path) -> None:
    """G1 A90 F600 with no XYZ motion: 600 degrees/min = 10 deg/s, 9 s (+ 10 / 3600 s of ramp), a at 1000 Hz; the
    same in G20 (degrees do not change with the length units)."""
    for units in ("G21", "G20"):
        f = figures(machine, f"{units} G1 A90 F600\nM2\n")
        assert (f["a_peak_hz"], f["x_peak_hz"]) == (1000, 0)
        assert f["job_duration_s"] == pytest.approx(9.0028, abs=0.002)


def test_without_xyz_motion_f_is_along_uvw(machine: Path) -> None:
    """G1 U10 A90 F600: U moves, XYZ does not: F is along U, 10 mm in 1 s (u at 10 mm/s x 200 = 2000 Hz), A its
    90 degrees in the same second (9000 Hz)."""
    f = figures(machine, "G21 G1 U10 A90 F600\nM2\n")
    assert (f["u_peak_hz"], f["a_peak_hz"], f["x_peak_hz"]) == (2000, 9000, 0)
    assert f["job_duration_s"] == pytest.approx(1.025, abs=0.002)


def test_the_rotary_counters_end_on_the_programmed_angle(machine: Path) -> None:
    """-45.5 degrees x 100 steps/degree = -4550 steps, whatever the moves before (G91 A90, A-30)."""
    machine.write_text(MACHINE + '[[check]]\ntype = "ValueAt"\nsignal = "pokeys.a.position"\nexpected = -4550\n')
    (machine.parent / "job.nc").write_text("G21 G91\nG0 A90\nG1 A-30 F3600\nG90 G0 A-45.5\nM2\n")
    result = run_scenario(load_machine(machine))
    assert result.verdict == "PASS" and len(result.checks) == 2, result.table()


def test_a_corner_between_moves_fed_along_different_axes_is_an_exact_stop() -> None:
    """G64 blends X+A into X (both fed along X) but stops between X+A and a pure rotary move (fed in degrees): the
    second pair plans as long under G64 P1 as under G61.1."""
    axes = [*(HostAxis(400, 50, 1000, name=a) for a in "xyz"), HostAxis(100, 360, 3600, name="a")]

    def slots(text: str) -> int:
        path = read_program(text, axes="xyza", host=HostSetup(axes="xyza"))
        return len(plan_toolpath(path, axes, n_axes=8, max_pulses_per_slot=125).counts)

    same_feed_axes = "G21\n{}\nG1 X10 A90 F600\nG1 X20 A135\nM2\n"
    other_feed_axes = "G21\n{}\nG1 X10 A90 F600\nG1 A180 F3600\nM2\n"
    assert slots(same_feed_axes.format("G64 P1")) < slots(same_feed_axes.format("G61.1"))
    assert slots(other_feed_axes.format("G64 P1")) == slots(other_feed_axes.format("G61.1"))


@pytest.mark.parametrize(("model", "program", "message"), [
    ("56E", "G21\nG0 X1 A90\n", r"job.nc:2:7: A word: a PoKeys56E has no A axis \(its pulse engine drives 3 axes: "
                                r"x, y, z; a PoKeys57CNC drives x, y, z, a, b, c, u, v\)"),
    ("57E", "G21\nG0 X1 C90\n", r"job.nc:2:7: C word: a PoKeys57E has no C axis"),
    ("57CNC", "G21\nG0 B10\n", r"job.nc:2:4: B word: the B axis of this PoKeys57CNC is not a G-code axis: give "
                               r"steps_per_unit, max_velocity, max_accel in .*job.toml: \[controller.axis.b\]"),
    ("57CNC", "G21\nG0 W10\n", r"job.nc:2:4: W word: a PoKeys57CNC has no W axis \(its pulse engine drives 8 axes: "
                               r"x, y, z, a, b, c, u, v\) \(LinuxCNC: Bad character 'w' used\)"),
])
def test_an_axis_word_the_machine_cannot_run_is_refused_naming_word_place_and_model(
        machine: Path, model: str, program: str, message: str) -> None:
    text = MACHINE.replace('model = "57CNC"', f'model = "{model}"')
    if model != "57CNC":
        text = text.split("[controller.axis.a]")[0] + "[host]" + text.split("[host]")[1]
    machine.write_text(text)
    (machine.parent / "job.nc").write_text(program + "M2\n")
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(machine))


def test_a_partly_tuned_extra_axis_is_refused(machine: Path) -> None:
    machine.write_text(MACHINE.replace("[controller.axis.u]\nsteps_per_unit = 200\n", "[controller.axis.u]\n"))
    (machine.parent / "job.nc").write_text("G21 G0 X1\nM2\n")
    with pytest.raises(ConfigurationError, match=r"job.toml: controller.axis.u.steps_per_unit is missing \(a G-code "
                                                 r"program needs steps_per_unit, max_velocity, max_accel on a G-code "
                                                 r"axis u \(units\)\)"):
        check_machine(load_machine(machine))


def test_the_interpreter_alone_refuses_an_axis_it_was_not_given() -> None:
    with pytest.raises(ConfigurationError, match=r"p.nc:1:7: U word: the machine has no U axis \(its axes: X, Y, Z, "
                                                 r"A\) \(LinuxCNC: Bad character 'u' used\)"):
        canonical(read_text("G0 X1 U2\nM2\n", source="p.nc"), axes="xyza")
