"""Trio WDOG switched off mid-move: the PWM output stops at that instant while the axis runs on.

Axis 3 (stepper, UNITS=100 counts/mm) moves 0 -> 200 mm at 100 mm/s with the laser gated on
from 20 to 180 mm at 20 kHz / 40 % (PWM_CYCLE=1000, PWM_MARK=400). The host switches WDOG off
at ``wdog_off_ms`` (any ns, not a servo tick)::

    wdog    ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|______________________
    gate    ______|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|______   (the FIFO still gates: 20 ON, 180 OFF)
    output  ______|||||||||||||||||_______________________   off at once
    power   ______/‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾\\______________________   decays with the tube's time constant

Checks: WDOG falls at exactly the commanded instant; the axis still reaches 200 mm and the gate
still switches at its positions. With ``laser``: the energy equals the closed form for the
window from the gate edge to the WDOG edge (1e-6 relative) and the power is gone 0.5 ms later.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from cosim.checks import DirectionSetup, EdgeAtPosition, IntervalsAbove, ValueAt
from cosim.controllers.trio import OFF, ON, TrioController, TrioProcess
from cosim.couplings.laser import couple_laser
from cosim.plants.laser import pwm_energy
from cosim.presets import load_preset
from cosim.scenario import Param, Run
from cosim.timebase import Priority

PARAMETERS = (
    Param("wdog_off_ms", 1000.123457, "ms", (1.0, 2000.0), "when the host switches WDOG off"),
    Param("laser", True, "", None, "drive the Laser FMU with the PWM output"),
)
UNTIL = "2.2 s"
PRESET = "laser_co2_40w"
UNITS = 100


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    trio = TrioController(sim)
    proc = TrioProcess(trio, base=(3,))
    proc.set("WDOG", OFF)
    for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", UNITS), ("SPEED", 100), ("ACCEL", 1000),
                        ("DECEL", 1000), ("PWM_CYCLE", 1000), ("PWM_MARK", 400)):
        proc.set(name, value)
    proc.pwm_control(1)
    proc.pwm_control(6)
    proc.pwm_control(4)
    proc.pwm_control(5)
    proc.table(0, 20, 180)
    t_off = sim.ticks(f"{p.wdog_off_ms} ms", name="wdog_off_ms")
    if p.laser:
        laser = run.plant("Laser", name="laser", preset=PRESET)
        couple_laser(trio.pwm_port(3), laser)
        laser.record(["power", "energy"], period=sim.ticks(100, "us"))

    def job() -> Any:
        yield sim.at(0, Priority.HOST)
        proc.set("WDOG", ON)
        yield proc.pwm_control(3, 1, ON, 0, 1)
        yield proc.moveabs(200)
        yield sim.at(t_off, Priority.HOST)
        proc.set("WDOG", OFF)

    sim.process(job())
    run.run_until(run.until)

    run.check(ValueAt("trio.wdog", t_off - 1, 1, name="WDOG on just before the commanded instant"))
    run.check(ValueAt("trio.wdog", t_off, 0, name="WDOG off at the commanded instant"))
    run.check(ValueAt("trio.axis3.dpos", None, 200, name="the axis runs on to 200 mm"))
    run.check(EdgeAtPosition("trio.axis3.gate", "trio.axis3.step", [(20 * UNITS + 1, 1), (180 * UNITS + 1, 0)],
                             tol_counts=0, name="the gate still switches at 20 and 180 mm"))
    run.check(DirectionSetup("trio.axis3.step", "trio.axis3.dir", sim.ticks("100 ns"),
                             trailing=True,  # TRM 8-165: the falling edge is the active one
                             name="axis 3: direction steady before the active edge of every step pulse"))
    if p.laser:
        preset = load_preset(PRESET)
        t_gate, level = sim.trace.edges("trio.axis3.gate")
        t_on = int(t_gate[1]) if t_gate.size > 1 and level[1] == 1 else t_off
        t_end = (run.until - 1) // sim.ticks(100, "us") * sim.ticks(100, "us")
        ns = Fraction(1, 10**9)
        expected, _ = pwm_energy([(t_on * ns, max(t_on, t_off) * ns)], period=1000, on=400,
                                 peak_power=preset["peak_power"], tau_rise=preset["tau_rise"],
                                 tau_fall=preset["tau_fall"], clock_hz=Fraction(int(preset["clock_frequency"])),
                                 duty_threshold=preset["duty_threshold"], t_end=t_end * ns)
        run.check(ValueAt("laser.energy", t_end, expected, tol=1e-6 * expected,
                          name="energy = closed form from the gate edge to the WDOG edge"))
        run.check(IntervalsAbove("laser.power", 0.01 * preset["peak_power"], start=t_off + sim.ticks(500, "us"),
                                 name="no power 0.5 ms after WDOG off"))
        run.figure("energy_J", lambda: float(laser.read("energy")), "J")
        run.figure("expected_energy_J", expected, "J")
    run.figure("t_wdog_off_ms", t_off / 1e6, "ms")
