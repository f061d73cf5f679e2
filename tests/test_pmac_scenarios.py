"""The bundled PMAC scenarios run, pass their checks (the hazard scenarios show their hazards) and report the
figures the issue asks for."""

from __future__ import annotations

import pytest

from cosim.runner import run_scenario
from cosim.scenario import bundled, load

PMAC_SCENARIOS = ["pmac_external_time_base", "pmac_ix94_slip", "pmac_ix94_max", "pmac_percent_slew",
                  "pmac_triggered_start", "pmac_stale_capture", "pmac_stale_capture_fix"]
#: The scenarios that demonstrate a hazard, and the rules of a healthy machine they break.
HAZARDS = {"pmac_ix94_slip": ["no slip"],
           "pmac_stale_capture": ["time zero = master position at mark 2 (1/256 count)",
                                  "still armed just before mark 2"]}


def test_all_pmac_scenarios_are_bundled() -> None:
    assert set(PMAC_SCENARIOS) <= set(bundled())


@pytest.mark.parametrize("name", PMAC_SCENARIOS)
def test_bundled_scenario_passes(name: str) -> None:
    result = run_scenario(load(name))
    assert result.error is None
    assert result.verdict == ("HAZARD SHOWN" if name in HAZARDS else "PASS"), result.table()
    assert [(h["check"], h["shown"]) for h in result.hazards] == [(n, True) for n in HAZARDS.get(name, [])]


def test_slip_scenario_reports_slip_and_limit_cycles() -> None:
    figures = run_scenario(load("pmac_ix94_slip")).figures
    assert figures["slip_counts"]["value"] > 2000
    assert figures["first_limit_cycle"]["value"] == 2
    assert figures["limit_cycles"]["value"] == figures["last_limit_cycle"]["value"] - 1
    assert figures["slave_lag_counts"]["value"] == pytest.approx(figures["slip_counts"]["value"])


def test_slip_scenario_with_a_fast_enough_ix94_has_no_slip() -> None:
    result = run_scenario(load("pmac_ix94_slip"), overrides={"ix94": "500000"})
    assert result.verdict == "HAZARD MISSED" and result.passed == 2, result.table()  # the model checks pass
    assert result.figures["slip_counts"]["value"] == 0 and result.figures["limit_cycles"]["value"] == 0


def test_slip_check_fails_when_the_reported_slip_disagrees() -> None:
    result = run_scenario(load("pmac_ix94_slip"), overrides={"slip_tol": "0.01"})  # the estimate is ~7 % off
    assert result.verdict == "FAIL"


def test_stale_capture_with_dummy_read_no_longer_reproduces_the_hazard() -> None:
    stale = run_scenario(load("pmac_stale_capture"))
    assert stale.figures["time_zero_error_counts"]["value"] == pytest.approx(-1000, abs=1 / 256)
    fixed = run_scenario(load("pmac_stale_capture"), overrides={"dummy_read": "true"})
    assert fixed.verdict == "HAZARD MISSED" and [h["shown"] for h in fixed.hazards] == [False, False]
    assert abs(fixed.figures["time_zero_error_counts"]["value"]) <= 1 / 256
    twin = run_scenario(load("pmac_stale_capture_fix"))
    assert [c["name"] for c in twin.checks[:2]] == [c["name"] for c in stale.checks]  # the same rules pass there


def test_triggered_start_error_within_1_256_count() -> None:
    result = run_scenario(load("pmac_triggered_start"), overrides={"mark_counts": "2345.678"})
    assert result.verdict == "PASS", result.table()
    assert abs(result.figures["start_error_counts"]["value"]) <= 1 / 256
