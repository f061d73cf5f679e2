"""The canonical program: what the interpreter asks of the machine, call by call, as LinuxCNC's canon.

The interpreter (:mod:`.interpreter`) turns a program into a list of :class:`Canon` calls named
and shaped like LinuxCNC's canonical machining functions (what its ``rs274`` prints), so the two
can be compared line by line:

======================================  =========================================================
call                                    arguments
======================================  =========================================================
``STRAIGHT_TRAVERSE``, ``STRAIGHT_FEED`` x, y, z, a, b, c, u, v, w: the end point in program
                                        coordinates (the active coordinate system and G92/G52
                                        offset applied, the tool length offset not) and units
``ARC_FEED``                            first end, second end, first centre, second centre,
                                        rotation (+n counter-clockwise turns, -n clockwise), end
                                        on the plane's normal axis, a, b, c, u, v, w
``SELECT_PLANE``                        ``XY``, ``XZ``, ``YZ``
``SET_FEED_RATE``                       units per minute (G94), or the inverse time (G93)
``SET_FEED_MODE``                       0 per minute, 1 inverse time, 2 per revolution
``DWELL``                               seconds
``USE_LENGTH_UNITS``                    ``MM``, ``INCHES``
``SET_G5X_OFFSET``                      index (1 = G54 .. 9 = G59.3), x..w
``SET_G92_OFFSET``                      x..w
``SET_XY_ROTATION``                     degrees
``USE_TOOL_LENGTH_OFFSET``              x..w of the tool offset in program units
``SELECT_TOOL``, ``CHANGE_TOOL``,       tool number
``CHANGE_TOOL_NUMBER``
``SET_SPINDLE_SPEED``                   rev/min (or surface speed under G96)
``START_SPINDLE_CLOCKWISE``,            (none)
``START_SPINDLE_COUNTERCLOCKWISE``,
``STOP_SPINDLE_TURNING``
``ORIENT_SPINDLE``                      spindle, angle [degrees] (M19 R), mode (M19 P: 0 shortest, 1
                                        clockwise, 2 counter-clockwise; G87: the spindle's direction)
``WAIT_ORIENT_COMPLETE``                spindle, timeout [s] (M19 Q)
``FLOOD_ON`` ``FLOOD_OFF`` ``MIST_ON``  (none)
``MIST_OFF``
``SET_MOTION_CONTROL_MODE``             ``EXACT_STOP`` (G61.1), ``EXACT_PATH`` (G61), ``CONTINUOUS``
                                        (G64) and the P tolerance (0: none)
``SET_NAIVECAM_TOLERANCE``              the Q tolerance of G64
``PROGRAM_STOP``, ``OPTIONAL_PROGRAM_   (none)
STOP``, ``PALLET_SHUTTLE``,
``PROGRAM_END``
``SET_MOTION_OUTPUT_BIT``,              output number (M62/M63 with motion; M64/M65 at once)
``CLEAR_MOTION_OUTPUT_BIT``,
``SET_AUX_OUTPUT_BIT``,
``CLEAR_AUX_OUTPUT_BIT``
``SET_MOTION_OUTPUT_VALUE``,            output number, value (M67 with motion, M68 at once)
``SET_AUX_OUTPUT_VALUE``
``WAIT``                                input number, digital (1) or analog (0), wait type
                                        (0 immediate, 1 rise, 2 fall, 3 high, 4 low), timeout [s]
``ENABLE_FEED_OVERRIDE`` ...            the override switches of M48-M53
``MESSAGE``, ``COMMENT``                the text (``(MSG, ...)``, ``(DEBUG, ...)``; comments)
``PRINT``                               the text of ``(PRINT, ...)`` (LinuxCNC writes it to stderr)
======================================  =========================================================

Each call carries where it comes from (``file:line``) for messages.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

Number = Fraction | float | int
Position = tuple[Number, Number, Number, Number, Number, Number, Number, Number, Number]
AXES = "xyzabcuvw"
MOTION = frozenset({"STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED"})


@dataclass(frozen=True, slots=True)
class Canon:
    """One canonical call: its name, arguments, and the program line it comes from."""

    name: str
    args: tuple[object, ...]
    source: str
    line: int

    @property
    def where(self) -> str:
        return f"{self.source}:{self.line}"


@dataclass
class CanonProgram:
    """A program's canonical calls and how it ended.

    Attributes
    ----------
    calls : list of Canon
    end : str
        ``M2``, ``M30``, ``%`` or ``""`` when the file ended without any of them (LinuxCNC's
        error "File ended with no percent sign or program end").
    skipped : list of str
        Words skipped under ``allow_unsupported`` (``file:line:column: word ...``).
    notes : list of str
        What the interpreter accepted without modelling it.
    """

    source: str
    calls: list[Canon] = field(default_factory=list)
    end: str = ""
    skipped: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    end_where: str = ""

    def motion(self) -> list[Canon]:
        """The motion calls only."""
        return [c for c in self.calls if c.name in MOTION]
