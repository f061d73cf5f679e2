"""LinuxCNC's own interpreter as the oracle of cosim's G-code reader: run both, compare the canonical calls.

``rs274`` (Debian's ``linuxcnc-uspace``) prints the canonical machining calls of a program, one a
line, numbers with 4 decimals (``STRAIGHT_FEED(1.0000, ...)``). To read them at full precision
rs274 runs under a shim of our own (:data:`SHIM_C`, compiled with the system's C compiler into
a temporary folder, loaded with ``LD_PRELOAD``): it wraps the C library's ``__fprintf_chk``,
``__vfprintf_chk`` and ``__printf_chk`` (the fortified ``fprintf``/``printf`` rs274's canonical
printer calls, ``nm -D /usr/bin/rs274``) and rewrites each ``%.4f`` and ``%f`` of the format to
``%.17g``, which prints every double so that it reads back bit for bit. LinuxCNC itself is
neither modified nor copied. The same program through cosim's
:class:`~cosim.controllers.pokeys.gcode.interpreter.Interpreter`, set up as rs274 runs without a
configuration (inch machine units: the tool table and stored offsets are in inches; the program
starts in mm), gives calls of the same names; :func:`compare` lines the two up call by call.

Used by ``tests/test_gcode_linuxcnc.py``; nothing in ``cosim`` imports it.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from cosim.controllers.pokeys.gcode.canon import CanonProgram
from cosim.controllers.pokeys.gcode.flow import ProgramError, read_source
from cosim.controllers.pokeys.gcode.interpreter import Interpreter
from cosim.controllers.pokeys.gcode.state import Tool

SAMPLES = Path("/usr/share/linuxcnc/ncfiles")
#: The canonical calls compared: motion, feeds, dwells, planes, tools, spindle, coolant, stops, modes, offsets.
COMPARED = frozenset({
    "STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED", "SET_FEED_RATE", "DWELL", "SELECT_PLANE", "SELECT_TOOL",
    "CHANGE_TOOL", "CHANGE_TOOL_NUMBER", "SET_SPINDLE_SPEED", "START_SPINDLE_CLOCKWISE",
    "START_SPINDLE_COUNTERCLOCKWISE", "STOP_SPINDLE_TURNING", "FLOOD_ON", "FLOOD_OFF", "MIST_ON", "MIST_OFF",
    "USE_LENGTH_UNITS", "PROGRAM_STOP", "OPTIONAL_PROGRAM_STOP", "PROGRAM_END", "PALLET_SHUTTLE",
    "SET_MOTION_CONTROL_MODE", "SET_G5X_OFFSET", "SET_G92_OFFSET", "USE_TOOL_LENGTH_OFFSET", "MESSAGE",
    "SET_MOTION_OUTPUT_BIT", "CLEAR_MOTION_OUTPUT_BIT", "SET_AUX_OUTPUT_BIT", "CLEAR_AUX_OUTPUT_BIT",
})
#: How many numbers rs274 prints of each call (it leaves out U, V, W).
PRINTED = {"STRAIGHT_TRAVERSE": 6, "STRAIGHT_FEED": 6, "ARC_FEED": 9, "SET_G5X_OFFSET": 7, "SET_G92_OFFSET": 6,
           "USE_TOOL_LENGTH_OFFSET": 9, "SET_MOTION_CONTROL_MODE": 2}
#: Issue 26's acceptance: numbers agree to 1e-9 mm (in an inch program: 1e-9 / 25.4 inch).
TOLERANCE_MM = 1e-9
#: The shim that makes rs274 print its numbers at full precision (see the module text).
SHIM_C = r"""
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* the format with each %.4f and %f as %.17g (the format itself if it does not fit) */
static const char *widen(const char *fmt, char *out, size_t size) {
    size_t o = 0;
    for (const char *p = fmt; *p;) {
        if (o + 8 >= size) return fmt;
        if (strncmp(p, "%.4f", 4) == 0) { memcpy(out + o, "%.17g", 5); o += 5; p += 4; }
        else if (strncmp(p, "%f", 2) == 0) { memcpy(out + o, "%.17g", 5); o += 5; p += 2; }
        else if (strncmp(p, "%%", 2) == 0) { out[o++] = '%'; out[o++] = '%'; p += 2; }
        else out[o++] = *p++;
    }
    out[o] = 0;
    return out;
}

int __vfprintf_chk(FILE *stream, int flag, const char *fmt, va_list ap) {
    char wide[4096];
    (void)flag;
    return vfprintf(stream, widen(fmt, wide, sizeof wide), ap);
}

int __fprintf_chk(FILE *stream, int flag, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int n = __vfprintf_chk(stream, flag, fmt, ap);
    va_end(ap);
    return n;
}

int __printf_chk(int flag, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    int n = __vfprintf_chk(stdout, flag, fmt, ap);
    va_end(ap);
    return n;
}
"""
#: The tool table both interpreters use [inch] (rs274 reads tool tables in inches).
TOOLS = [Tool(n, z_offset=Fraction(n, 10), diameter=Fraction(n, 40)) for n in range(1, 100)]
_LINE = re.compile(r"^\s*\d+ N\S* +([A-Z_0-9]+)\((.*)\)\s*$")
_TOKEN = re.compile(r'"[^"]*"|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|-?(?:inf|nan)|[A-Z_]+')


def rs274() -> str | None:
    """The path of LinuxCNC's standalone interpreter, or None."""
    return shutil.which("rs274")


def compiler() -> str | None:
    """The C compiler the shim is built with, or None."""
    return shutil.which("gcc") or shutil.which("cc")


def build_shim(folder: Path) -> Path:
    """Compile :data:`SHIM_C` into ``folder``; the shared library's path."""
    source = folder / "rs274_full_precision.c"
    library = folder / "rs274_full_precision.so"
    source.write_text(SHIM_C)
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler (gcc or cc) to build the rs274 full-precision shim")
    subprocess.run([cc, "-shared", "-fPIC", "-O2", "-o", str(library), str(source)], check=True,
                   capture_output=True, text=True)
    return library


@dataclass
class Outcome:
    """A program run by one interpreter: its compared calls, or the error that stopped it."""

    calls: list[tuple[str, tuple[object, ...]]]
    error: str | None


def _tokens(text: str) -> tuple[object, ...]:
    out: list[object] = []
    for t in _TOKEN.findall(text):
        if t.startswith('"'):
            out.append(t[1:-1])
        elif t[0].isdigit() or t[0] in "+-":
            out.append(float(t))
        else:
            out.append(t.removeprefix("CANON_PLANE_").removeprefix("CANON_UNITS_").removeprefix("CANON_"))
    return tuple(out)


def setup(folder: Path) -> tuple[Path, Path]:
    """Write the tool table and the INI file rs274 runs with (in ``folder``); their paths."""
    table = folder / "tools.tbl"
    table.write_text("".join(f"T{t.number} P{t.number} D{float(t.diameter):.6f} Z+{float(t.z_offset):.6f}\n"
                             for t in TOOLS))
    ini = folder / "rs274.ini"
    ini.write_text(f"[RS274NGC]\nSUBROUTINE_PATH = {SAMPLES}:{SAMPLES / 'ngcgui_lib'}:"
                   f"{SAMPLES / 'ngcgui_lib' / 'utilitysubs'}\nPARAMETER_FILE = {folder / 'rs274.var'}\n")
    (folder / "rs274.var").write_text("")
    return table, ini


def run_rs274(program: Path, table: Path, ini: Path, *, shim: Path | None = None, timeout_s: float = 60) -> Outcome:
    """``rs274 -g`` on ``program`` (from its own folder), its compared calls (full precision with ``shim``)."""
    env = dict(os.environ, LD_PRELOAD=str(shim)) if shim is not None else None
    done = subprocess.run(["rs274", "-i", str(ini), "-t", str(table), "-g", str(program)], cwd=program.parent,
                          stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout_s, env=env)
    calls = []
    error = None
    for line in done.stdout.splitlines():
        match = _LINE.match(line)
        if match is None:
            if line.strip() and line.strip() != "executing" and error is None:
                error = line.strip()
            continue
        name = match.group(1)
        if name in COMPARED:
            args = _tokens(match.group(2)) if name != "MESSAGE" else (match.group(2)[1:-1],)
            calls.append((name, args))
    if done.returncode == 0:
        error = None
    elif error is None:
        error = (done.stderr.strip().splitlines() or ["rs274 failed"])[-1]
    return Outcome(_drop_setup(calls), error)


def _drop_setup(calls: list[tuple[str, tuple[object, ...]]]) -> list[tuple[str, tuple[object, ...]]]:
    """rs274's own start-up calls (units, offsets) before the program's first line."""
    return calls[3:] if [c[0] for c in calls[:3]] == ["USE_LENGTH_UNITS", "SET_G5X_OFFSET", "SET_G92_OFFSET"] \
        else calls


def run_cosim(program: Path) -> tuple[Outcome, CanonProgram | None]:
    """cosim's interpreter on ``program`` set up as rs274 runs; its compared calls."""
    interp = Interpreter(machine_units="inch", units="mm", tools=[Tool(t.number, t.z_offset, t.x_offset, t.diameter)
                                                                   for t in TOOLS],
                         search_path=[SAMPLES, SAMPLES / "ngcgui_lib", SAMPLES / "ngcgui_lib" / "utilitysubs"],
                         axes="xyzabc", probe=True, max_lines=2_000_000)
    try:
        result = interp.run(read_source(program))
    except ProgramError as exc:
        return Outcome(_ours(interp.program), str(exc)), interp.program
    error = None if result.end else "File ended with no percent sign or program end"
    return Outcome(_ours(result), error), result


def _ours(program: CanonProgram) -> list[tuple[str, tuple[object, ...]]]:
    out = []
    for call in program.calls:
        if call.name not in COMPARED:
            continue
        args: tuple[object, ...]
        if call.name == "MESSAGE":
            args = (str(call.args[0]),)
        elif call.name == "SET_MOTION_CONTROL_MODE":
            args = call.args if call.args[0] == "CONTINUOUS" else call.args[:1]
            args = tuple(float(a) if not isinstance(a, str) else a for a in args)
        else:
            args = tuple(a if isinstance(a, str) else float(a) for a in call.args)  # type: ignore[arg-type]
        if call.name in PRINTED and call.name != "SET_MOTION_CONTROL_MODE":
            args = args[:PRINTED[call.name]]
        if call.name in ("USE_LENGTH_UNITS",):
            args = tuple(str(a) for a in args)
        out.append((call.name, args))
    return out


def compare(theirs: Outcome, ours: Outcome, *, tolerance_mm: float = TOLERANCE_MM) -> str | None:
    """None if the two agree call by call (numbers within ``tolerance_mm`` in mm programs, ``tolerance_mm / 25.4``
    in inch programs), else the first difference."""
    tolerance = tolerance_mm
    for k, (a, b) in enumerate(zip(theirs.calls, ours.calls, strict=False)):
        if a[0] != b[0] or len(a[1]) != len(b[1]) or \
                not all(_same(x, y, tolerance) for x, y in zip(a[1], b[1], strict=True)):
            return f"call {k}: LinuxCNC {_show(a)}, cosim {_show(b)}"
        if a[0] == "USE_LENGTH_UNITS":
            tolerance = tolerance_mm / 25.4 if a[1] == ("INCHES",) else tolerance_mm
    if len(theirs.calls) != len(ours.calls):
        k = min(len(theirs.calls), len(ours.calls))
        extra = theirs.calls[k] if len(theirs.calls) > k else ours.calls[k]
        return (f"LinuxCNC made {len(theirs.calls)} calls, cosim {len(ours.calls)}; the first extra: "
                f"{_show(extra)} ({'LinuxCNC' if len(theirs.calls) > k else 'cosim'})")
    if (theirs.error is None) != (ours.error is None):
        return f"LinuxCNC: {theirs.error or 'no error'}; cosim: {ours.error or 'no error'}"
    return None


def agree(theirs: Outcome, ours: Outcome, *, tolerance_mm: float = TOLERANCE_MM) -> str | None:
    """None if both refuse the program, or both run it with the same calls; else the first difference."""
    if theirs.error is not None and ours.error is not None:
        return None
    return compare(theirs, ours, tolerance_mm=tolerance_mm)


def largest_difference(theirs: Outcome, ours: Outcome) -> float:
    """The largest difference of any two numbers the two interpreters give, call by call [program units]."""
    largest = 0.0
    for a, b in zip(theirs.calls, ours.calls, strict=False):
        if a[0] == b[0] and len(a[1]) == len(b[1]):
            for x, y in zip(a[1], b[1], strict=True):
                if isinstance(x, float) and isinstance(y, float):
                    largest = max(largest, abs(x - y))
    return largest


def _same(x: object, y: object, tolerance: float) -> bool:
    if isinstance(x, float) and isinstance(y, float):
        return abs(x - y) <= tolerance
    return x == y


def _show(call: tuple[str, tuple[object, ...]]) -> str:
    return f"{call[0]}({', '.join(repr(a) if isinstance(a, float) else str(a) for a in call[1])})"
