"""Trio speed-linked laser power on a 2-axis path with corners: energy per unit length stays even at the corners.

Axes 2 and 3 (BASE(2,3), UNITS=100 counts/mm) trace a 40 x 30 mm right triangle (the hypotenuse
interpolated); every move ramps down to rest at a corner. With ``link`` the PWM mark follows the
path speed, ``PWM_CONTROL(2, multiplier, 0, limit, 2)``: mark = VP_SPEED * multiplier / 100000,
at most ``limit`` clocks, every servo cycle::

    VP_SPEED  /‾‾‾‾‾‾\\  /‾‾‾‾\\  /‾‾‾‾‾‾‾‾\\       slows to 0 at each corner
    pwm_mark  /‾‾‾‾‾‾\\  /‾‾‾‾\\  /‾‾‾‾‾‾‾‾\\       (link) follows it, capped at the limit
    fixed     ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾       (no link) the corners get far more energy per mm

Checks: the mark never exceeds the limit; energy per mm in the slow cycles near the corners
against the cruise cycles is within 10 % with the link (and well above without it). Figures
compare the energy per mm with and without the link (duty-weighted, from the trace) and, with
``laser``, the energy the Laser FMU delivered.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from cosim.checks import Bound, Check, Clock, DirectionSetup
from cosim.checks.base import Findings, held_index, records
from cosim.checks.result import Violation
from cosim.controllers.trio import OFF, ON, TrioController, TrioProcess
from cosim.couplings.laser import couple_laser
from cosim.scenario import Param, Run
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.trace import Trace

PARAMETERS = (
    Param("link", True, "", None, "link the PWM mark to the path speed (else a fixed mark = limit)"),
    Param("speed", 100.0, "mm/s", (1.0, 1000.0), "path speed (SPEED of axis 2, the base axis)"),
    Param("accel", 1000.0, "mm/s^2", (10.0, 100000.0), "ACCEL = DECEL of axis 2"),
    Param("limit", 500, "clocks", (1, 1000), "limit value of the link, and the fixed mark without it"),
    Param("laser", True, "", None, "drive the Laser FMU with the PWM output"),
)
UNTIL = "2 s"
CYCLE = 1000  # PWM_CYCLE [clocks]: 20 kHz
PEAK_W = 40.0  # peak power of the laser_co2_40w preset [W]
PATH = ((40, 0), (0, 30), (-40, -30))  # mm


@dataclass(frozen=True)
class CornerEnergyRatio(Check):
    """Energy per mm in slow servo cycles (corners) over that in cruise cycles, from mark and VP_SPEED.

    Per servo cycle the laser gets ``peak * min(mark, cycle)/cycle`` over ``period`` while the path
    advances ``VP_SPEED * period``; cycles slower than ``slow_fraction`` of the fastest are corners.
    """

    mark: str
    speed: str
    period: int
    cycle: int
    lower: float
    upper: float
    slow_fraction: float = 0.5

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        t_mark, mark = records(trace, self.mark, self)
        t_vp, vp = records(trace, self.speed, self)
        moving = t_vp[vp > 0]
        found = Findings(self.mark, description=f"energy per mm at corners / in cruise within "
                                                f"[{self.lower:g}, {self.upper:g}]")
        if not moving.size:
            return found
        ticks = np.arange(int(moving[0]), int(moving[-1]) + 1, self.period, dtype=np.int64)
        v = vp[held_index(t_vp, ticks)]
        duty = np.minimum(mark[held_index(t_mark, ticks)], self.cycle) / self.cycle
        slow, fast = (v > 0) & (v < self.slow_fraction * v.max()), v >= v.max() * (1 - 1e-9)
        ratio = float((duty[slow].sum() / v[slow].sum()) / (duty[fast].sum() / v[fast].sum()))
        found.checked = int(ticks.size)
        found.measured = {"corner_to_cruise_ratio": ratio, "slow_cycles": int(slow.sum())}
        if not self.lower <= ratio <= self.upper:
            found.n_violations = 1
            found.violations.append(Violation(0, ratio, f"{self.lower:g}..{self.upper:g}",
                                              f"energy per mm at corners is {ratio:.3g} x that in cruise"))
        return found


def energy_per_mm(trace: Trace, *, fixed_mark: int | None, period: int) -> float:
    """Duty-weighted laser energy per mm of path [J/mm] over the move (mark from the trace or fixed)."""
    t_vp, vp = trace.edges("trio.axis2.vp_speed")
    moving = t_vp[vp > 0]
    ticks = np.arange(int(moving[0]), int(moving[-1]) + 1, period, dtype=np.int64)
    v = vp[held_index(t_vp, ticks)]
    if fixed_mark is None:
        t_m, m = trace.edges("trio.axis3.pwm_mark")
        duty = np.minimum(m[held_index(t_m, ticks)], CYCLE) / CYCLE
    else:
        duty = np.where(v > 0, min(fixed_mark, CYCLE) / CYCLE, 0.0)
    return float(PEAK_W * duty.sum() / v.sum())  # (P * duty * T) / (v * T)


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    trio = TrioController(sim)
    proc = TrioProcess(trio, base=(2, 3))
    proc.set("WDOG", OFF)
    for axis in (2, 3):
        for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", 100), ("SPEED", p.speed), ("ACCEL", p.accel),
                            ("DECEL", p.accel)):
            proc.set(name, value, axis=axis)
    proc.set("PWM_CYCLE", CYCLE, axis=3)
    if p.link:
        proc.pwm_control(2, p.limit * 100_000 / p.speed, 0, p.limit, 2, axis=3)
    else:
        proc.set("PWM_MARK", p.limit, axis=3)
        proc.pwm_control(1, axis=3)
    if p.laser:
        laser = run.plant("Laser", name="laser", preset="laser_co2_40w")
        couple_laser(trio.pwm_port(3), laser)
        laser.record(["power", "energy"], period=trio.period_ticks)
        run.figure("laser_energy_per_mm_J", lambda: float(laser.read("energy")) / 120.0, "J/mm")

    def job() -> Any:
        yield sim.at(0, Priority.HOST)
        proc.set("WDOG", ON)
        for dx, dy in PATH:
            yield proc.move(dx, dy)
        yield proc.wait_idle()
        proc.set("WDOG", OFF)

    sim.process(job())
    period = trio.period_ticks
    run.check(Bound("trio.axis3.pwm_mark", lower=0, upper=p.limit, name="the mark never exceeds the limit value"))
    bounds = (0.9, 1.1) if p.link else (1.5, 1e9)
    run.check(CornerEnergyRatio("trio.axis3.pwm_mark", "trio.axis2.vp_speed", period, CYCLE, *bounds,
                                name="energy per mm at the corners " + (
                                    "matches cruise (link)" if p.link else "exceeds cruise (no link)")))
    run.check(Bound("trio.axis2.dpos", lower=0, upper=40, name="the path stays inside the triangle (x)"))
    for a in (2, 3):
        run.check(DirectionSetup(f"trio.axis{a}.step", f"trio.axis{a}.dir", sim.ticks("100 ns"),
                                 trailing=True,  # TRM 8-165: the falling edge is the active one
                                 name=f"axis {a}: direction steady before the active edge of every step pulse"))
    run.figure("energy_per_mm_J", lambda: energy_per_mm(sim.trace, fixed_mark=None, period=period), "J/mm")
    run.figure("energy_per_mm_fixed_mark_J", lambda: energy_per_mm(sim.trace, fixed_mark=p.limit, period=period),
               "J/mm")
