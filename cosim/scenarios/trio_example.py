"""Trio TN20-81 example: the note's BASIC program gates a laser at 110, 115, 195, 220 units, forward and back.

The program (``cosim/controllers/trio/examples/tn20_81.bas``) runs unmodified from its text on a
EURO205X model: axis 3 is a stepper (ATYPE=35, UNITS=16) that moves 0 -> 300 -> 0 units for ever,
with the gating FIFO loaded before each move::

    position   0 ........ 110 115 ....... 195 ... 220 ....... 300
    forward    GT:        ON  OFF         ON      OFF              counts 1761 1841 3121 3521
    reverse    LT:        OFF ON          OFF     ON               counts 1759 1839 3119 3519
    gate       ___________|‾‾‾|___________|‾‾‾‾‾‾‾|___________

Checks: every gate edge at the exact step count (GT: first count above position*UNITS, LT: first
count below) for every pass, no position loaded too late, the PWM at 20 kHz / 400 clocks, and the
direction output steady for the pulse width before the active (falling) edge of every step pulse.
With ``laser`` the output drives the Laser FMU and the energy per pass is a key figure.

The run ends when the passes are done (``UNTIL`` is a safety limit); ``--until`` stops it earlier,
and the checks of the whole job then fail (a note says so).
"""

from __future__ import annotations

from cosim.checks import DirectionSetup, EdgeAtPosition, ValueAt
from cosim.controllers.trio import TrioController
from cosim.controllers.trio.basic import example
from cosim.couplings.laser import couple_laser
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("speed", 1000.0, "units/s", (1.0, 5000.0), "SPEED of axis 3 (the program leaves the default)"),
    Param("accel", 1000.0, "units/s^2", (10.0, 100000.0), "ACCEL of axis 3"),
    Param("decel", 1000.0, "units/s^2", (10.0, 100000.0), "DECEL of axis 3"),
    Param("passes", 2, "", (1, 20), "forward + reverse passes before the program is stopped"),
    Param("laser", True, "", None, "drive the Laser FMU with the PWM output"),
)
UNTIL = "600 s"  # a safety limit: the run ends when the passes are done (or at --until)

FORWARD = [(1761, 1), (1841, 0), (3121, 1), (3521, 0)]
REVERSE = [(3519, 1), (3119, 0), (1839, 1), (1759, 0)]


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    trio = TrioController(sim)
    for name in ("speed", "accel", "decel"):
        trio.set_param(name.upper(), getattr(p, name), axis=3)
    if p.laser:
        laser = run.plant("Laser", name="laser", preset="laser_co2_40w")
        couple_laser(trio.pwm_port(3), laser)
        laser.record(["power", "energy"], period=sim.ticks(1, "ms"))
    program = example("tn20_81").start(trio)
    edges = len(FORWARD + REVERSE) * p.passes
    fired: list[int] = []

    def stop_after_the_last_pass(_entry: object, t: int) -> None:
        fired.append(t)
        if len(fired) == edges:
            program.stop()  # waits in WAIT IDLE; the move back to 0 finishes

    trio.gate(3).on_fire = stop_after_the_last_pass
    finished = run.run_job(lambda: program.finished and trio.axes[3].idle, step=sim.ticks(100, "ms"),
                           what="the passes")

    run.check(EdgeAtPosition("trio.axis3.gate", "trio.axis3.step", (FORWARD + REVERSE) * p.passes, tol_counts=0,
                             name="gate edges at the exact step counts, forward (GT) and reverse (LT)"))
    run.check(ValueAt("trio.axis3.pwm_cycle", None, 1000, name="PWM_CYCLE 1000 (20 kHz)"))
    run.check(ValueAt("trio.axis3.pwm_mark", None, 400, name="PWM_MARK 400"))
    run.check(ValueAt("trio.wdog", None, 1, name="WDOG on"))
    run.check(ValueAt("trio.axis3.dpos", None, 0, name="the axis is back at 0"))
    run.check(DirectionSetup("trio.axis3.step", "trio.axis3.dir", sim.ticks("100 ns"),
                             trailing=True,  # TRM 8-165: the falling edge is the active one
                             name="axis 3: direction steady before the active edge of every step pulse"))
    run.figure("late_positions", lambda: len(trio.gate(3).late))
    run.figure("step_pulses", lambda: int(sim.trace.segments("trio.axis3.step")["count"].sum()))
    if finished:
        run.figure("job_s", sim.timebase.seconds(sim.now), "s")
    if p.laser:
        run.figure("energy_J", lambda: float(laser.read("energy")), "J")
