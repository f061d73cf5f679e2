"""Trio EURO205X Motion Coordinator with the PWM FPGA: laser PWM and position-gated output (TN20-81).

Modules, one job each:

* :mod:`.params`     parameter names, defaults, allowed ranges, hardware constants;
* :mod:`.profile`    exact trapezoidal velocity profiles;
* :mod:`.counter`    step counters exact at every tick of a servo-cycle segment;
* :mod:`.motion`     axes, moves, servo-cycle demand and stepper pulse output;
* :mod:`.pwm`        the PWM generator, speed link, and the output in closed form;
* :mod:`.gate`       the 256-deep gating FIFO compared with the 29-bit PWM_ENCODER;
* :mod:`.outputs`    outputs that settle once per instant;
* :mod:`.controller` the controller: servo cycle, parameters, TABLE, commands;
* :mod:`.process`    the BASIC vocabulary for Python scenario scripts;
* :mod:`.grammar`    the grammar of the BASIC subset (lark, LALR);
* :mod:`.basic`      the interpreter of that subset (the note's example runs from its text);
* :mod:`.raster`     a raster engraving job that refills the gating FIFO.

Signals (``N`` = axis): ``trio.axisN.step`` / ``dir`` / ``gate`` / ``pwm_cycle`` / ``pwm_mark`` /
``pwm_phase`` / ``fifo_level`` / ``fifo_waiting`` / ``gate_late`` / ``vp_speed`` / ``mpos`` /
``dpos``, and ``trio.wdog``. See ``docs/trio.md``.
"""

from cosim.controllers.trio.controller import TrioController
from cosim.controllers.trio.params import FALSE, OFF, ON, TRUE
from cosim.controllers.trio.process import TrioProcess

__all__ = ["FALSE", "OFF", "ON", "TRUE", "TrioController", "TrioProcess"]
