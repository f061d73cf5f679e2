"""The Trio EURO205X Motion Coordinator: servo cycle, parameters, TABLE, VR, I/O and commands.

:class:`TrioController` owns the axes, TABLE and VR memory, the digital I/O, the channels, the
console, WDOG and its job (``trio.job``), and runs the servo cycle at ``k * SERVO_PERIOD`` (priority
SERVO; when a tick runs, and when it is computed in closed form instead, is :mod:`.servo`'s
business). Each servo tick, in this order:

1. latch MPOS of every axis (the pulses counted so far);
2. move waiting ``PWM_CONTROL(3)`` loads into FIFOs that now have room;
3. limits and jog inputs (:mod:`.supervise`);
4. end moves whose last cycle was output; load buffered moves whose axes are free (:mod:`.buffer`);
5. run one cycle of every move (a requested CANCEL first): demand positions, VP_SPEED, step
   pulses (:mod:`.motion`, :mod:`.linked`, :mod:`.datum`);
6. apply pending DEFPOS / OFFPOS offsets (after loading moves: a move issued right after DEFPOS is
   loaded before the new position applies, as the Trio manual warns; ``WAIT UNTIL OFFPOS=0``);
   keep positions within REP_DIST;
7. update speed-linked PWM marks from VP_SPEED of their link axis;
8. check FE_LIMIT, record DPOS, MPOS, VP_SPEED, then release programs waiting for move-buffer
   space, for idle axes or for an empty next-move buffer.

Commands come from programs (:class:`TrioProcess`, the BASIC interpreter); they take effect at
the instant they are given, in zero simulated time. The motion commands are in
:mod:`.motioncmds`, parameter access in :mod:`.parameters`.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from simpy.events import Event

from cosim import validate
from cosim.controllers.trio.axis import Axis
from cosim.controllers.trio.buffer import MoveBuffers
from cosim.controllers.trio.gate import GateFifo, toggled_entries
from cosim.controllers.trio.io import Channel, Console, DigitalIo
from cosim.controllers.trio.motioncmds import MotionCommands
from cosim.controllers.trio.outputs import SettledSignal
from cosim.controllers.trio.parameters import ParameterAccess, pwm_axes
from cosim.controllers.trio.params import (
    DEFAULT_DIR_SETUP_NS,
    DEFAULT_IO_CHANNELS,
    DEFAULT_SERVO_PERIOD_US,
    DEFAULT_STEP_PULSE_WIDTH_NS,
    DEFAULT_TABLE_SIZE,
    DEFAULT_VR_SIZE,
    FIFO_DEPTH,
    FIRST_OUTPUT,
    PWM_AXES,
    PWM_CLOCK_HZ,
    PWM_CLOCK_NS,
    PWM_ENCODER_MODULUS,
    PWM_REGISTER_MAX,
    STEPPER_ATYPES,
    check_servo_period_us,
    on_off,
)
from cosim.controllers.trio.pwm import PwmGenerator, PwmMode, SpeedLink
from cosim.controllers.trio.pwm_output import PwmOutput
from cosim.controllers.trio.servo import ServoLoop
from cosim.controllers.trio.supervise import before_moves, within_range, wrap
from cosim.errors import ConfigurationError, TimingViolation
from cosim.job import Job, JobState
from cosim.kernel import Simulation
from cosim.signals import PulseTrain, PwmPort, Signal, StepDirPort

#: Arguments each PWM_CONTROL mode takes after the mode.
PWM_CONTROL_ARGS = {0: (), 1: (), 2: ("multiplier", "offset", "limit value", "link axis"),
                    3: ("GT/LT", "ON/OFF", "table start", "table end"), 4: (), 5: (), 6: ()}


class TrioController(MotionCommands, ParameterAccess):
    """A EURO205X with the PWM FPGA: axes 0..n-1, PWM and gating on axes 2 and 3.

    Parameters
    ----------
    sim : Simulation
    servo_period_us : int
        SERVO_PERIOD [us]: 250, 500, 1000 (default) or 2000.
    n_axes : int
        Number of axes (4 by default; must include axes 2 and 3).
    table_size : int
        TABLE entries (16000 by default).
    vr_size : int
        VR globals, ``VR(0)..VR(vr_size - 1)`` (1024 by default).
    encoder_at_atype : int, optional
        Raw PWM_ENCODER value an axis shows after ATYPE=35 (the note: "will often have a value");
        default: drawn from ``sim.rng``, so programs must clear it with PWM_CONTROL(6).
    step_pulse_width_ns : int
        Step pulse width [ns]: from a pulse's leading edge to its active (trailing) edge, where
        it is counted (100 ns by default).
    dir_setup_ns : int
        Direction set-up [ns] from a change of the direction output to the leading edge of the
        next step pulse (0 by default: the direction changes with the leading edge, so the
        set-up before the active edge is the pulse width).
    device : str
        Trace device name (``trio``).
    """

    def __init__(self, sim: Simulation, *, servo_period_us: int = DEFAULT_SERVO_PERIOD_US, n_axes: int = 4,
                 table_size: int = DEFAULT_TABLE_SIZE, vr_size: int = DEFAULT_VR_SIZE,
                 encoder_at_atype: int | None = None, step_pulse_width_ns: int = DEFAULT_STEP_PULSE_WIDTH_NS,
                 dir_setup_ns: int = DEFAULT_DIR_SETUP_NS, device: str = "trio") -> None:
        self.sim = sim
        self.servo_period_us = check_servo_period_us(servo_period_us)
        self.period_ticks = sim.ticks(self.servo_period_us, "us", name="SERVO_PERIOD")
        self.period_s = Fraction(self.servo_period_us, 10**6)
        n_axes = validate.integer(n_axes, "n_axes", low=max(PWM_AXES) + 1, high=64)
        table_size = validate.integer(table_size, "table_size", low=1, unit="entries")
        vr_size = validate.integer(vr_size, "vr_size", low=1, high=1 << 20, unit="variables")
        self.device = device
        self.encoder_at_atype = None if encoder_at_atype is None else validate.integer(
            encoder_at_atype, "encoder_at_atype", low=0, high=PWM_ENCODER_MODULUS - 1, unit="(raw PWM_ENCODER)")
        width_ns = validate.integer(step_pulse_width_ns, "step_pulse_width_ns", low=1, high=10**6, unit="ns")
        self.pulse_width_ticks = sim.ticks(width_ns, "ns", name="step_pulse_width_ns")
        setup_ns = validate.integer(dir_setup_ns, "dir_setup_ns", low=0, high=10**6, unit="ns")
        self.dir_setup_ticks = sim.ticks(setup_ns, "ns", name="dir_setup_ns")
        self.axes = {n: Axis(sim, n, pwm=n in PWM_AXES, device=device, pulse_width=self.pulse_width_ticks,
                             dir_setup=self.dir_setup_ticks) for n in range(n_axes)}
        self.table_memory = [Fraction(0)] * table_size
        self.vr_memory: list[int | Fraction] = [0] * vr_size
        self.io = DigitalIo(sim, device, channels=DEFAULT_IO_CHANNELS, first_output=FIRST_OUTPUT)
        self.console = Console(sim, device)
        self.wdog = SettledSignal(sim, f"{device}.wdog", kind="bit",
                                  description="WDOG: drive enable; OFF switches the PWM outputs off")
        clock_ticks = sim.ticks(PWM_CLOCK_NS, "ns", name="PWM clock period (50 ns)")
        #: The PWM output pins in the trace (``trio.axisN.pwm_out``), by axis.
        self.pwm_outputs = {n: PwmOutput(sim, f"{self.axes[n].prefix}.pwm_out", self.pwm_port(n),
                                         clock_ticks=clock_ticks) for n in PWM_AXES}
        self.buffers = MoveBuffers(sim, self.axes, period_s=self.period_s)
        self._axis_list = list(self.axes.values())  # axis n at index n
        self._gates = [ax.gate for ax in self.axes.values() if ax.gate is not None]
        self._pwms = [ax.pwm for ax in self.axes.values() if ax.pwm is not None]
        #: Running programs by process number, and the programs RUN can start by name.
        self.processes: dict[int, Any] = {}
        self.programs: dict[str, Any] = {}
        self.wired: set[int] = set()
        #: The job: the processes a machine starts, until each has stopped (see :mod:`cosim.job`).
        self.job = Job(sim, device)
        self.system_values: dict[str, Any] = {}
        self.flags = 0
        self.channels: dict[int, Channel] = {}
        self.regist_inputs = {n: n for n in self.axes}
        self._trigger: Signal | None = None
        #: When the servo ticks run (explicit, skipped at rest, or in closed form): see :mod:`.servo`.
        self.servo = ServoLoop(self)
        for ax in self.axes.values():
            ax.sync = self.servo.sync
            if ax.gate is not None:
                ax.gate.sync = self.servo.sync

    @property
    def setup_ticks(self) -> int:
        """Direction set-up before the active edge of a step pulse [ticks]: dir_setup + the pulse width."""
        return self.dir_setup_ticks + self.pulse_width_ticks

    # -- the servo cycle ----------------------------------------------------------------------
    @property
    def ticks(self) -> int:
        """Servo ticks so far (at 0, SERVO_PERIOD, ...), run or skipped."""
        return self.servo.k_done + 1

    def settled(self) -> bool:
        """Nothing changes at the next servo tick unless a command changes it: every axis at rest and
        recorded, no move running or buffered, no load waiting for FIFO space, no program waiting on the
        servo cycle."""
        if self.buffers.busy:
            return False
        for axis in self.axes.values():
            if not axis.quiet:
                return False
        return all(not gate.has_waiting for gate in self._gates)

    def _tick(self) -> None:
        now = self.sim.now
        axes = self._axis_list
        for axis in axes:  # 1. latch MPOS (Axis.sample_mpos, inline: this runs every tick)
            if not axis.quiet:
                if axis.params["ATYPE"] in STEPPER_ATYPES:
                    axis.mnum, axis.mden = axis.feedback.value(now), 1
                else:
                    axis.mnum, axis.mden = axis.dnum, axis.dden
        for gate in self._gates:
            if gate._waiting:
                gate.retry_waiting()
        for axis in axes:
            if axis.supervised:
                before_moves(self, axis)
        buffers = self.buffers
        if buffers.pending:
            buffers.load(now)
        buffers.run_cycle(now, self.period_ticks, self.period_s)
        for axis in axes:  # a run of pulse segments ends: the last tick emitted some, this one none
            emitted = axis.emitted_at
            if emitted is not None and emitted != now:
                axis.emitted_at = None
                axis.step.end_run()  # type: ignore[union-attr]  # an axis that emitted has its outputs
        awake = [axis for axis in axes if not axis.quiet]
        for axis in awake:
            if axis.pending_shift:
                axis.apply_offset()
            if not within_range(axis):
                wrap(axis)
        for pwm in self._pwms:
            link = pwm.link
            if link is not None:
                link_axis = axes[link.link_axis]
                pwm.servo_update_ratio(link_axis.vnum, link_axis.vden)
        for axis in awake:
            params = axis.params
            if params["SERVO"] and params["ATYPE"] in STEPPER_ATYPES and axis.following_error_exceeds():
                self._following_error(axis)
            axis.record()
            axis.settle(now)
        buffers.release()

    def _following_error(self, axis: Axis) -> None:
        """TRM (SERVO): the following error bit is set in AXISSTATUS and the enable relay is forced OFF; here
        the run also stops with the error (the job stops: LIMIT)."""
        axis.fe_exceeded = True
        self.wdog.request(0)
        error = axis.dpos - axis.mpos_sampled
        self.job.stop(JobState.LIMIT, f"{axis.prefix}: following error {float(error):g} units exceeds FE_LIMIT")
        origin = f"{axis.current.origin}: " if axis.current is not None and axis.current.origin else ""
        raise TimingViolation(
            f"{origin}{axis.prefix}: following error {float(error):g} units exceeds FE_LIMIT = "
            f"{float(axis.params['FE_LIMIT']):g} at t = {self.sim.now} ns (the controller stops with a "
            "motion error)")

    # -- axes and parameters ------------------------------------------------------------------
    def axis(self, number: object, *, where: str = "") -> Axis:
        """Axis ``number`` (ConfigurationError naming the allowed axes if there is none)."""
        return self.axes[validate.integer(number, "axis", low=0, high=len(self.axes) - 1, where=where, whole=True)]

    # -- TABLE ----------------------------------------------------------------------------------
    def table(self, start: object, *values: object) -> None:
        """``TABLE(start, v1, v2, ...)``: write consecutive TABLE locations from ``start``."""
        first = self._table_index(start)
        self._table_index(first + len(values) - 1)
        for k, value in enumerate(values):
            self.table_memory[first + k] = validate.exact(value, f"TABLE({first + k})")

    def table_value(self, index: object) -> Fraction:
        """``TABLE(n)``: read one TABLE location."""
        return self.table_memory[self._table_index(index)]

    def _table_index(self, index: object) -> int:
        return validate.integer(index, "TABLE index", low=0, high=len(self.table_memory) - 1, whole=True)

    # -- VR -------------------------------------------------------------------------------------
    def vr(self, index: object) -> int | Fraction:
        """``VR(n)``: read a global variable (0 until written)."""
        return self.vr_memory[self._vr_index(index)]

    def set_vr(self, index: object, value: object) -> None:
        """``VR(n) = value``: write a global variable (shared by every process); VR holds numbers."""
        if isinstance(value, str) or not isinstance(value, int | Fraction):
            raise ConfigurationError(f"VR({index}) = {value!r} is not allowed (allowed: a number; VR holds numbers)")
        self.vr_memory[self._vr_index(index)] = value

    def _vr_index(self, index: object) -> int:
        return validate.integer(index, "VR index", low=0, high=len(self.vr_memory) - 1, whole=True)

    # -- PWM_CONTROL --------------------------------------------------------------------------
    def pwm_control(self, axis: int, mode: object, *args: object) -> Event | None:
        """``PWM_CONTROL(mode, ...)`` on ``axis``; mode 3 returns an event that succeeds once loaded.

        Raises
        ------
        ConfigurationError
            An axis without the feature, an unknown mode, a wrong number of arguments, a comparison
            flag other than 0/1, TABLE bounds, end before start, a limit outside 0..65535.
        """
        self.servo.wake()
        ax = self.axis(axis)
        if not ax.has_pwm:
            raise ConfigurationError.out_of_range("PWM_CONTROL axis", ax.number, pwm_axes())
        number = validate.integer(mode, "PWM_CONTROL mode", low=0, high=max(PWM_CONTROL_ARGS), whole=True)
        wanted = PWM_CONTROL_ARGS[number]
        if len(args) != len(wanted):
            names = ", ".join(wanted) if wanted else "nothing"
            raise ConfigurationError(f"PWM_CONTROL({number}) takes {len(wanted)} arguments after the mode "
                                     f"({names}); got {len(args)}")
        pwm, gate = ax.pwm, self._gate(ax.number, "PWM_CONTROL")
        assert pwm is not None
        if number == 0:
            pwm.switch(PwmMode.OFF)
            gate.gating_off()
            gate.set_pwm_on(False)
        elif number == 1:
            pwm.switch(PwmMode.FIXED)
            gate.set_pwm_on(True)
        elif number == 2:
            pwm.switch(PwmMode.LINKED, self._speed_link(*args))
            gate.set_pwm_on(True)
        elif number == 3:
            return gate.load(self._fifo_entries(ax, *args))
        elif number == 4:
            gate.empty()
        elif number == 5:
            gate.gating_on()
        else:
            gate.preset_encoder(0)
        return None

    def _speed_link(self, multiplier: object, offset: object, limit: object, link_axis: object) -> SpeedLink:
        lim = validate.integer(limit, "PWM_CONTROL(2) limit value", low=0, high=PWM_REGISTER_MAX, whole=True)
        link = validate.integer(link_axis, "PWM_CONTROL(2) link axis", low=0, high=len(self.axes) - 1, whole=True)
        return SpeedLink(validate.exact(multiplier, "PWM_CONTROL(2) multiplier"),
                         validate.exact(offset, "PWM_CONTROL(2) offset"), lim, link)

    def _fifo_entries(self, ax: Axis, compare: object, state: object, start: object, end: object) -> list[Any]:
        greater = validate.flag(compare, "PWM_CONTROL(3) GT/LT flag", allowed="1 (GT) or 0 (LT)")
        first_state = on_off(state, "PWM_CONTROL(3) ON/OFF")
        size = len(self.table_memory)
        bounds = f"0..{size - 1} (TABLE size {size})"
        first = validate.integer(start, "PWM_CONTROL(3) table start", low=0, high=size - 1, allowed=bounds, whole=True)
        last = validate.integer(end, "PWM_CONTROL(3) table end", low=0, high=size - 1, allowed=bounds, whole=True)
        validate.integer(last, "PWM_CONTROL(3) table end", low=first, allowed=f">= table start {first}")
        validate.integer(last - first + 1, "PWM_CONTROL(3) positions in one load", low=1, high=FIFO_DEPTH,
                         allowed=f"1..{FIFO_DEPTH} (the FIFO depth)")
        half = PWM_ENCODER_MODULUS // 2
        for k in range(first, last + 1):  # a compare position must fit the 29-bit register, signed
            validate.in_range(self.table_memory[k] * ax.units, f"PWM_CONTROL(3) position TABLE({k}) x UNITS",
                              low=-half, high=half, high_open=True,
                              allowed=f"-{half} <= counts < {half} (a signed 29-bit compare)")
        return toggled_entries(self.table_memory[first:last + 1], ax.units, greater=greater, first_state=first_state)

    def _gate(self, axis: int, what: str) -> GateFifo:
        gate = self.axes[axis].gate
        if gate is None:
            raise ConfigurationError.out_of_range(f"{what} axis", axis, pwm_axes())
        return gate

    def pwm(self, axis: int) -> PwmGenerator:
        """The PWM generator of a PWM axis."""
        pwm = self.axis(axis).pwm
        if pwm is None:
            raise ConfigurationError.out_of_range("PWM axis", axis, pwm_axes())
        return pwm

    def gate(self, axis: int) -> GateFifo:
        """The gating FIFO of a PWM axis."""
        return self._gate(self.axis(axis).number, "gating FIFO")

    def pwm_port(self, axis: int = 3) -> PwmPort:
        """The outputs that modulate a laser from PWM axis ``axis`` (see :mod:`cosim.couplings.laser`).

        ``enable`` is WDOG, ``gate`` the gate latch, ``period_clocks`` PWM_CYCLE, ``mark_clocks``
        the mark (0 while PWM is off), ``phase_clocks`` the clock count the carrier starts at; the
        clock is the 20 MHz PWM clock.
        """
        pwm, gate = self.pwm(axis), self.gate(axis)
        return PwmPort(enable=self.wdog.signal, gate=gate.output.signal, period_clocks=pwm.cycle_out.signal,
                       mark_clocks=pwm.mark_out.signal, phase_clocks=pwm.phase_out, clock_hz=Fraction(PWM_CLOCK_HZ))

    def step_dir(self, axis: int) -> StepDirPort:
        """The step/direction output of ``axis`` (pulses while ATYPE is 1 or 35).

        The port's ``active_delay`` is the step pulse width: a drive counts each pulse at its active
        (trailing) edge, as the controller does. Taking the port marks the axis as driving a plant:
        a move on it while ATYPE = 0 (no pulses) is then an error.
        """
        ax = self.axis(axis)
        self.wired.add(ax.number)
        step, direction = ax.ensure_outputs()
        return StepDirPort(step, direction, active_delay=self.pulse_width_ticks)

    # -- digital I/O, channels, flags ----------------------------------------------------------------
    def read_input(self, channel: object) -> int:
        """An input as a program sees it (1 ON, 0 OFF), INVERT_IN applied."""
        return self.io.read_input(channel)

    def read_input_signal(self, axis: int) -> Signal:
        """The registration input of ``axis`` (digital input ``regist_inputs[axis]``, by default the axis number)."""
        return self.io.input(self.regist_inputs.get(axis, axis))

    def channel(self, number: object) -> Channel:
        """Communication channel ``number`` (0..255): PRINT #n writes to the console, INPUT/GET #n read what
        :meth:`Channel.feed` gave it."""
        n = validate.integer(number, "channel", low=0, high=255, whole=True)
        if n not in self.channels:
            self.channels[n] = Channel(self.sim, n)
        return self.channels[n]

    def flag(self, number: object) -> int:
        """``FLAG(n)``: one of the 32 flags (1 or 0)."""
        n = validate.integer(number, "FLAG number", low=0, high=31, whole=True)
        return (self.flags >> n) & 1

    def set_flag(self, number: object, state: object) -> None:
        """``FLAG(n, ON/OFF)``."""
        n = validate.integer(number, "FLAG number", low=0, high=31, whole=True)
        self.flags = self.flags | (1 << n) if on_off(state, "FLAG state") else self.flags & ~(1 << n)

    def set_flags(self, value: object) -> None:
        """``FLAGS(value)``: all 32 flags at once."""
        self.flags = validate.integer(value, "FLAGS value", low=0, high=(1 << 32) - 1, whole=True)

    def clear_vr(self) -> None:
        """``CLEAR``: every VR back to 0."""
        self.vr_memory[:] = [0] * len(self.vr_memory)

    def trigger(self, *, origin: str = "") -> None:
        """``TRIGGER``: a marker in the trace (``trio.trigger`` counts them; on the controller it starts the
        SCOPE capture, which is not modelled)."""
        if self._trigger is None:
            self._trigger = Signal(self.sim, f"{self.device}.trigger", kind="int",
                                   description="TRIGGER commands so far (a marker: the SCOPE start)")
        self._trigger.set(self._trigger.value + 1)

    def analog_input(self, channel: object, *, where: str = "") -> int:
        """``AIN(n)``: not modelled: 0, listed in the notes."""
        self.sim.notes.not_modelled(self.device, f"AIN({channel})", 0, where=where)
        return 0

    def motion_error(self) -> int:
        """``MOTION_ERROR``: 1 while an axis has a motion error (a following error beyond FE_LIMIT)."""
        return int(any(axis.fe_exceeded for axis in self.axes.values()))

    def input(self, channel: object) -> Signal:
        """The signal of digital input ``channel`` (``trio.in.N``): drive it to feed ``IN(n)``."""
        return self.io.input(channel)

    def output(self, channel: object) -> Signal:
        """The signal of digital output ``channel`` (``trio.op.N``), set by ``OP(n, ON/OFF)``."""
        return self.io.output(channel)

    def outputs(self) -> list[Signal | PulseTrain]:
        """Every signal the controller drives (:class:`cosim.controllers.Controller`)."""
        out: list[Signal | PulseTrain] = [self.wdog.signal]
        for ax in self.axes.values():
            out += [s for s in (ax.step, ax.dir) if s is not None]
            if ax.pwm is not None and ax.gate is not None:
                out += [ax.gate.output.signal, ax.pwm.cycle_out.signal, ax.pwm.mark_out.signal, ax.pwm.phase_out]
        return out + self.io.outputs()

    def inputs(self) -> list[Signal]:
        """Every signal the controller reads: the digital inputs ``trio.in.0`` .. ``trio.in.31`` and the Z markers
        ``trio.axisN.z_mark`` in use (:meth:`Axis.ensure_z_mark`).

        Input signals are created on first use (a program creates those its ``IN(n)`` names when it
        starts; :meth:`input` creates one), so a trace holds only the inputs in use; asking for all
        of them here creates them all.
        """
        return [self.io.input(n) for n in range(self.io.channels)] + [
            a.z_mark for a in self.axes.values() if a.z_mark is not None]
