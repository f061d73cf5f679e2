"""Small Trio set-ups shared by the PWM tests."""

from __future__ import annotations

from cosim.controllers.trio import ON, TrioController, TrioProcess
from cosim.kernel import Simulation


def laser_axis(sim: Simulation, *, cycle: int = 1000, mark: int = 400,
               wdog: int = ON) -> tuple[TrioController, TrioProcess]:
    """Axis 3 with PWM on (mode 1, so no gating: the gate is open), WDOG as given, all at t = 0.

    ``cycle`` and ``mark`` are PWM_CYCLE and PWM_MARK [50 ns clocks]: 1000 is the note's 20 kHz.
    """
    trio = TrioController(sim, encoder_at_atype=0)
    p = TrioProcess(trio, base=(3,))
    p.set("PWM_CYCLE", cycle)
    p.set("PWM_MARK", mark)
    p.pwm_control(1)
    p.set("WDOG", wdog)
    return trio, p
