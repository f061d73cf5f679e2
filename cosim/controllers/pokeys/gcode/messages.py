"""Active comments and predefined parameters.

The last comment of a line is the active one (LinuxCNC's rule):

* ``(MSG, text)``: ``MESSAGE(text)``, the run's console shows it;
* ``(DEBUG, text)``: the same with parameters expanded (``#1``, ``#<name>``; ``%d``, ``%f``,
  ``%.3f`` set the format; the default shows 6 decimals), unless ``#5599`` is 0;
* ``(PRINT, text)``: expanded like DEBUG; LinuxCNC writes it to its standard error, cosim to the
  console;
* ``(LOG, ...)``, ``(LOGOPEN, ...)``, ``(LOGAPPEND, ...)``, ``(LOGCLOSE)``, ``(PROBEOPEN ...)``,
  ``(PROBECLOSE)``: accepted, listed as not modelled (no files are written);
* any other comment: ``COMMENT(text)``.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cosim.controllers.pokeys.gcode.params import EvalError, Number
from cosim.controllers.pokeys.gcode.state import MM_PER_INCH

if TYPE_CHECKING:
    from cosim.controllers.pokeys.gcode.interpreter import Interpreter

_ACTIVE = re.compile(r"^\s*(msg|debug|print|logopen|logappend|logclose|log|probeopen|probeclose)\s*,?", re.IGNORECASE)
_PARAM = re.compile(r"#(<[^>]*>|\d+)")
_FORMAT = re.compile(r"%(d|f|\.\d\s*f|lf)")


def comment(interp: Interpreter, text: str) -> None:
    """Act on a line's last comment."""
    match = _ACTIVE.match(text)
    if match is None:
        interp.emit("COMMENT", text)
        return
    kind = match.group(1).lower()
    rest = text[match.end():]
    if kind == "msg":
        interp.emit("MESSAGE", rest)
    elif kind == "debug":
        if interp.params.numbered[5599] != 0:
            interp.emit("MESSAGE", expand(interp, rest))
    elif kind == "print":
        interp.emit("PRINT", expand(interp, rest))
    else:
        interp.note(f"({kind.upper()}, ...) comments are accepted and not modelled (no log or probe files are "
                    "written)")
        interp.emit("COMMENT", text)


def expand(interp: Interpreter, text: str) -> str:
    """``text`` with each ``#n`` / ``#<name>`` replaced by its value in the current format."""
    out: list[str] = []
    fmt = "%lf"
    i = 0
    while i < len(text):
        f = _FORMAT.match(text, i)
        if f is not None and _PARAM.match(text, f.end()) is None:
            # a format not followed directly by a parameter still sets the format
            fmt = "%" + f.group(1).replace(" ", "")
            i = f.end()
            continue
        if f is not None:
            fmt = "%" + f.group(1).replace(" ", "")
            i = f.end()
        p = _PARAM.match(text, i)
        if p is None:
            out.append(text[i])
            i += 1
            continue
        token = p.group(1)
        name = token[1:-1].replace(" ", "").replace("\t", "").lower() if token.startswith("<") else int(token)
        try:
            value = interp.params.read(name)
        except EvalError:
            out.append("######")
        else:
            out.append(_format(fmt, value))
        i = p.end()
    return "".join(out)


def _format(fmt: str, value: Number) -> str:
    v = float(value)
    if fmt == "%d":
        return f"{v:.0f}"
    if fmt == "%f":
        return f"{v:.4f}"
    if fmt.startswith("%.") and fmt.endswith("f"):
        return f"{v:.{int(fmt[2:-1])}f}"
    return f"{v:.6f}"


_MOTION_CODE = {0: 0, 10: 10, 20: 20, 30: 30}


def predefined(interp: Interpreter, name: str) -> Number | None:
    """The value of a predefined named parameter (``_x``, ``_metric``, ...), or None."""
    s = interp.state
    flag = {
        "_metric": s.units == "mm", "_imperial": s.units == "inch", "_absolute": not s.incremental,
        "_incremental": s.incremental, "_inverse_time": s.feed_mode == 930, "_units_per_minute": s.feed_mode == 940,
        "_units_per_rev": s.feed_mode == 950, "_tool_offset": s.tool_length != 490,
        "_retract_r_plane": s.retract == 990, "_retract_old_z": s.retract == 980,
        "_spindle_rpm_mode": not s.css, "_spindle_css_mode": s.css, "_ijk_absolute_mode": s.ijk_absolute,
        "_lathe_diameter_mode": s.lathe == 70, "_lathe_radius_mode": s.lathe == 80,
        "_spindle_on": s.spindle != 0, "_spindle_cw": s.spindle == 1, "_mist": s.mist, "_flood": s.flood,
        "_speed_override": s.speed_override, "_feed_override": s.feed_override, "_adaptive_feed": s.adaptive,
        "_feed_hold": s.feed_hold,
    }
    if name in flag:
        return 1 if flag[name] else 0
    axes = "xyzabcuvw"
    if len(name) == 2 and name[1] in axes:
        return s.position[axes.index(name[1])]
    if name.startswith("_abs_") and len(name) == 6 and name[5] in axes:
        i = axes.index(name[5])
        return s.position[i] + s.origin[i] + s.axis_offset[i] + s.tlo[i]
    values: dict[str, Number] = {
        "_vmajor": 2.9, "_vminor": 0.0, "_line": interp.line, "_motion_mode": s.motion, "_plane": s.plane,
        "_ccomp": s.cutter, "_coord_system": {1: 540, 2: 550, 3: 560, 4: 570, 5: 580, 6: 590, 7: 591, 8: 592,
                                              9: 593}[s.coord],
        "_feed": s.feed, "_rpm": s.speed, "_current_tool": s.tool, "_current_pocket": _pocket(interp, s.tool),
        "_selected_tool": s.selected, "_selected_pocket": _pocket(interp, s.selected) if s.selected >= 0 else -1,
        "_value": interp.value, "_value_returned": interp.value_returned, "_task": 1,
        "_call_level": len(interp.frames) - 1, "_remap_level": 0,
    }
    return values.get(name)


def _pocket(interp: Interpreter, tool: int) -> int:
    if tool <= 0:
        return 0
    entry = interp.tools.get(tool)
    return entry.pocket or entry.number if entry else 0


def inch_factor(units: str) -> Number:
    """Program units per inch."""
    return MM_PER_INCH if units == "mm" else 1
