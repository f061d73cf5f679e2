"""Delta Tau PMAC external time base, Turbo PMAC triggered time base, and the Turbo PMAC language.

A slave axis runs on the time of a master encoder: an encoder conversion table entry
differentiates the master position every servo cycle into a time-base value, Ix93 points a
coordinate system at it, Ix94 limits how fast it may change, and the Turbo triggered entry
freezes, arms and starts motion at a captured master position. See ``docs/pmac.md``.

Modules, lowest layer first (``docs/pmac.md``, "Modules"): numbers, time and moves -- :mod:`.units`,
:mod:`.arith`, :mod:`.profile`, :mod:`.pieces`, :mod:`.paths`, :mod:`.motion`, :mod:`.runner`; hardware --
:mod:`.encoder`, :mod:`.ect`, :mod:`.coord`, :mod:`.motor`, :mod:`.servo`, :mod:`.ivartable`; the language
front end, one way from text to running -- :mod:`.source`, :mod:`.preprocess` (text), :mod:`.grammar`,
:mod:`.syntax`, :mod:`.nodes` (syntax tree), :mod:`.program`, :mod:`.setupfile` (program), :mod:`.bus`,
:mod:`.mvars`, :mod:`.evaluate`, :mod:`.interpreter`, :mod:`.commands`, :mod:`.runtime` (runtime); and
:mod:`.machine` (the controller), :mod:`.ports`. Encoders and their 1/T extension are shared with the
plants in :mod:`cosim.encoders`; ready-made machines are in :mod:`cosim.rigs`.
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
