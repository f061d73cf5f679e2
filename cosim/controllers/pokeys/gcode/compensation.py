"""Cutter radius compensation G40, G41, G42, G41.1, G42.1.

The modes are read and checked as LinuxCNC checks them (a D tool in the table, no change while
on); moves under compensation are refused by name: the offset path LinuxCNC computes (its entry
move, corner arcs and the errors of its look-ahead) is not modelled yet. Post the program with
the CAM system's wear/computer compensation instead.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode.params import Number, integer
from cosim.controllers.pokeys.gcode.words import WordError, Words, code_name

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter


def switch(interp: Interpreter, w: Words, code: int) -> None:
    s = interp.state
    column = w.g_columns.get(7, 0)
    if code == 400:
        s.cutter, s.cutter_radius = 400, 0
        return
    if s.cutter != 400:
        raise WordError("Cannot turn cutter radius comp on when already on", column)
    if code in (410, 420):
        d = integer(w.get("D")) if w.has("D") else s.tool
        if d is None or d < 0:
            raise WordError("Negative D word tool radius index used", w.column("D") or column)
        if d and d not in interp.tools:
            raise WordError(f"Requested tool {d} not found in the tool table", w.column("D") or column)
        tool = interp.tools.get(d)
        radius: Number = interp.machine_to_program(tool.diameter) / 2 if tool else 0
    else:
        radius = (w.get("D") or 0) / 2
    s.cutter, s.cutter_radius = code, radius


def _refuse(interp: Interpreter) -> None:
    raise WordError(f"{code_name('G', interp.state.cutter)} (cutter radius compensation): moves under compensation "
                    "are not modelled; post the program with the CAM system's compensation (G40)")


def straight(interp: Interpreter, end: list[Number], code: int) -> None:
    if interp.state.cutter_radius == 0:
        interp.emit("STRAIGHT_TRAVERSE" if code == 0 else "STRAIGHT_FEED", *end)
        interp.state.position = tuple(end)
        return
    _refuse(interp)


def arc(interp: Interpreter, end: list[Number], center: tuple[Number, Number], rotation: int, first: int,
        second: int, normal: int) -> None:
    if interp.state.cutter_radius == 0:
        interp.emit("ARC_FEED", end[first], end[second], center[0], center[1], rotation, end[normal], *end[3:])
        interp.state.position = tuple(end)
        return
    _refuse(interp)
