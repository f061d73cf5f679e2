"""The interpreter's modal state, in program units, as LinuxCNC keeps it.

Positions are program coordinates: the active coordinate system (G54..G59.3), the G92/G52 offset
and the XY rotation applied, the tool length offset not (LinuxCNC's ``current_x`` ...). Offsets
and the tool offset are kept in program units and converted when G20/G21 changes the units.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from fractions import Fraction

from cosim.controllers.pokeys.gcode.params import Number

MM_PER_INCH = Fraction(254, 10)
ZERO9: tuple[Number, ...] = (0,) * 9


@dataclass(frozen=True)
class Tool:
    """One tool of the machine's tool table (machine units).

    Parameters
    ----------
    number : int
        T number (> 0).
    z_offset, x_offset : number
        Tool length offset (and the X offset of lathe tools) [machine units].
    diameter : number
        Cutter diameter [machine units] (cutter radius compensation uses half of it).
    pocket : int
        Pocket (default: the tool number).
    """

    number: int
    z_offset: Number = 0
    x_offset: Number = 0
    diameter: Number = 0
    pocket: int = 0


@dataclass
class State:
    """What LinuxCNC's interpreter remembers between lines."""

    units: str = "mm"
    plane: int = 170
    incremental: bool = False
    ijk_absolute: bool = False
    feed_mode: int = 940
    feed: Number = 0
    speed: Number = 0
    spindle: int = 0  # 1 clockwise, -1 counter-clockwise, 0 stopped
    css: bool = False
    flood: bool = False
    mist: bool = False
    motion: int = 800
    cutter: int = 400
    cutter_radius: Number = 0
    tool_length: int = 490
    tlo: tuple[Number, ...] = ZERO9
    coord: int = 1
    origin: tuple[Number, ...] = ZERO9
    rotation: Number = 0
    axis_offset: tuple[Number, ...] = ZERO9
    retract: int = 990  # LinuxCNC starts in G99 (retract to R)
    path: int = 640
    path_p: Number = 0
    path_q: Number = 0
    position: tuple[Number, ...] = ZERO9
    tool: int = 0
    selected: int = -1
    lathe: int = 80
    feed_override: bool = True
    speed_override: bool = True
    adaptive: bool = False
    feed_hold: bool = True
    cycle_r: Number | None = None
    cycle_values: dict[str, Number] = field(default_factory=dict)
    cycle_old_z: Number = 0
    motion_outputs: dict[int, int] = field(default_factory=dict)
    comp_first: bool = False  # the next move is the entry move of cutter radius compensation
    comp_programmed: tuple[Number, ...] = ZERO9  # the programmed point under compensation (position: the tool's)

    def copy(self) -> State:
        return replace(self, cycle_values=dict(self.cycle_values), motion_outputs=dict(self.motion_outputs))
