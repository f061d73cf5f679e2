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
                 feedback: Callable[[], int | float] | None = None, device: str = "pmac") -> None:
        if axis not in cs.axes:
            raise ConfigurationError.out_of_range(f"axis of motor {number}", axis, ", ".join(cs.axes))
        self.number = number
        self.cs = cs
        self.axis = axis
        self.counts_per_unit = validate.exact(counts_per_unit, f"counts_per_unit of motor {number}")
        self.loop = loop
        self.feedback = feedback
        self.cmd = Fraction(0)
        self.act: float = 0.0
        p = f"{device}.motor{number}"
        self._cmd = Signal(sim, f"{p}.cmd_pos", kind="real", unit="counts", description="commanded position")
        self._act = Signal(sim, f"{p}.act_pos", kind="real", unit="counts", description="actual position")
        self._ferr = Signal(sim, f"{p}.following_error", kind="real", unit="counts", description="cmd - act")
        self._sync = Signal(sim, f"{p}.sync_error", kind="real", unit="counts",
                            description="master-derived position - actual (slip + following error)")
        self.dac = Signal(sim, f"{p}.dac", kind="int", unit="bits", description="16-bit DAC output")

    def update(self, cycle: int, t: int) -> None:
        """One servo cycle: command, feedback, PID, DAC."""
        self.cmd = self.cs.position(self.axis) * self.counts_per_unit
        ideal = self.cs.ideal_position(self.axis) * self.counts_per_unit
        if self.loop is not None:
            if self.feedback is None:
                raise ConfigurationError(f"motor {self.number} has a position loop but no feedback; "
                                         "set motor.feedback to a callable returning counts")
            self.act = float(self.feedback())
            self.dac.set(self.loop.update(float(self.cmd) - self.act))
        else:
            self.act = float(self.feedback()) if self.feedback is not None else float(self.cmd)
        self._cmd.set(float(self.cmd))
        self._act.set(self.act)
        self._ferr.set(float(self.cmd) - self.act)
        self._sync.set(float(ideal) - self.act)
