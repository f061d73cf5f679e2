"""O-word control flow: subroutines and their calls, if/elseif/else, while, do-while, repeat, break, continue.

:func:`oword` runs one O-word line for :class:`~.interpreter.Interpreter`: it moves the frame's
line pointer to the partner line (:meth:`~.flow.SourceFile.partner`), or pushes and pops call
frames (arguments in ``#1``..``#30``, local named parameters, ``#<_value>`` on return). Errors name
the O-word: ``O-word `if` o1: no matching endif``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode import execute
from cosim.controllers.pokeys.gcode.flow import Label, ProgramError, SourceFile, literal_label
from cosim.controllers.pokeys.gcode.params import EvalError, Number, integer, show
from cosim.controllers.pokeys.gcode.syntax import SourceLine

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

MAX_CALL_DEPTH = 70


@dataclass
class Frame:
    """A running file (the main program or a subroutine's): where it is, and what its call saved."""

    file: SourceFile
    pc: int
    saved: list[Number] | None = None
    label: Label | None = None
    repeats: dict[int, int] = field(default_factory=dict)
    call_where: str = ""


def oword(interp: Interpreter, line: SourceLine, frame: Frame) -> None:
    o = line.oword
    assert o is not None
    if line.words or line.settings:
        raise ProgramError(f"{interp.where}:{line.words[0].column if line.words else o.column}",
                           f"O-word `{o.keyword}`: no other words are allowed on an O-word line")
    source = frame.file
    label = literal_label(o.label)
    if label is None:
        try:
            value = interp.params.evaluate(o.label)  # type: ignore[arg-type]
        except EvalError as exc:
            raise ProgramError(f"{interp.where}:{o.column}", f"O-word label: {exc}") from None
        n = integer(value)
        if n is None:
            raise ProgramError(f"{interp.where}:{o.column}", f"O-word label {show(value)} is not an integer")
        label = n
    kw = o.keyword
    here = frame.pc - 1
    name = f"O-word `{kw}`"

    def args() -> list[Number]:
        try:
            return [interp.params.evaluate(a) for a in o.args]
        except EvalError as exc:
            raise ProgramError(f"{interp.where}:{o.column}", f"{name}: {exc}") from None

    def need(index: int | None, what: str) -> int:
        if index is None:
            raise ProgramError(f"{interp.where}:{o.column}", f"{name} {label_text(label)}: no matching {what}")
        return index

    if kw == "sub":
        end = need(source.partner(label, here, ("endsub",)), "endsub")
        frame.pc = end + 1
    elif kw in ("endsub", "return"):
        values = args()
        if len(interp.frames) == 1:
            if kw == "endsub":
                raise ProgramError(f"{interp.where}:{o.column}", f"{name} {label_text(label)} outside a subroutine")
            raise ProgramError(f"{interp.where}:{o.column}", f"{name} outside a subroutine")
        interp.value = values[0] if values else 0
        interp.value_returned = 1 if values else 0
        done = interp.frames.pop()
        assert done.saved is not None
        interp.params.leave(done.saved)
        marker = done.repeats.get(-1)
        if marker is not None and len(interp.saved_states) >= marker:
            saved = interp.saved_states[marker - 1]
            del interp.saved_states[marker - 1:]
            execute.restore(interp, saved)
    elif kw == "call":
        call(interp, label, args(), o.column)
    elif kw == "if":
        _if(interp, label, here, args(), frame, o.column)
    elif kw in ("elseif", "else"):
        # reached by running the branch before it: skip to endif
        frame.pc = need(source.partner(label, here, ("endif",)), "endif") + 1
    elif kw == "endif":
        pass
    elif kw == "while":
        cond = truth(args(), name, interp.where, o.column)
        if source.is_do_while(label, here):
            if cond:
                frame.pc = need(source.partner(label, here, ("do",), backward=True), "do") + 1
        elif not cond:
            frame.pc = need(source.partner(label, here, ("endwhile",)), "endwhile") + 1
    elif kw == "endwhile":
        frame.pc = need(source.partner(label, here, ("while",), backward=True), "while")
    elif kw == "do":
        pass
    elif kw == "repeat":
        values = args()
        count = integer(values[0]) if values else None
        if count is None:
            raise ProgramError(f"{interp.where}:{o.column}", f"{name} needs a whole number of repeats [n]")
        end = need(source.partner(label, here, ("endrepeat",)), "endrepeat")
        if count <= 0:
            frame.pc = end + 1
        else:
            frame.repeats[end] = count
    elif kw == "endrepeat":
        left = frame.repeats.get(here, 1) - 1
        if left > 0:
            frame.repeats[here] = left
            frame.pc = need(source.partner(label, here, ("repeat",), backward=True), "repeat") + 1
        else:
            frame.repeats.pop(here, None)
    elif kw in ("break", "continue"):
        _loop_jump(interp, kw, label, here, frame, need)

def _if(interp: Interpreter, label: Label, here: int, values: list[Number], frame: Frame, column: int) -> None:
    source = frame.file
    index = here
    cond = truth(values, "O-word `if`", interp.where, column)
    while not cond:  # (a true condition needs no endif until the branch reaches an else: rs274 runs it so)
        nxt = source.partner(label, index, ("elseif", "else", "endif"))
        if nxt is None:
            raise ProgramError(f"{interp.where}:{column}", f"O-word `if` {label_text(label)}: no matching endif")
        kw = source.lines[nxt].oword.keyword  # type: ignore[union-attr]
        if kw != "elseif":
            frame.pc = nxt + 1
            return
        line = source.lines[nxt]
        assert line.oword is not None
        try:
            cond = truth([interp.params.evaluate(a) for a in line.oword.args], "O-word `elseif`",
                          source.where(nxt), line.oword.column)
        except EvalError as exc:
            raise ProgramError(source.where(nxt, line.oword.column), f"O-word `elseif`: {exc}") from None
        index = nxt
    frame.pc = index + 1

def _loop_jump(interp: Interpreter, kw: str, label: Label, here: int, frame: Frame, need: object) -> None:
    source = frame.file
    head = source.partner(label, here, ("while", "do", "repeat"), backward=True)
    if head is None:
        raise ProgramError(interp.where, f"O-word `{kw}` {label_text(label)} outside a loop")
    head_kw = source.lines[head].oword.keyword  # type: ignore[union-attr]
    if head_kw == "repeat":
        end = source.partner(label, here, ("endrepeat",))
    elif head_kw == "do":
        end = source.partner(label, here, ("while",))
    else:
        end = source.partner(label, here, ("endwhile",))
    if end is None:
        raise ProgramError(interp.where, f"O-word `{kw}` {label_text(label)}: the loop has no end")
    if kw == "break":
        frame.repeats.pop(end, None)
        frame.pc = end + 1
    elif head_kw == "while":
        frame.pc = head
    else:
        frame.pc = end  # do-while: its while; repeat: its endrepeat

def call(interp: Interpreter, label: Label, values: list[Number], column: int) -> None:
    if len(values) > 30:
        raise ProgramError(f"{interp.where}:{column}", "O-word `call`: at most 30 arguments")
    if len(interp.frames) >= MAX_CALL_DEPTH:
        raise ProgramError(f"{interp.where}:{column}", f"O-word `call` {label_text(label)}: subroutines nested "
                                                     f"more than {MAX_CALL_DEPTH} deep")
    current = interp.frames[-1].file
    main = interp.frames[0].file
    target: SourceFile | None = None
    index: int | None = None
    for source in (current, main):
        index = source.sub(label)
        if index is not None:
            target = source
            break
    if target is None and isinstance(label, str):
        target = interp.library.find(label, main.path)
        if target is not None:
            index = target.sub(label)
            if index is None:
                raise ProgramError(f"{interp.where}:{column}", f"O-word `call` <{label}>: {target.path} does "
                                                             f"not define o<{label}> sub")
    if target is None or index is None:
        where = (f"; no {label}.ngc on the subroutine search path (host.subroutine_path) or beside the program"
                 if isinstance(label, str) else "")
        raise ProgramError(f"{interp.where}:{column}", f"O-word `call` {label_text(label)}: the subroutine is "
                                                     f"not defined{where}")
    saved = interp.params.enter(values)
    interp.value_returned = 0
    interp.frames.append(Frame(target, index + 1, saved, label, call_where=interp.where))

# -- one line ----------------------------------------------------------------------------------


def truth(values: list[Number], name: str, where: str, column: int) -> bool:
    if not values:
        raise ProgramError(f"{where}:{column}" if column else where, f"{name} needs a condition [expression]")
    return values[0] != 0


def label_text(label: Label | None) -> str:
    if isinstance(label, str):
        return f"o<{label}>"
    return f"o{label}"
