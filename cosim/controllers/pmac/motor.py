"""A PMAC motor: follows a coordinate-system axis, closes its position loop each servo cycle.

Each servo cycle (after the conversion table and the coordinate systems) the motor

* takes its commanded position from its axis: ``cmd = counts_per_unit * axis position``;
* reads its feedback (a callable returning the encoder count, e.g. the servo-axis plant);
* runs the PID (if any) on ``cmd - act`` and writes the DAC signal.

Signals: ``pmac.motorN.cmd_pos`` and ``act_pos`` [counts], ``following_error`` (cmd - act),
``sync_error`` (master-derived, slip-free command minus actual: Ix94 slip plus following error)
and ``dac`` [bits]. Without feedback the motor is ideal (act = cmd).
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim import validate
from cosim.controllers.pmac.coord import CoordinateSystem
from cosim.controllers.pmac.servo import PidLoop
from cosim.errors import ConfigurationError
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.kernel import Simulation


class Motor:
    """Motor ``#n`` assigned to an axis of a coordinate system (``#n->counts_per_unit X``).

    Parameters
    ----------
    sim : Simulation
    number : int
        Motor number n.
    cs : CoordinateSystem
    axis : str
        Axis letter in ``cs``.
    counts_per_unit : int or Fraction
        Axis scale [counts per axis unit].
    loop : PidLoop, optional
        Position loop; without it the motor is ideal.
    feedback : callable, optional
        Returns the actual position [counts]; required with a loop (may be set later).
    device : str
        Trace name prefix.
    """

    def __init__(self, sim: Simulation, number: int, cs: CoordinateSystem, *, axis: str = "X",
                 counts_per_unit: int | Fraction = 1, loop: PidLoop | None = None,
                 feedback: Callable[[], int | float] | None = None, device: str = "pmac",
                 terms: tuple[tuple[Fraction, str], ...] | None = None, offset: Fraction = Fraction(0)) -> None:
        for name in (a for _c, a in terms) if terms else (axis,):
            if name not in cs.axes:
                raise ConfigurationError.out_of_range(f"axis of motor {number}", name, ", ".join(cs.axes))
        self.terms = tuple((Fraction(c), a) for c, a in terms) if terms else None
        self.offset = Fraction(offset)
        self.number = number
        self.cs = cs
        self.axis = axis
        self.counts_per_unit = validate.exact(counts_per_unit, f"counts_per_unit of motor {number}")
        self.loop = loop
        self.feedback = feedback
        self._cmd_ratio = (0, 1)
        self.act: float = 0.0
        scale = self.counts_per_unit
        self._scale = (scale.numerator, scale.denominator)
        self._last: list[float | None] = [None, None, None, None]  # cmd, act, following error, sync error
        p = f"{device}.motor{number}"
        self._cmd = Signal(sim, f"{p}.cmd_pos", kind="real", unit="counts", description="commanded position")
        self._act = Signal(sim, f"{p}.act_pos", kind="real", unit="counts", description="actual position")
        self._ferr = Signal(sim, f"{p}.following_error", kind="real", unit="counts", description="cmd - act")
        self._sync = Signal(sim, f"{p}.sync_error", kind="real", unit="counts",
                            description="master-derived position - actual (slip + following error)")
        self.dac = Signal(sim, f"{p}.dac", kind="int", unit="bits", description="16-bit DAC output")

    @property
    def cmd(self) -> Fraction:
        """Commanded position [counts] (exact), as of the last servo cycle."""
        return Fraction(*self._cmd_ratio)

    @property
    def cmd_ratio(self) -> tuple[int, int]:
        """Commanded position [counts] as ``(numerator, denominator)``."""
        return self._cmd_ratio

    @property
    def axes(self) -> tuple[str, ...]:
        """The axes the motor follows (one, or the terms of a linear combination)."""
        return tuple(a for _c, a in self.terms) if self.terms else (self.axis,)

    def _combination(self, ideal: bool) -> tuple[int, int]:
        """``sum(c_i * axis_i) + offset`` [counts], exact (a motor defined on several axes)."""
        assert self.terms is not None
        total = self.offset
        for coefficient, axis in self.terms:
            total += coefficient * Fraction(*self.cs.position_ratio(axis, ideal=ideal))
        return total.numerator, total.denominator

    def update(self, cycle: int, t: int) -> None:
        """One servo cycle: command, feedback, PID, DAC.

        The command is the exact ratio of integers the coordinate system gives, times the scale;
        its float (``numerator / denominator``, correctly rounded) is what the PID and the trace see.
        """
        if self.terms is not None:
            num, den = self._cmd_ratio = self._combination(False)
            cmd = num / den
            ideal_num, ideal_den = self._combination(True)
            ideal = ideal_num / ideal_den
        else:
            scale_num, scale_den = self._scale
            num, den = self.cs.position_ratio(self.axis)
            num *= scale_num
            den *= scale_den
            self._cmd_ratio = (num, den)
            cmd = num / den
            ideal_num, ideal_den = self.cs.position_ratio(self.axis, ideal=True)
            ideal = ideal_num * scale_num / (ideal_den * scale_den)
        loop = self.loop
        if loop is not None:
            feedback = self.feedback
            if feedback is None:
                raise ConfigurationError(f"motor {self.number} has a position loop but no feedback; "
                                         "set motor.feedback to a callable returning counts")
            act = self.act = float(feedback())
            self.dac.set(loop.update(cmd - act))
        else:
            act = self.act = float(self.feedback()) if self.feedback is not None else cmd
        last = self._last
        if cmd != last[0]:
            last[0] = cmd
            self._cmd.set(cmd)
        if act != last[1]:
            last[1] = act
            self._act.set(act)
        error = cmd - act
        if error != last[2]:
            last[2] = error
            self._ferr.set(error)
        sync = ideal - act
        if sync != last[3]:
            last[3] = sync
            self._sync.set(sync)
