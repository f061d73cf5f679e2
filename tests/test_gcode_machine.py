"""G-code jobs in machine files: the router example, --set on the planner's keys, bad programs through the CLI.

    router.toml ──[[program]] pocket.nc──> plan (blend) ──HostApp (USB)──> engine ──> 3 NEMA 23 steppers
    job.toml (no plants) for the fast cases: time with feed_override / max_velocity, exit 2 with file:line

JobWatch, the spindle outputs on the engine's slots (job: 300 slots of 10 pulses, prefill 20,
host stall 100..160 ms as in test_pokeys_host.py):

    t [ms]        2     52            120 .. 161 underrun          243          342   343
    entry taken   0     50            (none)                       200          299
    spindle.on    1                                                0                  1 (M4, after the job)
    spindle.speed 100   200                                                           5
"""

from __future__ import annotations

import json
import re
from fractions import Fraction
from pathlib import Path

import pytest
from gcode_machines import ROUTER_AXES

from cosim.cli import main
from cosim.controllers.pokeys import PulseEngine, encode_entry
from cosim.controllers.pokeys.host import HostApp, Stall
from cosim.controllers.pokeys.job import JobWatch
from cosim.controllers.pokeys.link import LinkProfile
from cosim.controllers.pokeys.toolpath import Spindle
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.machine import load_machine
from cosim.machine.check import check_machine
from cosim.runner import run_scenario

ROUTER = Path(__file__).resolve().parent.parent / "examples" / "pokeys_router" / "router.toml"
MS = 1_000_000

JOB = f"""
[machine]
until = "12 s"

[controller]
family = "pokeys"
{ROUTER_AXES}
[host]
link = "ethernet"
feed_override = 1.0
path_mode = "exact_stop"

[[program]]
file = "job.nc"

[[check]]
type = "ValueAt"
signal = "pokeys.x.position"
expected = 40000
"""


@pytest.fixture
def job_machine(tmp_path: Path) -> Path:
    (tmp_path / "job.nc").write_text("G21 G90\nG1 X100 F1200\nM2\n")
    path = tmp_path / "job.toml"
    path.write_text(JOB)
    return path


def test_feed_override_and_max_velocity_change_the_job_time_as_expected(job_machine: Path) -> None:
    """100 mm at F1200 = 20 mm/s, 1000 mm/s^2: 5.02 s; at half the feed 10.01 s; G0 at 50 or 25 mm/s: 2.05, 4.025 s."""
    full = run_scenario(load_machine(job_machine))
    half = run_scenario(load_machine(job_machine), overrides={"feed_override": "0.5"})
    assert full.verdict == half.verdict == "PASS", (full.table(), half.table())
    assert half.parameters["host"]["feed_override"] == 0.5
    assert full.figures["job_duration_s"]["value"] == pytest.approx(5.02, abs=0.0025)
    assert half.figures["job_duration_s"]["value"] == pytest.approx(10.01, abs=0.0025)
    (job_machine.parent / "job.nc").write_text("G21 G90\nG0 X100\nM2\n")
    fast = run_scenario(load_machine(job_machine))
    slow = run_scenario(load_machine(job_machine), overrides={"x.max_velocity": "25"})
    assert fast.figures["job_duration_s"]["value"] == pytest.approx(2.05, abs=0.0025)
    assert slow.figures["job_duration_s"]["value"] == pytest.approx(4.025, abs=0.0025)
    assert fast.figures["x_peak_hz"]["value"] == 20_000 and slow.figures["x_peak_hz"]["value"] == 10_000


def test_a_feed_over_25_pulses_per_slot_is_slowed_and_the_result_says_so(job_machine: Path, tmp_path: Path) -> None:
    (job_machine.parent / "job.nc").write_text("G21 G90\nG1 X100 F6000\nM2\n")
    result = run_scenario(load_machine(job_machine), overrides={"x.max_velocity": "200"}, out=tmp_path / "out")
    assert result.verdict == "PASS", result.table()
    assert result.figures["slowed_lines"]["value"] == 1 and result.figures["x_peak_hz"]["value"] == 25_000
    # 0.4 pulses/slot^2 (1000 mm/s^2 x 400): each ramp to 25 pulses/slot covers 25^2 / 0.8 = 781 pulses,
    # so (40000 - 2 x 781) / 25 = 1537.5 slots at the limit, within a few slots of the ramps' quantisation
    assert 1536 <= result.figures["slots_at_limit"]["value"] <= 1541
    meta = json.loads((tmp_path / "out" / "trace_meta.json").read_text())
    assert meta["meta"]["gcode"]["notes"] == [f"{job_machine.parent / 'job.nc'}:2: feed 6000 mm/min needs 40000 "
                                              "pulses/s on x, more than the engine's 25 pulses per slot: slowed to "
                                              "3750 mm/min"]
    assert result.notes == meta["meta"]["gcode"]["notes"]  # in result.json and the terminal table too
    assert "note " + result.notes[0] in result.table()


def test_unsupported_words_can_be_skipped_and_are_listed_and_the_geometry_words_stay(job_machine: Path,
                                                                                    tmp_path: Path) -> None:
    """``G21 G90 M101``: M101 (a user M code) is skipped; G21 and G90 on its line still act (X100 mm)."""
    (job_machine.parent / "job.nc").write_text("G20\nG21 G90 M101\nG1 X100 F1200\nM2\n")
    with pytest.raises(ConfigurationError, match=r"job.nc:2:9: M101 is a user M code"):
        check_machine(load_machine(job_machine))
    result = run_scenario(load_machine(job_machine), overrides={"host.allow_unsupported": "true"}, out=tmp_path / "o")
    assert result.verdict == "PASS" and result.figures["skipped_words"]["value"] == 1
    meta = json.loads((tmp_path / "o" / "trace_meta.json").read_text())
    (skipped,) = meta["meta"]["gcode"]["skipped"]
    assert skipped.startswith(f"{job_machine.parent / 'job.nc'}:2:9: M101: M101 is a user M code")
    assert skipped.endswith("; word skipped")
    assert result.notes == ["skipped: " + skipped]


@pytest.mark.parametrize(("program", "message"), [
    ("G21\nG0 X1\nG38.2 Z-2 F100\n", r"job.nc:3:1: G38.2 needs a probe input: add probe = true to \[host\]"),
    ("G21\nM3 S100\nG33 Z-5 K1\n", r"job.nc:3:1: G33 \(spindle-synchronised motion\) needs a spindle encoder"),
    ("G21\nG0 X10\nG2 X0 Y0 I-4 J0 F100\n", r"job.nc:3:10: Radius to end of arc differs from radius to start"),
    ("G21\nG0 X10\nG1 X0 Y0\n", r"job.nc:3:1: Cannot do G1 with zero feed rate"),
    ("[machine]\nuntil = \"1 s\"\n", r"job.nc:1:1: not G-code"),
    ("o100 call\nM2\n", r"job.nc:1:6: O-word `call` o100: the subroutine is not defined"),
])
@pytest.mark.parametrize("command", ["run", "check-machine"])
def test_bad_programs_exit_2_with_file_line_and_reason(job_machine: Path, tmp_path: Path, program: str,
                                                       message: str, command: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    (job_machine.parent / "job.nc").write_text(program)
    args = [command, str(job_machine)] + (["--out", str(tmp_path / "o")] if command == "run" else [])
    assert main(args) == 2
    captured = capsys.readouterr()
    assert re.search(message, captured.out + captured.err)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda t: t.replace("[controller.axis.z]\nsteps_per_unit = 400\n", "[controller.axis.z]\n"),
     r"job.toml: controller.axis.z.steps_per_unit is missing \(a G-code program needs steps_per_unit, max_velocity, "
     r"max_accel on the x, y, z axes\)"),
    (lambda t: t + "\n[[move]]\ntarget = [1, 2, 3]\n",
     r"a machine runs either a G-code \[\[program\]\] or \[\[move\]\]"),
    (lambda t: t.replace('path_mode = "exact_stop"', 'path_mode = "round"'),
     r"host.path_mode: value = 'round' is not allowed \(allowed: exact_stop, blend\)"),
    (lambda t: t.replace("feed_override = 1.0", "feed_override = -1"), r"feed_override = -1 is not allowed"),
    (lambda t: t.replace("max_accel = 500", "max_accel = 0"),
     r"job.toml: controller.axis.z: max_accel = 0 is not allowed \(allowed: > 0 units/s\^2\)"),
    (lambda t: t.replace('[[program]]\nfile = "job.nc"\n', ""), r"host.feed_override: G-code settings need a G-code"),
])
def test_bad_gcode_settings_are_refused(job_machine: Path, edit: object, message: str) -> None:
    job_machine.write_text(edit(JOB))  # type: ignore[operator]
    with pytest.raises(ConfigurationError, match=message):
        check_machine(load_machine(job_machine))


def test_spindle_outputs_switch_at_the_slot_that_takes_their_entry_also_after_an_underrun(sim: Simulation) -> None:
    engine = PulseEngine(sim)
    HostApp(sim, engine, [encode_entry((10, 0, 0))] * 300, link=LinkProfile("fixed", latency_ns=200_000, jitter_ns=0),
            prefill_slots=20, stalls=[Stall(100 * MS, 60 * MS)])
    watch = JobWatch(sim, engine, slots=300, outputs=[
        (0, Spindle(True, False, Fraction(100), 1)), (50, Spindle(True, False, Fraction(200), 2)),
        (200, Spindle(False, False, Fraction(200), 3)), (300, Spindle(True, True, Fraction(5), 4))])
    sim.run(until=500 * MS)
    assert [(u.t_start, u.slots) for u in engine.underruns] == [(120 * MS, 41)]
    assert (watch.t_first, watch.t_last, watch.job_ticks) == (2 * MS, 342 * MS, 341 * MS)  # 300 slots + 41 empty
    assert sim.trace.edges("pokeys.spindle.on")[0].tolist() == [0, 2 * MS, 243 * MS, 343 * MS]
    assert sim.trace.edges("pokeys.spindle.speed")[1].tolist() == [0, 100, 200, 5]
    starts = sim.trace.segments("pokeys.x.step")["t0"]
    assert starts[[0, 50, 200, 299]].tolist() == [2 * MS + 5_000, 52 * MS + 5_000, 243 * MS + 5_000, 342 * MS + 5_000]


@pytest.mark.fmu
def test_the_router_example_runs_its_gcode_pocket_and_passes(tmp_path: Path) -> None:
    result = run_scenario(load_machine(ROUTER), out=tmp_path / "out")
    assert result.verdict == "PASS" and len(result.checks) == 13, result.table()  # 12 declared + the job check
    assert result.checks[0]["name"] == "the pokeys job completed"
    figures = {k: v["value"] for k, v in result.figures.items()}
    # the job ends with the engine's last slot (M2 reached, buffer drained): at a slot boundary (1 ms), the first
    # after the planned end job_done_ms (which counts from the switch to buffer mode, 0.1 ms off the slot grid)
    assert figures["job_s"] * 1000 == pytest.approx(round(figures["job_s"] * 1000), abs=1e-6)
    assert 0 < figures["job_s"] * 1000 - figures["job_done_ms"] < 1
    assert figures["underruns"] == 0 and figures["lost_steps"] == 0 and figures["slowed_lines"] == 0
    assert figures["x_peak_hz"] == 24_000  # rapids at 75 mm/s x 320 pulses/mm
    assert 15 < figures["job_duration_s"] < 19 and figures["min_buffer_level"] > 0
    slower = run_scenario(load_machine(ROUTER), overrides={"feed_override": "0.8", "until": '"23 s"'})
    assert slower.verdict == "PASS", slower.table()
    # the feeds take 1.25 times as long; rapids, the dwell and the corners (at the axes' limits) do not change
    job = figures["job_duration_s"]
    assert 1.1 * job < slower.figures["job_duration_s"]["value"] < 1.25 * job


@pytest.mark.fmu
def test_blending_corners_with_a_large_tolerance_is_faster_and_the_steppers_lose_steps() -> None:
    """path_tolerance 0.5 mm: a 90 deg corner at v^2 = 1500 mm/s^2 x 0.5 mm x s/(1-s), s = sin 45 deg: 42.6 mm/s
    (13.6 kHz), a speed step within one slot that the 6 kg x carriage's NEMA 23 cannot follow."""
    result = run_scenario(load_machine(ROUTER), overrides={"path_tolerance": "0.5"})
    failed = sorted(c["name"] for c in result.checks if not c["passed"])
    assert failed == ["x stepper lost no step", "y stepper lost no step"], result.table()
    assert result.figures["stepper_x_lost_steps"]["value"] > 100 and result.figures["job_duration_s"]["value"] < 17
