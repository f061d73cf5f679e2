"""The PoKeys pulse engine as a SimPy process in integer time.

Time is cut into 1 ms slots starting at ``t0_ns``. At every slot start (priority SLOT) the engine

1. reads the switch inputs (:mod:`~cosim.controllers.pokeys.switches`);
2. stops at once if the enabled emergency input or an enabled limit switch is tripped (limits
   are ignored while jogging): state 101 / 100, no pulses from this slot on (hard stop);
3. otherwise takes the slot's pulse counts - from the slot buffer in buffer and internal modes
   (the internal controller produces its slots into the same buffer, ``internal_lookahead_slots``
   ahead), straight from the speed controller when jogging, from the homing sequence when homing -
   and emits them: per axis one pulse-train segment, pulse k at
   ``slot_start + dir_setup_ns + (k * 1 ms) // count``; the direction output changes at the slot start;
4. adds the slot's counts to the position counters (so the counters always equal the pulses
   committed up to the end of the running slot) and records positions, buffer level, states.

A buffer slot is used in the slot that starts when it is taken. Commands from the host (fill,
clear, state changes, moves) act at once on the buffer and the state; the slot that is running
has already been committed and finishes.

An empty buffer in buffer mode emits no pulses; while a job is marked active
(:meth:`PulseEngine.mark_job`) such slots are recorded as an underrun.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Sequence
from fractions import Fraction
from typing import Any

from cosim.controllers.pokeys.buffer import SlotBuffer, check_entry, encode_entry
from cosim.controllers.pokeys.config import SLOTS_PER_S, EngineConfig
from cosim.controllers.pokeys.homing import HomingAxis
from cosim.controllers.pokeys.limits import (
    AXES,
    BUFFER_SLOTS,
    COUNT_MASK,
    DIRECTION_BIT,
    MAX_PULSES_PER_SLOT,
    SLOT_NS,
    check_axis,
    check_int_range,
    check_rate_hz,
    check_slot_count,
)
from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits
from cosim.controllers.pokeys.records import FillReply, Register, Status, Underrun
from cosim.controllers.pokeys.states import AxisState, EngineState
from cosim.controllers.pokeys.switches import SwitchInputs, SwitchSample
from cosim.errors import ConfigurationError
from cosim.kernel import At, Simulation
from cosim.signals import PulseTrain, Signal, StepDirPort, SwitchPort
from cosim.timebase import Priority

HOST_SETTABLE = (EngineState.STOPPED, EngineState.INTERNAL, EngineState.BUFFER, EngineState.JOGGING)


class PulseEngine:
    """Three-axis PoKeys pulse engine.

    Parameters
    ----------
    sim : Simulation
    config : EngineConfig, optional
    name : str
        Device prefix of every signal (``pokeys``).
    t0_ns : int, optional
        Start of slot 0 [ns] (default: now).

    Attributes
    ----------
    steps : list of PulseTrain
        ``<name>.<axis>.step``: one segment per slot with pulses; a plant subscribes to these.
    dirs : list of Signal
        ``<name>.<axis>.dir`` direction outputs (1 = activated = negative, unless inverted).
    positions : list of Register
        ``<name>.<axis>.position`` counters [pulses].
    buffer_level : Register
        ``<name>.buffer_level``: queued slots.
    switches : SwitchInputs
        The limit, home and emergency inputs.
    underruns : list of Underrun
        Closed underruns (see :attr:`all_underruns` for one still running).
    """

    def __init__(self, sim: Simulation, config: EngineConfig | None = None, *, name: str = "pokeys",
                 t0_ns: int | None = None) -> None:
        self.sim = sim
        self.config = config or EngineConfig()
        self.name = name
        self.t0_ns = sim.now if t0_ns is None else sim.timebase.check_ticks(t0_ns, name="t0_ns")
        cfg = self.config
        self.buffer = SlotBuffer(BUFFER_SLOTS)
        self.steps = [PulseTrain(sim, f"{name}.{a}.step", pulse_width=cfg.pulse_width_ns,
                                 description=f"step output {a}") for a in AXES]
        self.dirs = [Signal(sim, f"{name}.{a}.dir", initial=int(cfg.axes[i].invert_direction),
                            description=f"direction output {a} (1 = activated)") for i, a in enumerate(AXES)]
        self.positions = [Register(sim, f"{name}.{a}.position", unit="pulses", description=f"position counter {a}")
                          for a in AXES]
        self.axis_state_signals = [Signal(sim, f"{name}.{a}.axis_state", kind="int",
                                          description=f"axis state {a} (AxisState codes)") for a in AXES]
        self.switches = SwitchInputs(sim, cfg, name=name)
        self.state_signal = Signal(sim, f"{name}.state", kind="int", description="engine state (EngineState codes)")
        self.buffer_level = Register(sim, f"{name}.buffer_level", unit="slots",
                                     description="queued slots in the 128-slot buffer")
        self.underrun = Signal(sim, f"{name}.underrun", description="1 while the buffer runs empty during a job")
        self.underruns: list[Underrun] = []
        self.slot_index = 0
        self.job_active = False
        self._pos = [0, 0, 0]
        self._dir_bit = [False, False, False]
        self._state = EngineState.STOPPED
        self._axis_states = [AxisState.STOPPED] * 3
        self._sample = SwitchSample(0, 0, 0, False)
        self._underrun_start: int | None = None
        self._underrun_slots = 0
        self._limits = [SlotLimits.exact(a.max_speed_per_slot, a.accel_per_slot2, a.decel_per_slot2)
                        for a in cfg.axes]
        self._motions = [AxisMotion(lim) for lim in self._limits]
        self._homing: dict[int, HomingAxis] = {}
        self._setup = cfg.dir_setup_ns
        self._emitters = [train.emit for train in self.steps]
        self._pos_setters = [register.set for register in self.positions]
        sim.process(self.pulse_slot())

    # -- host commands ------------------------------------------------------------------------
    @property
    def state(self) -> EngineState:
        """Current engine state."""
        return self._state

    @property
    def free_slots(self) -> int:
        """Free space in the slot buffer (free-space query)."""
        return self.buffer.free

    def status(self) -> Status:
        """Status now: positions, engine state, switch states, axis states."""
        s = self._sample
        return Status(tuple(self._pos), self._state, s.limit_pos, s.limit_neg, s.home, s.emergency,
                      tuple(self._axis_states), self.buffer.free)

    def fill_buffer(self, entries: Sequence[object]) -> FillReply:
        """Fill-buffer command: queue as many of ``entries`` as fit, in order.

        Parameters
        ----------
        entries : sequence
            Slot entries, each 3 bytes (x, y, z; 7-bit count plus direction bit) or 3 signed counts.

        Returns
        -------
        FillReply
            Accepted count (advance the host's read pointer by this only) and the status.

        Raises
        ------
        ConfigurationError
            If an entry has more than 25 pulses on an axis or a count that does not fit 7 bits.
        """
        checked: list[bytes] = []
        for i, entry in enumerate(entries):
            raw = entry if type(entry) is bytes and len(entry) == 3 else check_entry(
                entry, where=f"fill_buffer slot {i}")
            if (raw[0] & COUNT_MASK) > MAX_PULSES_PER_SLOT or (raw[1] & COUNT_MASK) > MAX_PULSES_PER_SLOT or (
                    raw[2] & COUNT_MASK) > MAX_PULSES_PER_SLOT:
                for a, byte in enumerate(raw):
                    if byte & COUNT_MASK > MAX_PULSES_PER_SLOT:
                        check_slot_count(_signed(byte), where=f"fill_buffer slot {i} axis {AXES[a]}")
            checked.append(raw)
        accepted = self.buffer.fill(checked)
        self.buffer_level.set(self.buffer.level)
        return FillReply(accepted, self.status())

    def clear_buffer(self) -> int:
        """Clear-buffer command: drop every queued slot; returns how many were dropped."""
        dropped = self.buffer.clear()
        self.buffer_level.set(0)
        return dropped

    def set_state(self, state: EngineState | int) -> None:
        """Set the engine state (0 stopped, 1 internal, 2 buffer, 10 jogging) from the next slot on.

        Leaving a mode stops its controller at once; the buffer is left as it is (slots the
        internal controller queued are still there: clear the buffer or let them run out first).
        """
        try:
            new = EngineState(state)
        except ValueError:
            new = None
        if new not in HOST_SETTABLE:
            raise ConfigurationError.out_of_range("engine state", state, "0 stopped, 1 internal, 2 buffer, 10 jogging")
        assert new is not None
        self._homing.clear()
        for i, motion in enumerate(self._motions):
            motion.halt()
            motion.reset_position(self._pos[i] + (self._queued(i) if new == EngineState.INTERNAL else 0))
        self._set_state(new)
        if new != EngineState.BUFFER:
            self._close_underrun()

    def mark_job(self, active: bool) -> None:
        """Tell the engine a host job is running (an empty buffer in buffer mode is then an underrun)."""
        self.job_active = active
        if not active:
            self._close_underrun()

    def set_position(self, axis: int, position: int) -> None:
        """Set the position counter of ``axis`` (0..2) [pulses]."""
        check_axis(axis, where="set_position")
        self._pos[axis] = int(position)
        self.positions[axis].set(self._pos[axis])
        self._motions[axis].reset_position(self._pos[axis] + self._queued(axis))

    def move_to(self, targets: Sequence[int | None]) -> None:
        """Internal position control: move each axis to its target [pulses] (None: leave it)."""
        def apply(axis: int, value: object) -> None:
            target = check_int_range(value, "target position", -(2**31), 2**31 - 1, "pulses",
                                     where=f"move_to axis {AXES[axis]}")
            self._motions[axis].move_to(target)

        self._internal(targets, "move_to", apply)

    def run_at(self, speeds_hz: Sequence[int | Fraction | float | None]) -> None:
        """Internal speed control: run each axis at a signed speed [pulses/s] (None: leave it).

        Speeds are limited to the axis' maximum speed; more than 25 kHz is refused.
        """
        def apply(axis: int, value: object) -> None:
            self._motions[axis].run_at(self._clamped_per_slot(axis, value, "run_at"))

        self._internal(speeds_hz, "run_at", apply)

    def jog(self, axis: int, speed_hz: int | Fraction | float) -> None:
        """Jogging: run ``axis`` at a signed speed [pulses/s] with the speed controller, limits ignored."""
        check_axis(axis, where="jog")
        per_slot = self._clamped_per_slot(axis, speed_hz, "jog")
        if self._state != EngineState.JOGGING:
            self.set_state(EngineState.JOGGING)
        self._motions[axis].run_at(per_slot)

    def start_homing(self, axes: Sequence[int] = (0, 1, 2)) -> None:
        """Home the given axes (0..2) as the document describes (see :mod:`.homing`)."""
        if self._state.is_error:
            raise ConfigurationError.out_of_range("engine state for homing", int(self._state),
                                                  "not 100/101 (set state 0 first)")
        chosen = sorted({check_axis(a, where="start_homing") for a in axes})
        for a in chosen:
            if not self.config.axes[a].home_enabled:
                raise ConfigurationError.out_of_range(f"home switch of axis {AXES[a]} enabled", False, "True",
                                                      where="start_homing")
        self.set_state(EngineState.STOPPED)
        cfg = self.config
        for a in chosen:
            vmax = self.config.axes[a].max_speed_per_slot
            self._homing[a] = HomingAxis(vmax * cfg.homing_speed_pct / 100, vmax * cfg.homing_return_pct / 100,
                                         toward_negative=not cfg.axes[a].invert_homing)
            self._set_axis_state(a, AxisState.HOMING_START)
        self._set_state(EngineState.HOMING)

    @property
    def all_underruns(self) -> list[Underrun]:
        """Underruns so far, including one still running (its length up to the current slot's end)."""
        if self._underrun_start is None:
            return list(self.underruns)
        return [*self.underruns, Underrun(self._underrun_start, self._underrun_slots * SLOT_NS)]

    # -- ports and the controller protocol -------------------------------------------------------
    def step_dir(self, axis: int) -> StepDirPort:
        """The step/direction output of ``axis`` (0..2); reversed when its direction is inverted."""
        check_axis(axis, where="step_dir")
        return StepDirPort(self.steps[axis], self.dirs[axis], reversed=self.config.axes[axis].invert_direction)

    def switch_port(self, axis: int) -> SwitchPort:
        """The limit and home inputs of ``axis`` (0..2)."""
        check_axis(axis, where="switch_port")
        sw = self.switches
        return SwitchPort(limit_pos=sw.limit_pos[axis], limit_neg=sw.limit_neg[axis], home=sw.home[axis])

    def outputs(self) -> list[Signal | PulseTrain]:
        """Every signal the engine drives: step and direction outputs (:class:`cosim.controllers.Controller`)."""
        return [*self.steps, *self.dirs]

    def inputs(self) -> list[Signal]:
        """Every signal the engine reads: limit, home and emergency inputs."""
        sw = self.switches
        return [*sw.limit_pos, *sw.limit_neg, *sw.home, sw.emergency]

    # -- the slot process ---------------------------------------------------------------------
    def pulse_slot(self) -> Generator[Any, Any, None]:
        """SimPy process: one pass of :meth:`run_slot` at every slot start.

        Slots in a row with nothing else due in between run without a kernel event each
        (:meth:`~cosim.kernel.Simulation.skip_to`): same instants, same trace.
        """
        sim, env, t0 = self.sim, self.sim.env, self.t0_ns
        k = 0
        while True:
            yield At(env, t0 + k * SLOT_NS, Priority.SLOT)
            self.run_slot(t0 + k * SLOT_NS)
            k += 1
            while sim.skip_to(t0 + k * SLOT_NS):
                self.run_slot(t0 + k * SLOT_NS)
                k += 1

    def run_slot(self, t: int) -> None:
        """Everything the engine does at the slot start ``t`` [ns]."""
        self.slot_index += 1
        self._sample = sample = self.switches.sample()
        if sample.stop_candidate:
            self._evaluate_switches(sample)
        state = self._state
        if state is EngineState.BUFFER or state is EngineState.INTERNAL:
            entry = self.buffer.pop()
            if entry is None:
                if state is EngineState.BUFFER and self.job_active:
                    self._note_underrun(t)
                self._idle_axes()
            else:
                if self._underrun_start is not None:
                    self._close_underrun()
                self._emit_entry(t, entry)
            if state is EngineState.INTERNAL:
                self._produce()
            self.buffer_level.set(self.buffer.level, t)
        elif state is EngineState.JOGGING:
            self._emit_counts(t, [m.step() for m in self._motions])
        elif state is EngineState.HOMING:
            self._homing_slot(t, sample)

    def _evaluate_switches(self, sample: SwitchSample) -> None:
        if self.switches.emergency_tripped(sample):
            if self._state != EngineState.STOP_EMERGENCY:
                self._hard_stop(EngineState.STOP_EMERGENCY, [])
            return
        if self._state == EngineState.JOGGING or self._state.is_error:
            return
        tripped = self.switches.enabled_limits_tripped(sample)
        if tripped:
            self._hard_stop(EngineState.STOP_LIMIT, tripped)

    def _hard_stop(self, state: EngineState, limit_axes: list[int]) -> None:
        self._homing.clear()
        for motion in self._motions:
            motion.halt()
        self._close_underrun()
        for a in range(3):
            self._set_axis_state(a, AxisState.LIMIT if a in limit_axes else AxisState.ERROR)
        self._set_state(state)

    # -- emitting -----------------------------------------------------------------------------
    def _emit_entry(self, t: int, entry: bytes) -> None:
        """The buffer path of :meth:`_emit_axis` for all three axes, inlined (it runs every slot)."""
        states, dir_bit, pos, t_pulse = self._axis_states, self._dir_bit, self._pos, t + self._setup
        for a, byte in enumerate(entry):
            negative = byte >= DIRECTION_BIT
            if negative is not dir_bit[a]:
                dir_bit[a] = negative
                self.dirs[a].set(negative != self.config.axes[a].invert_direction)
            count = byte & COUNT_MASK
            if count:
                self._emitters[a](t_pulse, SLOT_NS, count, 0 if negative else 1)
                pos[a] += -count if negative else count
                self._pos_setters[a](pos[a], t)
                if states[a] is not AxisState.RUNNING:
                    self._set_axis_state(a, AxisState.RUNNING)
            elif states[a] is not AxisState.READY:
                self._set_axis_state(a, AxisState.READY)

    def _emit_counts(self, t: int, counts: Sequence[int], *, track_states: bool = True) -> None:
        for a, count in enumerate(counts):
            self._emit_axis(a, t, abs(count), count < 0 if count else self._dir_bit[a])
            if track_states:
                self._set_axis_state(a, AxisState.RUNNING if count else AxisState.READY)

    def _emit_axis(self, a: int, t: int, count: int, negative: bool) -> None:
        """Direction output at the slot start, then ``count`` pulses spread over the slot."""
        if negative is not self._dir_bit[a]:
            self._dir_bit[a] = negative
            self.dirs[a].set(negative != self.config.axes[a].invert_direction)
        if count:
            self.steps[a].emit(t + self._setup, SLOT_NS, count, 0 if negative else 1)
            position = self._pos[a] = self._pos[a] + (-count if negative else count)
            self.positions[a].set(position, t)

    def _idle_axes(self) -> None:
        for a in range(3):
            self._set_axis_state(a, AxisState.READY)

    # -- internal controller and homing --------------------------------------------------------
    def _internal(self, values: Sequence[object], what: str, apply: Callable[[int, object], None]) -> None:
        if self._state.is_error:
            raise ConfigurationError.out_of_range(f"engine state for {what}", int(self._state),
                                                  "not 100/101 (set state 0 first)")
        if len(values) != 3:
            raise ConfigurationError.out_of_range(f"{what} values", len(values), "3 (x, y, z; None to leave)")
        if self._state != EngineState.INTERNAL:
            self.set_state(EngineState.INTERNAL)
        for a, value in enumerate(values):
            if value is not None:
                apply(a, value)
        self._produce()
        self.buffer_level.set(self.buffer.level)

    def _produce(self) -> None:
        """Top the buffer up to the look-ahead with the internal controller's slots."""
        room = self.config.internal_lookahead_slots - self.buffer.level
        motions = self._motions
        while room > 0 and not all(m.done for m in motions):
            counts = [m.step() for m in motions]
            self.buffer.fill([encode_entry(counts, negative=[m.v < 0 for m in motions])])
            room -= 1

    def _homing_slot(self, t: int, sample: SwitchSample) -> None:
        counts = [0, 0, 0]
        for a, homing in self._homing.items():
            count, reset = homing.step(sample.home_tripped(a))
            counts[a] = count
            if reset:
                self._pos[a] = 0
                self.positions[a].set(0)
        self._emit_counts(t, counts, track_states=False)
        for a, homing in self._homing.items():
            self._set_axis_state(a, homing.phase)
        if all(h.done for h in self._homing.values()):
            self._set_state(EngineState.HOME)

    def _clamped_per_slot(self, axis: int, speed_hz: object, what: str) -> Fraction:
        rate = check_rate_hz(speed_hz, "speed_hz", signed=True, where=f"{what} axis {AXES[axis]}")
        vmax = self.config.axes[axis].max_speed_per_slot
        return max(-vmax, min(vmax, rate / SLOTS_PER_S))

    def _queued(self, axis: int) -> int:
        return sum(_signed(entry[axis]) for entry in self.buffer.peek_all())

    # -- bookkeeping --------------------------------------------------------------------------
    def _set_state(self, state: EngineState) -> None:
        self._state = state
        self.state_signal.set(int(state))
        if state == EngineState.STOPPED:
            for a in range(3):
                self._set_axis_state(a, AxisState.STOPPED)

    def _set_axis_state(self, axis: int, state: AxisState) -> None:
        if self._axis_states[axis] != state:
            self._axis_states[axis] = state
            self.axis_state_signals[axis].set(int(state))

    def _note_underrun(self, t: int) -> None:
        if self._underrun_start is None:
            self._underrun_start = t
            self._underrun_slots = 0
            self.underrun.set(1)
        self._underrun_slots += 1

    def _close_underrun(self) -> None:
        if self._underrun_start is not None:
            self.underruns.append(Underrun(self._underrun_start, self._underrun_slots * SLOT_NS))
            self._underrun_start = None
            self.underrun.set(0)


def _signed(byte: int) -> int:
    return -(byte & COUNT_MASK) if byte & DIRECTION_BIT else byte & COUNT_MASK
