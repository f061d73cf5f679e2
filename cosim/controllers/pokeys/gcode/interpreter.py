"""Running a G-code program into canonical calls, as LinuxCNC 2.9's interpreter does.

:class:`Interpreter` runs the lines of a :class:`~.flow.SourceFile` with O-word control flow and
subroutines (:mod:`.ocode`), evaluates each line's words (parameter settings take effect after the words are
read, before the line runs), and executes them in RS274/NGC's order of execution (the
:data:`ORDER` below), producing a :class:`~.canon.CanonProgram`. Motion is in :mod:`.motion`,
canned cycles in :mod:`.cycles`, comments and messages in :mod:`.messages`.

Refused before anything runs, with ``file:line:column`` and the construct by name: everything
LinuxCNC refuses (with its reason), and what this machine cannot simulate: spindle-synchronised
motion (``G33``, ``G33.1``, ``G76``), probing without a probe input (``G38.n``) and user M codes
``M100``-``M199``. With ``allow_unsupported`` those words are skipped (their motion too) and listed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

from cosim.controllers.pokeys.gcode import compensation, execute, messages, ocode
from cosim.controllers.pokeys.gcode.canon import Canon, CanonProgram
from cosim.controllers.pokeys.gcode.flow import Library, ProgramError, SourceFile, Stop
from cosim.controllers.pokeys.gcode.params import EvalError, Number, Parameters
from cosim.controllers.pokeys.gcode.state import MM_PER_INCH, ZERO9, State, Tool
from cosim.controllers.pokeys.gcode.syntax import SourceLine
from cosim.controllers.pokeys.gcode.words import WordError, Words, check_uses, code_name, evaluate_line

ORDER = ("comment", "feed mode G93-G95", "F", "S", "T", "M62-M68", "M6 M61", "M3 M4 M5 M19", "M70-M73",
         "M7 M8 M9", "M48-M53", "M100-M199", "G4", "G17-G19", "G20 G21", "G40-G42", "G43 G49", "G54-G59.3",
         "G61 G64", "G90 G91", "G98 G99", "G10 G28 G30 G52 G92", "motion", "M0 M1 M2 M30 M60")
UNSUPPORTED_MOTION = {330: "G33 (spindle-synchronised motion) needs a spindle encoder: cosim models no spindle "
                           "feedback",
                      331: "G33.1 (rigid tapping) needs a spindle encoder: cosim models no spindle feedback",
                      760: "G76 (threading) is spindle-synchronised: cosim models no spindle feedback"}
PROBES = (382, 383, 384, 385)


class Interpreter:
    """A LinuxCNC-like interpreter with its settings.

    Parameters
    ----------
    machine_units : {'mm', 'inch'}
        The units of stored parameters (offsets, G28/G30 positions) and of the tool table.
    units : {'mm', 'inch'}, optional
        Program units at the start (default: the machine's).
    tools : sequence of Tool
        The tool table.
    search_path : sequence of path
        Folders of subroutine files (``<name>.ngc``).
    allow_unsupported : bool
        Skip (and list) the words this machine cannot simulate instead of refusing the program.
    probe : bool
        The machine has a probe input (G38.n runs as a feed move that does not touch).
    axes : str
        The axis letters the machine has (lower case); a word for another axis is refused.
    inputs : mapping of str to int, optional
        The machine's inputs for M66, ``{"digital": n, "analog": m}`` (numbers 0..n-1, 0..m-1). With
        them the interpreter runs *live*: :meth:`run` returns after each M66 line
        (:attr:`suspended`, as LinuxCNC's interpreter waits for the input's value) and
        :meth:`resume` goes on with ``#5399`` set. Without them (default) an M66 reads 0 at once,
        as rs274 without a machine does.
    no_axis : mapping of str to str
        Why the machine has not got an axis, by its letter (``"A"``), for the refusal of its word
        (default: "the machine has no A axis").
    block_delete : bool
        Lines starting with ``/`` are skipped.
    max_lines : int
        Lines run at most (an endless loop is refused).
    """

    def __init__(self, *, machine_units: str = "mm", units: str | None = None, tools: Sequence[Tool] = (),
                 search_path: Sequence[str | Path] = (), allow_unsupported: bool = False, probe: bool = False,
                 axes: str = "xyzabc", block_delete: bool = False, max_lines: int = 5_000_000,
                 max_calls: int = 5_000_000, no_axis: Mapping[str, str] | None = None,
                 inputs: Mapping[str, int] | None = None) -> None:
        self.machine_units = machine_units
        self.tools = {t.number: t for t in tools}
        self.library = Library(search_path)
        self.allow_unsupported = allow_unsupported
        self.probe = probe
        self.axes = axes.upper()
        self.no_axis = dict(no_axis or {})
        self.inputs = dict(inputs) if inputs is not None else None
        self.suspended = False
        self.executed = 0
        self.block_delete = block_delete
        self.max_lines = max_lines
        self.max_calls = max_calls
        self.state = State(units=units or machine_units)
        self.params = Parameters(self._predefined)
        self.params.numbered[5220] = 1
        self.params.numbered[5599] = 1
        self.program = CanonProgram("")
        self.where = ""
        self.line = 0
        self.value: Number = 0
        self.value_returned = 0
        self.saved_states: list[State] = []
        self.frames: list[ocode.Frame] = []
        self.comp_queue = compensation.Queue()
        self.canon_tlo: tuple[Number, ...] = ZERO9
        self.canon_machine: tuple[Number, ...] = ZERO9  # where the last canonical move ended (machine coordinates)

    # -- output ------------------------------------------------------------------------------------
    def emit(self, name: str, *args: object) -> None:
        """A canonical call now (held back with the compensated move if cutter compensation holds one)."""
        if self.comp_queue and name in compensation.QUEUED:
            compensation.enqueue(self, name, list(args))
            return
        self.emit_now(name, self.line, *args)

    def emit_now(self, name: str, line: int, *args: object) -> None:
        self.program.calls.append(Canon(name, args, self.frames[-1].file.path if self.frames else "", line))
        if name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE", "ARC_FEED"):
            s = self.state
            if name == "ARC_FEED":
                first, second, normal = {170: (0, 1, 2), 180: (2, 0, 1), 190: (1, 2, 0)}.get(s.plane, (0, 1, 2))
                point: list[Any] = [0] * 9
                point[first], point[second], point[normal] = args[0], args[1], args[5]
                point[3:] = args[6:]
            else:
                point = list(args[:9])
            self.canon_tlo = s.tlo
            self.canon_machine = tuple(p + o + a + t for p, o, a, t in zip(point, s.origin, s.axis_offset, s.tlo,
                                                                           strict=True))
        if len(self.program.calls) > self.max_calls:
            raise ProgramError(self.where, f"the program makes more than {self.max_calls} canonical calls "
                                           "(an endless loop?)")

    def note(self, text: str) -> None:
        if text not in self.program.notes:
            self.program.notes.append(text)

    def skip(self, what: str, column: int) -> None:
        self.program.skipped.append(f"{self.where}:{column}: {what}; word skipped")

    # -- units ---------------------------------------------------------------------------------------
    def machine_to_program(self, value: Number) -> Number:
        """A length in machine units (stored parameters, tool table) in program units."""
        if self.machine_units == self.state.units:
            return value
        return value * MM_PER_INCH if self.machine_units == "inch" else value / MM_PER_INCH

    def program_to_machine(self, value: Number) -> Number:
        if self.machine_units == self.state.units:
            return value
        return value / MM_PER_INCH if self.machine_units == "inch" else value * MM_PER_INCH

    # -- running -----------------------------------------------------------------------------------
    def run(self, main: SourceFile) -> CanonProgram:
        """Run ``main`` to its end (or, live, to the first M66); the canonical program (raises ``ProgramError``)."""
        self.program = CanonProgram(main.path)
        self.frames = [ocode.Frame(main, main.start)]
        self.executed = 0
        return self._run()

    def resume(self, value: Number) -> CanonProgram:
        """After a live M66: ``#5399 = value`` (the input read, or -1 for a timeout), run on to the end or the next
        M66; the canonical program so far, the new calls appended (raises ``ProgramError``)."""
        if not self.suspended:
            raise ProgramError(self.where, "resume() without an M66 waiting for its input")
        self.suspended = False
        self.params.numbered[5399] = value
        return self._run()

    def _run(self) -> CanonProgram:
        try:
            while True:
                frame = self.frames[-1]
                source = frame.file
                end = source.stop if source.stop is not None else len(source.lines)
                if frame.pc >= end:
                    compensation.dequeue(self)
                    if len(self.frames) > 1:
                        raise ProgramError(source.where(frame.pc - 1), f"the file ended inside subroutine "
                                           f"{ocode.label_text(frame.label)} (no endsub)")
                    if source.stop is not None:
                        self.where, self.line = source.where(source.stop), source.stop + 1
                        self.program.end, self.program.end_where = "%", self.where
                    return self.program
                line = source.lines[frame.pc]
                self.line = line.number
                self.where = source.where(frame.pc)
                frame.pc += 1
                self.executed += 1
                if self.executed > self.max_lines:
                    raise ProgramError(self.where, f"the program runs more than {self.max_lines} lines (an endless "
                                                   "loop?)")
                if line.block_delete and self.block_delete:
                    continue
                try:
                    if line.oword is not None:
                        ocode.oword(self, line, frame)
                    elif not line.empty or line.comments:
                        self._line(line)
                except (WordError, EvalError) as exc:
                    column = getattr(exc, "column", 0) or 0
                    raise ProgramError(f"{self.where}:{column}" if column else self.where, str(exc)) from None
                if self.suspended:
                    return self.program
        except Stop:
            self.suspended = False  # M2 on the M66's line: the program has ended, nothing waits for the value
            return self.program

    # -- O-words -----------------------------------------------------------------------------------
    def _line(self, line: SourceLine) -> None:
        state = self.state
        words = evaluate_line(line, self.params)
        values = []
        for setting in line.settings:
            try:
                index = setting.index if isinstance(setting.index, str) else self.params.evaluate(setting.index)
                values.append((index, self.params.evaluate(setting.expr)))
            except EvalError as exc:
                raise ProgramError(self.where, f"parameter setting: {exc}") from None
        for index, value in values:
            try:
                self.params.write(index, float(value) if isinstance(value, Fraction) else value)
            except EvalError as exc:
                raise ProgramError(self.where, str(exc)) from None
        self._refuse_unsupported(words)
        check_uses(words, state.motion)
        for letter in words.values:
            if letter in "XYZABCUVW" and letter not in self.axes:
                why = self.no_axis.get(letter, f"the machine has no {letter} axis (its axes: {', '.join(self.axes)})")
                raise WordError(f"{letter} word: {why} (LinuxCNC: Bad character '{letter.lower()}' used)",
                                words.column(letter))
        if line.comments:
            messages.comment(self, line.comments[-1])
        if not words.g and not words.m and not words.values:
            return
        self._execute(words)

    def _refuse_unsupported(self, words: Words) -> None:
        motion_code = words.g.get(1)
        reason = None
        if motion_code in UNSUPPORTED_MOTION:
            reason = UNSUPPORTED_MOTION[motion_code]
        elif motion_code in PROBES and not self.probe:
            reason = (f"{code_name('G', motion_code)} needs a probe input: add probe = true to [host] in the machine "
                      "file (the probe trips at the end of the move)")
        if reason is not None and motion_code is not None:
            column = words.g_columns[1]
            if not self.allow_unsupported:
                raise WordError(reason, column)
            self.skip(f"{code_name('G', motion_code)} and its axis words: {reason}", column)
            del words.g[1]
            for letter in ("X", "Y", "Z", "A", "B", "C", "U", "V", "W", "I", "J", "K", "P", "Q", "L", "R", "E", "H"):
                words.values.pop(letter, None)
        user = words.m.get(10)
        if user is not None:
            reason = (f"M{user} is a user M code (a program M{user} that LinuxCNC runs from its configuration): "
                      "cosim cannot run it")
            if not self.allow_unsupported:
                raise WordError(reason, words.m_columns[10])
            self.skip(f"M{user}: {reason}", words.m_columns[10])
            del words.m[10]
            words.values.pop("P", None)
            words.values.pop("Q", None)

    def _execute(self, words: Words) -> None:
        execute.block(self, words)
        if words.m.get(6) == 6:
            # after a tool change LinuxCNC's interpreter re-reads its position from the end of the last move,
            # in the offsets in force now but with the tool offset of that move (a G43 on the M6 line does
            # not shift it; rs274 prints it so)
            s = self.state
            s.position = tuple(m - o - a - t for m, o, a, t in zip(self.canon_machine, s.origin, s.axis_offset,
                                                                   self.canon_tlo, strict=True))

    # -- predefined parameters ---------------------------------------------------------------------
    def _predefined(self, name: str) -> Number | None:
        return messages.predefined(self, name)


__all__ = ["ORDER", "ZERO9", "Interpreter", "ProgramError", "Stop", "Tool"]
