"""Bundled Trio scenarios: the note's example, raster refills keeping up and starving, speed link, WDOG off."""

from __future__ import annotations

import pytest

from cosim.runner import Result, run_scenario
from cosim.scenario import load


def run(name: str, **overrides: object) -> Result:
    return run_scenario(load(name), overrides={k: str(v) for k, v in overrides.items()})


def test_note_example_passes_with_every_edge_at_its_count() -> None:
    """trio_example: 2 passes, 16 gate edges at 1761 1841 3121 3521 | 3519 3119 1839 1759 (x2)."""
    result = run("trio_example", laser=False, passes=2)
    assert result.verdict == "PASS", result.table()
    # it ends when the passes are done, not at UNTIL (a safety limit): the run's end is the job's end
    assert result.simulated_s == result.figures["job_s"]["value"] and result.until == round(result.simulated_s * 1e9)
    assert 0.1 < result.simulated_s < 600
    assert result.checks[0]["checked"] == 16
    assert result.figures["late_positions"]["value"] == 0
    assert result.figures["step_pulses"]["value"] == 4 * 4800


def test_raster_refill_keeps_up_and_every_position_gives_its_edge() -> None:
    result = run("trio_raster", laser=False, lines=2, positions=800)
    assert result.verdict == "PASS", result.table()
    assert result.checks[0]["checked"] == 1600
    assert result.figures["most_positions_waiting"]["value"] == 64  # loads waited for room: the FIFO stayed full


def test_raster_with_a_slow_refill_names_the_positions_passed_before_loading() -> None:
    """Same job, one 64-position chunk every 40 ms at 4 positions/ms: the FIFO starves."""
    result = run("trio_raster", laser=False, lines=1, positions=800, refill_ms=40)
    assert result.verdict == "FAIL"
    late = result.checks[1]
    assert late["n_violations"] > 0 and late["measured"]["late_positions"] == late["n_violations"]
    first = late["violations"][0]
    assert first["detail"] == f"gate position {first['value']:g} units was passed before it was loaded; it fired " \
                              "at the load"
    starved = run("trio_raster_starved", laser=False, lines=1, positions=800)
    assert starved.verdict == "HAZARD SHOWN", starved.table()
    assert starved.hazards == [{"check": "no position is passed before it is loaded", "shown": True, "shows":
                                "a host refilling 64 positions every 40 ms starves the gating FIFO at 200 mm/s: "
                                "positions are passed before they are loaded and fire late"}]
    assert starved.checks[0]["name"] == late["name"]  # trio_raster's rule, which passes there
    assert starved.checks[0]["measured"]["late_positions"] == late["measured"]["late_positions"]
    assert starved.checks[0]["description"].startswith(
        "every gate position is loaded before the axis reaches it; passed before they were loaded [units]: "
        f"{first['value']:g}, ")


@pytest.mark.parametrize(("link", "more_at_corners"), [(True, False), (False, True)])
def test_speed_link_keeps_energy_per_mm_even_at_corners(link: bool, more_at_corners: bool) -> None:
    result = run("trio_speed_link", laser=False, link=link)
    assert result.verdict == "PASS", result.table()
    ratio = result.checks[1]["measured"]["corner_to_cruise_ratio"]
    assert (ratio > 1.5) == more_at_corners
    linked = result.figures["energy_per_mm_J"]["value"]
    fixed = result.figures["energy_per_mm_fixed_mark_J"]["value"]
    assert (linked < fixed) == link
    if link:  # 40 W at 50 % duty at 100 mm/s, everywhere along the path
        assert linked == pytest.approx(40 * 0.5 / 100, rel=0.01)


def test_wdog_off_mid_move_controller_part() -> None:
    result = run("trio_wdog_off", laser=False)
    assert result.verdict == "PASS", result.table()


@pytest.mark.fmu
def test_wdog_off_mid_move_with_the_laser_energy_in_closed_form() -> None:
    result = run("trio_wdog_off", laser=True)
    assert result.verdict == "PASS", result.table()
    assert result.figures["energy_J"]["value"] == pytest.approx(result.figures["expected_energy_J"]["value"],
                                                                rel=1e-6)


@pytest.mark.fmu
def test_speed_link_with_the_laser_delivers_the_linked_energy_per_mm() -> None:
    result = run("trio_speed_link", laser=True)
    assert result.verdict == "PASS", result.table()
    assert result.figures["laser_energy_per_mm_J"]["value"] == pytest.approx(
        result.figures["energy_per_mm_J"]["value"], rel=0.01)
