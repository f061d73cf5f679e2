"""Trio EURO205X Motion Coordinator with the PWM FPGA: laser PWM, position-gated output (TN20-81), Trio BASIC.

Modules, one job each:

* :mod:`.params`     parameter names, defaults, allowed ranges, hardware constants;
* :mod:`.profile`    exact trapezoids, the FORWARD ramp and the CANCEL stop;
* :mod:`.trig`       deterministic fixed-point angles, sines and cosines for arcs;
* :mod:`.paths`      the geometry of a move: line, arc, ray;
* :mod:`.counter`    step counters exact at every tick of a servo-cycle segment;
* :mod:`.motion`     moves, axes, servo-cycle demand and the step/direction output;
* :mod:`.buffer`     the move buffers and the programs waiting on them;
* :mod:`.pwm`        the PWM generator, speed link, and the output in closed form;
* :mod:`.gate`       the 256-deep gating FIFO compared with the 29-bit PWM_ENCODER;
* :mod:`.io`         digital inputs and outputs, the console PRINT writes to;
* :mod:`.outputs`    outputs that settle once per instant;
* :mod:`.controller` the controller: servo cycle, parameters, TABLE, VR, commands, ports;
* :mod:`.process`    one program's view (BASE, TICKS) and the BASIC vocabulary for Python;
* :mod:`.values`     BASIC numbers in the 32.32 variable format;
* :mod:`.grammar`, :mod:`.keywords`  the grammar of the BASIC subset (lark, LALR) and its vocabulary;
* :mod:`.compiler`, :mod:`.operations`  checks and compiles a program into flat operations;
* :mod:`.basic`      programs parsed, checked and run on processes (the note's example runs from its text);
* :mod:`.raster`     a raster engraving job that refills the gating FIFO.

Signals (``N`` = axis): ``trio.axisN.step`` / ``dir`` / ``gate`` / ``pwm_cycle`` / ``pwm_mark`` /
``pwm_phase`` / ``fifo_level`` / ``fifo_waiting`` / ``gate_late`` / ``late_positions`` /
``vp_speed`` / ``mpos`` / ``dpos``, ``trio.wdog``, ``trio.in.N``, ``trio.op.N``, ``trio.print``.
See ``docs/trio.md``.
"""

from cosim.controllers.trio.controller import TrioController
from cosim.controllers.trio.params import FALSE, OFF, ON, TRUE
from cosim.controllers.trio.process import TrioProcess

__all__ = ["FALSE", "OFF", "ON", "TRUE", "TrioController", "TrioProcess"]
