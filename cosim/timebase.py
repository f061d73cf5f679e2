"""Exact integer simulation time.

Simulation time is an integer count of ticks of a declared resolution (1 ns by default).
User values with units are converted once, at the edge, and a value that is not a whole number
of ticks is refused instead of being rounded silently. Floats appear only at the FMI boundary
(:meth:`TimeBase.seconds`).

Same-instant order
------------------
Events at the same tick run in the order of their :class:`Priority`, then in the order they
were scheduled. SimPy's own follow-on events (a process resuming after an event it waited for)
use ``URGENT`` / ``NORMAL`` and therefore run before the next named stage at that tick::

    URGENT(0) < NORMAL(1) < PLANT_EVENT < SERVO < SLOT_WATCH < SLOT < HOST < SETTLE < SAMPLE

so at one instant: plant events (a switch crossing found inside an FMU) are published first,
then the servo interrupt, then observers that look at a pulse engine just before its slot, the
slot itself, then the host application; outputs that may be switched several times at one
instant settle to their final level after that, and sampling for the record comes last, after
everything that instant changed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction
from functools import cached_property

from cosim import validate
from cosim.errors import ConfigurationError

#: Seconds per unit for the units accepted by :func:`TimeBase.ticks`.
UNITS_S: dict[str, Fraction] = {
    "s": Fraction(1),
    "ms": Fraction(1, 10**3),
    "us": Fraction(1, 10**6),
    "µs": Fraction(1, 10**6),
    "ns": Fraction(1, 10**9),
    "ps": Fraction(1, 10**12),
}

_QUANTITY = re.compile(r"^\s*([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-zµ]+)\s*$")


class Priority:
    """Named priorities of same-instant events (lower runs first).

    Plain ``int`` constants, not an enum: controllers name one for every event they schedule, and
    reading an enum member costs several times a class attribute (Python 3.11's ``EnumType`` has a
    ``__getattr__``), on the kernel's hottest path.
    """

    URGENT = 0  # SimPy: process start, interrupts
    NORMAL = 1  # SimPy: follow-on events (a process resuming)
    PLANT_EVENT = 2  # an event announced by a plant (switch crossing, registration mark)
    SERVO = 10  # servo interrupt of a motion controller
    SLOT_WATCH = 19  # an observer of a pulse engine, just before its slot (buffer level about to be read)
    SLOT = 20  # pulse-engine time slot
    HOST = 30  # host application (refill loop, program interpreter)
    SETTLE = 39  # outputs switched several times at one instant commit their final level
    SAMPLE = 40  # recording samples of analog outputs


@dataclass(frozen=True)
class TimeBase:
    """The declared resolution of simulation time.

    Parameters
    ----------
    resolution_s : Fraction
        Seconds per tick (1/10**9 = 1 ns by default).

    Examples
    --------
    >>> tb = TimeBase()
    >>> tb.ticks(1, "ms")
    1000000
    >>> tb.ticks("442.708 us")
    442708
    """

    resolution_s: Fraction = Fraction(1, 10**9)

    def __post_init__(self) -> None:
        object.__setattr__(self, "resolution_s", validate.positive(self.resolution_s, "resolution_s", unit="s"))

    @property
    def unit(self) -> str:
        """The resolution as a VCD-style timescale string, e.g. ``'1 ns'``."""
        for name, seconds in UNITS_S.items():
            if name == "µs":
                continue
            n = self.resolution_s / seconds
            if n.denominator == 1 and n.numerator in (1, 10, 100):
                return f"{n.numerator} {name}"
        return f"{float(self.resolution_s)} s"

    @property
    def ticks_per_second(self) -> Fraction:
        """Ticks in one second (exact)."""
        return 1 / self.resolution_s

    def ticks(self, value: int | float | str | Fraction | Decimal, unit: str | None = None, *,
              name: str = "time") -> int:
        """Convert a time with a unit to an exact integer tick count.

        Parameters
        ----------
        value : int, float, str, Fraction or Decimal
            The amount; a string may carry its unit (``"250 us"``).
        unit : str, optional
            One of ``s, ms, us, ns, ps``; required unless ``value`` is a string with a unit.
        name : str
            Name of the quantity, used in the error message.

        Raises
        ------
        ConfigurationError
            If the value is not a whole number of ticks, or the unit is unknown.
        """
        if isinstance(value, str):
            match = _QUANTITY.match(value)
            if match is None or unit is not None:
                raise ConfigurationError(
                    f"{name} = {value!r} is not a time; write a number and a unit, e.g. '250 us'"
                )
            value, unit = match.group(1), match.group(2)
        unit = validate.choice(unit, f"unit of {name}", tuple(UNITS_S))
        exact = validate.exact(value, name) * UNITS_S[unit] / self.resolution_s
        if exact.denominator != 1:
            raise ConfigurationError(
                f"{name} = {validate.shown(value)} {unit} is not a whole number of ticks of the resolution "
                f"{self.unit} ({float(exact)} ticks); choose a value that is a multiple of {self.unit}"
            )
        return int(exact)

    def check_ticks(self, value: object, *, name: str = "time", minimum: int | None = 0) -> int:
        """Accept an integer tick count (never a float) of at least ``minimum`` ticks."""
        return validate.integer(value, name, low=minimum, unit="ticks", kind=self._ticks_kind)

    @cached_property
    def _ticks_kind(self) -> str:  # built once: check_ticks runs for every event scheduled
        return f"an integer number of ticks ({self.unit} each); use TimeBase.ticks() to convert a value with a unit"

    def seconds(self, ticks: int) -> float:
        """Ticks to float seconds: for the FMI call boundary and for display only."""
        return float(ticks * self.resolution_s) if self.resolution_s.numerator != 1 else (
            ticks / self.resolution_s.denominator
        )

    def ticks_from_seconds_ceil(self, t_s: float) -> int:
        """The first tick at or after a float time reported by an FMU (event location)."""
        exact = Fraction(t_s) / self.resolution_s
        nearest = round(exact)
        if abs(exact - nearest) <= Fraction(1, 10**6):  # float noise of a time that was on a tick
            return int(nearest)
        return -((-exact.numerator) // exact.denominator)


NANOSECOND = TimeBase()
