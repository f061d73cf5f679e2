"""The Laser FMU, standalone: standard conformance, exact energy on any grid, errors, rebuild.

Timing picture of the reference case (20 MHz clock, period 1000 ticks = 50 us, on 400 = 20 us)::

    gate       ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾ (0 .. 10 ms)
    modulation ‾‾‾‾|______|‾‾‾‾|______|‾‾‾‾|______| ...  200 periods
               0   20us   50us
"""

from __future__ import annotations

import shutil
import zipfile
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu

from cosim.errors import ConfigurationError, FmuError
from cosim.fmu import Fmu
from cosim.fmubuild import ensure_fmu
from cosim.plants.laser import pwm_energy

pytestmark = pytest.mark.fmu

MS = 1_000_000  # ns
VERSIONS = (2, 3)


@pytest.fixture(scope="module", params=VERSIONS, ids=["fmi2", "fmi3"])
def laser_fmu(request: pytest.FixtureRequest) -> Path:
    return ensure_fmu("Laser", request.param)


def reference_energy(t_end_ns: int = 10 * MS, on: int = 400) -> float:
    energy, _ = pwm_energy([(Fraction(0), Fraction(t_end_ns, 10**9))], period=1000, on=on, peak_power=40.0,
                           tau_rise=100e-6, tau_fall=100e-6)
    return energy


def run_grid(path: Path, grid_ns: list[int], on: int = 400) -> Fmu:
    fmu = Fmu(path, parameters={"enable": True, "gate": True, "pwm_period": 1000, "pwm_on": on})
    for t in grid_ns:
        fmu.advance_to(t)
    return fmu


def test_validates_without_problems(laser_fmu: Path) -> None:
    assert validate_fmu(str(laser_fmu)) == []


def test_fmu_holds_its_sources_and_build_description(laser_fmu: Path) -> None:
    names = set(zipfile.ZipFile(laser_fmu).namelist())
    assert {"sources/model.c", "sources/cosim_fmu.c", "sources/model_vars.c", "sources/model_vars.h"} <= names
    if "fmi3" in laser_fmu.parts:
        assert "sources/buildDescription.xml" in names
        assert "binaries/x86_64-linux/Laser.so" in names
    else:
        assert "binaries/linux64/Laser.so" in names


def test_simulates_standalone_in_fmpy(laser_fmu: Path) -> None:
    result = simulate_fmu(str(laser_fmu), start_values={"enable": True, "gate": True, "pwm_on": 400},
                          stop_time=0.01, output_interval=1e-4)
    assert result["energy"][-1] == pytest.approx(reference_energy(), rel=1e-9)
    assert result["pwm_periods"][-1] == 201  # 200 whole periods, the 201st rises at 10 ms


@pytest.mark.parametrize("grid", ["one step", "1 us", "1 ms", "random"])
def test_energy_equals_closed_form_on_any_grid(laser_fmu: Path, grid: str) -> None:
    end = 10 * MS
    if grid == "one step":
        points = [end]
    elif grid == "random":
        rng = np.random.default_rng(7)
        gaps = rng.integers(1_000, 1 * MS, size=200)  # 1 us .. 1 ms
        points = [int(t) for t in np.cumsum(gaps) if t < end] + [end]
    else:
        step = {"1 us": 1_000, "1 ms": MS}[grid]
        points = list(range(step, end + 1, step))
    with run_grid(laser_fmu, points) as fmu:
        assert fmu.get("energy") == pytest.approx(reference_energy(), rel=1e-9)


@pytest.mark.parametrize(("period", "frequency_hz"), [(1000, 20_000), (200, 100_000)])
def test_pwm_frequency_from_period_in_clock_ticks(laser_fmu: Path, period: int, frequency_hz: int) -> None:
    fmu = Fmu(laser_fmu, parameters={"enable": True, "gate": True, "pwm_period": period, "pwm_on": period // 2})
    with fmu:
        fmu.advance_to(10 * MS - 1)  # just before the edge at 10 ms
        assert fmu.get("pwm_periods") == frequency_hz // 100


def test_on_time_at_or_above_period_is_continuously_on_and_zero_is_off(laser_fmu: Path) -> None:
    with run_grid(laser_fmu, [MS, 2 * MS], on=1000) as full, run_grid(laser_fmu, [2 * MS], on=0) as off:
        assert full.get("modulation") is True
        assert full.get("pwm_periods") == 1
        assert full.get("power") == pytest.approx(40.0 * (1 - np.exp(-20.0)), rel=1e-12)
        assert off.get("modulation") is False
        assert off.get("energy") == 0.0


def test_two_instances_are_independent_and_identical(laser_fmu: Path) -> None:
    with run_grid(laser_fmu, [3 * MS]) as a, run_grid(laser_fmu, [MS]) as b:
        b.set("gate", False)
        b.advance_to(3 * MS)
        assert a.get("energy") == pytest.approx(reference_energy(3 * MS), rel=1e-12)
        assert b.get("energy") < a.get("energy")
        with run_grid(laser_fmu, [3 * MS]) as c:
            assert c.get("energy") == a.get("energy")


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("clock_frequency", 0.0, "parameter clock_frequency = 0 Hz is not allowed (allowed: > 0 Hz)"),
        ("tau_fall", -1e-6, "parameter tau_fall = -9.9999999999999995e-07 s is not allowed (allowed: > 0 s)"),
        ("duty_threshold", 1.5, "parameter duty_threshold = 1.5 is not allowed (allowed: 0..1)"),
    ],
)
def test_bad_values_are_rejected_by_the_fmu_with_its_reason(laser_fmu: Path, name: str, value: float,
                                                            message: str) -> None:
    with pytest.raises(FmuError) as info:
        Fmu(laser_fmu, parameters={name: value})
    assert message in str(info.value)


@pytest.mark.parametrize(("name", "value"), [("pwm_period", -5), ("pwm_on", -1), ("pwm_period", 2**32 + 1000)])
def test_integers_outside_the_declared_range_never_reach_the_fmu(laser_fmu: Path, name: str, value: int) -> None:
    """pwm_period and pwm_on are declared min="0" (Int32): checked before the FMU, so nothing wraps."""
    with Fmu(laser_fmu, instance_name="laser") as fmu:
        with pytest.raises(ConfigurationError) as info:
            fmu.set(name, value)
        assert str(info.value) == f"laser (Laser.fmu): {name} = {value} is not allowed (allowed: 0..2147483647)"
        assert fmu.get(name) == {"pwm_period": 1000, "pwm_on": 0}[name] and not fmu.log


def test_parameters_are_fixed_after_initialisation(laser_fmu: Path) -> None:
    with Fmu(laser_fmu) as fmu, pytest.raises(FmuError, match="parameter peak_power is fixed after initialisation"):
        fmu.set("peak_power", 10.0)


def test_rebuilds_from_its_own_sources_in_a_clean_folder(laser_fmu: Path, tmp_path: Path) -> None:
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(laser_fmu) as zf:
        zf.extractall(unzipped)
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped), str(tmp_path / "build"))  # what another tool would do
    rebuilt = shutil.make_archive(str(tmp_path / "Laser"), "zip", unzipped)
    result = simulate_fmu(rebuilt, start_values={"enable": True, "gate": True, "pwm_on": 400}, stop_time=0.01)
    assert result["energy"][-1] == pytest.approx(reference_energy(), rel=1e-9)


def test_matches_the_reference_result(laser_fmu: Path) -> None:
    reference = np.genfromtxt(Path(__file__).parents[1] / "fmu_src/Laser/reference.csv", delimiter=",",
                              names=True, dtype=None, encoding="utf-8")
    result = simulate_fmu(str(laser_fmu), start_values={"enable": True, "gate": True, "pwm_on": 400},
                          stop_time=0.01, output_interval=5e-4)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    for name in ("power", "energy"):
        assert result[name].tolist() == pytest.approx(reference[name].tolist(), rel=1e-9, abs=1e-12)
    assert result["pwm_periods"].tolist() == reference["pwm_periods"].tolist()
