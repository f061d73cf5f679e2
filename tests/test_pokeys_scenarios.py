"""Bundled PoKeys scenarios: each passes its checks (a hazard scenario shows its hazard), and the figures show
what the scenario is about."""

from __future__ import annotations

import pytest

from cosim.runner import Result, run_scenario
from cosim.scenario import load

MS = 1_000_000


def run(name: str, **overrides: object) -> Result:
    return run_scenario(load(name), overrides={k: str(v) for k, v in overrides.items()})


def figure(result: Result, name: str) -> float:
    return float(result.figures[name]["value"])


@pytest.mark.parametrize("link", ["usb", "ethernet"])
def test_job_near_25_khz_keeps_every_slot_valid_and_counters_equal_the_pulses(link: str) -> None:
    result = run("pokeys_job", link=link, moves=1, distance=6_000)
    assert result.verdict == "PASS", result.table()
    by_name = {c["name"]: c for c in result.checks}
    assert by_name["x: at most 25 pulses per 1 ms slot"]["measured"]["max_pulses_per_window"] == 24
    assert by_name["x: pulses emitted add up to 6000"]["checked"] == 1
    assert by_name["no buffer underrun"]["passed"]


def test_job_at_25_khz_uses_all_25_pulses_of_a_slot_and_passes() -> None:
    result = run("pokeys_job", moves=1, distance=3_000, max_speed_hz=25_000)
    by_name = {c["name"]: c for c in result.checks}
    assert by_name["x: at most 25 pulses per 1 ms slot"]["measured"]["max_pulses_per_window"] == 25
    assert result.verdict == "PASS", result.table()


@pytest.mark.fmu
def test_job_drives_three_stepper_fmus_whose_commanded_steps_equal_the_counters() -> None:
    result = run("pokeys_job", moves=1, distance=3_000)
    assert result.verdict == "PASS", result.table()
    by_name = {c["name"]: c for c in result.checks}
    for axis, end in (("x", 3_000), ("y", -2_250), ("z", 1_500)):
        assert by_name[f"{axis}: stepper commanded_steps = position counter = {end}"]["checked"] == 1
    # at most one rate change per slot and axis, far fewer while the rate holds at cruise
    assert 0 < figure(result, "step_rate_changes") < 3 * figure(result, "slots")
    without = run("pokeys_job", moves=1, distance=3_000, steppers="false")
    assert without.verdict == "PASS" and "fmu_steps" not in without.figures
    assert not any("stepper" in c["name"] for c in without.checks)


def test_stall_underrun_is_reported_with_start_and_length_and_prefill_avoids_it() -> None:
    stalled = run("pokeys_stall")
    assert stalled.verdict == "HAZARD SHOWN", stalled.table()
    assert stalled.hazards == [{"check": "no buffer underrun", "shown": True, "shows": "a 60 ms host stall with "
                                "20 slots queued: the buffer runs empty and the axis stops dead mid-move"}]
    assert figure(stalled, "underruns") == 1
    start, length = figure(stalled, "underrun_start_ms"), figure(stalled, "underrun_length_ms")
    assert 315 <= start <= 321 and 40 <= length <= 44  # 20 slots after the stall starts; the stall + link delay
    underrun = stalled.checks[0]["violations"][0]  # the violated rule names the underrun's start and length
    assert (underrun["t_ns"], underrun["value"]) == (start * MS, length * MS)
    prefilled = run("pokeys_stall_prefill")
    assert prefilled.verdict == "PASS", prefilled.table()
    assert prefilled.checks[0]["name"] == stalled.checks[0]["name"] == "no buffer underrun"  # the same rule
    assert figure(prefilled, "underruns") == 0 and figure(prefilled, "lowest_buffer_level_during_job") > 30


def test_limit_trip_reports_stop_distance_and_time() -> None:
    result = run("pokeys_limit")
    assert result.verdict == "PASS", result.table()
    # 20 pulses per slot, 50 us apart: the trip at pulse k of a slot leaves 19 - k pulses of that slot
    assert 0 <= figure(result, "stop_distance_pulses") <= 19
    assert figure(result, "stop_time_us") == figure(result, "stop_distance_pulses") * 50
    assert run("pokeys_limit", limit_enabled=False).verdict == "FAIL"


def test_emergency_stops_every_axis_within_the_slot() -> None:
    result = run("pokeys_emergency")
    assert result.verdict == "PASS", result.table()
    assert all(c["measured"]["max_ns"] < MS for c in result.checks[:3])


def test_homing_resets_the_counter_with_the_documented_timing() -> None:
    result = run("pokeys_homing", start_pulses=100, max_speed_hz=10_000)
    assert result.verdict == "PASS", result.table()
    # search 1 pulse/slot in slots 0..99 (on the switch at 99.005 ms, seen at 100 ms); back-off
    # 0.1 pulse/slot: its pulse in slot 109 releases the switch; counter reset at the 110 ms slot start
    assert figure(result, "homing_time_ms") == 110
    assert figure(result, "final_counter") == 0


def test_internal_move_is_a_slot_trapezoid_through_the_buffer() -> None:
    result = run("pokeys_internal_move")
    assert result.verdict == "PASS", result.table()
    assert figure(result, "peak_buffer_level") == 10


def test_jogging_runs_past_an_enabled_limit() -> None:
    result = run("pokeys_jog_limit")
    assert result.verdict == "HAZARD SHOWN", result.table()
    assert [(h["check"], h["shown"]) for h in result.hazards] == [
        ("no pulse after the slot boundary at which the trip is seen", True),
        ("engine stopped by the limit switch", True)]
    assert [c["name"] for c in run("pokeys_limit").checks if c["name"] in {h["check"] for h in result.hazards}] == [
        h["check"] for h in result.hazards]  # pokeys_limit's own rules, which pass there
    # jogging at 10 kHz from 0: the limit trips at pulse 2000 (200 ms), pulses go on until the jog stops at 500 ms
    assert result.checks[1]["violations"][0]["value"] == 10  # state 10 (jogging) at the end, not 100
    assert figure(result, "travel_past_limit") == 3_000


@pytest.mark.parametrize(("name", "fix", "error"), [
    ("pokeys_stale_slots", "none", 100), ("pokeys_stale_slots_fix", "clear", 0), ("pokeys_stale_slots_fix", "wait", 0)])
def test_internal_to_buffer_hazard_and_its_fixes(name: str, fix: str, error: int) -> None:
    result = run(name, fix=fix)
    assert result.verdict == ("HAZARD SHOWN" if error else "PASS"), result.table()
    assert figure(result, "final_error") == error
    assert result.checks[0]["name"] == f"x ends at the planned position {int(figure(result, 'planned_position'))}"


def test_the_stale_slots_hazard_is_missed_when_the_host_clears_the_buffer() -> None:
    assert run("pokeys_stale_slots", fix="clear").verdict == "HAZARD MISSED"


POKEYS_SCENARIOS = ("pokeys_job", "pokeys_stall", "pokeys_stall_prefill", "pokeys_limit", "pokeys_emergency",
                    "pokeys_homing", "pokeys_internal_move", "pokeys_jog_limit", "pokeys_stale_slots",
                    "pokeys_stale_slots_fix")


def test_every_pokeys_scenario_is_bundled_with_a_description_and_parameters() -> None:
    from cosim.scenario import bundled

    assert set(POKEYS_SCENARIOS) <= set(bundled())
    for name in POKEYS_SCENARIOS:
        scenario = load(name)
        assert scenario.description.startswith("PoKeys "), name
        assert scenario.parameters, name
