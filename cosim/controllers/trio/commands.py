"""What each Trio BASIC command does when a program reaches it.

A handler takes the running program, its evaluated arguments and the ``AXIS(n)`` modifier (or
None) and returns an event the program waits for, or None. Modelled commands act through the
program's :class:`~cosim.controllers.trio.process.TrioProcess` (its BASE group) and the controller;
settings commands are listed in the run's notes ("set, not modelled", with their arguments);
motion commands without a model stop the program with an error naming them.
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from simpy.events import Event

from cosim.controllers.trio.runtime import BasicError
from cosim.controllers.trio.values import Datum, Value, integer_part, number, to_text

if TYPE_CHECKING:
    from cosim.controllers.trio.runtime import BasicRun

Handler = Callable[["BasicRun", list[Datum], "Value | None"], "Event | None"]


def _n(args: list[Datum], name: str) -> list[Value]:
    try:
        return [number(a, f"{name} argument {k + 1}") for k, a in enumerate(args)]
    except Exception as exc:
        raise BasicError(str(exc), 5) from None


def _text(value: Datum, name: str) -> str:
    if not isinstance(value, str):
        raise BasicError(f"{name} needs a program name in quotes, got {to_text(value)}", 5)
    return value


def _base(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.process.base(*_n(args, "BASE"))


def _table(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.process.table(*_n(args, "TABLE"))


def _pwm_control(run: BasicRun, args: list[Datum], axis: Value | None) -> Event | None:
    values = _n(args, "PWM_CONTROL")
    return run.process.pwm_control(values[0], *values[1:], axis=axis)


def _motion(method: str, name: str) -> Handler:
    def handler(run: BasicRun, args: list[Datum], axis: Value | None) -> Event | None:
        run.waiting_move = True
        event = getattr(run.process, method)(*_n(args, name), axis=axis)
        if event is not None and event.triggered:
            run.waiting_move = False
        elif event is not None:
            event.callbacks.append(lambda _e: setattr(run, "waiting_move", False))
        return event
    return handler


def _defpos(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.process.defpos(*_n(args, "DEFPOS"), axis=axis)


def _cancel(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    which = _n(args, "CANCEL")
    run.process.cancel(axis=axis, buffered=bool(which and which[0] == 1))


def _rapidstop(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.controller.rapidstop()


def _datum(run: BasicRun, args: list[Datum], axis: Value | None) -> Event | None:
    (sequence,) = _n(args, "DATUM")
    return run.process.datum(sequence, axis=axis)


def _regist(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.process.regist(*_n(args, "REGIST"), axis=axis)


def _trigger(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.controller.trigger(origin=run.where)


def _wa(run: BasicRun, args: list[Datum], axis: Value | None) -> Event:
    (ms,) = _n(args, "WA")
    return run.process.wa(ms, priority=run.priority)


def _op(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    values = _n(args, "OP")
    if len(values) == 1:
        run.controller.io.write_pattern(values[0])
    else:
        run.process.op(values[0], values[1])


def _run(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    name = _text(args[0], "RUN")
    process = _n(args[1:], "RUN")
    run.program_control.run_program(run, name, process[0] if process else None)


def _stop(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    if not args:
        run.program_control.stop_self(run)
        return
    name = _text(args[0], "STOP")
    process = _n(args[1:], "STOP")
    run.program_control.stop_program(run, name, process[0] if process else None)


def _halt(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.program_control.halt(run)


def _process(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    for number_, other in sorted(run.controller.processes.items()):
        run.print_text(f"Process {number_}: {other.name} running", end=True)


def _clear(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    run.controller.clear_vr()


def _bit(set_it: bool) -> Handler:
    def handler(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
        bit, vr = (integer_part(v) for v in _n(args, "SET_BIT" if set_it else "CLEAR_BIT"))
        if not 0 <= bit <= 23:
            raise BasicError(f"bit = {bit} is not allowed (allowed: 0..23)", 1)
        value = integer_part(number(run.controller.vr(vr), "VR"))
        run.controller.set_vr(vr, value | (1 << bit) if set_it else value & ~(1 << bit))
    return handler


def _flag(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    values = _n(args, "FLAG")
    if len(values) == 2:
        run.controller.set_flag(values[0], values[1])


def _flags(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    (value,) = _n(args, "FLAGS")
    run.controller.set_flags(value)


def _invert_in(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
    channel, state = _n(args, "INVERT_IN")
    run.controller.io.invert_input(channel, state)


#: Largest term of ENCODER_RATIO / STEP_RATIO (a 24-bit count).
RATIO_MAX = 16_777_215


def _ratio(name: str) -> Handler:
    """``ENCODER_RATIO(denominator, numerator)`` / ``STEP_RATIO(...)``: the ratio numerator / denominator is
    stored in the axis parameter of the same name (readable back) and listed as "set, not modelled"."""
    def handler(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
        denominator, numerator = (integer_part(v) for v in _n(args, name))
        for what, value, low in (("denominator", denominator, 1), ("numerator", numerator, 0)):
            if not low <= value <= RATIO_MAX:
                raise BasicError(f"{name} {what} = {value} is not allowed (allowed: {low}..{RATIO_MAX})", 1)
        run.process.set(name, Fraction(numerator, denominator), axis=axis)
    return handler


HANDLERS: dict[str, Handler] = {
    "BASE": _base, "TABLE": _table, "PWM_CONTROL": _pwm_control, "DEFPOS": _defpos,
    "MOVE": _motion("move", "MOVE"), "MOVEABS": _motion("moveabs", "MOVEABS"),
    "MOVECIRC": _motion("movecirc", "MOVECIRC"), "MOVEMODIFY": _motion("movemodify", "MOVEMODIFY"),
    "FORWARD": _motion("forward", "FORWARD"), "REVERSE": _motion("reverse", "REVERSE"),
    "CONNECT": _motion("connect", "CONNECT"), "CAMBOX": _motion("cambox", "CAMBOX"), "CAM": _motion("cam", "CAM"),
    "MOVELINK": _motion("movelink", "MOVELINK"),
    "CANCEL": _cancel, "RAPIDSTOP": _rapidstop, "DATUM": _datum, "REGIST": _regist, "TRIGGER": _trigger,
    "WA": _wa, "OP": _op, "RUN": _run, "STOP": _stop, "HALT": _halt, "PROCESS": _process, "CLEAR": _clear,
    "CLEAR_BIT": _bit(False), "SET_BIT": _bit(True), "FLAG": _flag, "FLAGS": _flags, "INVERT_IN": _invert_in,
    "ENCODER_RATIO": _ratio("ENCODER_RATIO"), "STEP_RATIO": _ratio("STEP_RATIO"),
}


def setting(name: str) -> Handler:
    """A command accepted and listed as "set, not modelled" with its arguments."""
    def handler(run: BasicRun, args: list[Datum], axis: Value | None) -> None:
        shown = ", ".join(a if isinstance(a, str) else to_text(a) for a in args)
        run.sim.notes.not_modelled(run.controller.device, name, f"({shown})" if args else "", where=run.where)
    return handler


def not_modelled(name: str) -> Handler:
    """A command that moves or switches outputs without a model: an error naming it when the program reaches it."""
    what = "an output timer" if name == "TIMER" else "a motion command"
    def handler(run: BasicRun, args: list[Datum], axis: Value | None) -> Any:
        raise BasicError(f"{name} is {what} of Trio BASIC this model does not simulate (see docs/trio.md for "
                         "the modelled ones)", 8)
    return handler
