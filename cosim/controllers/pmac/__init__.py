"""Delta Tau PMAC external time base and Turbo PMAC triggered time base.

A slave axis runs on the time of a master encoder: an encoder conversion table entry
differentiates the master position every servo cycle into a time-base value, Ix93 points a
coordinate system at it, Ix94 limits how fast it may change, and the Turbo triggered entry
freezes, arms and starts motion at a captured master position. See ``docs/pmac.md``.

Modules: :mod:`.units` (I10, servo clock, 2^-23 ms units), :mod:`.encoder` (1/T extension,
capture), :mod:`.ect` (conversion table), :mod:`.motion` and :mod:`.profile` (moves), :mod:`.coord`
(coordinate system, Ix93/Ix94, slip), :mod:`.servo` (PID design and loop), :mod:`.motor`,
:mod:`.ivars` (the I-variables), :mod:`.machine` (the controller). Programs as text:
:mod:`.grammar`, :mod:`.statements`, :mod:`.nodes`, :mod:`.program`, :mod:`.setupfile` (reading),
:mod:`.arith`, :mod:`.mvars`, :mod:`.interpreter`, :mod:`.runtime` (running). Encoders and their
1/T extension are shared with the plants in :mod:`cosim.encoders`; ready-made machines are in
:mod:`cosim.rigs`.
"""

from cosim.controllers.pmac.coord import CoordinateSystem, LimitEvent
from cosim.controllers.pmac.ect import (
    ARMED,
    FROZEN,
    PMAC_ECT_BASE,
    RUNNING,
    TURBO_ECT_BASE,
    ConversionTable,
    OneOverTEntry,
    TimeBaseEntry,
    TriggeredTimeBaseEntry,
    TriggerStart,
    pmac_default_table,
)
from cosim.controllers.pmac.encoder import EncoderChannel
from cosim.controllers.pmac.machine import Pmac
from cosim.controllers.pmac.motion import Delay, Dwell, LinearMove, Move, RapidAxis, RapidMove
from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.program import parse_text
from cosim.controllers.pmac.servo import MotorModel, PidDesign, PidLoop, design_pid
from cosim.controllers.pmac.setupfile import parse_setup
from cosim.controllers.pmac.units import (
    I10_DEFAULT,
    IX94_DEFAULT,
    IX94_MAX,
    ServoClock,
    formula_percent,
    percent,
    scale_factor_for,
)

__all__ = [
    "ARMED",
    "FROZEN",
    "I10_DEFAULT",
    "IX94_DEFAULT",
    "IX94_MAX",
    "PMAC_ECT_BASE",
    "RUNNING",
    "TURBO_ECT_BASE",
    "ConversionTable",
    "CoordinateSystem",
    "Delay",
    "Dwell",
    "EncoderChannel",
    "LimitEvent",
    "LinearMove",
    "Motor",
    "MotorModel",
    "Move",
    "OneOverTEntry",
    "PidDesign",
    "PidLoop",
    "Pmac",
    "RapidAxis",
    "RapidMove",
    "ServoClock",
    "TimeBaseEntry",
    "TriggerStart",
    "TriggeredTimeBaseEntry",
    "design_pid",
    "formula_percent",
    "parse_setup",
    "parse_text",
    "percent",
    "pmac_default_table",
    "scale_factor_for",
]
