"""Trio raster engraving: thousands of gate positions per line, the host refills the 256-deep FIFO in time.

Axis 3 (x, UNITS=100 counts/mm) rasters bidirectionally, axis 2 (y) steps over; every line has
``positions`` gate positions every ``pitch_um`` (ON/OFF alternating) loaded from TABLE into the
gating FIFO ``chunk`` at a time: as many as fit before the move, then one chunk every
``refill_ms`` (a load that does not fit waits, and the host with it)::

    fifo_level   256 ‾‾\\__/‾‾\\__/‾‾\\__/ ... \\___      refills keep it from running empty
    gate         _|‾|_|‾|_|‾|_|‾|_ ...                 one edge per programmed position

Checks: every programmed position gives its edge at the exact count (GT forward: first count
above, LT back: first count below), and no position is passed before it is loaded. With a slow
refill (``--set refill_ms=40``) the FIFO starves and the late positions are reported;
``trio_raster_starved`` is that run.

The run ends when the job is done (``UNTIL`` is a safety limit); ``--until`` stops it earlier, and
the checks of the whole job then fail (a note says so).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim.checks import Check, Clock, DirectionSetup, EdgeAtPosition
from cosim.checks.base import Findings, fmt, records
from cosim.checks.result import MAX_REPORTED, Violation
from cosim.controllers.trio import OFF, ON, TrioController, TrioProcess
from cosim.controllers.trio.raster import RasterJob
from cosim.couplings.laser import couple_laser
from cosim.scenario import Param, Run
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.trace import Trace

PARAMETERS = (
    Param("lines", 3, "", (1, 7), "raster lines (alternating direction)"),
    Param("positions", 2000, "", (2, 2000), "gate positions per line (lines x positions <= 16000 TABLE entries)"),
    Param("pitch_um", 50, "um", (10, 1000), "distance between gate positions"),
    Param("speed", 200.0, "mm/s", (1.0, 1000.0), "raster speed (SPEED of axis 3)"),
    Param("chunk", 64, "", (1, 256), "positions per PWM_CONTROL(3) load"),
    Param("refill_ms", 5.0, "ms", (0.0, 1000.0), "host refill period (0: as soon as there is room)"),
    Param("laser", True, "", None, "drive the Laser FMU with the PWM output"),
)
UNTIL = "600 s"  # a safety limit: the run ends when the job is done (or at --until)
UNITS = 100  # counts/mm


@dataclass(frozen=True)
class LatePositions(Check):
    """Gate positions passed before they were loaded (the ``gate_late`` records of an axis).

    Parameters
    ----------
    signal : str
        ``trio.axisN.gate_late``: one record [units] per position that fired late.
    programmed : int
        Positions the job programmed (what was checked).

    Each late position is a violation; the description lists them [units] (the first 40).
    """

    signal: str = "trio.axis3.gate_late"
    programmed: int = 0

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        t, position = records(trace, self.signal, self)
        shown = ", ".join(fmt(x) for x in position[:40]) + (" ..." if position.size > 40 else "")
        found = Findings(self.signal, checked=self.programmed)
        found.measured = {"late_positions": int(position.size)}
        if position.size:
            found.measured.update(first_late_units=float(position[0]), last_late_units=float(position[-1]))
        found.description = "every gate position is loaded before the axis reaches it" + (
            f"; passed before they were loaded [units]: {shown}" if shown else "")
        found.n_violations = int(position.size)
        for k in range(min(position.size, MAX_REPORTED)):
            found.violations.append(Violation(clock.t_ns(t[k]), float(position[k]), "loaded before it is reached",
                                              f"gate position {fmt(position[k])} units was passed before it was "
                                              "loaded; it fired at the load"))
        return found


def raster_job(run: Run) -> tuple[RasterJob, TrioController]:
    """Set up the controller, run the job to its end and declare its figures; returns the job and the controller."""
    sim, p = run.sim, run.p
    trio = TrioController(sim)
    proc = TrioProcess(trio, base=(3,))
    proc.set("WDOG", OFF)
    for axis in (2, 3):
        for name, value in (("ATYPE", 35), ("SERVO", ON), ("UNITS", UNITS), ("SPEED", p.speed), ("ACCEL", 5000),
                            ("DECEL", 5000)):
            proc.set(name, value, axis=axis)
    proc.set("PWM_CYCLE", 1000)
    proc.set("PWM_MARK", 500)
    proc.pwm_control(1)
    proc.pwm_control(6)
    proc.pwm_control(4)
    proc.pwm_control(5)
    proc.set("WDOG", ON)
    job = RasterJob(lines=p.lines, positions=p.positions, pitch=Fraction(p.pitch_um, 1000), chunk=p.chunk,
                    refill_ms=Fraction(str(p.refill_ms)))
    job.fill_table(proc)
    if p.laser:
        laser = run.plant("Laser", name="laser", preset="laser_co2_40w")
        couple_laser(trio.pwm_port(3), laser)
        run.figure("energy_J", lambda: float(laser.read("energy")), "J")
    done: list[bool] = []

    def host() -> Any:
        yield sim.at(0, Priority.HOST)
        yield from job.run(proc)
        done.append(True)

    sim.process(host())
    finished = run.run_job(lambda: bool(done), step=sim.ticks(100, "ms"), what="the raster job")
    waiting = sim.trace.edges("trio.axis3.fifo_waiting")[1]
    run.figure("late_positions", lambda: len(trio.gate(3).late))
    run.figure("most_positions_waiting", float(waiting.max()))
    if finished:
        run.figure("job_s", sim.timebase.seconds(sim.now), "s")
    return job, trio


def check_direction_setup(run: Run, trio: TrioController, job: RasterJob) -> None:
    """The direction outputs of the raster axes (Y moves only between lines) are steady before the active edge
    of every step pulse."""
    for a in (3, 2) if job.lines > 1 else (3,):
        run.check(DirectionSetup(f"trio.axis{a}.step", f"trio.axis{a}.dir", run.sim.ticks("100 ns"),
                                 trailing=True,  # TRM 8-165: the falling edge is the active one
                                 name=f"axis {a}: direction steady before the active edge of every step pulse"))


def scenario(run: Run) -> None:
    job, trio = raster_job(run)
    run.check(EdgeAtPosition("trio.axis3.gate", "trio.axis3.step", job.expected_edges(Fraction(UNITS)), tol_counts=0,
                             name="every programmed position gives its gate edge at the exact count"))
    run.check(LatePositions("trio.axis3.gate_late", programmed=job.lines * job.positions,
                            name="no position is passed before it is loaded"))
    check_direction_setup(run, trio, job)
