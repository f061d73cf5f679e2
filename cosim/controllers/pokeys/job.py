"""Following a streamed job through the engine: when its slots run, and the outputs that go with them.

The host knows where in its job a spindle (or laser) command, a coolant or tool change, a pause
or an output word falls: before slot ``n``. It switches the output when the engine takes that
slot from the buffer, at that slot's start
(priority ``HOST``, after the engine's ``SLOT``), so the output changes between the motion before
the command and the motion after it, wherever underruns or the prefill have moved the job in
time. :class:`JobWatch` also records when the job's first and last slots ran (its job time).

It counts the entries the engine has taken (:attr:`~cosim.controllers.pokeys.buffer.SlotBuffer.taken`)
and sleeps until the earliest slot start at which the next marked slot can be taken (one entry per
slot at most), so it costs a few kernel events per mark, not one per slot.

A job with waits grows while it runs (:mod:`~cosim.controllers.pokeys.gcodejob`): :meth:`JobWatch.extend`
adds the slots and outputs of each piece the host gets after a wait, and the job's last slot is
known once the last piece is in (``complete``).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Sequence
from typing import Any

from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.toolpath import Message, Output, Spindle
from cosim.kernel import Simulation
from cosim.signals import Signal
from cosim.timebase import Priority
from cosim.validate import integer


class JobWatch:
    """The slots of a job of ``slots`` entries as the engine runs them, and its spindle outputs.

    Parameters
    ----------
    sim : Simulation
    engine : PulseEngine
        The engine the job is streamed into (its buffer's taken count must start at 0 with the job).
    slots : int
        Entries in the job.
    outputs : sequence of (int, Spindle or Output)
        Output changes and the index of the job slot they start at (``slots``: after the last one).
    on_end : callable, optional
        Called (no arguments) at the start of the slot after the job's last one: the buffer has drained.
    complete : bool
        The job's slots are all given (default); False: more come with :meth:`extend`.

    Attributes
    ----------
    t_first, t_last : int or None
        Start of the slot that took the job's first and last entry [ticks].
    spindle_on, spindle_ccw, spindle_speed : Signal
        ``<engine>.spindle.on`` (M3/M4 = 1, M5 = 0), ``.ccw`` (M4), ``.speed`` (S).
    signals : dict of str to Signal
        ``<engine>.<name>`` of every :class:`~cosim.controllers.pokeys.toolpath.Output` of the job
        (``coolant_flood``, ``coolant_mist``, ``tool``, ``tool_changing``, ``paused``, ``waiting``,
        ``dout<n>``, ``aout<n>``), from 0.
    """

    def __init__(self, sim: Simulation, engine: PulseEngine, *, slots: int,
                 outputs: Sequence[tuple[int, Spindle | Output | Message]] = (),
                 on_end: Callable[[], None] | None = None, complete: bool = True) -> None:
        self.sim = sim
        self.engine = engine
        self.slots = integer(slots, "job slots", low=0)
        name = engine.name
        self.spindle_on = Signal(sim, f"{name}.spindle.on", description="spindle (or laser) on: M3, M4; off: M5")
        self.spindle_ccw = Signal(sim, f"{name}.spindle.ccw", description="spindle counter-clockwise (M4)")
        self.spindle_speed = Signal(sim, f"{name}.spindle.speed", kind="real", description="spindle speed (S word)")
        self.outputs: list[tuple[int, Spindle | Output | Message]] = []
        self.signals: dict[str, Signal] = {}
        self.complete = complete
        self._more: Any = None  # the event follow_job waits on for more of a growing job
        self._add(outputs)
        self.on_end = on_end
        self.t_first: int | None = None
        self.t_last: int | None = None
        if self.slots or not complete:
            sim.process(self.follow_job())
        else:
            for _, record in self.outputs:
                self._apply(record)
            if on_end is not None:
                on_end()

    @property
    def job_ticks(self) -> int | None:
        """From the start of the job's first slot to the end of its last [ticks], once it has run."""
        if self.t_first is None or self.t_last is None:
            return None
        return self.t_last + self.engine.slot_ticks - self.t_first

    def extend(self, slots: int, outputs: Sequence[tuple[int, Spindle | Output | Message]] = (), *,
               complete: bool) -> None:
        """The job has ``slots`` entries now, and these ``outputs`` (job slot indices) more; ``complete``: no more
        come."""
        self.slots = integer(slots, "job slots", low=self.slots)
        self._add(outputs)
        self.complete = complete
        if self._more is not None and not self._more.triggered:
            self._more.succeed()

    def _add(self, outputs: Sequence[tuple[int, Spindle | Output | Message]]) -> None:
        name = self.engine.name
        for index, record in sorted(outputs, key=lambda item: item[0]):
            integer(index, "output slot", low=self.outputs[-1][0] if self.outputs else 0, high=self.slots)
            self.outputs.append((index, record))
            if isinstance(record, Output) and record.name not in self.signals:
                self.signals[record.name] = Signal(self.sim, f"{name}.{record.name}", kind=_kind(record.name),
                                                   description=_DESCRIPTIONS.get(record.name.rstrip("0123456789"),
                                                                                 "a G-code output"))

    def follow_job(self) -> Generator[Any, Any, None]:
        """SimPy process: wait for each marked slot to be taken; switch outputs, note first and last."""
        pending = self.outputs
        done = 0  # outputs applied
        while True:
            last = self.slots - 1 if self.complete else None
            marks = [] if self.t_first is not None or self.slots == 0 else [0]
            if done < len(pending) and (last is None or pending[done][0] <= last):
                marks.append(pending[done][0])
            if last is not None and last >= 0 and self.t_last is None:
                marks.append(last)
            if not marks:
                if last is not None:
                    break
                self._more = self.sim.env.event()
                yield self._more
                self._more = None
                continue
            index = min(marks)
            t = yield from self._taken(index)
            if index == 0 and self.t_first is None:
                self.t_first = t
            if self.complete and index == self.slots - 1:
                self.t_last = t
            while done < len(pending) and pending[done][0] == index:
                self._apply(pending[done][1])
                done += 1
        # after the job: at the start of the slot after its last one
        yield self.sim.at(self.sim.now + self.engine.slot_ticks, Priority.HOST)
        for _, record in pending[done:]:
            self._apply(record)
        if self.on_end is not None:
            self.on_end()

    def _taken(self, index: int) -> Generator[Any, Any, int]:
        """Wait until entry ``index`` is taken; the start of the slot that took it [ticks]."""
        engine, slot = self.engine, self.engine.slot_ticks
        while engine.buffer.taken <= index:
            # slots run so far: engine.slot_index; one entry per slot at most
            t = engine.t0 + (engine.slot_index + index - engine.buffer.taken) * slot
            yield self.sim.at(max(t, self.sim.now), Priority.HOST)
        return engine.t0 + (engine.slot_index - 1 - (engine.buffer.taken - 1 - index)) * slot

    def _apply(self, record: Spindle | Output | Message) -> None:
        if isinstance(record, Message):
            self.sim.trace.write_line(self.sim.now, "gcode", f"{record.kind}: {record.text}" if record.kind == "MSG"
                                      else record.text)
            return
        if isinstance(record, Output):
            signal = self.signals[record.name]
            signal.set(float(record.value) if signal.kind == "real" else int(record.value))
            return
        self.spindle_on.set(int(record.on))
        self.spindle_ccw.set(int(record.ccw))
        self.spindle_speed.set(float(record.speed))


_DESCRIPTIONS = {"coolant_flood": "flood coolant (M8 on, M9 off)", "coolant_mist": "mist coolant (M7 on, M9 off)",
                 "tool": "the tool in the spindle (M6, M61)", "tool_changing": "1 while a tool change (M6) runs",
                 "paused": "1 while the program is paused (M0, M1, M60) until the operator resumes",
                 "waiting": "1 while an M66 waits on an input (L1-L4)",
                 "dout": "digital output (M62/M64 on, M63/M65 off)", "aout": "analog output (M67, M68)"}


def _kind(name: str) -> str:
    if name.startswith("aout"):
        return "real"
    return "int" if name == "tool" else "bit"
