"""A G-code job in pieces: the moves between the host's waits, planned as the job runs.

A program without waits is one piece, planned whole before the run (:func:`plan_toolpath` on its
whole tool path). A :class:`~cosim.controllers.pokeys.toolpath.Wait` ends a piece at rest:

* ``M66`` on the machine's inputs (``din<n>``, ``ain<n>``): LinuxCNC's interpreter stops reading
  ahead at an M66 until the motion before it has ended and the input has been read into
  ``#5399``, and so does this one (a *live* :class:`~.gcode.interpreter.Interpreter`): what comes
  after may depend on the value (``o1 if [#5399 LT 0]``);
* ``M0``/``M1``/``M60`` resumed by the operator's cycle start (``cycle_start``).

The host (:class:`~cosim.controllers.pokeys.host.HostApp`) streams a piece, waits as the wait
says and then asks :meth:`GcodeJob.next_piece` for the next one with the value it read; the
interpreter goes on from the line after the M66, the new canonical calls become tool path steps
(:mod:`.gcode.program`) and the steps up to the next wait are planned from where the last piece
ended, in the path control mode in force there (:mod:`.pathplan`).

::

    text ──Interpreter (live)──> calls ──follower──> steps ─┬─ up to a Wait ──plan_toolpath──> Piece 1
                                                            ├─ up to the next Wait ─────────> Piece 2
                                 resume(#5399) ──> more calls ... (after an M66 is read)
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

from cosim.controllers.pokeys.gcode.flow import ProgramError, SourceFile
from cosim.controllers.pokeys.gcode.interpreter import Interpreter
from cosim.controllers.pokeys.gcode.program import HostSetup, follower
from cosim.controllers.pokeys.pathplan import HostAxis, PathSettings, plan_toolpath
from cosim.controllers.pokeys.toolpath import Message, Output, PathControl, Point, Spindle, Step, Toolpath, Wait
from cosim.controllers.pokeys.trajectory import Counts
from cosim.errors import ConfigurationError


@dataclass
class Piece:
    """The slots of one piece of a job, its outputs (index in the piece) and the wait that ends it (None: the
    program's end)."""

    counts: list[Counts]
    outputs: list[tuple[int, Spindle | Output | Message]] = field(default_factory=list)
    wait: Wait | None = None


class GcodeJob:
    """A program on a machine, planned piece by piece (see the module text).

    Parameters
    ----------
    interpreter : Interpreter
        Set up for the machine (live, with ``inputs``, when the program may wait on inputs).
    source : SourceFile
        The program.
    setup : HostSetup
        What the host does between moves.
    axes : sequence of HostAxis
        One per axis of ``setup.axes``.
    settings : PathSettings
    n_axes, max_pulses_per_slot : int
        The engine's axes and pulses per slot.

    Attributes
    ----------
    counts : list of tuple
        Every slot planned so far.
    notes : list of str
        Feeds the planner slowed (one per line), over all pieces so far.
    end_steps : tuple of int
        Where the last piece planned ends [steps].
    """

    def __init__(self, interpreter: Interpreter, source: SourceFile, setup: HostSetup, axes: Sequence[HostAxis], *,
                 settings: PathSettings, n_axes: int, max_pulses_per_slot: int) -> None:
        self.interpreter = interpreter
        self.setup = setup
        self.axes = list(axes)
        self.settings = settings
        self.n_axes = n_axes
        self.max_pulses_per_slot = max_pulses_per_slot
        try:
            self.program = interpreter.run(source)
        except ProgramError as exc:
            raise ConfigurationError(str(exc)) from None
        self.follower = follower(self.program, setup)
        self.queue: deque[Step] = deque(self.follower.advance())
        self.position: Point = (Fraction(0),) * len(setup.axes)
        self.path_control: PathControl | None = None
        self.value: float | None = None
        self.counts: list[Counts] = []
        self.notes: list[str] = []
        self.end_steps: tuple[int, ...] = ()
        self.pieces = 0

    @property
    def not_modelled(self) -> list[str]:
        """What the program sets that is accepted and not modelled (the follower's notes), so far."""
        return self.follower.notes

    @property
    def skipped(self) -> list[str]:
        """Words skipped under ``allow_unsupported``, so far."""
        return self.program.skipped

    @property
    def ending(self) -> str:
        """How the program ended (``M2``, ``M30``, ``%``; ``""``: not, or not yet)."""
        return self.program.end

    def next_piece(self, value: float | None = None) -> Piece:
        """The next piece: the first, or the one after the wait that ended the last (``value``: what an M66 read:
        the input, or -1 after its timeout). Raises ``ConfigurationError`` for a program error in it."""
        if value is not None:
            self.value = value
        steps: list[Step] = []
        while True:
            while self.queue:
                step = self.queue.popleft()
                if isinstance(step, Wait):
                    return self._plan(steps, step)
                steps.append(step)
            if not self.interpreter.suspended:
                return self._plan(steps, None)
            if self.value is None:  # pragma: no cover - a live M66 always makes a reading Wait first
                raise ConfigurationError(f"{self.interpreter.where}: M66 resumed without the value it read")
            try:
                self.interpreter.resume(self.value)
            except ProgramError as exc:
                raise ConfigurationError(str(exc)) from None
            self.value = None
            self.queue.extend(self.follower.advance())

    def _plan(self, steps: list[Step], wait: Wait | None) -> Piece:
        prefix = [self.path_control] if self.path_control is not None else []
        path = Toolpath((*prefix, *steps), source=self.program.source, start=self.position, axes=self.setup.axes)
        planned = plan_toolpath(path, self.axes, settings=self.settings, n_axes=self.n_axes,
                                max_pulses_per_slot=self.max_pulses_per_slot)
        self.position = path.end
        for step in steps:
            if isinstance(step, PathControl):
                self.path_control = step
        self.end_steps = planned.end_steps
        self.notes.extend(n for n in planned.notes if n not in self.notes)
        self.counts.extend(planned.counts)
        self.pieces += 1
        return Piece(planned.counts, list(planned.outputs), wait)
