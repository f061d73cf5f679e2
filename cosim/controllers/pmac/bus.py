"""The controller as its programs see it: what the runtime may ask of a PMAC (a protocol, no code).

The runtime layer (:mod:`.mvars`, :mod:`.evaluate`, :mod:`.interpreter`, :mod:`.runtime`) reaches the
controller only through :class:`Registers`, so it never imports :mod:`.machine`, which imports it:
the layers import one way (text -> syntax tree -> program -> runtime -> machine).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from cosim.controllers.pmac.coord import CoordinateSystem
    from cosim.controllers.pmac.ect import ConversionTable
    from cosim.controllers.pmac.motor import Motor
    from cosim.job import Job
    from cosim.kernel import Simulation

Value = int | Fraction


class Registers(Protocol):
    """I-variables and registers of a controller, as programs and M-variables reach them."""

    sim: Simulation
    device: str

    @property
    def started(self) -> bool:
        """True once the servo clock runs."""
        ...

    @property
    def cycle(self) -> int:
        """The servo cycle that ran last (-1 before the first)."""
        ...

    def get_ivar(self, number: int) -> Value:
        """I``number`` now."""
        ...

    def set_ivar(self, number: int, value: Value, *, where: str = "") -> None:
        """Write I``number`` (checked against its range)."""
        ...

    def ivar_is_volatile(self, number: int) -> bool:
        """True if I``number`` changes by itself (a countdown timer): a read of it is not stable."""
        ...

    def has_register(self, space: str, address: int) -> bool:
        """True if the model has register ``space:address`` (X or Y)."""
        ...

    def read_word(self, space: str, address: int) -> int:
        """The 24-bit word at ``space:address`` (an X read of a capture register re-arms it)."""
        ...

    def write_word(self, space: str, address: int, value: int, *, where: str = "") -> None:
        """Write a Y word of the conversion table (= the I-variable of that line)."""
        ...

    def register_is_volatile(self, space: str, address: int) -> bool:
        """True if the register changes by itself (encoder counts, captures, table results)."""
        ...


class Controller(Registers, Protocol):
    """Everything the program system (:mod:`.runtime`, :mod:`.commands`) asks of a PMAC (:class:`~.machine.Pmac`)."""

    table: ConversionTable
    cs: dict[int, CoordinateSystem]
    motors: dict[int, Motor]
    job: Job

    def build_table(self, lines: dict[int, int], *, where: dict[int, str]) -> None:
        """Build the conversion table from setup lines."""
        ...

    def coordinate_system(self, number: int) -> CoordinateSystem:
        """Coordinate system ``&number`` (created on first use)."""
        ...

    def motor_axes(self, cs: int) -> set[str]:
        """Axes of coordinate system ``cs`` that a motor is assigned to."""
        ...

    def inverse_motors(self, cs: int) -> list[int]:
        """Motors ``#n->I`` of coordinate system ``cs``."""
        ...

    def rapid_parameters(self, cs: int, axis: str) -> tuple[Fraction, Fraction, Fraction]:
        """RAPID speed [units/ms], TA and TS [ms] of ``axis``."""
        ...

    def command_percent(self, number: int, pct: int | Fraction) -> int:
        """``&x %n``."""
        ...

    def define_motor(self, number: int, *, cs: int, axis: str | None = None, counts_per_unit: int | Fraction = 1,
                     terms: tuple[tuple[Fraction, str], ...] | None = None, offset: Fraction = Fraction(0),
                     where: str = "") -> Motor:
        """``#n->...``: a motor on a linear combination of axes."""
        ...

    def define_kinematic_motor(self, number: int, *, cs: int, inverse: bool, where: str = "") -> Motor | None:
        """``#n->I`` or ``#n->0``."""
        ...

    def undefine(self, cs: int | None, *, where: str = "") -> None:
        """``UNDEFINE`` or ``UNDEFINE ALL``."""
        ...
