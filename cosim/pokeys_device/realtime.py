"""Real-time pacing: the simulation consumes one 1 ms slot per millisecond of wall clock.

The pacer maps wall-clock time to simulated time once, at :meth:`RealtimePacer.start`
(``wall0`` <-> ``sim0``), and from then on *catches up*: it runs the simulation to the end of the
slot the wall clock is in::

    wall clock   |0 ms      |1 ms      |2 ms      |3 ms
    catch-up             ^ 1.3 ms: sim.run(until = 2 ms) - slot starts 0 and 1 processed
    host request                   ^ 1.6 ms: catch up (nothing to do), then handle at sim.now = 2 ms

Catch-ups happen at every slot boundary (ticker threads sleep to the boundary) and before every
request (:meth:`RealtimePacer.current`), so a host always sees the device as of the current slot
and a command acts before the next slot start, as on the device. Simulated instants are always
exact integer ticks ``sim0 + k * slot_ticks`` (the slot converted once to the simulation's
resolution); only the decision *when* to run comes from the wall clock (in nanoseconds). One lock
guards the simulation: whichever thread holds it runs it.

On a virtual machine a CPU now and then stalls for milliseconds. There is one ticker per CPU (up to
``tickers``), each pinned to its CPU, all waking at every boundary: the first one awake catches up,
the others find nothing to do. With ``rt_priority`` the tickers and the serving thread ask for
``SCHED_FIFO`` while pacing (Linux, needs the privilege; without it pacing goes on at normal
priority and the report says so).

Lag report: for every slot start, lag = (wall time when the catch-up that processed it returned) -
(the slot's wall instant), in slots. Keeping up means a lag below one slot for every slot.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from cosim.controllers.pokeys import SLOT_NS
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.signals import Sampled
from cosim.validate import integer

Clock = Callable[[], int]


@dataclass(frozen=True)
class LagReport:
    """How far the simulation lagged the wall clock.

    Attributes
    ----------
    slots : int
        Slot starts processed in real time.
    max_lag_slots, mean_lag_slots : float
        Largest and mean lag [slots].
    late_slots : int
        Slots processed one slot or more after their wall instant.
    catch_ups : int
        Catch-ups that ran the simulation.
    worst_t_ns : int
        Simulated start of the slot with the largest lag [ns].
    rt_priority : int or None
        The SCHED_FIFO priority pacing ran with (None: normal scheduling).
    tickers : int
        Ticker threads.
    """

    slots: int
    max_lag_slots: float
    mean_lag_slots: float
    late_slots: int
    catch_ups: int
    worst_t_ns: int = 0
    rt_priority: int | None = None
    tickers: int = 0

    @property
    def kept_up(self) -> bool:
        """True if every slot was processed within one slot of its wall instant."""
        return self.late_slots == 0

    def summary(self) -> str:
        """One line for humans."""
        scheduling = f"SCHED_FIFO {self.rt_priority}" if self.rt_priority else "normal scheduling"
        return (f"lag over {self.slots} slots: max {self.max_lag_slots:.3f} slots, mean {self.mean_lag_slots:.3f} "
                f"slots (worst at {self.worst_t_ns / 1e6:.0f} ms), {self.late_slots} slots >= 1 slot late "
                f"({self.catch_ups} catch-ups, {self.tickers} tickers, {scheduling})")


class RealtimePacer:
    """Runs a :class:`Simulation` in step with the wall clock, one slot per ``slot_ns`` of wall time.

    Parameters
    ----------
    sim : Simulation
        Its clock must be on the slot grid when :meth:`start` is called.
    slot_ns : int
        Slot length [ns] (1 ms): of wall time, and of simulated time (``slot_ticks`` at the
        simulation's resolution).
    clock : callable
        Wall clock [ns] (``time.monotonic_ns``; a fake one in tests).
    record_lag : bool
        Record ``pokeys_device.lag`` [us] in the trace at every catch-up.
    rt_priority : int, optional
        Ask for SCHED_FIFO with this priority (1..99) for the pacing threads while :meth:`run` runs.
    tickers : int
        Most ticker threads (one per CPU the process may use, pinned to it).

    Attributes
    ----------
    lock : threading.RLock
        Guards the simulation: hold it (or use :meth:`current`) for anything that touches it while
        :meth:`run` runs.
    """

    def __init__(self, sim: Simulation, *, slot_ns: int = SLOT_NS, clock: Clock = time.monotonic_ns,
                 record_lag: bool = True, rt_priority: int | None = None, tickers: int = 2) -> None:
        integer(slot_ns, "slot_ns", low=1, allowed="> 0 ns (an integer)")
        if rt_priority is not None:
            integer(rt_priority, "rt_priority", low=1, high=99, allowed="1..99 (SCHED_FIFO) or None")
        integer(tickers, "tickers", low=1, high=8)
        self.sim = sim
        self.slot_ns = slot_ns
        self.slot_ticks = sim.ticks(slot_ns, "ns", name="slot_ns")
        self.clock = clock
        self.rt_priority = rt_priority
        self.rt_applied: int | None = None
        self.max_tickers = tickers
        self.lock = threading.RLock()
        self._lag_signal = (Sampled(sim, "pokeys_device.lag", unit="us", description="wall-clock lag of the last "
                                    "slot start processed") if record_lag else None)
        self._wall0: int | None = None
        self._sim0 = 0
        self._slots = 0
        self._lag_sum_ns = 0
        self._lag_max_ns = 0
        self._late = 0
        self._catch_ups = 0
        self._worst_t = 0
        self._tickers: list[Ticker] = []

    @property
    def started(self) -> bool:
        """True after :meth:`start`."""
        return self._wall0 is not None

    @property
    def wall0(self) -> int:
        """Wall-clock instant [ns] of simulated ``sim0`` (raises before :meth:`start`)."""
        if self._wall0 is None:
            raise ConfigurationError("the pacer has not been started")
        return self._wall0

    def start(self) -> None:
        """Tie the simulation's current instant to the wall clock's now."""
        self._wall0 = self.clock()
        self._sim0 = self.sim.now

    def catch_up(self) -> None:
        """Run the simulation to the end of the slot the wall clock is in (no-op when up to date)."""
        with self.lock:
            self._catch_up()

    @contextlib.contextmanager
    def current(self) -> Iterator[None]:
        """Hold the simulation, caught up to the wall clock, for the body (handling one request)."""
        with self.lock:
            self._catch_up()
            yield

    def try_catch_up(self) -> None:
        """Catch up unless another thread is running the simulation right now (it catches up too)."""
        if self.lock.acquire(blocking=False):
            try:
                self._catch_up()
            finally:
                self.lock.release()

    def _catch_up(self) -> None:
        if self._wall0 is None:
            return
        while True:  # until up to date: the wall clock moves on while the simulation runs
            wall = self.clock() - self._wall0
            target = self._sim0 + (wall // self.slot_ns + 1) * self.slot_ticks
            first = self.sim.now
            if target <= first:
                return
            self.sim.run(until=target)
            self._account(first, target, self.clock() - self._wall0)

    def _account(self, first: int, target: int, done: int) -> None:
        """Lag of the slots ``[first, target)`` [ticks], all processed at wall time ``done`` [ns since ``wall0``]."""
        n = (target - first) // self.slot_ticks
        first_wall = (first - self._sim0) // self.slot_ticks * self.slot_ns
        lag_first = done - first_wall  # slot k started at wall instant first_wall + k * slot_ns
        if lag_first > self._lag_max_ns:
            self._lag_max_ns, self._worst_t = lag_first, first
        self._lag_sum_ns += n * done - (n * first_wall + self.slot_ns * n * (n - 1) // 2)
        if lag_first >= self.slot_ns:
            self._late += min(n, (lag_first - self.slot_ns) // self.slot_ns + 1)
        self._slots += n
        self._catch_ups += 1
        if self._lag_signal is not None:
            self._lag_signal.record((done - (first_wall + (n - 1) * self.slot_ns)) // 1000)

    def report(self) -> LagReport:
        """The lag so far."""
        mean = self._lag_sum_ns / self._slots / self.slot_ns if self._slots else 0.0
        worst_ns = int(self._worst_t * self.sim.timebase.resolution_s * 10**9)
        return LagReport(self._slots, self._lag_max_ns / self.slot_ns, mean, self._late, self._catch_ups,
                         worst_ns, self.rt_applied, len(self._tickers))

    async def run(self, stop: asyncio.Event) -> None:
        """Pace until ``stop`` is set (await it in the serving event loop)."""
        restore = raise_priority(self.rt_priority) if self.rt_priority else None
        self.rt_applied = self.rt_priority if restore else None
        if not self.started:
            self.start()
        self.catch_up()  # slot 0 starts now
        cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else [None]
        pinned = len(cpus) > 1
        self._tickers = [Ticker(self, cpu if pinned else None) for cpu in cpus[:self.max_tickers]]
        for ticker in self._tickers:
            ticker.start()
        try:
            await stop.wait()
        finally:
            for ticker in self._tickers:
                ticker.stop()
            if restore is not None:
                restore()
        self.catch_up()


class Ticker(threading.Thread):
    """Sleeps to every slot boundary and catches the simulation up (if no other thread is at it).

    Parameters
    ----------
    pacer : RealtimePacer
    cpu : int, optional
        Pin the thread to this CPU.
    """

    def __init__(self, pacer: RealtimePacer, cpu: int | None) -> None:
        super().__init__(name=f"pokeys-device-ticker-{cpu}", daemon=True)
        self.pacer = pacer
        self.cpu = cpu
        self._stop_event = threading.Event()

    def run(self) -> None:
        pacer, slot = self.pacer, self.pacer.slot_ns
        if self.cpu is not None:
            with contextlib.suppress(OSError, AttributeError):
                os.sched_setaffinity(0, {self.cpu})
        if pacer.rt_applied:
            raise_priority(pacer.rt_applied)
        wall0 = pacer.wall0
        k = (pacer.clock() - wall0) // slot + 1
        while not self._stop_event.is_set():
            delay_ns = wall0 + k * slot - pacer.clock()
            if delay_ns > 0:
                time.sleep(delay_ns / 1e9)
            if self._stop_event.is_set():
                break
            pacer.try_catch_up()
            k = max(k + 1, (pacer.clock() - wall0) // slot + 1)

    def stop(self) -> None:
        """Stop ticking and wait for the thread."""
        self._stop_event.set()
        self.join(timeout=1.0)


def raise_priority(priority: int) -> Callable[[], None] | None:
    """SCHED_FIFO ``priority`` for the calling thread; a function restoring the old policy, or None if refused."""
    if not hasattr(os, "sched_setscheduler"):
        return None
    try:
        policy, param = os.sched_getscheduler(0), os.sched_getparam(0)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except OSError:
        return None

    def restore() -> None:
        with contextlib.suppress(OSError):
            os.sched_setscheduler(0, policy, param)

    return restore
