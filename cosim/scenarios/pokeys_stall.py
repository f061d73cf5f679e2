"""PoKeys host stall: the host freezes for 60 ms while only 20 slots are queued, and the buffer runs empty.

A one-axis move streamed by the host; at ``stall_at_ms`` the host process stalls for ``stall_ms``
(an OS hiccup). The queued ``prefill`` slots run out, and the slot starts in buffer mode that find
the buffer empty until data comes again are an underrun: no pulses, the axis stops dead in the
middle of the move::

    host          ====|  stalled 60 ms       |=====
    buffer_level  20 \\___________0___________/‾‾‾‾      (20 ms later)
    underrun           ______|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____     start and length reported

The hazard: the healthy rule "no buffer underrun" fails (verdict HAZARD SHOWN), and the underrun
is reported with its start time and length; ``pokeys_stall_prefill`` is the same job with enough
prefill to ride out the stall, and the same rule passes there.
"""

from __future__ import annotations

from cosim.checks import IntervalsAbove
from cosim.controllers.pokeys import EngineConfig, PulseEngine, Underrun, uniform_axes
from cosim.controllers.pokeys.host import HostApp, Stall
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.scenario import Param, Run

MS = 1_000_000

PARAMETERS = (
    Param("prefill", 20, "slots", (1, 128), "slots queued before the start, and the level the host keeps"),
    Param("stall_at_ms", 300, "ms", (0, 10_000), "when the host stalls"),
    Param("stall_ms", 60, "ms", (1, 10_000), "how long the host stalls"),
    Param("link", "usb", "", ("usb", "ethernet"), "host link profile"),
    Param("distance", 15_000, "pulses", (1, 1_000_000), "x travel of the move"),
)
UNTIL = "1.5 s"


def stalled_job(run: Run) -> tuple[PulseEngine, HostApp]:
    """The job and the stalled host (shared with ``pokeys_stall_prefill``)."""
    p = run.p
    config = EngineConfig(axes=uniform_axes(max_speed_hz=20_000, accel=400_000, decel=400_000))
    engine = PulseEngine(run.sim, config)
    entries = to_entries(plan([Move((p.distance, 0, 0))], config.axes))
    host = HostApp(run.sim, engine, entries, link=p.link, prefill_slots=p.prefill,
                   stalls=[Stall(p.stall_at_ms * MS, p.stall_ms * MS)])
    ms = run.sim.ticks("1 ms")
    run.figure("underruns", lambda: len(engine.underruns))
    run.figure("underrun_start_ms", lambda: _first(engine.underruns).t_start / ms, "ms")
    run.figure("underrun_length_ms", lambda: _first(engine.underruns).length / ms, "ms")
    return engine, host


def scenario(run: Run) -> None:
    stalled_job(run)
    run.hazard(no_underrun(), shows=f"a {run.p.stall_ms} ms host stall with {run.p.prefill} slots queued: the "
                                    "buffer runs empty and the axis stops dead mid-move")


def no_underrun() -> IntervalsAbove:
    """The healthy rule (shared with ``pokeys_stall_prefill``): the buffer never runs empty."""
    return IntervalsAbove("pokeys.underrun", 0, name="no buffer underrun")


def _first(underruns: list[Underrun]) -> Underrun:
    return underruns[0] if underruns else Underrun(0, 0, 0)
