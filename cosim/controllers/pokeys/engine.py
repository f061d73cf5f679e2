"""The PoKeys pulse engine as a SimPy process in integer time.

Time is cut into 1 ms slots starting at ``t0``. Every period is derived once from the
simulation's resolution (``slot_ticks = sim.ticks(SLOT_NS, "ns")``, likewise the direction set-up
and the pulse width); a figure that is not a whole number of ticks is refused with the time
base's error. At every slot start (priority SLOT) the engine

1. reads the switch inputs (:mod:`~cosim.controllers.pokeys.switches`);
2. stops at once if the enabled emergency input or an enabled limit switch is tripped (limits
   are ignored while jogging): state 101 / 100, no pulses from this slot on (hard stop);
3. otherwise takes the slot's pulse counts - from the slot buffer in buffer and internal modes
   (the internal controller produces its slots into the same buffer, ``internal_lookahead_slots``
   ahead), straight from the speed controller when jogging, from the homing sequence when homing -
   and emits them: per axis one pulse-train segment, pulse k at
   ``slot_start + dir_setup + (k * slot) // count`` (floored to the resolution); the direction
   output changes at the slot start;
4. adds the slot's counts to the position counters (so the counters always equal the pulses
   committed up to the end of the running slot) and records positions, buffer level, states.

A buffer slot is used in the slot that starts when it is taken. Commands from the host (fill,
clear, state changes, moves) act at once on the buffer and the state; the slot that is running
has already been committed and finishes.

A fill with an entry the device model cannot emit (more pulses than its per-slot limit, or the
reserved x byte 0xFF of pulse engine v1) is refused as a whole: nothing of it is queued, the
refusal is recorded (:attr:`PulseEngine.refusals`, ``<name>.refused_fills``) and the Python API
raises :class:`~cosim.errors.ConfigurationError`; the virtual device answers it with 0 accepted.

An empty buffer in buffer mode emits no pulses. Underruns follow one rule
(:class:`~cosim.controllers.pokeys.records.Underrun`): empty slot starts in buffer mode after a slot
that took data, ended by a slot start that takes data again in buffer mode.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Sequence
from fractions import Fraction
from itertools import accumulate
from numbers import Integral
from operator import sub
from typing import Any

from cosim.controllers.pokeys.buffer import SlotBuffer, check_entry, encode_entry, signed_count
from cosim.controllers.pokeys.config import EngineConfig, rate_hz
from cosim.controllers.pokeys.homing import HomingAxis
from cosim.controllers.pokeys.limits import (
    BUFFER_SLOTS,
    COUNT_MASK,
    DIRECTION_BIT,
    SLOT_NS,
    SLOTS_PER_S,
    check_axis,
)
from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits
from cosim.controllers.pokeys.records import FillReply, Refusal, Register, Status, Underrun
from cosim.controllers.pokeys.states import AxisState, EngineState
from cosim.controllers.pokeys.switches import SwitchInputs, SwitchSample
from cosim.errors import ConfigurationError
from cosim.kernel import At, Simulation
from cosim.signals import PulseTrain, Signal, StepDirPort, SwitchPort
from cosim.timebase import Priority
from cosim.validate import integer

# States read on every slot, as module constants: reading an enum member (EngineState.BUFFER) costs several
# times a global on Python 3.11 (its EnumType has a __getattr__).
_BUFFER, _INTERNAL = EngineState.BUFFER, EngineState.INTERNAL
_JOGGING, _HOMING = EngineState.JOGGING, EngineState.HOMING
_RUNNING, _READY = AxisState.RUNNING, AxisState.READY

_BYTES_ONLY = {bytes}

HOST_SETTABLE = (EngineState.STOPPED, EngineState.INTERNAL, EngineState.BUFFER, EngineState.JOGGING)


def host_state(state: object) -> EngineState:
    """``state`` as one of the states a host may set (0 stopped, 1 internal, 2 buffer, 10 jogging), else raise."""
    try:
        new = EngineState(state)  # type: ignore[arg-type]  # any value: the enum refuses what is not a state
    except ValueError:
        new = None
    if new not in HOST_SETTABLE:
        raise ConfigurationError.out_of_range("engine state", state, "0 stopped, 1 internal, 2 buffer, 10 jogging")
    assert new is not None
    return new


class PulseEngine:
    """PoKeys pulse engine of any model (:mod:`.models`): 3 axes on the 56 series, up to 8 on the 57CNC.

    Parameters
    ----------
    sim : Simulation
    config : EngineConfig, optional
    name : str
        Device prefix of every signal (``pokeys``).
    t0 : int, optional
        Start of slot 0 [ticks] (default: now).
    pulse_train : callable, optional
        Class of the step outputs (default :class:`~cosim.signals.PulseTrain`: one segment per
        slot); called as ``pulse_train(sim, name, pulse_width=..., description=...)``.

    Attributes
    ----------
    axis_names : tuple of str
        The axes, index 0 first (x, y, z, ...).
    slot_ticks, dir_setup_ticks, pulse_width_ticks : int
        Slot length, direction set-up and pulse width [ticks of the simulation's resolution].
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
        Underruns so far (each recorded when data ends it).
    refusals : list of Refusal
        Fill commands refused for an entry the model cannot emit.
    """

    def __init__(self, sim: Simulation, config: EngineConfig | None = None, *, name: str = "pokeys",
                 t0: int | None = None, pulse_train: Callable[..., PulseTrain] = PulseTrain) -> None:
        self.sim = sim
        self.config = cfg = config or EngineConfig()
        self.device = cfg.device
        self.name = name
        self.t0 = sim.now if t0 is None else sim.timebase.check_ticks(t0, name="t0")
        self.slot_ticks = sim.ticks(SLOT_NS, "ns", name="slot length (1 ms)")
        self.pulse_width_ticks = sim.ticks(cfg.pulse_width_ns, "ns", name="pulse_width_ns")
        self.dir_setup_ticks = sim.ticks(cfg.dir_setup_ns, "ns", name="dir_setup_ns")
        n = len(cfg.axes)
        self.axis_names = names = self.device.axis_names
        self.buffer = SlotBuffer(BUFFER_SLOTS)
        # every slot start says which axes have pulses: the trains announce where their runs of segments end
        self.steps = [pulse_train(sim, f"{name}.{a}.step", pulse_width=self.pulse_width_ticks,
                                  description=f"step output {a}", announces_ends=True) for a in names]
        self.dirs = [Signal(sim, f"{name}.{a}.dir", initial=int(cfg.axes[i].invert_direction),
                            description=f"direction output {a} (1 = activated)") for i, a in enumerate(names)]
        self.positions = [Register(sim, f"{name}.{a}.position", unit="pulses", description=f"position counter {a}")
                          for a in names]
        self.axis_state_signals = [Signal(sim, f"{name}.{a}.axis_state", kind="int",
                                          description=f"axis state {a} (AxisState codes)") for a in names]
        self.switches = SwitchInputs(sim, cfg, name=name)
        self.host_inputs: list[Signal] = []  # inputs the host reads (a G-code job's M66 and cycle start)
        self.state_signal = Signal(sim, f"{name}.state", kind="int", description="engine state (EngineState codes)")
        self.buffer_level = Register(sim, f"{name}.buffer_level", unit="slots",
                                     description="queued slots in the 128-slot buffer")
        self.underrun = Register(sim, f"{name}.underrun", unit="", kind="bit",
                                 description="1 during the empty slots of an underrun (recorded when data ends it)")
        self.refused_fills = Register(sim, f"{name}.refused_fills", unit="fills",
                                      description="fill commands refused: an entry the device model cannot emit")
        self.underruns: list[Underrun] = []
        self.refusals: list[Refusal] = []
        self.slot_index = 0
        self._pos = [0] * n
        self._dir_bit = [False] * n
        self._state = EngineState.STOPPED
        self._axis_states = [AxisState.STOPPED] * n
        self._sample = SwitchSample(0, 0, 0, False)
        self._armed = False  # a buffer-mode slot took data since buffer mode began
        self._stretch_start: int | None = None
        self._stretch_slots = 0
        self._limits = self._slot_limits(cfg)
        self._motions = [AxisMotion(lim) for lim in self._limits]
        self._homing: dict[int, HomingAxis] = {}
        self._over_limit = tuple(b & COUNT_MASK > self.device.max_pulses_per_slot for b in range(256))
        self._emitters = [train.emit for train in self.steps]
        self._pos_setters = [register.set for register in self.positions]
        self._entry_plans: dict[bytes, tuple[tuple[int, bool, int, int, int], ...]] = {}
        self._accepted_entries: set[bytes] = set()  # entries (bytes of this engine's width) a fill has passed
        self._keys: dict[bytes, bytes] = {}  # entry -> direction bits and moving axes (see _run_slots)
        self._counts: dict[bytes, tuple[int, ...]] = {}  # entry -> pulses per axis
        self._masks: dict[bytes, int] = {}  # entry -> the axes with pulses (bit a: axis a)
        self._pulsing = 0  # the axes with pulses in the last slot (their trains' runs go on)
        self._last_key: bytes | None = None  # of the entry the last slot took (None: it took none)
        self._run_emitters = [train.emit_run for train in self.steps]
        self._register_extenders: dict[bytes, Callable[..., None]] = {}  # by run key: its registers at once
        #: The trace takes the position counters and the buffer level in runs (an exported FMU's outputs: not).
        self._registers_take_runs = all(sim.trace.takes_runs(r.name) for r in (*self.positions, self.buffer_level))
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

    def axis(self, axis: object, *, where: str = "") -> int:
        """``axis`` if it is an axis index of this engine (0..2 on a 56E), else ConfigurationError."""
        return check_axis(axis, where=where, count=len(self.axis_names))

    def status(self) -> Status:
        """Status now: positions, engine state, switch states, axis states, buffer, refusals."""
        s = self._sample
        return Status(tuple(self._pos), self._state, s.limit_pos, s.limit_neg, s.home, s.emergency,
                      tuple(self._axis_states), self.buffer.free, self.buffer.level, len(self.refusals))

    def fill_buffer(self, entries: Sequence[object]) -> FillReply:
        """Fill-buffer command: queue as many of ``entries`` as fit, in order.

        Parameters
        ----------
        entries : sequence
            Slot entries, each one byte per axis (7-bit count plus direction bit) or one signed
            count per axis.

        Returns
        -------
        FillReply
            Accepted count (advance the host's read pointer by this only) and the status.

        Raises
        ------
        ConfigurationError
            If an entry has more pulses on an axis than the model emits per slot (25 on a 56E),
            holds the reserved x byte 0xFF (pulse engine v1), or does not fit 7 bits. Nothing of
            the command is queued, and the refusal is recorded (:attr:`refusals`).
        """
        if (type(entries) is list and entries and set(map(type, entries)) == _BYTES_ONLY
                and self._accepted_entries.issuperset(entries)):  # every entry passed a fill before: valid
            accepted = self.buffer.fill(entries)
            self.buffer_level.set(self.buffer.level)
            return FillReply(accepted, self.status())
        n = len(self.axis_names)
        over, reserved, limit = self._over_limit, self.device.reserved_x_byte, self.device.max_pulses_per_slot
        checked: list[bytes] = []
        for i, entry in enumerate(entries):
            if type(entry) is bytes and len(entry) == n:
                raw = entry
            else:
                if isinstance(entry, Sequence) and not isinstance(entry, bytes | bytearray | str) and len(entry) == n:
                    for a, count in enumerate(entry):  # a count too large for an axis byte is over every limit
                        if isinstance(count, Integral) and not isinstance(count, bool) and abs(int(count)) > limit:
                            self._refuse(i, a, int(count))
                raw = check_entry(entry, axes=n, where=f"fill_buffer slot {i}")
            if raw[0] == reserved:
                self._refuse(i, 0, signed_count(raw[0]), reserved=True)
            if any(over[b] for b in raw):
                a = next(a for a, b in enumerate(raw) if over[b])
                self._refuse(i, a, signed_count(raw[a]))
            checked.append(raw)
        if len(self._accepted_entries) < 4096:  # (bounded: a job's distinct entries are few)
            self._accepted_entries.update(checked)
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
        new = host_state(state)
        self._homing.clear()
        for i, motion in enumerate(self._motions):
            motion.halt()
            motion.reset_position(self._pos[i] + (self._queued(i) if new == EngineState.INTERNAL else 0))
        self._set_state(new)

    def reconfigure(self, config: EngineConfig) -> None:
        """Give the running engine a new configuration (the host changed parameters or switch wiring).

        The model, the number of axes and the pulse width (the step outputs are declared with it)
        stay as built. The new switch enables, polarity and direction inversion act from now on
        (an inverted direction output changes at once); the internal controller restarts from rest
        at its committed position with the new limits, as after a state change; homing in progress
        keeps the speeds it started with.
        """
        if not isinstance(config, EngineConfig):
            raise ConfigurationError.out_of_range("config", config, "an EngineConfig")
        old = self.config
        for field_name in ("model", "pulse_width_ns"):
            if getattr(config, field_name) != getattr(old, field_name):
                raise ConfigurationError.out_of_range(
                    f"reconfigure {field_name}", getattr(config, field_name),
                    f"{getattr(old, field_name)!r} (fixed when the engine was built)")
        self.dir_setup_ticks = self.sim.ticks(config.dir_setup_ns, "ns", name="dir_setup_ns")
        self.config = config
        self.switches.reconfigure(config)
        self._limits = self._slot_limits(config)
        internal = self._state == EngineState.INTERNAL
        self._motions = [AxisMotion(lim, position=self._pos[a] + (self._queued(a) if internal else 0))
                         for a, lim in enumerate(self._limits)]
        for a, axis in enumerate(config.axes):
            self.dirs[a].set(int(self._dir_bit[a] != axis.invert_direction))

    def set_position(self, axis: int, position: int) -> None:
        """Set the position counter of ``axis`` [pulses]."""
        self.axis(axis, where="set_position")
        self._pos[axis] = integer(position, "position counter", low=-(2**31), high=2**31 - 1, unit="pulses",
                                  where="set_position")
        self.positions[axis].set(self._pos[axis])
        self._motions[axis].reset_position(self._pos[axis] + self._queued(axis))

    def move_to(self, targets: Sequence[int | None]) -> None:
        """Internal position control: move each axis to its target [pulses] (None: leave it)."""
        def apply(axis: int, value: object) -> None:
            target = integer(value, "target position", low=-(2**31), high=2**31 - 1, unit="pulses",
                             where=f"move_to axis {self.axis_names[axis]}")
            self._motions[axis].move_to(target)

        self._internal(targets, "move_to", apply)

    def run_at(self, speeds_hz: Sequence[int | Fraction | float | None]) -> None:
        """Internal speed control: run each axis at a signed speed [pulses/s] (None: leave it).

        Speeds are limited to the axis' maximum speed; more than the model's maximum is refused.
        """
        def apply(axis: int, value: object) -> None:
            self._motions[axis].run_at(self._clamped_per_slot(axis, value, "run_at"))

        self._internal(speeds_hz, "run_at", apply)

    def jog(self, axis: int, speed_hz: int | Fraction | float) -> None:
        """Jogging: run ``axis`` at a signed speed [pulses/s] with the speed controller, limits ignored."""
        self.axis(axis, where="jog")
        per_slot = self._clamped_per_slot(axis, speed_hz, "jog")
        if self._state != EngineState.JOGGING:
            self.set_state(EngineState.JOGGING)
        self._motions[axis].run_at(per_slot)

    def start_homing(self, axes: Sequence[int] | None = None) -> None:
        """Home the given axes (default: all) as the document describes (see :mod:`.homing`)."""
        if self._state.is_error:
            raise ConfigurationError.out_of_range("engine state for homing", int(self._state),
                                                  "not 100/101 (set state 0 first)")
        wanted = range(len(self.axis_names)) if axes is None else axes
        chosen = sorted({self.axis(a, where="start_homing") for a in wanted})
        cfg = self.config
        for a in chosen:
            if not cfg.axes[a].home_enabled:
                raise ConfigurationError.out_of_range(f"home switch of axis {self.axis_names[a]} enabled", False,
                                                      "True", where="start_homing")
        self.set_state(EngineState.STOPPED)
        for a in chosen:
            vmax = cfg.axes[a].max_speed_per_slot
            self._homing[a] = HomingAxis(vmax * cfg.homing_speed_pct / 100, vmax * cfg.homing_return_pct / 100,
                                         toward_negative=not cfg.axes[a].invert_homing, reset_at=cfg.homing_reset)
            self._set_axis_state(a, AxisState.HOMING_START)
        self._set_state(EngineState.HOMING)

    # -- ports and the controller protocol -------------------------------------------------------
    def step_dir(self, axis: int) -> StepDirPort:
        """The step/direction output of ``axis`` (0..n-1); reversed when its direction is inverted."""
        axis = self.axis(axis, where="step_dir")
        return StepDirPort(self.steps[axis], self.dirs[axis], reversed=self.config.axes[axis].invert_direction)

    def switch_port(self, axis: int) -> SwitchPort:
        """The limit and home inputs of ``axis`` (0..n-1)."""
        axis = self.axis(axis, where="switch_port")
        sw = self.switches
        return SwitchPort(limit_pos=sw.limit_pos[axis], limit_neg=sw.limit_neg[axis], home=sw.home[axis])

    def outputs(self) -> list[Signal | PulseTrain]:
        """Every signal the engine drives: step and direction outputs (:class:`cosim.controllers.Controller`)."""
        return [*self.steps, *self.dirs]

    def inputs(self) -> list[Signal]:
        """Every signal the engine reads: limit, home and emergency inputs (and those its host reads)."""
        sw = self.switches
        return [*sw.limit_pos, *sw.limit_neg, *sw.home, sw.emergency, *self.host_inputs]

    # -- the slot process ---------------------------------------------------------------------
    def pulse_slot(self) -> Generator[Any, Any, None]:
        """SimPy process: one pass of :meth:`run_slot` at every slot start.

        Slots in a row with nothing else due in between run without a kernel event each
        (:meth:`~cosim.kernel.Simulation.skip_to`): same instants, same trace. Where such slots take
        buffer entries that go on as the last slot did (:meth:`_run_slots`), they are emitted
        together, one pulse-train run per axis (:meth:`~cosim.signals.PulseTrain.emit_run`).
        """
        sim, env, t0, slot, switches = self.sim, self.sim.env, self.t0, self.slot_ticks, self.switches
        k = 0
        while True:
            yield At(env, t0 + k * slot, Priority.SLOT)
            t = t0 + k * slot
            if self._runs_ok() and not (sample := switches.sample()).stop_candidate:
                self._sample = sample
                free = sim.run_bound()  # this slot runs now whatever else is due at t (later priorities)
                done = self._run_slots(t, int(min(-(-(free - t) // slot), BUFFER_SLOTS)) if free > t else 1)
                if not done:
                    self.run_slot(t)
                k += done or 1
            else:
                self.run_slot(t)
                k += 1
            while True:
                t = t0 + k * slot
                if self._runs_ok():  # a run may pass quiet events (the host's own): they see nothing of it
                    free = sim.run_bound()
                    if free > t:
                        done = self._run_slots(t, int(min(-(-(free - t) // slot), BUFFER_SLOTS)))
                        if done:
                            k += done
                            continue
                if sim.free_until() <= t:
                    break  # something else is due first: wait for the slot's event
                sim.skip_to(t)
                self.run_slot(t)
                k += 1

    def _runs_ok(self) -> bool:
        """Can slots go as runs now: buffer mode, going on from a slot that took data, listeners that take runs."""
        if (self._state is not _BUFFER or self._stretch_start is not None or self._last_key is None
                or not self._registers_take_runs):
            return False
        for train in self.steps:
            if not train.takes_runs:
                return False
        return not self._sample.stop_candidate

    def _run_slots(self, t: int, most: int) -> int:
        """Run the slots starting at ``t``, ``t + slot``, ... (at most ``most``, nothing else due before the last)
        whose buffer entries go on as the last slot's did: the same direction bits, pulses on the same axes.

        Returns how many (0: none), the clock at the last one's start. The trace and the listeners see
        what :meth:`run_slot` at each slot start would have given them.
        """
        key, keys, counts_of = self._last_key, self._keys, self._counts
        if key is None:  # (_runs_ok: a run goes on from a slot that took data)
            return 0
        counts: list[tuple[int, ...]] = []
        for entry in self.buffer.peek(most):
            entry_key = keys.get(entry)
            if entry_key is None:
                self._entry_plan(entry)
                entry_key = keys[entry]
            if entry_key != key:
                break
            counts.append(counts_of[entry])
        n = len(counts)
        if not n:
            return 0
        sim = self.sim
        if t != sim.now:
            sim.skip_to(t)  # the first slot's start (nothing is due before the last one's)
        self.buffer.drop(n)
        self.slot_index += n
        slot, setup = self.slot_ticks, self.dir_setup_ticks
        times = range(t, t + n * slot, slot)
        pos, emitters, registers = self._pos, self._run_emitters, self.positions
        names: list[int] = []
        columns: list[Sequence[int]] = []
        by_axis = list(zip(*counts, strict=True))  # the counts of the run's slots, axis by axis
        for a, moving in enumerate(key):
            if moving & 1:
                column = list(by_axis[a])
                if moving >= DIRECTION_BIT:
                    emitters[a](t + setup, slot, column, 0, setup)
                    positions = list(accumulate(column, sub, initial=pos[a]))
                else:
                    emitters[a](t + setup, slot, column, 1, setup)
                    positions = list(accumulate(column, initial=pos[a]))
                del positions[0]  # the position before the run
                pos[a] = registers[a].value = positions[-1]
                names.append(a)
                columns.append(positions)
        level = self.buffer.level
        columns.append(range(level + n - 1, level - 1, -1))
        self.buffer_level.value = level
        extend = self._register_extenders.get(key)
        if extend is None:  # the position counters of the moving axes and the buffer level, at the slot starts
            extend = self._register_extenders[key] = self.sim.trace.values_extenders(
                [*(registers[a].name for a in names), self.buffer_level.name])
        extend(times, columns)
        if n > 1:
            sim.skip_to(times[-1], passes=n - 1)
        return n

    def run_slot(self, t: int) -> None:
        """Everything the engine does at the slot start ``t`` [ticks]."""
        pulsed, self._pulsing = self._pulsing, 0
        self.slot_index += 1
        self._sample = sample = self.switches.sample()
        if sample.stop_candidate:
            self._evaluate_switches(sample)
        state = self._state
        if state is _BUFFER or state is _INTERNAL:
            entry = self.buffer.pop()
            if entry is None:
                self._last_key = None
                if state is _BUFFER and self._armed:
                    if self._stretch_start is None:
                        self._stretch_start = t
                    self._stretch_slots += 1
                self._idle_axes()
            else:
                if state is _BUFFER:
                    if self._stretch_start is not None:
                        self._close_underrun(t)
                    self._armed = True
                self._emit_entry(t, entry)
                self._last_key = self._keys[entry]
                self._pulsing = self._masks[entry]
            if state is _INTERNAL:
                self._produce()
            self.buffer_level.set(self.buffer.level, t)
        elif state is _JOGGING:
            self._emit_counts(t, [m.step() for m in self._motions])
        elif state is _HOMING:
            self._homing_slot(t, sample)
        ended = pulsed & ~self._pulsing
        if ended:  # axes whose run of segments ends with the last slot: at the start of this one, dir_setup before
            for a, train in enumerate(self.steps):
                if ended >> a & 1:
                    train.end_run()

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
        for a in range(len(self._axis_states)):
            self._set_axis_state(a, AxisState.LIMIT if a in limit_axes else AxisState.ERROR)
        self._set_state(state)

    # -- emitting -----------------------------------------------------------------------------
    def _emit_entry(self, t: int, entry: bytes) -> None:
        """The buffer path of :meth:`_emit_axis` for every axis, inlined (it runs every slot).

        Each distinct entry is decoded once (a job's entries repeat: the planner shares equal ones).
        """
        plan = self._entry_plans.get(entry)
        if plan is None:
            plan = self._entry_plan(entry)
        states, dir_bit, pos, pos_setters, emitters = (self._axis_states, self._dir_bit, self._pos,
                                                       self._pos_setters, self._emitters)
        t_pulse, slot = t + self.dir_setup_ticks, self.slot_ticks
        for a, negative, count, direction, delta in plan:
            if negative is not dir_bit[a]:
                dir_bit[a] = negative
                self.dirs[a].set(negative != self.config.axes[a].invert_direction)
            if count:
                emitters[a](t_pulse, slot, count, direction)
                pos[a] = position = pos[a] + delta
                pos_setters[a](position, t)
                if states[a] is not _RUNNING:
                    self._set_axis_state(a, _RUNNING)
            elif states[a] is not _READY:
                self._set_axis_state(a, _READY)

    def _entry_plan(self, entry: bytes) -> tuple[tuple[int, bool, int, int, int], ...]:
        """``(axis, negative, count, direction, signed count)`` of each axis of ``entry``, kept for its next use."""
        plan = []
        for a, byte in enumerate(entry):
            negative = byte >= DIRECTION_BIT
            count = byte & COUNT_MASK
            plan.append((a, negative, count, 0 if negative else 1, -count if negative else count))
        if len(self._entry_plans) >= 4096:  # a job with many distinct entries: keep the tables bounded
            self._entry_plans.clear()
            self._keys.clear()
            self._counts.clear()
            self._masks.clear()
        self._entry_plans[entry] = kept = tuple(plan)
        # what a run of slots must keep: the direction bits, and which axes have pulses (bit 0)
        self._keys[entry] = bytes(b & DIRECTION_BIT | (1 if b & COUNT_MASK else 0) for b in entry)
        self._counts[entry] = tuple(b & COUNT_MASK for b in entry)
        self._masks[entry] = sum(1 << a for a, b in enumerate(entry) if b & COUNT_MASK)
        return kept

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
            self._pulsing |= 1 << a
            self._emitters[a](t + self.dir_setup_ticks, self.slot_ticks, count, 0 if negative else 1)
            position = self._pos[a] = self._pos[a] + (-count if negative else count)
            self.positions[a].set(position, t)

    def _idle_axes(self) -> None:
        for a in range(len(self._axis_states)):
            self._set_axis_state(a, AxisState.READY)

    # -- internal controller and homing --------------------------------------------------------
    def _internal(self, values: Sequence[object], what: str, apply: Callable[[int, object], None]) -> None:
        if self._state.is_error:
            raise ConfigurationError.out_of_range(f"engine state for {what}", int(self._state),
                                                  "not 100/101 (set state 0 first)")
        n = len(self.axis_names)
        if len(values) != n:
            raise ConfigurationError.out_of_range(f"{what} values", len(values),
                                                  f"{n} ({', '.join(self.axis_names)}; None to leave)")
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
        counts = [0] * len(self.axis_names)
        for a, homing in self._homing.items():
            count, reset = homing.step(sample.home_tripped(a))
            counts[a] = count
            if reset:
                self._pos[a] = 0
                self.positions[a].set(0, t)
        self._emit_counts(t, counts, track_states=False)
        for a, homing in self._homing.items():
            self._set_axis_state(a, homing.phase)
        if all(h.done for h in self._homing.values()):
            self._set_state(EngineState.HOME)

    def _clamped_per_slot(self, axis: int, speed_hz: object, what: str) -> Fraction:
        rate = rate_hz(speed_hz, "speed_hz", high=self.device.max_rate_hz, signed=True,
                       where=f"{what} axis {self.axis_names[axis]}")
        vmax = self.config.axes[axis].max_speed_per_slot
        return max(-vmax, min(vmax, rate / SLOTS_PER_S))

    def _queued(self, axis: int) -> int:
        return sum(signed_count(entry[axis]) for entry in self.buffer.peek_all())

    @staticmethod
    def _slot_limits(config: EngineConfig) -> list[SlotLimits]:
        return [SlotLimits.exact(a.max_speed_per_slot, a.accel_per_slot2, a.decel_per_slot2) for a in config.axes]

    # -- bookkeeping --------------------------------------------------------------------------
    def _refuse(self, index: int, axis: int, count: int, *, reserved: bool = False) -> None:
        """Record the refusal of a fill whose entry ``index`` the model cannot emit on ``axis``, and raise."""
        device = self.device
        limit = device.max_pulses_per_slot
        where = f"fill_buffer slot {index} axis {self.axis_names[axis]}"
        if reserved:
            error = ConfigurationError.out_of_range(
                "x byte", "0xFF", f"a pulse count -{limit}..{limit} (0xFF is the vendor's reserved 'special command' "
                f"on a PoKeys{device.name})", where=where)
        else:
            try:
                integer(count, "pulses per slot", low=-limit, high=limit,
                        allowed=f"-{limit}..{limit} ({device.max_rate_hz} Hz at {SLOT_NS} ns slots on a "
                                f"PoKeys{device.name})", where=where)
                return
            except ConfigurationError as exc:
                error = exc
        self.refusals.append(Refusal(self.sim.now, index, axis, count, limit, str(error)))
        self.refused_fills.set(len(self.refusals))
        raise error

    def _set_state(self, state: EngineState) -> None:
        self._state = state
        self._last_key = None  # a run of slots goes on only from a slot that took data in this state
        self.state_signal.set(int(state))
        if state != EngineState.BUFFER:
            self._armed, self._stretch_start, self._stretch_slots = False, None, 0
        if state == EngineState.STOPPED:
            for a in range(len(self._axis_states)):
                self._set_axis_state(a, AxisState.STOPPED)

    def _set_axis_state(self, axis: int, state: AxisState) -> None:
        if self._axis_states[axis] != state:
            self._axis_states[axis] = state
            self.axis_state_signals[axis].set(int(state))

    def _close_underrun(self, t: int) -> None:
        assert self._stretch_start is not None
        underrun = Underrun(self._stretch_start, t, self._stretch_slots)
        self.underruns.append(underrun)
        self.underrun.set(1, underrun.t_start)
        self.underrun.set(0, t)
        self._stretch_start, self._stretch_slots = None, 0

