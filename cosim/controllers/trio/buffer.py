"""The move buffers: one running and one buffered move per axis, and the programs that wait on them.

A move command (``MOVE``, ``MOVEABS``, ``MOVECIRC``, ``FORWARD``, ``REVERSE``) goes into the
buffer of every axis it moves if they all have room, else the program waits (in issue order)
until the servo cycle frees them. At each servo tick moves whose last cycle was output leave,
buffered moves whose axes are all free are loaded, a requested ``CANCEL`` takes effect, and every
running move runs one cycle. ``WAIT IDLE`` returns at the tick where the axes have neither a
running nor a buffered move, ``WAIT LOADED`` where they have no buffered move.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from fractions import Fraction

from simpy.events import Event

from cosim.controllers.trio.axis import Axis
from cosim.controllers.trio.motion import Move
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation


class MoveBuffers:
    """The move buffers of the axes of one controller.

    Parameters
    ----------
    sim : Simulation
    axes : dict of int to Axis
    period_s : Fraction
        The servo period [s].
    """

    def __init__(self, sim: Simulation, axes: dict[int, Axis], *, period_s: Fraction) -> None:
        self.sim = sim
        self.axes = axes
        self.period_s = period_s
        self._queued: list[Move] = []
        self._running: list[Move] = []  # loaded, in load order
        self._moved: list[Axis] = []  # axes a move ran in the last cycle (their VP_SPEED goes back to 0)
        self._move_waiters: deque[tuple[Move, Event]] = deque()
        self._waiters: list[tuple[Callable[[], bool], Event]] = []

    # -- commands -----------------------------------------------------------------------------
    def add(self, move: Move) -> Event:
        """Buffer ``move``: an event that succeeds once it is in the buffers (at once if there is room)."""
        done = self.sim.env.event()
        if not self._move_waiters and self._can_queue(move):
            self._queue(move)
            done.succeed()
        else:
            self._move_waiters.append((move, done))
        return done

    def cancel(self, axes: Sequence[int]) -> None:
        """``CANCEL``: the running move of each axis decelerates from the next servo tick on."""
        for a in axes:
            move = self.axes[a].current
            if move is not None and not move.done:
                move.cancel_requested = True

    def drop_buffered(self, axes: Sequence[int]) -> None:
        """``CANCEL(1)``, ``RAPIDSTOP``: the moves buffered on ``axes`` are dropped."""
        for move in [m for m in self._queued if set(m.axes) & set(axes)]:
            self._queued.remove(move)
            for a in move.axes:
                if self.axes[a].queued is move:
                    self.axes[a].queued = None

    def start_now(self, move: Move) -> None:
        """A move the servo cycle starts itself (a jog): loaded at this tick, on idle axes."""
        self._queue(move)

    def wait(self, condition: Callable[[], bool]) -> Event:
        """An event that succeeds now, or at the first servo tick where ``condition()`` holds."""
        done = self.sim.env.event()
        if condition():
            done.succeed()
        else:
            self._waiters.append((condition, done))
        return done

    def idle(self, axes: Sequence[int]) -> bool:
        """No move running or buffered on any of ``axes``."""
        return all(self.axes[a].idle for a in axes)

    def loaded(self, axes: Sequence[int]) -> bool:
        """No move buffered (nor waiting to be) behind the running one on any of ``axes``."""
        return all(self.axes[a].queued is None for a in axes) and not any(
            set(move.axes) & set(axes) for move, _ in self._move_waiters)

    def _can_queue(self, move: Move) -> bool:
        return all(self.axes[a].queued is None for a in move.axes)

    @property
    def busy(self) -> bool:
        """A move runs, is buffered or waits to be, or a program waits on the servo cycle."""
        return bool(self._queued or self._running or self._move_waiters or self._waiters)

    @property
    def pending(self) -> bool:
        """A running move may end or a buffered one start: :meth:`load` has work."""
        return bool(self._queued) or bool(self._running)

    def _queue(self, move: Move) -> None:
        for a in move.axes:
            axis = self.axes[a]
            axis.queued = move
            axis.quiet = False
        self._queued.append(move)

    # -- the servo cycle ----------------------------------------------------------------------
    def load(self, now: int) -> None:
        """End moves whose last cycle was output; load buffered moves whose axes are free."""
        axes = self.axes
        for move in [m for m in self._running if m.done]:
            self._running.remove(move)
            for a in move.axes:
                if axes[a].current is move:
                    axes[a].current = None
        for move in list(self._queued):
            if all(axes[a].current is None for a in move.axes):
                try:
                    move.load(axes, now, self.period_s)
                except ConfigurationError as exc:  # a plan that fails stops the job, naming where the move came from
                    raise ConfigurationError(f"{move.origin}: {exc}" if move.origin else str(exc)) from exc
                for a in move.axes:
                    axes[a].current, axes[a].queued = move, None
                self._queued.remove(move)
                self._running.append(move)
                self._running.sort(key=lambda m: min(m.axes))  # cycles run in axis order
        for move in self._running:
            if self._queued and move.axis_objects and move.axis_objects[0].params.get("MERGE"):
                self._merge(move)

    def _merge(self, move: Move) -> None:
        """MERGE = ON: a linear move buffered on the same axes joins the running one (see :meth:`Move.absorb`)."""
        for queued in self._queued:
            if queued.axes == move.axes and move.absorb(queued, self.axes, self.period_s):
                self._queued.remove(queued)
                for a in queued.axes:
                    self.axes[a].queued = None
                return

    def run_cycle(self, now: int, period_ticks: int, period_s: Fraction) -> None:
        """One cycle of every running move: demands, VP_SPEED and step pulses."""
        axes = self.axes
        for axis in self._moved:
            axis.vnum, axis.vden = 0, 1
        moved = self._moved = []
        for move in self._running:
            if move.modify_to is not None:
                end, move.modify_to = move.modify_to, None
                move.modify(end, axes, period_s)
            if move.cancel_requested:
                move.stop(period_s, Fraction(axes[move.axes[0]].params["DECEL"]))
            move.advance()
            v_num, v_den, origin = move.v_num, move.v_den, move.origin
            for a, num, den in zip(move.axes, move.nums, move.dens, strict=True):
                axis = axes[a]
                moved.append(axis)
                axis.vnum, axis.vden = v_num, v_den
                axis.output_cycle(now, period_ticks, num, den, origin)

    def release(self) -> None:
        """After the servo cycle: buffer waiting moves that now fit, release satisfied waits."""
        while self._move_waiters and self._can_queue(self._move_waiters[0][0]):
            move, done = self._move_waiters.popleft()
            self._queue(move)
            done.succeed()
        still = []
        for condition, done in self._waiters:
            if condition():
                done.succeed()
            else:
                still.append((condition, done))
        self._waiters = still
