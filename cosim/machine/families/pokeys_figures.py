"""Job-level figures of a PoKeys machine: what a user asks of a job before building the machine.

================================  =====================================================================
figure                            meaning
================================  =====================================================================
``slots``, ``pulses``             planned slots, and pulses over every axis
``fill_commands``                 fill-buffer round trips the host made
``job_done_ms``                   when the last planned slot would end without underruns [ms]
``job_duration_s``                from the start of the job's first slot to the end of its last, as run [s]
``<axis>_peak_hz``                highest pulse rate of the axis: its largest slot count x 1000 [Hz]
``slots_at_limit``                slots in which some axis ran at the engine's limit (25 pulses on a 56E)
``min_buffer_level``              fewest slots queued at a slot start while the host still had slots to send
``underruns``, ``underrun_slots``  underruns of the job and their empty slots
``first_underrun_ms``             start of the first underrun [ms] (nan: none), ``first_underrun_slots`` its length
``slowed_lines``                  G-code lines whose feed the planner slowed (the notes are in ``trace_meta.json``)
``skipped_words``                 G-code words skipped under ``allow_unsupported``
``<plant>_lost_steps``            full steps a Stepper plant has lost at the end (``lost_full_steps``), and
``lost_steps``                    their sum over the machine's steppers
================================  =====================================================================
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cosim.controllers.pokeys import PulseEngine
from cosim.controllers.pokeys.gcodejob import GcodeJob
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.job import JobWatch
from cosim.controllers.pokeys.limits import SLOTS_PER_S
from cosim.controllers.pokeys.pathplan import PlannedJob
from cosim.scenario import Run

LOST_STEPS = "lost_full_steps"
"""The Stepper plant's output that counts the full steps it lost."""


def declare_figures(run: Run, engine: PulseEngine, host: HostApp, watch: JobWatch, counts: Sequence[Sequence[int]],
                    job: PlannedJob | GcodeJob | None) -> None:
    """Declare the job figures of the module docstring on ``run`` (``counts`` and ``job`` may grow as the job runs:
    a G-code job with waits; ``slots`` counts the idle slots of its waits too)."""
    sim = run.sim
    trace = sim.trace
    ms = sim.ticks(1, "ms")
    nan = float("nan")
    run.figure("slots", lambda: len(host.entries))
    run.figure("pulses", lambda: sum(abs(c) for slot in counts for c in slot))
    run.figure("fill_commands", lambda: len(host.fills))
    run.figure("job_done_ms", lambda: (host.t_buffer_mode or 0) / ms + len(host.entries), "ms")
    run.figure("job_duration_s", lambda: nan if watch.job_ticks is None else sim.timebase.seconds(watch.job_ticks),
               "s")
    limit = engine.device.max_pulses_per_slot
    for train in engine.steps:
        axis = train.name.split(".")[-2]
        run.figure(f"{axis}_peak_hz", lambda name=train.name: _peak(trace.segments(name)["count"]),  # type: ignore[misc]
                   "Hz")

    def at_limit() -> float:
        starts = [seg["t0"][seg["count"] >= limit] for seg in (trace.segments(t.name) for t in engine.steps)]
        return float(_distinct(np.concatenate(starts))) if starts else 0.0

    run.figure("slots_at_limit", at_limit)

    def min_level() -> float:
        if watch.t_first is None:
            return nan
        t, level = trace.edges(engine.buffer_level.name)
        end = host.t_last_accepted if host.t_last_accepted is not None else watch.t_first
        inside = level[(t >= watch.t_first) & (t <= end)]
        return float(inside.min()) if inside.size else float(trace.value_at(engine.buffer_level.name, end))

    run.figure("min_buffer_level", min_level, "slots")
    run.figure("underruns", lambda: len(engine.underruns))
    run.figure("underrun_slots", lambda: sum(u.slots for u in engine.underruns), "slots")
    run.figure("first_underrun_ms", lambda: engine.underruns[0].t_start / ms if engine.underruns else nan, "ms")
    run.figure("first_underrun_slots", lambda: engine.underruns[0].slots if engine.underruns else 0, "slots")
    if job is not None:
        run.figure("slowed_lines", lambda: len(job.notes))
        run.figure("skipped_words", lambda: len(job.skipped))
    steppers = [p for p in run.plants if LOST_STEPS in p.variable_names()]
    for plant in steppers:
        run.figure(f"{plant.name}_lost_steps", lambda plant=plant: abs(float(plant.read(LOST_STEPS))),  # type: ignore[misc]
                   "full steps")
    if steppers:
        run.figure("lost_steps", lambda: sum(abs(float(p.read(LOST_STEPS))) for p in steppers), "full steps")


def _peak(count: np.ndarray) -> float:
    return float(count.max()) * SLOTS_PER_S if count.size else 0.0


def _distinct(values: np.ndarray) -> int:
    """How many different values (``np.unique(values).size``, without np.unique's import of numpy.ma)."""
    ordered = np.sort(values)
    return int(ordered.size and 1 + np.count_nonzero(ordered[1:] != ordered[:-1]))
