"""The event kernel: one SimPy environment whose clock is an integer tick count.

:class:`Simulation` owns the SimPy environment, the :class:`~cosim.timebase.TimeBase` and the
:class:`~cosim.trace.Trace`. Controllers are SimPy processes that wait with :meth:`Simulation.at`
/ :meth:`Simulation.after` (integer ticks and a named :class:`~cosim.timebase.Priority`).

Plants that can announce events (an FMU with event indicators) register a *look-ahead*: just
before the kernel moves its clock from ``now`` to the next scheduled instant ``t_next``, every
look-ahead is called with ``t_next``. Nothing can change the plant's inputs in ``[now, t_next)``,
so the plant may safely advance to ``t_next``; if it finds an event earlier it schedules it, and
the kernel runs that event first.

A callback scheduled with :meth:`Simulation.call_at` can be taken back with
:meth:`Simulation.cancel` before it fires: it then never runs, and :meth:`Simulation.due_by` /
:meth:`Simulation.skip_to` no longer see it (a coupling that arms a check for an instant which
usually turns out not to be needed keeps the controllers' shortcut working).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from heapq import heappop, heappush
from operator import methodcaller
from typing import Any

import simpy
from simpy.core import EmptySchedule, Infinity, StopSimulation
from simpy.events import Event, EventPriority

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.notes import Notes
from cosim.timebase import Priority, TimeBase
from cosim.trace import Trace

LookAhead = Callable[[int], None]
#: A queue entry of SimPy's: (tick, priority, insertion number, event).
Entry = tuple[int, int, int, Event]


class _Environment(simpy.Environment):
    """A SimPy environment that calls look-aheads before its clock moves.

    Its :meth:`step` is SimPy's own (the same order, the same handling of a stopped run and of a
    failed event) with the kernel's additions in front: cancelled events at the queue's head are
    dropped, progress is reported, look-aheads are called. Those run only while one of them has
    something to do (a flag for cancelled events and progress, and the look-aheads' list), so that
    an event costs about what a bare SimPy event does. The clock is always an ``int``: every entry
    point makes its tick one.
    """

    def __init__(self) -> None:
        super().__init__(initial_time=0)
        self.look_aheads: list[LookAhead] = []
        self._on_progress: Callable[[int], None] | None = None
        self._cancelled = 0
        self._special = False  # cancelled events queued or progress wanted
        self._steps = 0  # kernel events run
        self._skips = 0  # passes fast paths ran without an event (Simulation.skip_to, the master's sampling)

    def _update(self) -> None:
        self._special = bool(self._cancelled or self._on_progress is not None)

    @property
    def on_progress(self) -> Callable[[int], None] | None:
        """Called with the clock every 4096 steps of work (events and fast-path passes), if set."""
        return self._on_progress

    @on_progress.setter
    def on_progress(self, callback: Callable[[int], None] | None) -> None:
        self._on_progress = callback
        self._update()

    @property
    def cancelled(self) -> int:
        """Cancelled events still in the queue (dropped when they reach its head)."""
        return self._cancelled

    @cancelled.setter
    def cancelled(self, count: int) -> None:
        self._cancelled = count
        self._update()

    def drop_cancelled(self) -> None:
        """Remove cancelled events from the head of the queue."""
        queue = self._queue
        dropped = 0
        while queue and getattr(queue[0][3], "cancelled", False):
            heappop(queue)
            dropped += 1
        if dropped:
            self._cancelled -= dropped
            if not self._cancelled:
                self._update()

    def peek(self) -> float:
        if self._cancelled:
            self.drop_cancelled()
        queue = self._queue
        return queue[0][0] if queue else Infinity

    def step(self) -> None:
        self._steps += 1
        if self._special or self.look_aheads:
            self._before_step()
        # SimPy's Environment.step (simpy 4.1), inline:
        try:
            self._now, _, _, event = heappop(self._queue)
        except IndexError:
            raise EmptySchedule from None
        callbacks, event.callbacks = event.callbacks, None  # type: ignore[assignment]
        try:
            for callback in callbacks:
                callback(event)
        except StopSimulation:
            # As SimPy does: the callbacks not run yet run when the simulation resumes.
            event.callbacks = callbacks[callbacks.index(callback) + 1:]
            self.schedule(event, EventPriority(-1))
            raise
        if not event._ok and not hasattr(event, "_defused"):
            exc = type(event._value)(*event._value.args)
            exc.__cause__ = event._value
            raise exc

    def _before_step(self) -> None:
        """Drop cancelled events at the head, report progress, call the look-aheads (before the clock moves)."""
        if self._cancelled:
            self.drop_cancelled()
        if self._on_progress is not None and not (self._steps + self._skips) & 0xFFF:
            self._on_progress(int(self._now))
        queue = self._queue
        if self.look_aheads and queue:
            t_next = queue[0][0]
            if self._now < t_next:
                for look_ahead in self.look_aheads:
                    look_ahead(int(t_next))

    def count_step(self, now: float) -> None:
        """Count one step of work a fast path ran without an event; report progress."""
        self._skips += 1
        if self._on_progress is not None and not (self._steps + self._skips) & 0xFFF:
            self._on_progress(int(now))


class At(Event):
    """An event that fires at an absolute tick with a named priority.

    Scheduled as SimPy's ``env.schedule(event, priority, t - env.now)`` does (the same queue entry),
    without its call.
    """

    cancelled = False  # set by Simulation.cancel
    _ok = True  # triggered when made: every At succeeds
    quiet_for = 0  # see Simulation.quiet_at

    def __init__(self, env: simpy.Environment, t: int, priority: int, value: Any = None) -> None:
        # Event.__init__, inline (as SimPy's own Timeout does); the event is triggered already (_ok).
        self.env = env
        self.callbacks: list[Callable[[Event], None]] = []
        self._value = value
        queue: list[Entry] = env._queue  # type: ignore[assignment]
        heappush(queue, (t, priority, next(env._eid), self))


class _Call(At):
    """An event of :meth:`Simulation.call_at`: its one callback calls ``call()``."""

    _value = None
    call: Callable[[], None]


#: The callback of a ``_Call`` event: ``event.call()``, in C (no Python frame between SimPy and the callback).
_call = methodcaller("call")


def integer_ticks(value: object) -> int:
    """A count of ticks >= 0 (a quiet event's ``quiet_for``), or ConfigurationError."""
    return validate.integer(value, "quiet_for", low=0, unit="ticks")


def _nothing() -> None:
    return None


_new = object.__new__


class Simulation:
    """A co-simulation in exact integer time.

    Parameters
    ----------
    timebase : TimeBase, optional
        Declared resolution (1 ns by default).
    seed : int
        Seed of the simulation's random generator (:attr:`rng`); same seed, same trace.

    Examples
    --------
    >>> sim = Simulation()
    >>> log = []
    >>> def blink(sim):
    ...     for k in range(3):
    ...         yield sim.at(k * 500)
    ...         log.append(sim.now)
    >>> _ = sim.process(blink(sim))
    >>> sim.run(until=2_000)
    >>> log
    [0, 500, 1000]
    """

    def __init__(self, *, timebase: TimeBase | None = None, seed: int = 0) -> None:
        from cosim.validate import integer

        self.seed = integer(seed, "seed", low=0, high=2**63 - 1)
        self.timebase = timebase or TimeBase()
        self.env = _Environment()
        # SimPy's queue and its entry counter (made once, with the environment), for the scheduling methods
        self._queue: list[Entry] = self.env._queue  # type: ignore[assignment]
        self._eid: Iterator[int] = self.env._eid
        self.trace = Trace(self.timebase)
        self.notes = Notes()  # what the run's result lists besides checks: see cosim.notes
        self._rng: Any = None  # made on first use (numpy.random costs ~20 ms of start-up to import)
        self._closers: list[Callable[[], None]] = []
        self._stoppers: list[Callable[[int], None]] = []

    @property
    def rng(self) -> Any:
        """The simulation's random generator, ``numpy.random.default_rng(seed)`` (made on first use)."""
        if self._rng is None:
            import numpy as np

            self._rng = np.random.default_rng(self.seed)
        return self._rng

    @property
    def now(self) -> int:
        """Current simulation time in ticks (an ``int``: every way to schedule or move the clock makes it one)."""
        return self.env._now  # type: ignore[return-value]

    def ticks(self, value: int | float | str, unit: str | None = None, *, name: str = "time") -> int:
        """Shorthand for :meth:`TimeBase.ticks`."""
        return self.timebase.ticks(value, unit, name=name)

    def at(self, t: int, priority: int = Priority.NORMAL, value: Any = None) -> Event:
        """An event at absolute tick ``t`` (not in the past)."""
        env = self.env
        if type(t) is not int or t < env._now:  # the common case costs one test
            t = self._checked_t(t)
        event = _new(At)  # At(env, t, priority, value), without the call
        event.env, event.callbacks, event._value = env, [], value
        heappush(self._queue, (t, priority, next(self._eid), event))
        return event

    def after(self, delay: int, priority: int = Priority.NORMAL, value: Any = None) -> Event:
        """An event ``delay`` ticks from now."""
        if type(delay) is not int or delay < 0:
            delay = self.timebase.check_ticks(delay, name="delay")
        env = self.env
        t: int = env._now + delay  # type: ignore[assignment]  # (the clock is an int)
        event = _new(At)
        event.env, event.callbacks, event._value = env, [], value
        heappush(self._queue, (t, priority, next(self._eid), event))
        return event

    def quiet_at(self, t: int, priority: int, *, quiet_for: int) -> Event:
        """:meth:`at`, for a process that keeps to itself: a *quiet* event.

        The waiting process promises that, resumed at ``t``, it reads and changes only its own
        state (no signal, no other device) and that nothing it then causes that others could see
        happens before ``t + quiet_for`` (a host whose command reaches the device one link
        latency later). :meth:`run_bound` lets a controller's run of slots go past such an event.
        """
        if type(quiet_for) is not int or quiet_for < 0:  # the common case costs one test
            quiet_for = integer_ticks(quiet_for)
        event = self.at(t, priority)
        if quiet_for:
            event.quiet_for = quiet_for  # type: ignore[attr-defined]
        return event

    def quiet_after(self, delay: int, priority: int, *, quiet_for: int) -> Event:
        """:meth:`quiet_at` ``delay`` ticks from now."""
        if type(quiet_for) is not int or quiet_for < 0:
            quiet_for = integer_ticks(quiet_for)
        event = self.after(delay, priority)
        if quiet_for:
            event.quiet_for = quiet_for  # type: ignore[attr-defined]
        return event

    def call_at(self, t: int, priority: int, callback: Callable[[], None]) -> Event:
        """Run ``callback()`` at tick ``t`` with ``priority`` (no process needed); :meth:`cancel` takes it back."""
        env = self.env
        if type(t) is not int or t < env._now:
            t = self._checked_t(t)
        event = _new(_Call)
        event.env, event.callbacks, event.call = env, [_call], callback
        heappush(self._queue, (t, priority, next(self._eid), event))
        return event

    def _checked_t(self, t: object) -> int:
        """``t`` as an int tick, or ConfigurationError: not an integer, negative, or in the past."""
        ticks = self.timebase.check_ticks(t, name="t")
        if ticks < self.now:
            raise ConfigurationError(f"t = {t} ticks is in the past (now = {self.now})")
        return ticks

    def cancel(self, event: Event) -> None:
        """Take back an event of :meth:`call_at` that has not fired: its callback never runs.

        From then on :meth:`due_by` and :meth:`skip_to` do not see it (it leaves the queue when it
        reaches the queue's head). An event that has fired or is cancelled already is left alone.
        Only for events no process waits on: a process waiting on a cancelled event would wait for ever.
        """
        if not isinstance(event, At):
            raise ConfigurationError(f"cancel: {event!r} is not an event of Simulation.call_at")
        if event.callbacks is None or event.cancelled:
            return
        event.cancelled = True
        event.callbacks = []
        if isinstance(event, _Call):
            event.call = _nothing  # the callback's closure is freed now, not when the entry leaves the queue
        env = self.env
        env._cancelled += 1
        env._special = True

    def due_by(self, t: int) -> bool:
        """Is any event queued at or before tick ``t``? (SimPy's public ``peek``.)

        A run's ``until`` is a queued event too, so a loop that asks before each pass never runs
        past the end of the run.
        """
        return self.env.peek() <= t

    def free_until(self) -> float:
        """The first tick at which something else may happen: the next queued event (``inf`` if none).

        ``now`` while a look-ahead is registered (a plant could announce an event at any instant).
        A process resumed by an event of its own may do, at once, what it would do at instants before
        this tick, then move the clock with :meth:`skip_to` (see there).
        """
        env = self.env
        if env.look_aheads:
            return env._now
        return env.peek()

    def run_bound(self) -> float:
        """Like :meth:`free_until`, but a quiet event (:meth:`quiet_at`) at ``t`` counts only from
        ``t + quiet_for``: the first tick at which something a run of slots could see may happen.

        A process may do, at once, the work of its instants before this tick (a run of slots handed
        to its listeners); the clock stays where it is (:meth:`skip_to` refuses to pass a queued
        event) and the quiet events run at their own instants afterwards.
        """
        env = self.env
        if env.look_aheads:
            return env._now
        queue = self._queue
        if env._cancelled:
            env.drop_cancelled()
        if not queue:
            return Infinity
        t_head, _, _, head = queue[0]
        quiet = getattr(head, "quiet_for", 0)
        if not quiet:
            return t_head
        bound = t_head + quiet
        for t, _, _, event in queue:  # (a short queue: the controllers' and the plants' next events)
            if t < bound:
                t += getattr(event, "quiet_for", 0)
                if t < bound:
                    bound = t
        return bound

    def skip_to(self, t: int, *, passes: int = 1) -> bool:
        """Move the clock to tick ``t`` at once if nothing else can happen before it; else do nothing.

        For a process that runs at many instants in a row (a controller's slot loop): instead of
        yielding one event per instant it may call its next pass directly when this returns True.
        That holds when no look-ahead is registered (no plant could announce an event) and no event
        is due at or before ``t`` (:meth:`due_by`), so the run is the same as with an event at
        ``t``, at a fraction of the cost.

        Call it only from a process resumed by an event of its own (an ``At`` that nothing else
        waits on): other callbacks of a shared event would run after the jump and see the later
        clock.

        ``passes``: how many passes of work the jump stands for (a process that did the work of
        several instants at once, up to ``t``), for progress reports.

        Returns
        -------
        bool
            True if the clock now reads ``t``.
        """
        env = self.env
        if env.look_aheads or t < env._now:
            return False
        if env._cancelled:
            env.drop_cancelled()
        queue = self._queue
        if queue and queue[0][0] <= t:  # due_by(t)
            return False
        env._now = int(t)  # SimPy has no public setter; nothing is due before t, so no event is skipped
        before = env._steps + env._skips
        env._skips += passes  # env.count_step(t), inline
        if env._on_progress is not None and (before ^ (before + passes)) >> 12:  # crossed a multiple of 4096
            env._on_progress(int(t))
        return True

    def process(self, generator: Generator[Event, Any, Any]) -> simpy.Process:
        """Start a SimPy process."""
        return self.env.process(generator)

    def add_look_ahead(self, look_ahead: LookAhead) -> None:
        """Register a look-ahead called with ``t_next`` before the clock moves (see module doc)."""
        self.env.look_aheads.append(look_ahead)

    def on_close(self, closer: Callable[[], None]) -> None:
        """Register a teardown action (closing FMUs), run by :meth:`close` in reverse order."""
        self._closers.append(closer)

    def on_stop(self, stopper: Callable[[int], None]) -> None:
        """Call ``stopper(t)`` whenever :meth:`run` returns or fails, with the instant reached.

        For recorders that hold an open stretch (the Trio's PWM output): they write what they hold
        up to ``t`` into the trace, so that it is complete whenever the run is read.
        """
        self._stoppers.append(stopper)

    def run(self, until: int, *, stop_when: Callable[[], bool] | None = None, every: int | None = None) -> None:
        """Run until tick ``until`` (exclusive for events scheduled exactly then).

        With ``stop_when``, the run also stops at the first multiple of ``every`` ticks after now
        (``now + every``, ``now + 2 every``...) at which ``stop_when()`` is true, before any event
        of that instant, as if ``until`` had been that instant (for a job that ends on its own).

        The trace's end is set to the instant reached, also when a process fails, so whoever
        writes the trace afterwards (the runner) keeps everything recorded up to that instant;
        then the :meth:`on_stop` callbacks are called (once per call).
        """
        until = self.timebase.check_ticks(until, name="until")  # an int: the clock stays one
        end: At | None = None
        watching: list[At] = []  # the next check of stop_when
        if stop_when is not None and until > self.now:  # (else env.run says why it cannot run)
            every = validate.integer(every, "every", low=1, unit="ticks", kind="a whole number of ticks")
            end = At(self.env, until, Priority.URGENT)  # as env.run(until=int) makes it, but cancellable
            self._watch(stop_when, every, until, end, watching)
        try:
            self.env.run(until=until if end is None else end)
        finally:
            for event in watching:  # stopped otherwise (an error): no check left for a later run
                self.cancel(event)
            self.trace.end_t = self.now
            for stopper in self._stoppers:
                stopper(self.now)

    def _watch(self, stop_when: Callable[[], bool], every: int, until: int, end: At, watching: list[At]) -> None:
        def arm() -> None:
            watching.clear()
            if self.now + every < until:
                event = At(self.env, self.now + every, Priority.URGENT)
                event.callbacks.append(check)
                watching.append(event)

        def check(_event: Event) -> None:
            watching.clear()
            if stop_when():
                self.cancel(end)
                raise simpy.core.StopSimulation(None)
            arm()

        arm()

    def close(self) -> None:
        """Tear down everything registered with :meth:`on_close`."""
        while self._closers:
            self._closers.pop()()

    def __enter__(self) -> Simulation:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
