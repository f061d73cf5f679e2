"""The PMAC model on the real Conveyor and Servo FMUs (issue 7 point 5).

Timing picture of the coupled run (scenario ``pmac_fmu_slave``; conveyor at 32 counts/ms from
t = 0, first mark at 1000.355 counts; servo interrupts every 442,708/442,709 ns)::

    servo interrupt  |    |    |    |    |    |    |    |    |    |    |    |
    conveyor.mark    ______________________|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾   at 31,261,094 ns (FMI 3.0 event)
    capture          ______________________^ 1/T position at the mark tick, truncated to 1/256 count
    pmac.ect.method  $B‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$A‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾   next interrupt
    servo u_cmd      0 V ......................... PID(DAC) * 10 V / 32768 at every interrupt

Encoder edge instants (float seconds from the FMUs) become integer ns once, in
``PlantEncoder``, as the first tick at or after the edge.
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from cycle_probe import record_each_cycle

from cosim import rigs
from cosim.controllers.pmac import (
    ARMED,
    FROZEN,
    I10_DEFAULT,
    EncoderChannel,
    LinearMove,
    Pmac,
    ServoClock,
    design_pid,
    formula_percent,
)
from cosim.controllers.pmac.servo import DAC_VOLTS_PER_BIT
from cosim.couplings.encoder import PlantEncoder, watch_mark
from cosim.couplings.servo import (
    connect_servo,
    dac_volts,
    full_model_margins,
    full_scale_speed_counts_per_ms,
    servo_motor_model,
)
from cosim.encoders import EncoderSample
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.master import Plant
from cosim.plants.conveyor import ConveyorParameters
from cosim.plants.servo import ServoParameters, linear_model
from cosim.presets import load_preset
from cosim.runner import Result, run_scenario
from cosim.scenario import load
from cosim.signals import Signal
from cosim.timebase import Priority

MS = 1_000_000  # ns
COUNTS_PER_METRE = 50_000.0  # conveyor_web_200mm_wheel
MOTOR = ServoParameters.from_mapping(load_preset("servo_maxon_re40_24v"))


class EncoderDouble:
    """A plant double with the FMUs' encoder outputs (edge instants in float seconds)."""

    name = "double"

    def __init__(self, sim: Simulation, **outputs: float) -> None:
        self.sim = sim
        self.outputs = {"encoder_count": 0, "edge_direction": 1, "t_last_edge": 0.0, "t_prev_edge": 0.0, **outputs}
        self.driven: list[tuple[str, float]] = []

    def variable_names(self) -> list[str]:
        return [*self.outputs, "u_cmd"]

    def read(self, variable: str) -> float:
        return self.outputs[variable]

    def drive(self, variable: str, signal: Signal, *, convert: object) -> None:
        assert callable(convert)
        signal.subscribe(lambda s: self.driven.append((variable, convert(s.value))))


def conveyor(sim: Simulation, *, counts_per_ms: Fraction, mark_offset_m: float = 0.05) -> tuple[Plant, float]:
    """The Conveyor FMU (FMI 3.0) at a constant speed from t = 0; returns it and its speed [m/s]."""
    speed = float(counts_per_ms) * 1000 / COUNTS_PER_METRE
    belt = ConveyorParameters.from_mapping({**load_preset("conveyor_web_200mm_wheel"), "speed_start": speed,
                                            "mark_offset": mark_offset_m})
    plant = Plant.load(sim, "Conveyor", name="conveyor", parameters=belt.as_fmu_parameters())
    plant.set({"speed_cmd": speed})
    return plant, speed


# -- the adapter, on doubles ----------------------------------------------------------------------------
def test_plant_encoder_ceils_edge_instants_to_ns_and_ignores_the_start_time(sim: Simulation) -> None:
    double = EncoderDouble(sim, encoder_count=7, t_last_edge=1.2345674e-3, t_prev_edge=0.0)
    encoder = PlantEncoder(double)
    assert encoder.sample(0) == EncoderSample(7, 1_234_568, None, 1)  # 1,234,567.4 ns -> first tick after
    double.outputs.update(t_prev_edge=1.0e-3, edge_direction=-1)
    assert encoder.sample(0) == EncoderSample(7, 1_234_568, 1_000_000, -1)
    double.outputs.update(t_last_edge=0.0)  # the FMU's "no edge yet"
    assert encoder.sample(0) == EncoderSample(7, None, None, -1)


def test_plant_encoder_position_is_1_over_t_truncated(sim: Simulation) -> None:
    double = EncoderDouble(sim, encoder_count=10, t_last_edge=31.25e-6, t_prev_edge=0.0)
    encoder = PlantEncoder(double, start=-1)
    sim.run(until=31_250 + 15_625 + 976)  # half a count + 1/32 count after the edge, less 1 ns
    assert encoder.position(fraction_bits=5) == Fraction(10 * 32 + 16, 32)
    assert encoder.position(fraction_bits=8) == Fraction(10 * 256 + 135, 256)


def test_plant_encoder_takes_the_first_tick_at_or_after_each_edge(sim: Simulation) -> None:
    double = EncoderDouble(sim, encoder_count=5)
    encoder = PlantEncoder(double)
    cases = [  # (t_last_edge [s], tick [ns])
        (0.054693046875, 54_693_047),      # mark 2 of the flying shear: 54,693,046.875 ns -> the next ns
        (442_708e-9, 442_708),             # a whole ns in float: that ns
        (1e-3 + 5e-16, 1_000_000),         # 0.5e-6 ns above a tick: float noise, that tick
        (1e-3 - 5e-16, 1_000_000),         # 0.5e-6 ns below: that tick
        (1e-3 + 1.5e-15, 1_000_001),       # 1.5e-6 ns above: past the tick, the next one
        (1.0000005e-3, 1_000_001),         # half a ns: the next one
    ]
    for t_last_s, tick in cases:
        double.outputs.update(t_last_edge=t_last_s)
        assert encoder.sample(0).last_edge_t == tick, t_last_s
    double.outputs.update(t_last_edge=2e-3, t_prev_edge=1.0000005e-3)  # the edge before is read again as previous
    assert encoder.sample(0) == EncoderSample(5, 2_000_000, 1_000_001, 1)


def test_plant_encoder_reads_the_fmu_outputs_as_read_one_by_one(sim: Simulation) -> None:
    plant, _speed = conveyor(sim, counts_per_ms=Fraction(32))
    encoder = PlantEncoder(plant)
    sim.run(until=3 * MS + 123)
    count, last_s, prev_s = plant.read("encoder_count"), plant.read("t_last_edge"), plant.read("t_prev_edge")
    assert count == 96  # 32 counts/ms for 3 ms
    assert encoder.sample(sim.now) == EncoderSample(
        int(count), sim.timebase.ticks_from_seconds_ceil(last_s), sim.timebase.ticks_from_seconds_ceil(prev_s), 1)


def test_plant_encoder_reads_only_now(sim: Simulation) -> None:
    encoder = PlantEncoder(EncoderDouble(sim))
    with pytest.raises(ConfigurationError, match=r"t of PlantEncoder\.sample = 5 is not allowed"):
        encoder.sample(5)


def test_dac_drives_u_cmd_in_volts(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.coordinate_system(1)
    motor = pmac.add_motor(1, loop=None)
    double = EncoderDouble(sim, encoder_count=3)
    connect_servo(motor, double)
    motor.dac.set(32767)
    motor.dac.set(-16384)
    assert double.driven == [("u_cmd", 32767 * 10 / 32768), ("u_cmd", -5.0)]
    assert motor.feedback is not None and motor.feedback() == 3.0
    assert dac_volts(32768) == 10.0 and Fraction(10, 32768) == DAC_VOLTS_PER_BIT


def test_connect_servo_refuses_a_finer_extension_than_the_hardware(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.coordinate_system(1)
    with pytest.raises(ConfigurationError, match=r"fraction_bits = 9 is not allowed \(allowed: 0..8\)"):
        connect_servo(pmac.add_motor(1), EncoderDouble(sim), fraction_bits=9)


# -- the design model of the Servo FMU --------------------------------------------------------------------
def test_servo_design_model_matches_the_linear_model_without_inductance() -> None:
    model = servo_motor_model(MOTOR)
    dc_speed = float(linear_model(MOTOR, output="speed").dcgain())  # rad/s per V; L has no DC effect
    counts_per_rad = MOTOR.counts_per_rev / (2 * math.pi)
    assert model.gain_counts_per_s_per_bit == pytest.approx(dc_speed * counts_per_rad * 10 / 32768, rel=1e-12)
    assert model.gain_counts_per_s_per_bit == pytest.approx(7.740, abs=1e-3)
    assert full_scale_speed_counts_per_ms(MOTOR) == pytest.approx(253.6, abs=0.05)  # 32767 bits = 9.9997 V
    assert model.tau_s == pytest.approx(MOTOR.resistance * MOTOR.inertia
                                        / (MOTOR.torque_constant * MOTOR.back_emf_constant), rel=1e-12)


def test_pid_on_the_full_servo_model_is_stable_with_stated_margins() -> None:
    design = design_pid(servo_motor_model(MOTOR), period_s=ServoClock(I10_DEFAULT).period_s, bandwidth_hz=100)
    gm_db, pm_deg, radius = full_model_margins(design, MOTOR)
    assert design.phase_margin_deg == pytest.approx(66.4, abs=0.1)  # on the design model
    assert pm_deg == pytest.approx(56.2, abs=0.1) and gm_db == pytest.approx(12.1, abs=0.1)  # with L: less
    assert radius < 1


# -- the FMUs ---------------------------------------------------------------------------------------------
@pytest.mark.fmu
def test_watch_mark_refuses_fmi2_which_cannot_locate_the_edge(sim: Simulation) -> None:
    plant = Plant.load(sim, "Conveyor", name="conveyor", fmi_version=2)
    with pytest.raises(ConfigurationError, match="FMI version of conveyor for the capture trigger = 2"):
        watch_mark(plant)


@pytest.mark.fmu
@pytest.mark.parametrize(("counts_per_ms", "scale_factor", "pct"), [
    (Fraction(32), 4096, 100),   # 0.64 m/s at RTIF 32 counts/ms
    (Fraction(24), 4096, 75),    # 3/4 of it
    (Fraction(25), 4096, Fraction(625, 8)),  # the preset's 0.5 m/s: 78.125 %
    (Fraction(64), 2048, 100),   # 1.28 m/s, the manual's 64 counts/ms with SF 2048
])
def test_time_base_percent_from_the_fmu_conveyor_equals_the_formula(
        sim: Simulation, counts_per_ms: Fraction, scale_factor: int, pct: Fraction) -> None:
    assert formula_percent(scale_factor, counts_per_ms) == pct
    plant, _speed = conveyor(sim, counts_per_ms=counts_per_ms)
    rig = rigs.external_time_base(sim, PlantEncoder(plant), scale_factor=scale_factor)
    rig.pmac.start()
    cycles = 60
    values = record_each_cycle(sim, rig.pmac.clock, lambda k, t: rig.entry.result, cycles=cycles)
    sim.run(until=rig.pmac.clock.t(cycles))
    expected = pct * I10_DEFAULT / 100  # register units (2^-23 ms per servo cycle)
    quantum = 2 * scale_factor  # one 1/32 count per servo cycle
    one_ns = quantum * 32 * counts_per_ms / MS  # master travel in 1 ns: interrupts are 442,708 or 442,709 ns apart
    running = values[1:]  # cycle 0 only stores the source
    assert all(abs(v - expected) < quantum + one_ns for v in running), [v - expected for v in running]
    assert abs(sum(running) / len(running) - expected) <= Fraction(2 * quantum, len(running))


@pytest.mark.fmu
@pytest.mark.parametrize("mark_offset_m", [0.0200071, 0.01234567, 0.015])
def test_triggered_start_time_zero_is_the_conveyor_position_at_the_mark_edge(
        sim: Simulation, mark_offset_m: float) -> None:
    """``time zero`` (1/256 count, truncated) vs the belt position of the mark's leading edge."""
    plant, _speed = conveyor(sim, counts_per_ms=Fraction(32), mark_offset_m=mark_offset_m)
    rig = rigs.triggered_time_base(sim, PlantEncoder(plant), watch_mark(plant), scale_factor=512, method=FROZEN)
    rig.cs.run_program([LinearMove(100, 32_000, 5)])
    sim.call_at(MS, Priority.HOST, lambda: rig.pmac.set_ivar(8000, (ARMED << 20) | rigs.MASTER_CHANNEL))
    rig.pmac.start()
    sim.run(until=35 * MS)
    mark_pos = Fraction(mark_offset_m * COUNTS_PER_METRE)
    assert len(rig.entry.starts) == 1
    error = Fraction(rig.entry.starts[0].time_zero_pos256, 256) - mark_pos
    one_ns = Fraction(32, MS)  # master travel in 1 ns: the capture is at the first tick at or after the edge
    assert -Fraction(1, 256) < error <= one_ns, float(error)  # truncated to 1/256 count
    t, value = sim.trace.edges("conveyor.mark")
    assert rig.entry.starts[0].capture_t == t[value == 1][0]


@pytest.mark.fmu
def test_capture_on_the_fmu_mark_latches_once_per_mark(sim: Simulation) -> None:
    plant, _speed = conveyor(sim, counts_per_ms=Fraction(32), mark_offset_m=0.0100003)
    channel = EncoderChannel(sim, rigs.MASTER_CHANNEL, PlantEncoder(plant), trigger=watch_mark(plant))
    sim.run(until=20 * MS)
    (t_capture, pos256), = channel.captures
    assert t_capture == 15_625_469  # 500.015 counts at 32 counts/ms = 15,625,468.75 ns, ceiled
    assert pos256 == 500 * 256 + 3  # 0.015 count = 3.84/256, truncated


@pytest.fixture(scope="module")
def slave_run() -> Result:
    return run_scenario(load("pmac_fmu_slave"))


@pytest.mark.fmu
def test_fmu_slave_scenario_passes_and_reports_its_figures(slave_run: Result) -> None:
    result = slave_run
    assert result.error is None
    assert result.verdict == "PASS", result.table()
    figures = {name: f["value"] for name, f in result.figures.items()}
    assert -1 / 256 < figures["start_error_counts"] <= 32 / MS  # truncation, and at most 1 ns of master travel
    assert figures["mark_time_ms"] == pytest.approx(1000.355 / 32, abs=1e-6)


@pytest.mark.fmu
def test_servo_fmu_follows_the_time_base_move_within_the_stated_bound(slave_run: Result) -> None:
    """100 Hz loop, 64 counts/ms: |sync error| <= 65 counts on the move, within 1/2 count at the end."""
    figures = {name: f["value"] for name, f in slave_run.figures.items()}
    assert figures["max_abs_sync_error"] <= 65
    assert abs(figures["final_position_error"]) <= 0.5
    assert figures["max_pole_radius_full_model"] < 1


@pytest.mark.fmu
def test_sync_check_fails_with_a_slower_loop() -> None:
    result = run_scenario(load("pmac_fmu_slave"), overrides={"bandwidth_hz": "50"})
    assert result.verdict == "FAIL"
    assert result.figures["max_abs_sync_error"]["value"] > 100
