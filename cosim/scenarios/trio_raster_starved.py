"""Trio raster engraving with a slow host: the FIFO starves and the positions passed before loading are named.

The job of ``trio_raster`` with the host refilling one 64-position chunk every 40 ms while the axis
uses up 4 positions per ms at 200 mm/s: the FIFO runs empty, the axis passes positions before
they are loaded, and they fire late, at the load::

    fifo_level   256 ‾‾\\_____/\\_____/\\____      empty between refills
    gate_late             x x x x   x x x      the positions passed while it was empty

The hazard: ``trio_raster``'s rule "no position is passed before it is loaded" fails (verdict
HAZARD SHOWN): each late position is a violation, they are listed (in user units) in the check's
description and counted in its figures. The run ends when the job is done (``UNTIL`` is a safety
limit); ``--until`` stops it earlier.
"""

from __future__ import annotations

from cosim.checks import ValueAt
from cosim.scenario import Param, Run
from cosim.scenarios.trio_raster import LatePositions, check_direction_setup, raster_job

PARAMETERS = (
    Param("lines", 2, "", (1, 7), "raster lines (alternating direction)"),
    Param("positions", 2000, "", (2, 2000), "gate positions per line (lines x positions <= 16000 TABLE entries)"),
    Param("pitch_um", 50, "um", (10, 1000), "distance between gate positions"),
    Param("speed", 200.0, "mm/s", (1.0, 1000.0), "raster speed (SPEED of axis 3)"),
    Param("chunk", 64, "", (1, 256), "positions per PWM_CONTROL(3) load"),
    Param("refill_ms", 40.0, "ms", (0.0, 1000.0), "host refill period: too slow for the raster speed"),
    Param("laser", True, "", None, "drive the Laser FMU with the PWM output"),
)
UNTIL = "600 s"  # a safety limit: the run ends when the job is done (or at --until)


def scenario(run: Run) -> None:
    job, trio = raster_job(run)
    run.hazard(LatePositions("trio.axis3.gate_late", programmed=job.lines * job.positions,
                             name="no position is passed before it is loaded"),
               shows=f"a host refilling {run.p.chunk} positions every {run.p.refill_ms:g} ms starves the gating "
                     f"FIFO at {run.p.speed:g} mm/s: positions are passed before they are loaded and fire late")
    run.check(ValueAt("trio.axis3.fifo_level", None, 0, name="every loaded position was used"))
    check_direction_setup(run, trio, job)
