"""The host application: keeps the slot buffer filled over a link with delays and stalls.

The host holds the whole job as slot entries (see :mod:`~cosim.controllers.pokeys.planner`) and a
read pointer. Every ``period_ns`` (cycle k at ``start + k * period``, priority HOST) it

1. waits out an injected stall if the cycle falls inside one (the host process is frozen: an OS
   hiccup, a busy GUI thread);
2. offers the next slots, at most ``max_slots_per_fill`` (18 fit one 64-byte packet) and only as
   many as keep its estimate of the queued slots at ``prefill_slots``;
3. waits one link delay, the device accepts as many as fit, one link delay back, and the host
   advances its read pointer **by the accepted count only**.

Before the job starts the host fills the buffer with up to ``prefill_slots`` slots, then switches
the engine to buffer mode (one more round trip). Its estimate of the queued slots is
``slots accepted - slots elapsed since buffer mode began``, from its own clock. An empty buffer
in the middle of the job is the engine's underrun (:class:`~cosim.controllers.pokeys.records.Underrun`).

Times given in nanoseconds (``period_ns``, ``start_ns``, stalls) are converted once to ticks of
the simulation's resolution, which refuses a time that is not a whole number of ticks; times the
host records (:class:`FillRecord`, :attr:`HostApp.t_buffer_mode`) are in ticks.

**Waits.** A job may end in a :class:`~cosim.controllers.pokeys.toolpath.Wait` (a G-code M66 on an
input, an M0 resumed by cycle start): the rest of the job comes from ``next_piece`` once the wait
has ended. While it waits the host keeps the buffer at its level with *idle* slots (no pulses,
the direction bits as they were), so the engine never runs dry; the wait starts when the engine
takes the first idle slot (the motion before it has ended). At each of its cycles from then on
the host reads the input (its value at that instant: a pulse between two cycles is missed, as
by any polling host) and, as LinuxCNC's M66 does, ends the wait: L0 at once with the value; L3 /
L4 when the input is high / low; L1 / L2 on a rise / fall (seen low, then high; seen high, then
low); or, ``timeout`` seconds after the start, with -1. The idle slots not yet sent are dropped
and the next piece follows the ones the device has taken: motion resumes after the idle slots
still queued (up to ``prefill_slots``), the host's latency.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, overload

from cosim.controllers.pokeys.buffer import Entry, check_entry, signed_count
from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.limits import BUFFER_SLOTS, COUNT_MASK, DIRECTION_BIT, FILL_SLOTS_PER_PACKET, SLOT_NS
from cosim.controllers.pokeys.link import Link, LinkProfile
from cosim.controllers.pokeys.states import EngineState
from cosim.controllers.pokeys.toolpath import Wait
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.signals import Signal
from cosim.timebase import Priority
from cosim.validate import integer

NextPiece = Callable[[float | None, int, tuple[bool, ...]], tuple[Sequence[object], Wait | None]]
"""``next_piece(value, first_index, direction_bits) -> (entries, wait)``: the job's next entries after a wait
(``value``: what the wait read, None for a wait that reads nothing), which start at entry ``first_index``
with the engine's direction bits ``direction_bits``, and the wait that ends them (None: the job's end)."""


@dataclass(frozen=True)
class Stall:
    """The host does nothing in ``[t_start_ns, t_start_ns + duration_ns)``."""

    t_start_ns: int
    duration_ns: int

    def __post_init__(self) -> None:
        integer(self.t_start_ns, "stall t_start_ns", low=0, high=2**62, unit="ns")
        integer(self.duration_ns, "stall duration_ns", low=1, high=2**62, unit="ns")

    @property
    def t_end_ns(self) -> int:
        """First instant after the stall [ns]."""
        return self.t_start_ns + self.duration_ns


@dataclass(frozen=True)
class FillRecord:
    """One fill-buffer round trip as the host saw it: sent, taken by the device, reply back [ticks]."""

    t_send: int
    t_device: int
    t_reply: int
    offered: int
    accepted: int


class FillLog:
    """The host's fill round trips, reduced as they come: totals of all of them, the first ``keep`` in full.

    A job of an hour sends over a million fill commands; keeping each as a :class:`FillRecord`
    would make the run's memory grow with simulated time, and only the totals are used (figures,
    reports). ``len()`` is the number of fills sent; indexing and iteration give the records kept.

    Parameters
    ----------
    keep : int
        Records kept in full (the first ones), >= 0.

    Attributes
    ----------
    offered, accepted : int
        Slots offered and accepted over all fills [slots].
    partial : int
        Fills of which the device took fewer slots than offered.
    longest_round_trip : int
        Longest time from sending a fill to its reply [ticks] (0 before the first).
    """

    def __init__(self, keep: int = 1000) -> None:
        self.keep = integer(keep, "keep", low=0, unit="records")
        self.kept: list[FillRecord] = []
        self.count = 0
        self.offered = 0
        self.accepted = 0
        self.partial = 0
        self.longest_round_trip = 0

    def append(self, record: FillRecord) -> None:
        """Count one fill (and keep it if fewer than ``keep`` are kept)."""
        self.count += 1
        self.offered += record.offered
        self.accepted += record.accepted
        self.partial += record.accepted < record.offered
        self.longest_round_trip = max(self.longest_round_trip, record.t_reply - record.t_send)
        if len(self.kept) < self.keep:
            self.kept.append(record)

    def __len__(self) -> int:
        return self.count

    def __iter__(self) -> Iterator[FillRecord]:
        return iter(self.kept)

    @overload
    def __getitem__(self, index: int) -> FillRecord: ...

    @overload
    def __getitem__(self, index: slice) -> list[FillRecord]: ...

    def __getitem__(self, index: int | slice) -> FillRecord | list[FillRecord]:
        return self.kept[index]


class HostApp:
    """A host application streaming a job into the engine's slot buffer.

    Parameters
    ----------
    sim : Simulation
    engine : PulseEngine
    entries : sequence
        The job: slot entries (one byte per engine axis, or one signed count per axis).
    link : {'usb', 'ethernet'} or LinkProfile
        Delay model of the link; delays come from ``sim.rng``.
    period_ns : int
        Host loop period [ns] (default 1 ms).
    prefill_slots : int
        Slots queued before buffer mode starts, and the level the host keeps (1..128).
    max_slots_per_fill : int
        Slots per fill command (1..128; 18 fit one packet).
    stalls : sequence of Stall
        Injected host stalls.
    start_ns : int
        When the host starts [ns].
    keep_fills : int
        Fill round trips kept in full in :attr:`fills` (the first ones; all are counted).
    wait : Wait, optional
        The wait that ends ``entries`` (see the module text); then ``next_piece`` gives the rest.
    next_piece : callable, optional
        :data:`NextPiece`: the job's entries after a wait.
    inputs : mapping of str to Signal
        The inputs a wait may read, by name (``din0``, ``ain1``, ``cycle_start``); one not given reads 0.

    Attributes
    ----------
    fills : FillLog
        The fill round trips: ``len(fills)`` commands sent, their totals, the first ``keep_fills``.
    t_buffer_mode : int or None
        When the host sent "buffer mode" [ticks] (its own clock's origin for the queued-slot estimate).
    t_last_accepted : int or None
        When the device accepted the job's last slots [ticks].
    waits : list of tuple
        The waits ended so far: (wait, start, end [ticks], value read or -1 after the timeout).
    """

    def __init__(self, sim: Simulation, engine: PulseEngine, entries: Sequence[object], *,
                 link: str | LinkProfile = "usb", period_ns: int = 1_000_000, prefill_slots: int = BUFFER_SLOTS,
                 max_slots_per_fill: int = FILL_SLOTS_PER_PACKET, stalls: Sequence[Stall] = (),
                 start_ns: int = 0, keep_fills: int = 1000, wait: Wait | None = None,
                 next_piece: NextPiece | None = None, inputs: Mapping[str, Signal] | None = None) -> None:
        self.sim = sim
        self.engine = engine
        # equal entries share one object: a job of an hour holds millions of slots, mostly repeats
        self.entries: list[Entry] = _checked_all(engine, entries)
        self.link = Link(sim, link)
        self.period_ns = integer(period_ns, "period_ns", low=1, high=10**10, unit="ns")
        self.period = sim.ticks(period_ns, "ns", name="period_ns")
        self.prefill_slots = integer(prefill_slots, "prefill_slots", low=1, high=BUFFER_SLOTS, unit="slots")
        self.max_slots_per_fill = integer(max_slots_per_fill, "max_slots_per_fill", low=1, high=BUFFER_SLOTS,
                                          unit="slots")
        for s in stalls:
            if not isinstance(s, Stall):
                raise ConfigurationError.out_of_range("stall", s, "Stall(t_start_ns, duration_ns)")
        self.stalls = sorted(stalls, key=lambda s: s.t_start_ns)
        self._stalls = [(sim.ticks(s.t_start_ns, "ns", name="stall t_start_ns"),
                         sim.ticks(s.t_end_ns, "ns", name="stall end")) for s in self.stalls]
        self.start_ns = integer(start_ns, "start_ns", low=0, unit="ns")
        self.start = sim.ticks(start_ns, "ns", name="start_ns")
        self.read_pointer = 0
        self._cycle = 0  # the host loop's cycle (see refill_buffer)
        self.fills = FillLog(keep_fills)
        self.t_buffer_mode: int | None = None
        self.t_last_accepted: int | None = None
        self.inputs = dict(inputs or {})
        if wait is not None and next_piece is None:
            raise ConfigurationError(f"host: the job waits on {wait.input} (line {wait.line}) and nothing gives what "
                                     "comes after (next_piece)")
        self.next_piece = next_piece
        self.wait: Wait | None = None
        self.waits: list[tuple[Wait, int, int, float]] = []
        self._begin_wait(wait)
        sim.process(self.refill_buffer())

    @property
    def finished(self) -> bool:
        """Every slot of the job was accepted by the device (and no wait is left)."""
        return self.read_pointer >= len(self.entries) and self.wait is None

    def stall_end(self, t: int) -> int | None:
        """End of the stall containing ``t`` [ticks], or None."""
        for start, end in self._stalls:
            if start <= t < end:
                return end
        return None

    def refill_buffer(self) -> Generator[Any, Any, None]:
        """SimPy process: prefill, start buffer mode, then refill every period until the job is sent."""
        sim = self.sim
        yield sim.at(self.start, Priority.HOST)
        while not self.finished:
            end = self.stall_end(sim.now)
            if end is not None:
                yield self._wake_at(end)
            started = self.t_buffer_mode is not None
            if self.wait is not None and started:
                self._check_wait()
            want = self.prefill_slots - self._estimated_level() if started else self.prefill_slots - self.read_pointer
            if self.wait is not None:  # idle slots while the host waits
                self.entries.extend([self._idle] * max(0, min(want, self.max_slots_per_fill)
                                                       - (len(self.entries) - self.read_pointer)))
            want = min(want, self.max_slots_per_fill, len(self.entries) - self.read_pointer)
            full = False
            if want > 0:
                full = (yield from self._fill(want)) < want
            if not started and (self.read_pointer >= self.prefill_slots or self.finished or full):
                yield from self._start_buffer_mode()
                continue
            self._cycle = self._next_cycle(sim.now)
            yield self._wake_at(self.start + self._cycle * self.period)

    def _next_cycle(self, t: int) -> int:
        """The host loop's next cycle after one that ended at ``t`` (the next period start, none skipped before)."""
        return max(self._cycle + 1, -(-(t - self.start) // self.period))

    def _keeps_to_itself(self, accepted: int = 0) -> bool:
        """Will the host, resumed next (after ``accepted`` more slots were accepted), touch only its own state
        until it sends a command? In buffer mode, with no wait (a wait reads the device's progress) and
        slots left to send (else the job ends there)."""
        return (self.t_buffer_mode is not None and self.wait is None
                and self.read_pointer + accepted < len(self.entries))

    def _wake_at(self, t: int) -> Any:
        """The event of the host's next cycle at ``t``: quiet (:meth:`~cosim.kernel.Simulation.quiet_at`) while
        the host keeps to itself: the command it may send then reaches the device the next link delay later
        (drawn already, or at least the latency)."""
        if self._keeps_to_itself():
            return self.sim.quiet_at(t, Priority.HOST, quiet_for=self.link.next_delay())
        return self.sim.at(t, Priority.HOST)

    # -- waits ------------------------------------------------------------------------------------------
    def _begin_wait(self, wait: Wait | None) -> None:
        self.wait = wait
        self._wait_index = len(self.entries)  # the first idle slot
        self._wait_start: int | None = None
        self._seen = False  # rise: the input was seen low (fall: high)
        self._timeout = None if wait is None or wait.timeout is None else \
            math.ceil(wait.timeout * self.sim.ticks(1, "s"))
        last = self.entries[-1] if self.entries else bytes(len(self.engine.axis_names))
        self._idle: Entry = bytes(b & DIRECTION_BIT for b in last)

    def _check_wait(self) -> None:
        """One reading of the input at this cycle; the wait ends if it says so."""
        wait, engine, now = self.wait, self.engine, self.sim.now
        assert wait is not None
        if self._wait_start is None:
            if engine.buffer.taken <= self._wait_index:
                return  # the motion before the wait is still running
            self._wait_start = engine.t0 + (engine.slot_index - 1 - (engine.buffer.taken - 1 - self._wait_index)) \
                * engine.slot_ticks
        signal = self.inputs.get(wait.input)
        value = signal.value if signal is not None else 0  # an input nothing drives reads 0
        high = bool(value)
        done: float | None = None
        if wait.mode == 0:
            done = float(value)
        elif wait.mode in (3, 4):
            done = float(high) if high == (wait.mode == 3) else None
        elif high != (wait.mode == 1):
            self._seen = True
        elif self._seen:
            done = float(high)
        if done is None and self._timeout is not None and now - self._wait_start >= self._timeout:
            done = -1.0
        if done is not None:
            self._end_wait(done)

    def _end_wait(self, value: float) -> None:
        wait = self.wait
        assert wait is not None and self.next_piece is not None and self._wait_start is not None
        self.waits.append((wait, self._wait_start, self.sim.now, value))
        del self.entries[max(self.read_pointer, self._wait_index):]  # idle slots not sent
        first = len(self.entries)
        bits = tuple(bool(b & DIRECTION_BIT) for b in self._idle)
        entries, after = self.next_piece(value if wait.reads else None, first, bits)
        self.entries.extend(_checked_all(self.engine, entries, first))
        self._begin_wait(after)

    def _estimated_level(self) -> int:
        assert self.t_buffer_mode is not None
        elapsed = (self.sim.now - self.t_buffer_mode) // self.engine.slot_ticks + 1
        return self.read_pointer - elapsed

    def _fill(self, want: int) -> Generator[Any, Any, int]:
        t_send = self.sim.now
        yield self.sim.after(self.link.delay(), Priority.HOST)
        t_device = self.sim.now
        offered = self.entries[self.read_pointer:self.read_pointer + want]
        reply = self.engine.fill_buffer(offered)
        if self._keeps_to_itself(reply.accepted):  # the reply: bookkeeping, then the next (quiet) cycle
            t_reply = self.sim.now + self.link.delay()
            t_next = self.start + self._next_cycle(t_reply) * self.period
            yield self.sim.quiet_at(t_reply, Priority.HOST, quiet_for=t_next - t_reply + self.link.next_delay())
        else:
            yield self.sim.after(self.link.delay(), Priority.HOST)
        self.read_pointer += reply.accepted
        if reply.accepted:
            self.t_last_accepted = t_device
        self.fills.append(FillRecord(t_send, t_device, self.sim.now, len(offered), reply.accepted))
        return reply.accepted

    def _start_buffer_mode(self) -> Generator[Any, Any, None]:
        t_send = self.sim.now
        yield self.sim.after(self.link.delay(), Priority.HOST)
        self.engine.set_state(EngineState.BUFFER)
        self.t_buffer_mode = t_send  # the host's own clock: when it sent the command
        yield self.sim.after(self.link.delay(), Priority.HOST)


def _checked_all(engine: PulseEngine, entries: Sequence[object], first: int = 0) -> list[Entry]:
    """:func:`_checked` of every entry (``first``: the index of the first), equal entries as one object.

    A bytes entry equal to one checked before is that one again (the check reads only its value):
    a planned job is mostly repeats, so it costs a dictionary look-up, and an error names the
    first slot that holds the bad value, as checking each in turn does.
    """
    shared: dict[object, Entry] = {}
    out: list[Entry] = []
    append = out.append
    for i, entry in enumerate(entries, first):
        raw = shared.get(entry) if type(entry) is bytes else None
        if raw is None:
            raw = _checked(engine, entry, i)
            raw = shared.setdefault(raw, raw)
            if type(entry) is bytes:
                shared[entry] = raw
        append(raw)
    return out


def _checked(engine: PulseEngine, entry: object, index: int) -> Entry:
    """A job entry the engine's model can emit (the host refuses a job it could never send)."""
    raw = check_entry(entry, axes=len(engine.axis_names), where=f"host job slot {index}")
    limit, rate = engine.device.max_pulses_per_slot, engine.device.max_rate_hz
    for a, byte in enumerate(raw):
        if byte & COUNT_MASK > limit:
            integer(signed_count(byte), "pulses per slot", low=-limit, high=limit,
                    allowed=f"-{limit}..{limit} ({rate} Hz at {SLOT_NS} ns slots)",
                    where=f"host job slot {index} axis {engine.axis_names[a]}")
    return raw
