"""The Stepper FMU: pulse placement, following and losing steps, switch events, conformance.

A controller holding a pulse frequency over 1 ms slots drives the FMU with one step per slot::

    slot         |<---- 1 ms ---->|<---- 1 ms ---->|<---- 1 ms ---->|
    step_rate    r0               r1               r2
    step_phase   p0               p1               p2       (fraction of a period elapsed)
    pulses       |   |   |   |   |  |  |  |  |  |  | | | | | | | |
    FMU steps    [---------------)[---------------)[---------------)

Pulse j of a step is at t_start + (j - phase) / |rate| (phase 0: a pulse at t_start); a pulse at
the end of a step belongs to the next one.
"""

from __future__ import annotations

import itertools
import math
import shutil
import zipfile
from collections.abc import Iterator
from fractions import Fraction
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.build import build_platform_binary
from fmpy.validation import validate_fmu

from cosim.couplings.stepper import segment_rate_hz
from cosim.errors import ConfigurationError, FmuError
from cosim.fmu import Fmu
from cosim.fmubuild import ensure_fmu
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.plants.stepper import (
    StepperParameters,
    drive_slots,
    linear_model,
    max_acceleration_rad_s2,
    phase_after,
    pulse_instants,
    trapezoid_rates,
)
from cosim.presets import load_preset, read_preset
from cosim.signals import Signal
from cosim.timebase import Priority, TimeBase

pytestmark = pytest.mark.fmu

US = 1_000  # ns
MS = 1_000_000  # ns
VERSIONS = (2, 3)
NEMA17 = "nema17_17hs16_2004s1"
NEMA23 = "nema23_23hs30_2804s"
REFERENCE_START = {"step_rate": 3200.0, "limit_pos_position": 0.0004}


@pytest.fixture(scope="module", params=VERSIONS, ids=["fmi2", "fmi3"])
def stepper_fmu(request: pytest.FixtureRequest) -> Path:
    return ensure_fmu("Stepper", request.param)


@pytest.fixture(scope="module")
def stepper_fmi3() -> Path:
    return ensure_fmu("Stepper", 3)


def advance(fmu: Fmu, t: int) -> None:
    """Advance to ``t`` through any early returns at switch events."""
    while fmu.advance_to(t) < t:
        pass


# -- the FMU as a standard FMU -----------------------------------------------------------------
def test_validates_without_problems(stepper_fmu: Path) -> None:
    assert validate_fmu(str(stepper_fmu)) == []


def test_fmu_holds_its_sources_and_build_description(stepper_fmu: Path) -> None:
    names = set(zipfile.ZipFile(stepper_fmu).namelist())
    assert {"sources/model.c", "sources/model.h", "sources/cosim_fmu.c", "sources/model_vars.c",
            "documentation/readme.md"} <= names
    if "fmi3" in stepper_fmu.parts:
        assert {"sources/buildDescription.xml", "binaries/x86_64-linux/Stepper.so"} <= names
    else:
        assert "binaries/linux64/Stepper.so" in names


def test_simulates_standalone_in_fmpy(stepper_fmu: Path) -> None:
    result = simulate_fmu(str(stepper_fmu), start_values={"step_rate": 3200.0}, stop_time=0.1,
                          output_interval=1e-3)
    # pulses at 0, 1/3200 s, ... 0.0996875 s: the one at 0.1 s belongs to the next step
    assert result["commanded_steps"][-1] == 320
    assert result["last_pulse_time"][-1] == pytest.approx(0.0996875, abs=1e-12)
    assert result["angle"][-1] == pytest.approx(2 * math.pi * 320 / 3200, abs=2 * math.pi / 3200)
    assert not result["lost_steps"].any()


def test_rebuilds_from_its_own_sources_in_a_clean_folder(stepper_fmu: Path, tmp_path: Path) -> None:
    unzipped = tmp_path / "fmu"
    with zipfile.ZipFile(stepper_fmu) as zf:
        zf.extractall(unzipped)
    shutil.rmtree(unzipped / "binaries")
    (tmp_path / "build").mkdir()
    build_platform_binary(str(unzipped), str(tmp_path / "build"))
    rebuilt = shutil.make_archive(str(tmp_path / "Stepper"), "zip", unzipped)
    result = simulate_fmu(rebuilt, start_values={"step_rate": 3200.0}, stop_time=0.01)
    assert result["commanded_steps"][-1] == 32


def test_matches_the_reference_result(stepper_fmu: Path) -> None:
    reference = np.genfromtxt(Path(__file__).parents[1] / "fmu_src/Stepper/reference.csv", delimiter=",",
                              names=True, dtype=None, encoding="utf-8")
    result = simulate_fmu(str(stepper_fmu), start_values=REFERENCE_START, stop_time=0.1, output_interval=1e-3)
    assert result["time"].tolist() == pytest.approx(reference["time"].tolist(), abs=1e-12)
    for name in ("angle", "speed", "carriage_position", "position_error", "torque", "last_pulse_time"):
        assert result[name].tolist() == pytest.approx(reference[name].tolist(), rel=1e-7, abs=1e-10), name
    for name in ("commanded_steps", "lost_full_steps", "lost_steps", "limit_pos", "limit_neg", "home"):
        assert result[name].tolist() == reference[name].tolist(), name
    assert reference["limit_pos"].tolist()[49:51] == [False, True]  # trips at 49.77 ms


def test_two_instances_are_independent_and_identical(stepper_fmu: Path) -> None:
    with Fmu(stepper_fmu, parameters={"step_rate": 3200.0}) as a, Fmu(stepper_fmu) as b:
        advance(a, 5 * MS)
        b.set("step_rate", -6400.0)
        advance(b, 5 * MS)
        advance(a, 10 * MS)
        assert (a.get("commanded_steps"), b.get("commanded_steps")) == (32, -32)
        with Fmu(stepper_fmu, parameters={"step_rate": 3200.0}) as c:
            advance(c, 10 * MS)
            assert c.get("angle") == a.get("angle")


# -- pulse placement -------------------------------------------------------------------------------
@pytest.mark.parametrize(("rate", "phase", "expected_ns"), [
    (3000, Fraction(0), [0, 333_333, 666_667]),           # phase 0: a pulse at the step start
    (3000, Fraction(1, 2), [166_667, 500_000, 833_333]),  # half a period already elapsed
    (-2000, Fraction(3, 4), [125_000, 625_000]),          # the sign is the direction
])
def test_pulses_land_where_the_rule_puts_them(stepper_fmu: Path, rate: int, phase: Fraction,
                                              expected_ns: list[int]) -> None:
    instants = pulse_instants(Fraction(0), Fraction(1, 1000), rate_hz=Fraction(rate), phase=phase)
    assert [round(t * 10**9) for t in instants] == expected_ns
    with Fmu(stepper_fmu, parameters={"step_rate": float(rate), "step_phase": float(phase)}) as fmu:
        for t_ns, n in zip(expected_ns, range(1, len(expected_ns) + 1), strict=True):
            fmu.advance_to(t_ns + 1)  # just after pulse n
            assert fmu.get("commanded_steps") == int(math.copysign(n, rate))
            assert fmu.get("last_pulse_time") == pytest.approx(float(instants[n - 1]), abs=1e-15)
        fmu.advance_to(MS)
        assert fmu.get("pulse_phase") == pytest.approx(float(phase_after(Fraction(1, 1000), rate_hz=Fraction(rate),
                                                                         phase=phase)), abs=1e-9)


def slot_controller(periods_ns: list[int]) -> tuple[list[tuple[int, int, Fraction]], list[int]]:
    """A pulse generator that holds an integer period per 1 ms slot (a pulse when the time since
    the last one reaches the period): the slots' (start, period, phase) and every pulse instant."""
    slots, pulses = [], []
    last: int | None = None
    for k, period in enumerate(periods_ns):
        start = k * MS
        elapsed = period if last is None else start - last
        slots.append((start, period, Fraction(min(elapsed, period), period) % 1))
        t = start if elapsed >= period else last + period  # type: ignore[operator]
        while t < start + MS:
            pulses.append(t)
            last = t
            t += period
    return slots, pulses


def test_one_step_per_slot_equals_one_step_per_pulse(stepper_fmu: Path) -> None:
    rates = np.r_[np.linspace(2_000, 40_000, 20), np.linspace(40_000, 2_000, 20)]
    slots, pulses = slot_controller([round(1e9 / r) for r in rates])
    slot_ends = [start + MS for start, _, _ in slots]
    outputs = ("commanded_steps", "last_pulse_time", "angle", "speed")

    per_slot = []
    with Fmu(stepper_fmu) as fmu:
        for (_, period, phase), end in zip(slots, slot_ends, strict=True):
            fmu.set("step_rate", 1e9 / period)
            fmu.set("step_phase", float(phase))
            fmu.advance_to(end)
            per_slot.append([fmu.get(name) for name in outputs])

    per_pulse, seen = [], []
    following = dict(zip(pulses, [*pulses[1:], slot_ends[-1] + 1], strict=True))
    with Fmu(stepper_fmu) as fmu:
        t = 0
        for stop in sorted((set(pulses) | set(slot_ends)) - {0}):
            if t in following:  # one event per pulse: a train anchored at this pulse
                fmu.set("step_rate", 1e9 / (following[t] - t))
                fmu.set("step_phase", 0.0)
            fmu.advance_to(stop)
            if stop in following:
                seen.append(fmu.get("last_pulse_time"))
            if stop in slot_ends:
                per_pulse.append([fmu.get(name) for name in outputs])
            t = stop

    assert [round(s * 1e9) for s in seen] == pulses[:-1]  # read at each next pulse: the one before it
    expected_counts = [sum(1 for p in pulses if p < end) for end in slot_ends]
    assert [row[0] for row in per_slot] == [row[0] for row in per_pulse] == expected_counts
    for a, b in zip(per_slot, per_pulse, strict=True):
        assert a[1] == pytest.approx(b[1], abs=1e-12)  # same pulse instants [s]
        assert a[2] == pytest.approx(b[2], abs=1e-9)  # same trajectory [rad]
        assert a[3] == pytest.approx(b[3], abs=1e-6)  # [rad/s]
    assert [round(row[1] * 1e9) for row in per_slot] == [max(p for p in pulses if p < end) for end in slot_ends]


def test_held_inputs_continue_the_train_on_any_grid(stepper_fmu: Path, sim: Simulation) -> None:
    grid = np.cumsum(sim.rng.integers(1 * US, 700 * US, size=60))
    with Fmu(stepper_fmu, parameters={"step_rate": 4321.0, "step_phase": 0.375}) as one, \
            Fmu(stepper_fmu, parameters={"step_rate": 4321.0, "step_phase": 0.375}) as many:
        for t in grid:
            many.advance_to(int(t))
        one.advance_to(int(grid[-1]))
        expected = pulse_instants(Fraction(0), Fraction(int(grid[-1]), 10**9), rate_hz=Fraction(4321),
                                  phase=Fraction(3, 8))
        assert one.get("commanded_steps") == many.get("commanded_steps") == len(expected)
        assert many.get("last_pulse_time") == pytest.approx(float(expected[-1]), abs=1e-12)
        assert many.get("angle") == pytest.approx(one.get("angle"), abs=1e-9)


def test_a_pulse_train_segment_maps_to_rate_and_phase(stepper_fmu: Path) -> None:
    rate, phase = segment_rate_hz(TimeBase(), 1 * MS, 7, -1), 0.0  # PulseTrain.emit(t0, 1 ms, 7, direction 0)
    with Fmu(stepper_fmu, parameters={"step_rate": rate, "step_phase": phase}) as fmu:
        fmu.advance_to(1 * MS)
        fmu.set("step_rate", 0.0)
        fmu.advance_to(2 * MS)
        assert fmu.get("commanded_steps") == -7
        assert fmu.get("last_pulse_time") == pytest.approx(6 / 7 * 1e-3, abs=1e-12)  # within 1 ns of (6 ms)//7


def test_disabled_driver_ignores_pulses_and_releases_the_rotor(stepper_fmu: Path) -> None:
    with Fmu(stepper_fmu, parameters={"step_rate": 5000.0, "enable": False, "detent_torque": 0.0}) as fmu:
        fmu.advance_to(2 * MS)
        assert fmu.get("commanded_steps") == 0
        assert (fmu.get("current_a"), fmu.get("current_b"), fmu.get("angle")) == (0.0, 0.0, 0.0)


# -- motion ------------------------------------------------------------------------------------------
def test_follows_every_step_inside_the_pull_out_curve(stepper_fmu: Path) -> None:
    """NEMA 17 preset with a 1 kg carriage: 0 -> 5 rev/s in 100 ms, 50 ms at speed, back to 0."""
    rates = trapezoid_rates(5 * 200 * 16, ramp_slots=100, hold_slots=50)
    with Fmu(stepper_fmu, parameters={**load_preset(NEMA17), "carriage_mass": 1.0}) as fmu:
        count = drive_slots(fmu, rates)
        advance(fmu, (len(rates) + 300) * MS)  # settle
        assert fmu.get("commanded_steps") == count == sum(rates) / 1000
        assert abs(fmu.get("position_error")) < 1.0
        assert (fmu.get("lost_steps"), fmu.get("lost_full_steps")) == (False, 0)
        assert fmu.get("carriage_position") == pytest.approx(count / 3200 * 0.008, abs=0.008 / 3200)


def test_loses_steps_beyond_the_pull_out_torque_and_reports_it(stepper_fmu: Path) -> None:
    """Same motor with 20 times its rotor inertia as load: 0 -> 10 rev/s in 10 ms needs about
    6300 rad/s2, more than the motor can force (Kt I / J = 2800 rad/s2)."""
    preset = load_preset(NEMA17)
    params = StepperParameters.from_parameters({**preset, "load_inertia": 20 * preset["rotor_inertia"]})
    assert max_acceleration_rad_s2(params) < 2 * math.pi * 10 / 0.010
    rates = trapezoid_rates(10 * 200 * 16, ramp_slots=10, hold_slots=20)
    with Fmu(stepper_fmu, parameters={**preset, "load_inertia": params.load_inertia}) as fmu:
        count = drive_slots(fmu, rates)
        advance(fmu, (len(rates) + 100) * MS)
        assert fmu.get("commanded_steps") == count
        assert fmu.get("lost_steps") is True
        lost = fmu.get("lost_full_steps")
        assert lost > 0 and lost % 4 == 0  # whole tooth pitches, rotor behind
        assert fmu.get("position_error") / 16 == pytest.approx(lost, abs=2.0)


def oscillation(times_ns: np.ndarray, speed: np.ndarray) -> tuple[float, float]:
    """Damped frequency [rad/s] from the speed's zero crossings and decay rate [1/s] from its peaks."""
    i = np.nonzero(np.sign(speed[:-1]) != np.sign(speed[1:]))[0]
    crossings = (times_ns[i] + (times_ns[i + 1] - times_ns[i]) * speed[i] / (speed[i] - speed[i + 1])) / 1e9
    omega_d = math.pi * (len(crossings) - 1) / (crossings[-1] - crossings[0])
    peaks = [(times_ns[a + 1 + np.argmax(np.abs(speed[a + 1:b + 1]))] / 1e9, np.abs(speed[a + 1:b + 1]).max())
             for a, b in itertools.pairwise(i)]
    decay = math.log(peaks[0][1] / peaks[-1][1]) / (peaks[-1][0] - peaks[0][0])
    return omega_d, decay


def test_small_signal_natural_frequency_matches_the_linear_model(stepper_fmu: Path) -> None:
    """One microstep of 1/256 step from rest at a full-step position: the rotor rings at
    sqrt(Nr (Kt I + 4 Td) / J)."""
    params = {"microsteps": 256, "detent_torque": 0.05, "viscous_damping": 2e-4}
    with Fmu(stepper_fmu, parameters={**params, "step_rate": 1000.0}) as fmu:
        fmu.advance_to(1 * US)  # the pulse at t = 0
        fmu.set("step_rate", 0.0)
        times = np.arange(10 * US, 20 * MS + 1, 10 * US)
        samples = []
        for t in times:
            fmu.advance_to(int(t))
            samples.append(fmu.get("speed"))
    speed = np.array(samples)
    omega_d, decay = oscillation(times, speed)
    wn_fmu = math.hypot(omega_d, decay)
    wn, zeta, _ = control.damp(linear_model(params), doprint=False)
    expected = StepperParameters.from_parameters(params)
    assert wn[0] == pytest.approx(expected.natural_frequency_rad_s, rel=1e-9)
    assert wn[0] == pytest.approx(math.sqrt(50 * (0.159 * 2.0 + 4 * 0.05) / 5.4e-6), rel=1e-9)
    assert wn_fmu == pytest.approx(wn[0], rel=0.02)
    assert decay / wn_fmu == pytest.approx(zeta[0], rel=0.1)


def test_small_step_response_matches_the_linear_model_with_its_current_loop(stepper_fmu: Path) -> None:
    """NEMA 17 preset (L = 2.6 mH, current loop 20 us, detent 0.015 N.m) at 256 microsteps: the
    rotor's response to one microstep follows G(s) = Nr Kt I / ((tau s + 1)(J s^2 + B s + K))."""
    params = {**load_preset(NEMA17), "microsteps": 256}
    times = np.arange(0, 20 * MS + 1, 50 * US)
    with Fmu(stepper_fmu, parameters={**params, "step_rate": 1000.0}) as fmu:
        fmu.advance_to(1)  # the pulse at t = 0
        fmu.set("step_rate", 0.0)
        angle = []
        for t in times[1:]:
            fmu.advance_to(int(t))
            angle.append(fmu.get("angle"))
    microstep = StepperParameters.from_parameters(params).microstep_angle_rad
    expected = control.step_response(linear_model(params), T=times / 1e9).outputs * microstep
    assert np.max(np.abs(np.array(angle) - expected[1:])) < 0.005 * microstep  # without the lag: 3 %
    assert np.ptp(angle) > 0.5 * microstep  # it did move (and ring)


def test_current_follows_its_command_with_a_first_order_rise(stepper_fmu: Path) -> None:
    """Full steps (wave drive) with L/R = 1 ms and ample voltage: after the pulse at t = 0 phase B
    rises as I (1 - exp(-t / tau)) and phase A falls as I exp(-t / tau)."""
    params = {"microsteps": 1, "phase_inductance": 1.1e-3, "phase_resistance": 1.1, "current_tau": 1e-3,
              "supply_voltage": 1000.0, "step_rate": 100.0}
    with Fmu(stepper_fmu, parameters=params) as fmu:
        for t in (100 * US, 1 * MS, 3 * MS):
            fmu.advance_to(t)
            assert fmu.get("current_b") == pytest.approx(2.0 * (1 - math.exp(-t / 1e6)), rel=1e-6)
            assert fmu.get("current_a") == pytest.approx(2.0 * math.exp(-t / 1e6), rel=1e-6)


def test_the_bus_voltage_limits_the_current_rise(stepper_fmu: Path) -> None:
    params = {"microsteps": 1, "phase_inductance": 2.6e-3, "supply_voltage": 5.2, "step_rate": 100.0}
    with Fmu(stepper_fmu, parameters=params) as fmu:
        fmu.advance_to(100 * US)
        bound = 5.2 / 2.6e-3 * 100e-6  # di/dt <= V / L: 0.2 A after 100 us instead of 2 A
        assert 0.95 * bound < fmu.get("current_b") <= bound


@pytest.mark.parametrize(("rev_per_s", "supply_voltage", "loses"), [(10, 24.0, False), (20, 24.0, True),
                                                                    (20, 96.0, False)])
def test_pull_out_torque_falls_with_speed_as_back_emf_eats_the_bus_voltage(
        stepper_fmu: Path, rev_per_s: int, supply_voltage: float, loses: bool) -> None:
    """NEMA 17 preset against 0.2 N.m (63 % of Kt I): fine at 10 rev/s on 24 V; at 20 rev/s the
    back-EMF (Kt w = 20 V) leaves too little voltage to drive the current, unless the bus is higher."""
    rates = trapezoid_rates(rev_per_s * 200 * 16, ramp_slots=100, hold_slots=50)
    params = {**load_preset(NEMA17), "load_torque": 0.2, "supply_voltage": supply_voltage}
    with Fmu(stepper_fmu, parameters=params) as fmu:
        drive_slots(fmu, rates)
        assert fmu.get("lost_steps") is loses


def test_coulomb_friction_holds_below_and_slips_above_its_torque(stepper_fmu: Path) -> None:
    free = {"enable": False, "detent_torque": 0.0, "viscous_damping": 0.0, "friction_torque": 0.01}
    with Fmu(stepper_fmu, parameters={**free, "load_torque": 0.008}) as held, \
            Fmu(stepper_fmu, parameters={**free, "load_torque": 0.011}) as slipping:
        held.advance_to(10 * MS)
        slipping.advance_to(10 * MS)
        assert (held.get("speed"), held.get("angle")) == (0.0, 0.0)
        assert slipping.get("speed") == pytest.approx(-0.001 / 5.4e-6 * 0.01, rel=1e-9)


def test_coulomb_friction_stops_a_coasting_rotor_and_keeps_it_stopped(stepper_fmu: Path) -> None:
    """A free rotor pushed by 0.02 N.m against 0.01 N.m friction for 5 ms coasts to rest in the
    next 5 ms (decelerated by friction alone) and then sticks: speed exactly 0."""
    free = {"enable": False, "detent_torque": 0.0, "viscous_damping": 0.0, "friction_torque": 0.01}
    alpha = 0.01 / 5.4e-6  # rad/s2, both ways
    with Fmu(stepper_fmu, parameters={**free, "load_torque": -0.02}) as fmu:
        fmu.advance_to(5 * MS)
        fmu.set("load_torque", 0.0)
        fmu.advance_to(20 * MS)
        assert fmu.get("speed") == 0.0
        assert fmu.get("angle") == pytest.approx(alpha * 0.005**2, abs=1e-6)


def test_lead_screw_moves_the_carriage_both_ways(stepper_fmu: Path) -> None:
    with Fmu(stepper_fmu, parameters={"step_rate": -3200.0, "carriage_start": 0.1, "screw_lead": 0.005}) as fmu:
        advance(fmu, 100 * MS)
        fmu.set("step_rate", 0.0)
        advance(fmu, 400 * MS)
        assert fmu.get("commanded_steps") == -320
        assert fmu.get("carriage_position") == pytest.approx(0.1 - 0.1 * 0.005, abs=0.005 / 3200)


# -- switches ---------------------------------------------------------------------------------------
SWITCH_AT = 0.0004  # m from the start


def constant_speed_move(switch: str) -> tuple[dict[str, float | int], float]:
    """1 rev/s at 256 microsteps with damping ratio 0.7: after settling the rotor turns at exactly
    2 pi rad/s behind the commanded staircase's mean (half a microstep ahead of the ramp) by the
    load angle asin(B w / Kt I) / Nr. Returns the parameters and the analytic crossing time [s]."""
    p = StepperParameters.from_parameters({"microsteps": 256})
    damping = 2 * 0.7 * math.sqrt(p.stiffness * p.inertia)
    omega = 2 * math.pi
    lag = math.asin(damping * omega / p.torque_amplitude) / p.rotor_teeth
    theta_switch = SWITCH_AT * 2 * math.pi / 0.008
    t_cross = (theta_switch - p.microstep_angle_rad / 2 + lag) / omega
    sign = 1 if switch == "limit_pos" else -1
    params: dict[str, float | int] = {"microsteps": 256, "viscous_damping": damping, "step_rate": sign * 51200.0,
                                      f"{switch}_position": sign * SWITCH_AT}
    if switch == "limit_neg":
        params["home_position"] = -1.0  # out of the way
    return params, t_cross


@pytest.mark.parametrize("switch", ["limit_pos", "limit_neg", "home"])
def test_switch_crossing_is_an_event_within_1_us_of_the_analytic_time(stepper_fmi3: Path, switch: str) -> None:
    params, t_cross = constant_speed_move(switch)
    t_cross_ns = t_cross * 1e9
    with Fmu(stepper_fmi3, parameters=params) as fmu, Fmu(stepper_fmi3, parameters=params) as before:
        reached = fmu.advance_to(100 * MS)  # one step: it returns early at the crossing
        assert fmu.events == 1
        assert abs(reached - t_cross_ns) < 1 * US
        assert fmu.get(switch) is True  # normally closed: true = open = tripped
        before.advance_to(math.floor(t_cross_ns) - 1 * US)
        assert before.get(switch) is False


def test_fmi2_shows_the_switch_at_the_end_of_the_step() -> None:
    params, t_cross = constant_speed_move("limit_pos")
    with Fmu(ensure_fmu("Stepper", 2), parameters=params) as fmu:
        t = 0
        while not fmu.get("limit_pos"):
            t += MS
            assert fmu.advance_to(t) == t  # no early return on FMI 2.0
        assert t == math.ceil(t_cross * 1000) * MS


def test_the_master_publishes_the_switch_edge_at_the_event_tick(sim: Simulation) -> None:
    """A controller re-sets the same rate every 1 ms slot; the FMU runs one step per slot and the
    watched limit switch changes at the exact crossing tick."""
    params, t_cross = constant_speed_move("limit_pos")
    rate = float(params.pop("step_rate"))
    step_rate = Signal(sim, "ctl.x.step_rate", kind="real", initial=0.0)
    axis = Plant.load(sim, "Stepper", name="x", fmi_version=3, parameters=params)
    axis.drive("step_rate", step_rate)
    axis.watch("limit_pos")

    def pulse_slot() -> Iterator[object]:
        for k in range(100):
            yield sim.at(k * MS, Priority.SLOT)
            step_rate.set(rate)

    sim.process(pulse_slot())  # type: ignore[arg-type]
    sim.run(until=100 * MS)
    times, values = sim.trace.edges("x.limit_pos")
    assert values.tolist() == [0.0, 1.0]
    assert abs(int(times[1]) - t_cross * 1e9) < 1 * US


# -- bad parameters -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("name", "value", "message"), [
    ("rotor_inertia", -1e-6, "parameter rotor_inertia = -9.9999999999999995e-07 kg.m2 is not allowed "
                             "(allowed: > 0 kg.m2)"),
    ("steps_per_rev", 0, "parameter steps_per_rev = 0 is not allowed (allowed: > 0 and <= 100000)"),
    ("steps_per_rev", 202, "parameter steps_per_rev = 202 is not allowed (allowed: a positive multiple of 4"),
    ("microsteps", 3, "parameter microsteps = 3 is not allowed (allowed: 1, 2, 4, 8, 16, 32, 64, 128, 256)"),
    ("limit_neg_position", 0.5, "parameter limit_neg_position = 0.5 m is not allowed (allowed: < limit_pos_position"),
    ("step_phase", 1.0, "input step_phase = 1 is not allowed (allowed: >= 0 and < 1)"),
    ("step_rate", 2e7, "input step_rate = 20000000 Hz is not allowed (allowed: -10000000..10000000 Hz)"),
])
def test_bad_parameters_fail_with_the_fmus_reason(stepper_fmu: Path, name: str, value: float, message: str) -> None:
    with pytest.raises(FmuError) as info:
        Fmu(stepper_fmu, parameters={name: value})
    assert message in str(info.value)


def test_an_integer_outside_its_declared_range_is_refused_before_the_fmu(stepper_fmu: Path) -> None:
    with pytest.raises(ConfigurationError, match=r"^fmu \(Stepper.fmu\): microsteps = 512 is not allowed "
                                                 r"\(allowed: 1..256\)$"):
        Fmu(stepper_fmu, parameters={"microsteps": 512})


def test_a_phase_of_one_set_while_running_fails_the_step(stepper_fmu: Path) -> None:
    with Fmu(stepper_fmu) as fmu:
        fmu.set("step_phase", 1.0)
        with pytest.raises(FmuError, match="input step_phase = 1 is not allowed"):
            fmu.advance_to(MS)


# -- presets and the Python companion -------------------------------------------------------------------
@pytest.mark.parametrize(("preset", "holding_torque", "inertia"), [(NEMA17, 0.45, 5.4e-6), (NEMA23, 1.9, 4.8e-5)])
def test_presets_cite_their_sources_and_load(stepper_fmi3: Path, preset: str, holding_torque: float,
                                             inertia: float) -> None:
    data = read_preset(preset)
    assert data["model"] == "Stepper" and len(data["sources"]) >= 3
    p = StepperParameters.from_parameters(data["parameters"])
    assert math.sqrt(2) * p.torque_amplitude == pytest.approx(holding_torque, rel=0.01)
    assert p.rotor_inertia == inertia
    with Fmu(stepper_fmi3, parameters=data["parameters"]) as fmu:
        fmu.set("step_rate", 1000.0)
        advance(fmu, 10 * MS)
        assert fmu.get("commanded_steps") == 10


def test_parameter_defaults_are_the_fmus_start_values() -> None:
    assert StepperParameters() == StepperParameters.from_parameters()


def test_linear_model_has_the_holding_stiffness() -> None:
    p = StepperParameters.from_parameters({"detent_torque": 0.02, "load_inertia": 1e-6, "carriage_mass": 2.0})
    assert p.inertia == pytest.approx(5.4e-6 + 1e-6 + 2.0 * (0.008 / (2 * math.pi)) ** 2, rel=1e-12)
    assert p.stiffness == pytest.approx(50 * (0.159 * 2.0 + 0.08), rel=1e-12)
    g = linear_model(p)
    assert float(g.dcgain()) == pytest.approx(0.318 / 0.398, rel=1e-12)
    lagged = linear_model({"phase_inductance": 1e-3, "current_tau": 1e-4})
    assert len(lagged.poles()) == 3 and min(lagged.poles().real) == pytest.approx(-1e4, rel=1e-9)


@pytest.mark.parametrize(("field", "value", "allowed"), [
    ("microsteps", 3, "1, 2, 4"), ("steps_per_rev", 0, "a positive multiple of 4"), ("rotor_inertia", 0.0, "> 0"),
    ("current", float("nan"), "a finite number"), ("rotor_inertia", float("inf"), "a finite number"),
])
def test_linear_model_refuses_what_the_fmu_refuses(field: str, value: float, allowed: str) -> None:
    with pytest.raises(ConfigurationError, match=f"{field} = {value!r} is not allowed \\(allowed: {allowed}"):
        StepperParameters.from_parameters({field: value})


def test_pulse_rule_helpers_refuse_bad_values() -> None:
    with pytest.raises(ConfigurationError, match=r"^phase = 1 is not allowed \(allowed: 0 <= phase < 1\)$"):
        pulse_instants(Fraction(0), Fraction(1), rate_hz=Fraction(10), phase=Fraction(1))
    assert pulse_instants(Fraction(0), Fraction(1), rate_hz=Fraction(0), phase=Fraction(0)) == []


def test_drive_slots_counts_signed_pulses_and_refuses_a_bad_slot(stepper_fmi3: Path) -> None:
    """3 kHz for two slots, then -1.5 kHz for two: 6 pulses out, 3 back (the phase carries 1.5 per slot)."""
    with Fmu(stepper_fmi3) as fmu:
        rates = [Fraction(3000)] * 2 + [Fraction(-1500)] * 2
        assert drive_slots(fmu, rates) == 6 - 3 == fmu.get("commanded_steps")
        assert fmu.t == 4 * MS and fmu.get("step_rate") == 0.0
        with pytest.raises(ConfigurationError, match=r"slot_ns = 0 is not allowed \(allowed: >= 1 tick\)"):
            drive_slots(fmu, rates, slot_ns=0)
    assert trapezoid_rates(3000, ramp_slots=3, hold_slots=1, down=False) == [1000, 2000, 3000, 3000]
