"""Laser PWM: a 40 W CO2 laser gated on twice by a scripted modulation source; energy checked in closed form.

The source sets enable (the controller's watchdog) at 0, the PWM period and on-time in ticks of
the 20 MHz modulation clock, and opens the gate twice::

    enable  ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    gate    ___|‾‾‾‾‾‾‾ gate_ms ‾‾‾‾‾‾‾|___ gap_ms ___|‾‾‾‾ gate_ms ‾‾‾‾|______
              0.1 ms

The Laser FMU resolves the carrier itself; the master steps it only at the gate changes and at
the requested samples. Checks: the energy delivered equals the closed-form integral of the
first-order power response (1e-9 relative), the power never exceeds the peak, and the gate is
open exactly as long as programmed.
"""

from __future__ import annotations

from fractions import Fraction

from cosim.checks import Bound, Duration, EdgeRef, ValueAt
from cosim.controllers.scripted import play
from cosim.plants.laser import pwm_energy
from cosim.presets import load_preset
from cosim.scenario import Param, Run
from cosim.signals import Signal

PARAMETERS = (
    Param("pwm_period", 1000, "clocks", (1, 65535), "PWM period in 20 MHz clock ticks (1000 = 20 kHz)"),
    Param("pwm_on", 400, "clocks", (0, 65535), "on-time per period (0 off, >= period continuously on)"),
    Param("gate_ms", 2.0, "ms", (0.001, 10.0), "how long each gate window stays open"),
    Param("gap_ms", 1.0, "ms", (0.0, 10.0), "gap between the two gate windows"),
    Param("sample_us", 10, "us", (1, 1000), "sampling period of power and energy in the trace"),
    Param("fmi_version", 3, "", (2, 3), "which build of the Laser FMU to use"),
)
UNTIL = "8 ms"

PRESET = "laser_co2_40w"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    start = sim.ticks(100, "us")
    gate_ns = sim.ticks(p.gate_ms, "ms")
    second = start + gate_ns + sim.ticks(p.gap_ms, "ms")
    windows = [(start, start + gate_ns), (second, second + gate_ns)]

    enable = Signal(sim, "ctl.laser.enable", description="watchdog / laser enable")
    gate = Signal(sim, "ctl.laser.gate", description="gate output")
    period = Signal(sim, "ctl.laser.pwm_period", kind="int", initial=p.pwm_period, unit="clocks")
    on = Signal(sim, "ctl.laser.pwm_on", kind="int", initial=p.pwm_on, unit="clocks")

    laser = run.plant("Laser", name="laser", preset=PRESET, fmi_version=p.fmi_version)
    laser.drive("enable", enable, convert=bool)
    laser.drive("gate", gate, convert=bool)
    laser.drive("pwm_period", period, convert=int)
    laser.drive("pwm_on", on, convert=int)
    sample = sim.ticks(p.sample_us, "us")
    laser.record(["power", "energy"], period=sample)

    play(sim, [(0, {enable: 1})] + [(t, {gate: v}) for a, b in windows for t, v in ((a, 1), (b, 0))])

    preset = load_preset(PRESET)
    t_check = (run.until - 1) // sample * sample  # the last sample before the end
    seconds = [(Fraction(a, 10**9), Fraction(b, 10**9)) for a, b in windows if a < t_check]
    expected, _ = pwm_energy(
        [(a, min(b, Fraction(t_check, 10**9))) for a, b in seconds], period=p.pwm_period, on=p.pwm_on,
        peak_power=preset["peak_power"], tau_rise=preset["tau_rise"], tau_fall=preset["tau_fall"],
        clock_hz=Fraction(int(preset["clock_frequency"])), duty_threshold=preset["duty_threshold"],
        t_end=Fraction(t_check, 10**9))

    run.check(ValueAt("laser.energy", t=t_check, expected=expected, tol=1e-9 * max(expected, 1e-12),
                      name="energy equals the closed form (1e-9 relative)"))
    run.check(Bound("laser.power", lower=0.0, upper=preset["peak_power"], name="power within 0..peak"))
    run.check(Duration(start=EdgeRef("ctl.laser.gate", 1), end=EdgeRef("ctl.laser.gate", 0), equals=gate_ns,
                       name="each gate window lasts gate_ms"))

    run.figure("energy_J", lambda: float(laser.read("energy")), "J")
    run.figure("expected_energy_J", expected, "J")
    run.figure("pwm_frequency_kHz", preset["clock_frequency"] / p.pwm_period / 1e3, "kHz")
    run.figure("fmu_steps", lambda: laser.steps)
