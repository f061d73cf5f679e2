"""PID position loop: designed with python-control for a stated bandwidth, run at the servo rate."""

from __future__ import annotations

import math

import pytest

from cosim import rigs
from cosim.controllers.pmac.motion import LinearMove
from cosim.controllers.pmac.servo import MotorModel, PidLoop, design_pid
from cosim.controllers.pmac.units import ServoClock
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import DcMotor, IdealConveyor

MOTOR = MotorModel(gain_counts_per_s_per_bit=6.0, tau_s=0.01)  # ~197 counts/ms at full DAC, 10 ms
PERIOD_S = ServoClock().period_s


def test_design_prints_bandwidth_and_margins_and_is_stable(capsys: pytest.CaptureFixture[str]) -> None:
    design = design_pid(MOTOR, period_s=PERIOD_S, bandwidth_hz=50)
    print(design)
    out = capsys.readouterr().out
    assert "crossover 50.0 Hz" in out and "closed-loop bandwidth" in out
    assert "phase margin" in out and "gain margin" in out and "stable" in out
    assert design.stable and design.max_pole_radius < 1
    assert design.phase_margin_deg > 60
    assert design.gain_margin_db > 10
    assert 50 < design.bandwidth_hz < 100  # closed-loop -3 dB above the crossover
    assert design.kp > 0 and design.ki > 0 and design.kd > 0


@pytest.mark.parametrize("bandwidth_hz", [20, 100, 200])
def test_design_hits_the_stated_crossover(bandwidth_hz: float) -> None:
    import control
    import numpy as np

    design = design_pid(MOTOR, period_s=PERIOD_S, bandwidth_hz=bandwidth_hz)
    controller = control.ss(np.array(design.a), np.array(design.b).reshape(-1, 1), np.array(design.c).reshape(1, -1),
                            design.d, PERIOD_S)
    loop = control.sample_system(MOTOR.transfer_function(), PERIOD_S, method="zoh") * controller
    z = np.exp(1j * 2 * math.pi * bandwidth_hz * PERIOD_S)
    assert abs(complex(loop(z))) == pytest.approx(1.0, rel=1e-9)
    phase_margin = 180 + math.degrees(np.angle(complex(loop(z))))
    assert design.phase_margin_deg == pytest.approx(phase_margin, abs=1e-3)
    assert design.stable


def test_closed_loop_follows_a_time_base_move_on_the_motor_stand_in(sim: Simulation) -> None:
    r"""Slave under PID at the servo rate follows a master-driven move (2000 counts at 40 counts/ms,
    TA 20 ms, done at ~70 ms): the following error stays bounded, the DAC never saturates, and the
    axis settles to within one count.

        cmd     __/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
        error   _/^^^^^^^^^^^^^^\______ (< 100 counts, then -> 0)
    """
    design = design_pid(MOTOR, period_s=PERIOD_S, bandwidth_hz=50)
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, loop=PidLoop(design))
    plant = DcMotor(sim, gain=MOTOR.gain_counts_per_s_per_bit, tau_s=MOTOR.tau_s)
    plant.drive("command", rig.motor.dac)
    rig.motor.feedback = lambda: plant.read("encoder_count")
    rig.cs.run_program([LinearMove(2000, 40_000, 20)])
    rig.pmac.start()
    sim.run(until=sim.ticks("250 ms"))
    t, err = sim.trace.edges("pmac.motor1.following_error")
    assert max(abs(err)) < 100  # counts
    assert max(abs(err[t >= 200_000_000])) <= 1
    assert rig.motor.cmd == 2000 and abs(rig.motor.act - 2000) <= 1
    _t_dac, dac = sim.trace.edges("pmac.motor1.dac")
    assert max(abs(dac)) < 32767  # never saturated


def test_unstable_gains_diverge_in_simulation(sim: Simulation) -> None:
    """The same loop with 30x the gain is unstable at the servo rate: the run shows it."""
    design = design_pid(MOTOR, period_s=PERIOD_S, bandwidth_hz=50)
    from dataclasses import replace

    hot = replace(design, c=tuple(30 * c for c in design.c), d=30 * design.d)
    belt = IdealConveyor(sim, speed_counts_per_ms=64)
    rig = rigs.external_time_base(sim, belt, scale_factor=2048, loop=PidLoop(hot))
    plant = DcMotor(sim, gain=MOTOR.gain_counts_per_s_per_bit, tau_s=MOTOR.tau_s)
    plant.drive("command", rig.motor.dac)
    rig.motor.feedback = lambda: plant.read("encoder_count")
    rig.cs.run_program([LinearMove(200, 40_000, 20)])
    rig.pmac.start()
    sim.run(until=sim.ticks("60 ms"))
    _t_dac, dac = sim.trace.edges("pmac.motor1.dac")
    assert max(abs(dac)) == 32767


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"bandwidth_hz": 0},
         r"bandwidth_hz = 0 is not allowed \(allowed: 0 < bandwidth <= servo rate / 10 = 225.9 Hz"),
        ({"bandwidth_hz": 300}, r"bandwidth_hz = 300"),
        ({"bandwidth_hz": 50, "integral_ratio": 1}, r"integral_ratio = 1 is not allowed \(allowed: > 1\)"),
    ],
)
def test_bad_design_inputs(kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        design_pid(MOTOR, period_s=PERIOD_S, **kwargs)


def test_bad_motor_model() -> None:
    with pytest.raises(ConfigurationError, match=r"tau_s = 0 is not allowed \(allowed: > 0\)"):
        MotorModel(6.0, 0)


def test_motor_with_loop_needs_feedback(sim: Simulation) -> None:
    design = design_pid(MOTOR, period_s=PERIOD_S, bandwidth_hz=50)
    rig = rigs.external_time_base(sim, IdealConveyor(sim, speed_counts_per_ms=64), scale_factor=2048,
                                  loop=PidLoop(design))
    rig.pmac.start()
    with pytest.raises(ConfigurationError, match="motor 1 has a position loop but no feedback"):
        sim.run(until=1_000)
