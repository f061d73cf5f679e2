"""Digital inputs and outputs, and the console that ``PRINT`` writes to.

* ``IN(n)`` reads input ``n`` (``trio.in.N``, a bit signal that the controller only reads: a
  machine file's stimulus table, a test or a plant output drives it; see
  :meth:`TrioController.inputs`). Channels 0..31 (model choice).
* ``OP(n, ON/OFF)`` sets output ``n`` (``trio.op.N``); outputs settle once per instant like the
  other outputs (:mod:`~cosim.controllers.trio.outputs`). Outputs are channels 8..31: on the
  controller channels 0..7 are inputs only (model choice; the numbering of the EURO205X I/O was
  not re-read in a manual). ``READ_OP(n)`` (and ``OP(n)`` in an expression) reads back the state
  written last.
* ``PRINT`` lines go to :class:`Console`: each with the simulated time, the process, the program
  and its line; the trace signal ``trio.print`` counts them, so the trace shows when they were
  written; each is also logged (INFO) on the ``cosim.trio.console`` logger.

Signals are created on first use (a program's literal channels when it starts), so a trace holds
only the channels a machine uses.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

from cosim import validate
from cosim.controllers.trio.outputs import SettledSignal
from cosim.controllers.trio.params import on_off
from cosim.signals import Signal

if TYPE_CHECKING:
    from simpy.events import Event

    from cosim.kernel import Simulation

#: Every console line is also logged here (INFO), for a runner that shows or stores a run's log.
LOG = logging.getLogger("cosim.trio.console")


class DigitalIo:
    """The digital inputs and outputs of the controller.

    Parameters
    ----------
    sim : Simulation
    device : str
        Trace device name (``trio``).
    channels : int
        Number of channels; inputs are ``0..channels-1``.
    first_output : int
        Lowest channel that is an output.
    """

    def __init__(self, sim: Simulation, device: str, *, channels: int, first_output: int) -> None:
        self.sim = sim
        self.device = device
        self.channels = channels
        self.first_output = first_output
        self._inputs: dict[int, Signal] = {}
        self._outputs: dict[int, SettledSignal] = {}
        self._inverted: set[int] = set()

    def _input_channel(self, channel: object) -> int:
        return validate.integer(channel, "input", low=0, high=self.channels - 1, whole=True)

    def _output_channel(self, channel: object) -> int:
        return validate.integer(channel, "output", low=self.first_output, high=self.channels - 1, whole=True,
                                allowed=f"{self.first_output}..{self.channels - 1} (0..{self.first_output - 1} "
                                        "are inputs only)")

    def input(self, channel: object, *, initial: int = 0) -> Signal:
        """The signal of input ``channel`` (``trio.in.N``), created on first use (at ``initial``)."""
        n = self._input_channel(channel)
        signal = self._inputs.get(n)
        if signal is None:
            signal = self._inputs[n] = Signal(self.sim, f"{self.device}.in.{n}", kind="bit", initial=initial,
                                              description=f"digital input {n} (IN({n}))")
        return signal

    def output(self, channel: object) -> Signal:
        """The signal of output ``channel`` (``trio.op.N``), created on first use."""
        return self._output(self._output_channel(channel)).signal

    def _output(self, n: int) -> SettledSignal:
        out = self._outputs.get(n)
        if out is None:
            out = self._outputs[n] = SettledSignal(self.sim, f"{self.device}.op.{n}", kind="bit",
                                                   description=f"digital output {n} (OP({n}, ON/OFF))")
        return out

    def read_input(self, channel: object) -> int:
        """``IN(n)``: 1 (ON) or 0 (OFF), inverted where ``INVERT_IN(n, ON)`` asked for it."""
        signal = self.input(channel)
        level = 1 if signal.value else 0
        return level ^ 1 if self._inverted and int(signal.name.rsplit(".", 1)[1]) in self._inverted else level

    def invert_input(self, channel: object, state: object) -> None:
        """``INVERT_IN(n, ON/OFF)``: a program reads input ``n`` inverted (the signal is what the wire carries)."""
        n = self._input_channel(channel)
        if on_off(state, f"INVERT_IN({n}) state"):
            self._inverted.add(n)
        else:
            self._inverted.discard(n)

    def write_pattern(self, pattern: object) -> None:
        """``OP(value)``: outputs 8..31 at once from the bits 8..31 of ``value``."""
        bits = validate.integer(pattern, "OP bit pattern", low=0, high=(1 << self.channels) - 1, whole=True)
        for n in range(self.first_output, self.channels):
            self._output(n).request((bits >> n) & 1)

    def write_output(self, channel: object, state: object) -> None:
        """``OP(n, state)``: set output ``n`` ON (1, or TRUE) or OFF (0), settled at the end of the instant."""
        n = self._output_channel(channel)
        self._output(n).request(on_off(state, f"OP({n}) state"))

    def read_output(self, channel: object) -> int:
        """``READ_OP(n)``: the state written last, 1 (ON) or 0 (OFF)."""
        n = self._output_channel(channel)
        out = self._outputs.get(n)
        return 0 if out is None else int(out.value)

    def inputs(self) -> list[Signal]:
        """The input signals created so far."""
        return [self._inputs[n] for n in sorted(self._inputs)]

    def outputs(self) -> list[Signal]:
        """The output signals created so far."""
        return [self._outputs[n].signal for n in sorted(self._outputs)]


class Channel:
    """A communication channel (serial port, Motion Perfect channel...): text arriving for INPUT, GET, KEY.

    Parameters
    ----------
    sim : Simulation
    number : int
        The channel number programs write with ``#``.
    """

    def __init__(self, sim: Simulation, number: int) -> None:
        self.sim = sim
        self.number = number
        self.buffer = ""
        self._arrival = sim.env.event()

    def feed(self, text: str) -> None:
        """Characters arrive now (``\r`` or ``\n`` ends a line)."""
        self.buffer += text
        arrival, self._arrival = self._arrival, self.sim.env.event()
        arrival.succeed()

    @property
    def waiting(self) -> bool:
        """A character waits to be read (``KEY``)."""
        return bool(self.buffer)

    def read_char(self) -> int | None:
        """The code of the next character (``GET``), or None when none waits."""
        if not self.buffer:
            return None
        char, self.buffer = self.buffer[0], self.buffer[1:]
        return ord(char)

    def read_line(self) -> str | None:
        """The next line without its end (``INPUT``, ``LINPUT``), or None while no line end has arrived."""
        ends = [k for k in (self.buffer.find("\r"), self.buffer.find("\n")) if k >= 0]
        if not ends:
            return None
        end = min(ends)
        line = self.buffer[:end]
        rest = self.buffer[end + 1:]
        if self.buffer[end] == "\r" and rest.startswith("\n"):
            rest = rest[1:]
        self.buffer = rest
        return line

    def arrival(self) -> Event:
        """An event that succeeds when more characters arrive."""
        return self._arrival


@dataclass(frozen=True)
class ConsoleLine:
    """One line a program printed.

    Parameters
    ----------
    t : int
        When it was completed [ticks].
    process : int
        The process that printed it.
    program : str
        Program name.
    line : int
        Program line of the PRINT that completed it.
    text : str
        The text.
    """

    t: int
    process: int
    program: str
    line: int
    text: str


class Console:
    """Where ``PRINT`` writes: lines with their simulated time; ``trio.print`` counts them in the trace."""

    def __init__(self, sim: Simulation, device: str) -> None:
        self.sim = sim
        self.device = device
        self.lines: list[ConsoleLine] = []
        self.count = Signal(sim, f"{device}.print", kind="int", unit="lines",
                            description="PRINT lines written so far (the text is in the controller's console)")

    def write(self, *, process: int, program: str, line: int, text: str) -> None:
        """Record a completed line now."""
        self.lines.append(ConsoleLine(self.sim.now, process, program, line, text))
        self.sim.trace.write_line(self.sim.now, f"{self.device}.proc{process}", f"{program}:{line}  {text}")
        self.count.set(len(self.lines))
        LOG.info("t = %d ticks [%d] %s:%d  %s", self.sim.now, process, program, line, text)

    def error(self, *, process: int, text: str) -> None:
        """A run-time error message on the console (not a PRINT line: ``trio.print`` does not count it)."""
        self.sim.trace.write_line(self.sim.now, f"{self.device}.proc{process}", text)
        LOG.info("t = %d ticks [%d] %s", self.sim.now, process, text)

    def text(self) -> str:
        """Every line as ``t [ms]  process  program:line  text``, one per line."""
        return "".join(f"{self.sim.timebase.seconds(c.t) * 1e3:12.6f} ms  [{c.process}] {c.program}:{c.line}  "
                       f"{c.text}\n" for c in self.lines)
