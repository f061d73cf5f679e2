"""Test doubles that give the controllers on main a ``controller.job`` (cosim.job), driven from outside.

Each controller family will create ``controller.job = Job(sim, device)`` and drive it itself; until
then these doubles do it from what the controllers expose, so that the machine builder's job check
and ``job_s`` can be tested on real machines:

========  ===========================================================================================
Trio      one part per process the machine file started; it finishes when its SimPy process ends
PMAC      one part per coordinate system while it runs a program (``program_done`` false), polled at
          each servo interrupt
PoKeys    the job starts with the first slot taken from the buffer and is done at the end of the slot
          that took its last entry; engine state 100 (limit) or 101 (emergency) stops it
========  ===========================================================================================

``drive_jobs(monkeypatch)`` installs all three around the families' ``start``.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import Any

import pytest

from cosim.controllers.pokeys import PulseEngine
from cosim.controllers.pokeys.states import EngineState
from cosim.job import Job, JobState
from cosim.kernel import Simulation
from cosim.machine.families import pmac as pmac_family
from cosim.machine.families import pokeys as pokeys_family
from cosim.machine.families import trio as trio_family
from cosim.timebase import Priority


def trio_job(sim: Simulation, trio: Any) -> Job:
    """Each running process is a part of the job; it ends when the process does."""
    job = trio.job = Job(sim, trio.device)
    for run in list(trio.processes.values()):
        part = f"process {run.number}"
        job.begin(part)

        def follow(run: Any = run, part: str = part) -> Generator[Any, Any, None]:
            yield run.process_handle
            job.finish(part)

        sim.process(follow())
    return job


def pmac_job(sim: Simulation, pmac: Any) -> Job:
    """A coordinate system running a program is a part of the job (polled each servo interrupt)."""
    job = pmac.job = Job(sim, pmac.device)

    def poll() -> Generator[Any, Any, None]:
        k = pmac.clock.first_cycle_at_or_after(sim.now)
        running: set[int] = set()
        while True:
            yield sim.at(pmac.clock.t(k), Priority.SETTLE)
            for number, cs in pmac.cs.items():
                if not cs.program_done and number not in running:
                    running.add(number)
                    job.begin(f"CS{number}")
                elif cs.program_done and number in running:
                    running.discard(number)
                    job.finish(f"CS{number}")
            k += 1

    sim.process(poll())
    return job


def pokeys_job(sim: Simulation, engine: PulseEngine, slots: int) -> Job:
    """The streamed job of ``slots`` entries: running from its first slot, done at the end of its last."""
    job = engine.job = Job(sim, engine.name)  # type: ignore[attr-defined]

    def poll() -> Generator[Any, Any, None]:
        k = 0
        while True:
            yield sim.at(k * engine.slot_ticks, Priority.SETTLE)
            state = engine.state
            if state in (EngineState.STOP_LIMIT, EngineState.STOP_EMERGENCY):
                limit = state == EngineState.STOP_LIMIT
                job.stop(JobState.LIMIT if limit else JobState.EMERGENCY,
                         f"the engine stopped ({state.name}, state {int(state)})")
                return
            taken = engine.buffer.taken
            if taken and job.state == JobState.IDLE:
                job.begin("job")
            if slots and taken >= slots and engine.buffer.level == 0:
                job.finish("job")
                return
            k += 1

    sim.process(poll())
    return job


def drive_jobs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Wrap the three families' ``start`` so that each machine's controller gets a driven job."""
    start_trio = trio_family.TrioFamily.start
    start_pmac = pmac_family.PmacFamily.start
    start_pokeys = pokeys_family.PoKeysFamily.start
    hosts: list[Any] = []

    class RecordedHost(pokeys_family.HostApp):  # type: ignore[misc]
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            hosts.append(self)

    # A family that drives its own job (controller.job after its start) keeps it: the double stands in only
    # where a family does not yet.
    def trio(self: Any, run: Any, controller: Any, *args: Any, **kwargs: Any) -> None:
        start_trio(self, run, controller, *args, **kwargs)
        if getattr(controller, "job", None) is None:
            trio_job(run.sim, controller)

    def pmac(self: Any, run: Any, controller: Any, *args: Any, **kwargs: Any) -> None:
        start_pmac(self, run, controller, *args, **kwargs)
        if getattr(controller, "job", None) is None:
            pmac_job(run.sim, controller)

    def pokeys(self: Any, run: Any, controller: Any, *args: Any, **kwargs: Any) -> None:
        start_pokeys(self, run, controller, *args, **kwargs)
        if getattr(controller, "job", None) is None:
            pokeys_job(run.sim, controller, len(hosts[-1].entries))

    monkeypatch.setattr(pokeys_family, "HostApp", RecordedHost)
    monkeypatch.setattr(trio_family.TrioFamily, "start", trio)
    monkeypatch.setattr(pmac_family.PmacFamily, "start", pmac)
    monkeypatch.setattr(pokeys_family.PoKeysFamily, "start", pokeys)
