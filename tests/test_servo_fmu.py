"""The Servo FMU, standalone and in a simulation: exact step response, friction, encoder timestamps.

Timing picture of the step test (maxon RE 40 defaults, u_cmd = 1 V -> 2.4 V on the motor)::

    u_cmd    ____|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    speed        /‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾  -> 79.7 rad/s (tau 4.4 ms and 0.29 ms)
    encoder      | | ||||||||||||||||||||||||||||  an edge every 39 us at speed (2000 counts/rev)
                 0    5 ms                    20 ms
"""

from __future__ import annotations

import doctest
import math
import shutil
import zipfile
from collections.abc import Generator
from pathlib import Path

import control
import numpy as np
import pytest
from encoder_oracle import one_over_t_position
from fmpy import simulate_fmu
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu
from simpy.events import Event

import cosim.plants.servo
from cosim import fmudesc
from cosim.errors import ConfigurationError, FmuError
from cosim.fmu import Fmu
from cosim.fmubuild import SOURCE_DIR, ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.plants.servo import (
    ServoParameters,
    linear_model,
    steady_state_speed,
)
from cosim.presets import load_preset
from cosim.signals import Signal
from cosim.timebase import Priority

pytestmark = pytest.mark.fmu

MS = 1_000_000  # ns
VERSIONS = (2, 3)
#: The defaults with a little viscous friction, so every term of the linear model is exercised.
MOTOR = ServoParameters(viscous_friction=2e-6)
REFERENCE_INPUT = np.array([(0.0, 5.0, 0.01), (0.025, 5.0, 0.01), (0.025, -5.0, 0.01), (0.05, -5.0, 0.01)],
                           dtype=[("time", float), ("u_cmd", float), ("load_torque", float)])
REFERENCE_START = {"coulomb_friction": 4e-3, "viscous_friction": 1e-6}


@pytest.fixture(scope="module", params=VERSIONS, ids=["fmi2", "fmi3"])
def servo_fmu(request: pytest.FixtureRequest) -> Path:
    return ensure_fmu("Servo", request.param)


def counts(angle_rad: float, counts_per_rev: int = 2000) -> float:
    return angle_rad * counts_per_rev / (2 * math.pi)


def read_edge(fmu: Fmu, t_ns: int) -> float:
    """The 1/T position [counts] a controller computes at ``t_ns`` from the FMU's outputs."""
    return one_over_t_position(edge_count=int(fmu.get("edge_count")), edge_direction=int(fmu.get("edge_direction")),
                               t_last_edge_s=float(fmu.get("t_last_edge")),
                               t_prev_edge_s=float(fmu.get("t_prev_edge")), t_s=t_ns * 1e-9)


# -- standard conformance --------------------------------------------------------------------------
def test_validates_without_problems(servo_fmu: Path) -> None:
    assert validate_fmu(str(servo_fmu)) == []


def test_fmu_holds_its_sources(servo_fmu: Path) -> None:
    names = set(zipfile.ZipFile(servo_fmu).namelist())
    assert {"sources/model.c", "sources/encoder.c", "sources/model.h", "sources/cosim_fmu.c",
            "sources/model_vars.c", "documentation/readme.md", "documentation/reference.csv"} <= names


def test_encoder_source_is_the_same_in_both_plants() -> None:
    def packed(model: str) -> bytes:
        with zipfile.ZipFile(ensure_fmu(model, 3)) as zf:
            return zf.read("sources/encoder.c")

    servo = packed("Servo")
    assert servo == packed("Conveyor") == (SOURCE_DIR / "common" / "encoder.c").read_bytes()


def test_simulates_standalone_in_fmpy(servo_fmu: Path) -> None:
    result = simulate_fmu(str(servo_fmu), start_values={"u_cmd": 1.0}, stop_time=0.05, output_interval=1e-3)
    assert result["speed"][-1] == pytest.approx(steady_state_speed(ServoParameters(), u_cmd_v=1.0), rel=1e-4)
    assert result["encoder_count"][-1] == math.floor(counts(result["angle"][-1]))


# -- dynamics ----------------------------------------------------------------------------------------
def test_step_response_matches_the_linear_model(servo_fmu: Path) -> None:
    """Speed, angle and current after a 1 V step, every 0.1 ms for 20 ms, against python-control."""
    grid = np.arange(0, 201) * 100_000
    with Fmu(servo_fmu, parameters={**MOTOR.as_fmu_parameters(), "u_cmd": 1.0}) as fmu:
        rows = []
        for t in grid:
            fmu.advance_to(int(t))
            rows.append((fmu.get("speed"), fmu.get("angle"), fmu.get("current")))
    got = np.array(rows)
    for column, output in enumerate(("speed", "angle", "current")):
        expected = control.step_response(linear_model(MOTOR, output=output), T=grid * 1e-9).outputs
        scale = np.max(np.abs(expected))
        assert np.max(np.abs(got[:, column] - expected)) < 1e-7 * scale, output


def test_linear_model_has_the_datasheet_mechanical_time_constant() -> None:
    """maxon gives tau_m = 4.67 ms for the RE 40 (24 V): R J / (Kt Ke) of the model's defaults."""
    tau_m = ServoParameters().resistance * ServoParameters().inertia / (30.2e-3 * 30.12e-3)
    poles = np.sort(control.poles(linear_model(ServoParameters())).real)
    assert tau_m == pytest.approx(4.67e-3, rel=2e-3)
    assert -1 / poles[-1] - 1 / poles[0] == pytest.approx(tau_m, rel=0.01)  # the sum of the two lags


@pytest.mark.parametrize("grid", ["one step", "10 us", "random"])
def test_result_does_not_depend_on_the_communication_grid(servo_fmu: Path, grid: str, sim: Simulation) -> None:
    end = 10 * MS
    if grid == "one step":
        points = [end]
    elif grid == "10 us":
        points = list(range(10_000, end + 1, 10_000))
    else:
        points = sorted({int(t) for t in sim.rng.integers(1, end, size=300)} | {end})
    parameters = {"u_cmd": 3.0, "coulomb_friction": 4e-3, "load_torque": 0.02}
    with Fmu(servo_fmu, parameters=parameters) as fmu, Fmu(servo_fmu, parameters=parameters) as one:
        for t in points:
            fmu.advance_to(t)
        one.advance_to(end)
        for name in ("angle", "speed", "current", "t_last_edge", "t_prev_edge"):
            assert fmu.get(name) == pytest.approx(one.get(name), rel=1e-10, abs=1e-12), name
        assert fmu.get("encoder_count") == one.get("encoder_count")


@pytest.mark.parametrize(
    ("u_cmd_v", "coulomb_nm", "load_nm"),
    [
        (1.0, 0.0, 0.0),      # no friction
        (1.0, 4e-3, 0.0),     # Coulomb friction lowers the speed
        (-2.0, 4e-3, 0.01),   # backwards, the load torque helps
        (0.01, 4e-3, 0.0),    # stall torque 2.4 mN.m < 4 mN.m: held at rest
        (0.0, 4e-3, 0.003),   # a load within the friction does not turn the rotor
        (0.0, 4e-3, 0.01),    # a larger one does: backwards
    ],
)
def test_steady_state_speed_with_friction_and_load(servo_fmu: Path, u_cmd_v: float, coulomb_nm: float,
                                                   load_nm: float) -> None:
    params = ServoParameters(viscous_friction=5e-6, coulomb_friction=coulomb_nm)
    expected = steady_state_speed(params, u_cmd_v=u_cmd_v, load_torque_nm=load_nm)
    with Fmu(servo_fmu, parameters={**params.as_fmu_parameters(), "u_cmd": u_cmd_v, "load_torque": load_nm}) as fmu:
        fmu.advance_to(200 * MS)  # 45 mechanical time constants
        assert fmu.get("speed") == pytest.approx(expected, rel=1e-9, abs=1e-12)
        assert fmu.get("stuck") is (expected == 0.0)
        if expected == 0.0:
            assert fmu.get("angle") == 0.0  # held from the start: not even a fraction of a count


def test_the_rotor_comes_to_an_exact_standstill_and_breaks_away_again(servo_fmu: Path) -> None:
    """Command off at 50 ms: Coulomb friction stops the rotor and holds it; 100 ms later it is reversed."""
    with Fmu(servo_fmu, parameters={"u_cmd": 2.0, "coulomb_friction": 4e-3}) as fmu:
        fmu.advance_to(50 * MS)
        fmu.set("u_cmd", 0.0)
        fmu.advance_to(100 * MS)
        stopped_at = fmu.get("angle")
        assert (fmu.get("stuck"), fmu.get("speed")) == (True, 0.0)
        fmu.advance_to(150 * MS)
        assert (fmu.get("angle"), fmu.get("encoder_count")) == (stopped_at, math.floor(counts(stopped_at)))
        fmu.set("u_cmd", -2.0)
        fmu.advance_to(250 * MS)
        assert fmu.get("stuck") is False
        assert fmu.get("speed") == pytest.approx(
            steady_state_speed(ServoParameters(coulomb_friction=4e-3), u_cmd_v=-2.0), rel=1e-9)


def test_amplifier_saturates_at_the_supply_voltage(servo_fmu: Path) -> None:
    with Fmu(servo_fmu, parameters={"u_cmd": 20.0}) as fmu:
        fmu.advance_to(100 * MS)
        assert fmu.get("motor_voltage") == 24.0
        assert fmu.get("speed") == pytest.approx(24.0 / 30.12e-3, rel=1e-9)  # no-load speed at 24 V


# -- encoder -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("u_cmd_v", [1.5, -0.7])
def test_one_over_t_position_error_is_below_1_256_count_at_constant_speed(servo_fmu: Path, u_cmd_v: float,
                                                                           sim: Simulation) -> None:
    """After settling (300 ms = 68 mechanical time constants), at 200 random instants in 100 ms."""
    angle_model = linear_model(MOTOR, output="angle")
    instants = np.sort(sim.rng.integers(300 * MS, 400 * MS, size=200))
    worst = 0.0
    with Fmu(servo_fmu, parameters={**MOTOR.as_fmu_parameters(), "u_cmd": u_cmd_v}) as fmu:
        for t in instants:
            fmu.advance_to(int(t))
            exact = u_cmd_v * control.step_response(angle_model, T=[0.0, t * 1e-9]).outputs[-1]
            worst = max(worst, abs(read_edge(fmu, int(t)) - counts(exact)))
            assert fmu.get("edge_direction") == (1 if u_cmd_v > 0 else -1)
            assert fmu.get("edge_count") == fmu.get("encoder_count") + (0 if u_cmd_v > 0 else 1)
    assert worst < 1 / 256
    assert worst < 1e-5  # in fact limited by rounding, not by the model


def test_edges_are_timestamped_at_exact_boundaries_after_a_reversal(servo_fmu: Path) -> None:
    """Reversed at 30 ms: the first down edge is at the instant the angle drops below its boundary."""
    with Fmu(servo_fmu, parameters={"u_cmd": 0.5}) as fmu:
        fmu.advance_to(30 * MS)
        fmu.set("u_cmd", -0.5)
        t = 30 * MS
        while fmu.get("edge_direction") == 1:
            t += 10_000
            fmu.advance_to(t)
        boundary = fmu.get("edge_count")
        assert boundary == fmu.get("encoder_count") + 1
        t_edge_ns = fmu.get("t_last_edge") * 1e9
        assert t - 10_000 < t_edge_ns <= t
    with Fmu(servo_fmu, parameters={"u_cmd": 0.5}) as probe:  # the same run, stopped around the edge instant
        probe.advance_to(30 * MS)
        probe.set("u_cmd", -0.5)
        probe.advance_to(math.floor(t_edge_ns))
        before = counts(probe.get("angle"))
        probe.advance_to(math.ceil(t_edge_ns))
        after = counts(probe.get("angle"))
    assert after < boundary <= before


# -- errors ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("inertia", -1e-5, "parameter inertia = -1.0000000000000001e-05 kg.m2 is not allowed (allowed: > 0 kg.m2)"),
        ("counts_per_rev", 0, "parameter counts_per_rev = 0 is not allowed (allowed: > 0)"),
        ("counts_per_rev", 1002, "parameter counts_per_rev = 1002 is not allowed (allowed: a positive multiple of 4"),
        ("resistance", 0.0, "parameter resistance = 0 Ohm is not allowed (allowed: > 0 Ohm)"),
        ("inductance", -1e-3, "parameter inductance = -0.001 H is not allowed (allowed: > 0 H)"),
        ("coulomb_friction", -0.1, "parameter coulomb_friction = -0.10000000000000001 N.m is not allowed "
                                   "(allowed: >= 0 N.m)"),
        ("max_step", 0.0, "parameter max_step = 0 s is not allowed (allowed: > 0 s)"),
    ],
)
def test_bad_parameters_fail_at_initialisation_naming_the_parameter(servo_fmu: Path, name: str, value: float,
                                                                     message: str) -> None:
    with pytest.raises(FmuError) as info:
        Fmu(servo_fmu, parameters={name: value})
    assert message in str(info.value)


def test_torque_and_back_emf_constants_that_disagree_are_logged(servo_fmu: Path) -> None:
    with Fmu(servo_fmu, parameters={"back_emf_constant": 0.06}) as fmu:
        assert any("[Warning]" in line and "back_emf_constant = 0.06" in line for line in fmu.log)


def test_python_parameters_refuse_what_the_fmu_refuses() -> None:
    with pytest.raises(ConfigurationError, match=r"inertia = -1e-05 is not allowed \(allowed: > 0\)"):
        ServoParameters(inertia=-1e-5)
    with pytest.raises(ConfigurationError, match="counts_per_rev = 1002"):
        ServoParameters(counts_per_rev=1002)
    with pytest.raises(ConfigurationError, match=r"^ServoParameters: viscous_friction = nan is not allowed"):
        ServoParameters(viscous_friction=float("nan"))
    with pytest.raises(ConfigurationError, match="not Servo parameters: inertial"):
        ServoParameters.from_mapping({"inertial": 1.0})


def test_python_defaults_are_the_fmu_defaults() -> None:
    spec = fmudesc.load_spec(SOURCE_DIR / "Servo")
    for name, value in ServoParameters().as_fmu_parameters().items():
        assert spec.variable(name).start == value, name


# -- instances, presets, master ----------------------------------------------------------------------
def test_two_instances_are_independent(servo_fmu: Path) -> None:
    with Fmu(servo_fmu, parameters={"u_cmd": 1.0}) as a, Fmu(servo_fmu, parameters={"u_cmd": -1.0}) as b:
        a.advance_to(20 * MS)
        b.advance_to(20 * MS)
        assert a.get("angle") == -b.get("angle") > 0
        assert a.get("encoder_count") == -b.get("encoder_count") - 1  # floor of opposite positions


def test_preset_reproduces_the_datasheet_no_load_speed(servo_fmu: Path) -> None:
    """maxon RE 40 (24 V): 7580 rpm at no load; the preset's Coulomb friction is its no-load torque."""
    preset = load_preset("servo_maxon_re40_24v")
    with Fmu(servo_fmu, parameters={**preset, "u_cmd": 10.0}) as fmu:
        fmu.advance_to(100 * MS)
        rpm = fmu.get("speed") * 60 / (2 * math.pi)
    assert rpm == pytest.approx(7580, rel=0.005)
    assert ServoParameters.from_mapping(preset).coulomb_friction == pytest.approx(30.2e-3 * 0.137, rel=1e-3)


@pytest.mark.parametrize("fmi_version", VERSIONS)
def test_servo_driven_by_a_controller_signal(sim: Simulation, fmi_version: int) -> None:
    """A DAC signal steps to 2 V at 1 ms; the plant is advanced only when it changes or is read."""
    dac = Signal(sim, "ctrl.axis1.dac", kind="real", initial=0.0, unit="V")
    axis = Plant.load(sim, "Servo", name="axis1", fmi_version=fmi_version, parameters=MOTOR.as_fmu_parameters())
    axis.drive("u_cmd", dac)
    seen: list[float] = []

    def controller() -> Generator[Event, object, None]:
        yield sim.at(1 * MS, Priority.SERVO)
        dac.set(2.0)
        yield sim.at(11 * MS, Priority.SERVO)
        seen.append(float(axis.read("speed")))

    sim.process(controller())
    sim.run(until=12 * MS)
    expected = 2.0 * control.step_response(linear_model(MOTOR), T=[0.0, 10e-3]).outputs[-1]
    assert seen == [pytest.approx(expected, rel=1e-9)]
    assert axis.steps == 2  # to 1 ms (input change) and to 11 ms (read)


# -- rebuild and reference ---------------------------------------------------------------------------
def test_rebuilds_from_its_own_sources_in_a_clean_folder(servo_fmu: Path, tmp_path: Path) -> None:
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(servo_fmu) as zf:
        zf.extractall(unzipped)
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped), str(tmp_path / "build"))  # what another tool would do
    rebuilt = shutil.make_archive(str(tmp_path / "Servo"), "zip", unzipped)
    result = simulate_fmu(rebuilt, start_values={"u_cmd": 1.0}, stop_time=0.05, output_interval=1e-3)
    assert result["speed"][-1] == pytest.approx(steady_state_speed(ServoParameters(), u_cmd_v=1.0), rel=1e-4)


def test_matches_the_reference_result(servo_fmu: Path) -> None:
    reference = np.genfromtxt(SOURCE_DIR / "Servo" / "reference.csv", delimiter=",", names=True, dtype=None,
                              encoding="utf-8")
    result = simulate_fmu(str(servo_fmu), start_values=REFERENCE_START, input=REFERENCE_INPUT, stop_time=0.05,
                          output_interval=1e-3)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    for name in ("angle", "speed", "current", "t_last_edge", "t_prev_edge"):
        assert result[name].tolist() == pytest.approx(reference[name].tolist(), rel=1e-9, abs=1e-9), name
    for name in ("encoder_count", "edge_count", "edge_direction"):
        assert result[name].tolist() == reference[name].tolist(), name


def test_docstring_examples() -> None:
    failures, _ = doctest.testmod(cosim.plants.servo)
    assert failures == 0
