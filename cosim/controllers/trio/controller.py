"""The Trio EURO205X Motion Coordinator: servo cycle, parameters, TABLE, VR, I/O and commands.

:class:`TrioController` owns the axes, TABLE and VR memory, the digital I/O, the console and WDOG,
and runs the servo cycle as a SimPy process at ``k * SERVO_PERIOD`` (priority SERVO). Each servo
tick, in this order:

1. latch MPOS of every axis (the pulses counted so far);
2. move waiting ``PWM_CONTROL(3)`` loads into FIFOs that now have room;
3. end moves whose last cycle was output; load buffered moves whose axes are free (:mod:`.buffer`);
4. run one cycle of every move (a requested CANCEL first): demand positions, VP_SPEED, step
   pulses (:mod:`.motion`);
5. apply pending DEFPOS offsets (after loading moves: a move issued right after DEFPOS is
   loaded before the new position applies, as the Trio manual warns; ``WAIT UNTIL OFFPOS=0``);
6. update speed-linked PWM marks from VP_SPEED of their link axis;
7. check FE_LIMIT, record DPOS, MPOS, VP_SPEED, then release programs waiting for move-buffer
   space, for idle axes or for an empty next-move buffer.

Commands come from programs (:class:`TrioProcess`, the BASIC interpreter); they take effect at
the instant they are given, in zero simulated time. Moves are buffered one deep per axis (the
running move and one more); a further move makes its program wait.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from simpy.events import Event

from cosim import validate
from cosim.controllers.trio.buffer import MoveBuffers
from cosim.controllers.trio.gate import GateFifo, toggled_entries
from cosim.controllers.trio.io import Console, DigitalIo
from cosim.controllers.trio.axis import Axis
from cosim.controllers.trio.motion import Move
from cosim.controllers.trio.outputs import SettledSignal
from cosim.controllers.trio.params import (
    ATYPE_STEPPER_PWM,
    ATYPE_VIRTUAL,
    STEPPER_ATYPES,
    AXIS_PARAMS,
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
    READ_ONLY_AXIS_PARAMS,
    SYSTEM_PARAMS,
    check_servo_period_us,
    on_off,
    unknown_name,
)
from cosim.controllers.trio.paths import ArcPath
from cosim.controllers.trio.pwm import PwmGenerator, PwmMode, SpeedLink
from cosim.controllers.trio.pwm_output import PwmOutput
from cosim.controllers.trio.servo import ServoLoop
from cosim.errors import ConfigurationError, TimingViolation
from cosim.kernel import Simulation
from cosim.signals import PulseTrain, PwmPort, Signal, StepDirPort
from cosim.timebase import Priority

#: Arguments each PWM_CONTROL mode takes after the mode.
PWM_CONTROL_ARGS = {0: (), 1: (), 2: ("multiplier", "offset", "limit value", "link axis"),
                    3: ("GT/LT", "ON/OFF", "table start", "table end"), 4: (), 5: (), 6: ()}


class TrioController:
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
        self._gates = [ax.gate for ax in self.axes.values() if ax.gate is not None]
        self._pwms = [ax.pwm for ax in self.axes.values() if ax.pwm is not None]
        #: Running programs by process number, and the programs RUN can start by name.
        self.processes: dict[int, Any] = {}
        self.programs: dict[str, Any] = {}
        self.wired: set[int] = set()
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
        for gate in self._gates:
            if gate.has_waiting:
                return False
        return True

    def _tick(self) -> None:
        now = self.sim.now
        awake = [axis for axis in self.axes.values() if not axis.quiet]
        for axis in awake:
            axis.sample_mpos(now)
        for gate in self._gates:
            if gate.has_waiting:
                gate.retry_waiting()
        buffers = self.buffers
        if buffers.pending:
            buffers.load(now)
        buffers.run_cycle(now, self.period_ticks, self.period_s)
        for axis in awake:
            axis.apply_offset()
        for pwm in self._pwms:
            link = pwm.link
            if link is not None:
                link_axis = self.axes[link.link_axis]
                pwm.servo_update_ratio(link_axis.vnum, link_axis.vden)
        for axis in awake:
            params = axis.params
            if params["SERVO"] and params["ATYPE"] in STEPPER_ATYPES and axis.following_error_exceeds():
                self._following_error(axis)
            axis.record()
            axis.settle(now)
        buffers.release()

    def _following_error(self, axis: Axis) -> None:
        error = axis.dpos - axis.mpos_sampled
        origin = f"{axis.current.origin}: " if axis.current is not None and axis.current.origin else ""
        raise TimingViolation(
            f"{origin}{axis.prefix}: following error {float(error):g} units exceeds FE_LIMIT = "
            f"{float(axis.params['FE_LIMIT']):g} at t = {self.sim.now} ns (the controller stops with a "
            "motion error)")

    # -- axes and parameters ------------------------------------------------------------------
    def axis(self, number: object, *, where: str = "") -> Axis:
        """Axis ``number`` (ConfigurationError naming the allowed axes if there is none)."""
        return self.axes[validate.integer(number, "axis", low=0, high=len(self.axes) - 1, where=where, whole=True)]

    def set_param(self, name: str, value: object, *, axis: int | None = None) -> None:
        """Write parameter ``name`` (vendor name) of ``axis`` (or a controller parameter)."""
        self.servo.wake()
        key = name.upper()
        if key == "WDOG":
            self.wdog.request(on_off(value, "WDOG"))
            return
        if key in SYSTEM_PARAMS or key in READ_ONLY_AXIS_PARAMS:
            hint = " (use DEFPOS)" if key in ("DPOS", "MPOS") else ""
            raise ConfigurationError(f"{key} is read-only{hint}")
        if key not in AXIS_PARAMS:
            raise ConfigurationError(unknown_name(key))
        spec = AXIS_PARAMS[key]
        ax = self.axis(0 if axis is None else axis)
        if spec.pwm_only and not ax.has_pwm:
            raise ConfigurationError.out_of_range(f"axis of {key}", ax.number, _pwm_axes())
        converted = spec.convert(value, key, "")
        if key == "ATYPE" and converted == ATYPE_STEPPER_PWM and not ax.has_pwm:
            raise ConfigurationError.out_of_range(f"axis of ATYPE={ATYPE_STEPPER_PWM}", ax.number, _pwm_axes())
        was_stepper = ax.stepper
        ax.quiet = False
        old = ax.params[key]
        ax.params[key] = converted
        if key == "ATYPE" and ax.stepper and not was_stepper:
            ax.became_stepper()
        if key == "ATYPE" and converted == ATYPE_STEPPER_PWM and old != ATYPE_STEPPER_PWM:
            assert ax.gate is not None
            raw = (int(self.sim.rng.integers(0, PWM_ENCODER_MODULUS)) if self.encoder_at_atype is None
                   else self.encoder_at_atype)
            ax.gate.preset_encoder(raw)
        elif key == "INVERT_STEP":
            ax.set_invert_step(int(converted))
        elif key == "PWM_CYCLE":
            assert ax.pwm is not None
            ax.pwm.set_cycle(int(converted))
        elif key == "PWM_MARK":
            assert ax.pwm is not None
            ax.pwm.set_mark(int(converted))

    def get_param(self, name: str, *, axis: int | None = None) -> Fraction:
        """Read parameter ``name`` of ``axis`` (or a controller parameter) now, exactly."""
        self.servo.sync()
        key = name.upper()
        if key == "WDOG":
            return Fraction(int(self.wdog.value))
        if key == "SERVO_PERIOD":
            return Fraction(self.servo_period_us)
        ax = self.axis(0 if axis is None else axis)
        if key in AXIS_PARAMS:
            if AXIS_PARAMS[key].pwm_only and not ax.has_pwm:
                raise ConfigurationError.out_of_range(f"axis of {key}", ax.number, _pwm_axes())
            return Fraction(ax.params[key])
        now = self.sim.now
        values: dict[str, Any] = {
            "DPOS": lambda: ax.dpos, "MPOS": lambda: ax.mpos_at(now), "VP_SPEED": lambda: ax.vp_speed,
            "OFFPOS": lambda: ax.offpos, "IDLE": lambda: -1 if ax.idle else 0,
            "LOADED": lambda: -1 if self.buffers.loaded((ax.number,)) else 0,
            "FE": lambda: ax.dpos - ax.mpos_at(now),
            "PWM_ENCODER": lambda: self._gate(ax.number, "PWM_ENCODER").encoder_value(),
        }
        if key not in values:
            raise ConfigurationError(unknown_name(key))
        return Fraction(values[key]())

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

    def set_vr(self, index: object, value: int | Fraction) -> None:
        """``VR(n) = value``: write a global variable (shared by every process)."""
        self.vr_memory[self._vr_index(index)] = value

    def _vr_index(self, index: object) -> int:
        return validate.integer(index, "VR index", low=0, high=len(self.vr_memory) - 1, whole=True)

    # -- motion commands ----------------------------------------------------------------------
    def defpos(self, axes: Sequence[int], positions: Sequence[object]) -> None:
        """``DEFPOS(p1, ...)`` for ``axes``: applied by the next servo cycle (see OFFPOS)."""
        self.servo.wake()
        _check_count("DEFPOS", positions, axes)
        for a, p in zip(axes, positions, strict=False):
            self.axis(a).defpos(validate.exact(p, "DEFPOS position"))

    def move(self, axes: Sequence[int], values: Sequence[object], *, absolute: bool, origin: str = "") -> Event:
        """``MOVE`` / ``MOVEABS`` on ``axes`` (the first is the base axis): an event once it is buffered."""
        self.servo.wake()
        command = "MOVEABS" if absolute else "MOVE"
        _check_count(command, values, axes)
        group = self._group(axes[:len(values)], command)
        move = Move(group, command, tuple(validate.exact(v, f"{command} value") for v in values), origin)
        return self.buffers.add(move)

    def movecirc(self, axes: Sequence[int], values: Sequence[object], *, origin: str = "") -> Event:
        """``MOVECIRC(end1, end2, centre1, centre2, direction)`` on the first two of ``axes``.

        End and centre are relative to the start [units]; direction 0 is anticlockwise, 1 clockwise.
        """
        self.servo.wake()
        if len(values) != 5:
            raise ConfigurationError.out_of_range("number of MOVECIRC values", len(values),
                                                  "5 (end1, end2, centre1, centre2, direction)")
        if len(axes) < 2:
            raise ConfigurationError.out_of_range("number of BASE axes for MOVECIRC", len(axes),
                                                  ">= 2 (the arc is in the plane of the first two)")
        group = self._group(axes[:2], "MOVECIRC")
        e1, e2, c1, c2 = (validate.exact(v, "MOVECIRC value") for v in values[:4])
        direction = int(validate.flag(values[4], "MOVECIRC direction", true=(1,), allowed="0 (anticlockwise) or "
                                      "1 (clockwise)"))
        path = ArcPath.plan((e1, e2), (c1, c2), clockwise=direction == 1, tolerance=1 / self.axes[group[0]].units)
        return self.buffers.add(Move(group, "MOVECIRC", (e1, e2, c1, c2, Fraction(direction)), origin, path=path))

    def forward(self, axis: int, *, reverse: bool = False, origin: str = "") -> Event:
        """``FORWARD`` / ``REVERSE``: a continuous move of ``axis`` at its SPEED until ``CANCEL``."""
        self.servo.wake()
        command = "REVERSE" if reverse else "FORWARD"
        return self.buffers.add(Move(self._group((axis,), command), command, (), origin))

    def _group(self, axes: Sequence[int], command: str) -> tuple[int, ...]:
        group = tuple(self.axis(a).number for a in axes)
        base = self.axes[group[0]]
        validate.positive(base.params["SPEED"], f"SPEED of axis {base.number} for {command}")
        for a in group:
            if a in self.wired and self.axes[a].params["ATYPE"] == ATYPE_VIRTUAL:
                raise ConfigurationError(
                    f"{command} on axis {a}: its step/direction output drives a plant, but ATYPE = 0 (virtual) "
                    "gives no step pulses (allowed: ATYPE = 1 or 35 before moving the axis)")
        return group

    def cancel(self, axes: Sequence[int]) -> None:
        """``CANCEL``: the running moves of ``axes`` decelerate at DECEL from the next servo tick."""
        self.servo.wake()
        self.buffers.cancel(tuple(self.axis(a).number for a in axes))

    def wait_idle(self, axes: Sequence[int]) -> Event:
        """An event that succeeds at the servo tick where every axis in ``axes`` is idle."""
        self.servo.sync()
        group = tuple(self.axis(a).number for a in axes)
        return self.buffers.wait(lambda: self.buffers.idle(group))

    def wait_loaded(self, axes: Sequence[int]) -> Event:
        """An event that succeeds at the servo tick where no move waits behind the running one on ``axes``."""
        self.servo.sync()
        group = tuple(self.axis(a).number for a in axes)
        return self.buffers.wait(lambda: self.buffers.loaded(group))

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
            raise ConfigurationError.out_of_range("PWM_CONTROL axis", ax.number, _pwm_axes())
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
            raise ConfigurationError.out_of_range(f"{what} axis", axis, _pwm_axes())
        return gate

    def pwm(self, axis: int) -> PwmGenerator:
        """The PWM generator of a PWM axis."""
        pwm = self.axis(axis).pwm
        if pwm is None:
            raise ConfigurationError.out_of_range("PWM axis", axis, _pwm_axes())
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

    # -- digital I/O ------------------------------------------------------------------------------
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
        """Every signal the controller reads: the digital inputs ``trio.in.0`` .. ``trio.in.31``.

        Input signals are created on first use (a program creates those its ``IN(n)`` names when it
        starts; :meth:`input` creates one), so a trace holds only the inputs in use; asking for all
        of them here creates them all.
        """
        return [self.io.input(n) for n in range(self.io.channels)]


def _pwm_axes() -> str:
    return ", ".join(map(str, PWM_AXES)) + " (the axes with the PWM feature)"


def _check_count(command: str, values: Sequence[object], axes: Sequence[int]) -> None:
    if not values or len(values) > len(axes):
        raise ConfigurationError.out_of_range(f"number of {command} values", len(values),
                                              f"1..{len(axes)} (one per BASE axis)")

