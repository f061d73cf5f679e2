"""Reading and writing parameters (a part of :class:`~.controller.TrioController`).

Every axis parameter of :data:`~.params.AXIS_PARAMS` is range-checked when written. Those the
model uses act (UNITS, SPEED, ACCEL, DECEL, ATYPE, SERVO, FE_LIMIT, INVERT_STEP, PWM_CYCLE,
PWM_MARK, CREEP, JOGSPEED, DATUM_IN, FWD_IN, REV_IN, FWD_JOG, REV_JOG, FAST_JOG, FS_LIMIT, RS_LIMIT,
REP_DIST, REP_OPTION, MERGE, SRAMP); the others (gains, windows, encoder set-up...) are stored,
read back as written, and listed in the run's notes as "set, not modelled" with where they were
set. ``OFFPOS = d`` shifts DPOS and MPOS by ``d`` at the next servo tick (as DEFPOS does).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any

from cosim import validate
from cosim.controllers.trio.keywords import SYSTEM_STORED
from cosim.controllers.trio.params import (
    ATYPE_STEPPER_PWM,
    AXIS_PARAMS,
    PWM_AXES,
    PWM_ENCODER_MODULUS,
    READ_NOT_MODELLED,
    READ_ONLY_AXIS_PARAMS,
    SYSTEM_PARAMS,
    on_off,
    unknown_name,
)
from cosim.controllers.trio.status import axis_status, move_type, remaining
from cosim.controllers.trio.supervise import supervised
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis
    from cosim.controllers.trio.buffer import MoveBuffers
    from cosim.controllers.trio.gate import GateFifo
    from cosim.controllers.trio.outputs import SettledSignal
    from cosim.controllers.trio.servo import ServoLoop
    from cosim.kernel import Simulation


def pwm_axes() -> str:
    return ", ".join(map(str, PWM_AXES)) + " (the axes with the PWM feature)"


class ParameterAccess:
    """``NAME = value`` and ``NAME`` for axis, system and stored parameters."""

    sim: Simulation
    axes: dict[int, Axis]
    buffers: MoveBuffers
    servo: ServoLoop
    wdog: SettledSignal
    servo_period_us: int
    encoder_at_atype: int | None
    device: str
    system_values: dict[str, Any]

    def axis(self, number: object, *, where: str = "") -> Axis:
        raise NotImplementedError  # pragma: no cover - provided by the controller

    def _gate(self, axis: int, what: str) -> GateFifo:
        raise NotImplementedError  # pragma: no cover - provided by the controller

    def set_param(self, name: str, value: object, *, axis: int | None = None, where: str = "") -> None:
        """Write parameter ``name`` (vendor name) of ``axis`` (or a controller parameter)."""
        self.servo.wake()
        key = name.upper()
        if key == "WDOG":
            self.wdog.request(on_off(value, "WDOG"))
            return
        if key == "OFFPOS":
            ax = self.axis(0 if axis is None else axis)
            ax.shift(validate.exact(value, "OFFPOS"))
            return
        if key in SYSTEM_STORED:
            self.system_values[key] = validate.exact(value, key)
            self.sim.notes.not_modelled(self.device, key, value, where=where)
            return
        if key in SYSTEM_PARAMS or key in READ_ONLY_AXIS_PARAMS:
            hint = " (use DEFPOS)" if key in ("DPOS", "MPOS") else ""
            raise ConfigurationError(f"{key} is read-only{hint}")
        if key not in AXIS_PARAMS:
            raise ConfigurationError(unknown_name(key))
        spec = AXIS_PARAMS[key]
        ax = self.axis(0 if axis is None else axis)
        if spec.pwm_only and not ax.has_pwm:
            raise ConfigurationError.out_of_range(f"axis of {key}", ax.number, pwm_axes())
        converted = spec.convert(value, key, "")
        if key == "ATYPE" and converted == ATYPE_STEPPER_PWM and not ax.has_pwm:
            raise ConfigurationError.out_of_range(f"axis of ATYPE={ATYPE_STEPPER_PWM}", ax.number, pwm_axes())
        if not spec.acts:
            ax.params[key] = converted
            self.sim.notes.not_modelled(self.device, f"{key}(axis {ax.number})", _shown(converted), where=where)
            return
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
        ax.supervised = supervised(ax)

    def get_param(self, name: str, *, axis: int | None = None) -> Fraction:
        """Read parameter ``name`` of ``axis`` (or a controller parameter) now, exactly."""
        self.servo.sync()
        key = name.upper()
        if key == "WDOG":
            return Fraction(int(self.wdog.value))
        if key == "SERVO_PERIOD":
            return Fraction(self.servo_period_us)
        if key in SYSTEM_STORED:
            return Fraction(self.system_values.get(key, SYSTEM_STORED[key]))
        if key == "PI":
            from cosim.controllers.trio.trig import pi_down

            return pi_down()
        ax = self.axis(0 if axis is None else axis)
        if key in AXIS_PARAMS:
            if AXIS_PARAMS[key].pwm_only and not ax.has_pwm:
                raise ConfigurationError.out_of_range(f"axis of {key}", ax.number, pwm_axes())
            return Fraction(ax.params[key])
        if key in READ_NOT_MODELLED:
            self.sim.notes.not_modelled(self.device, f"{key}(axis {ax.number}) read", READ_NOT_MODELLED[key])
            return Fraction(READ_NOT_MODELLED[key])
        now = self.sim.now
        values: dict[str, Any] = {
            "DPOS": lambda: ax.dpos, "MPOS": lambda: ax.mpos_at(now), "VP_SPEED": lambda: ax.vp_speed,
            "OFFPOS": lambda: ax.offpos, "IDLE": lambda: -1 if ax.idle else 0,
            "LOADED": lambda: -1 if self.buffers.loaded((ax.number,)) else 0,
            "FE": lambda: ax.dpos - ax.mpos_at(now),
            "PWM_ENCODER": lambda: self._gate(ax.number, "PWM_ENCODER").encoder_value(),
            "AXISSTATUS": lambda: axis_status(self, ax), "AXIS_STATUS": lambda: axis_status(self, ax),
            "MARK": lambda: -1 if ax.mark else 0, "REG_POS": lambda: ax.reg_pos,
            "MTYPE": lambda: move_type(ax.current), "NTYPE": lambda: move_type(ax.queued),
            "REMAIN": lambda: remaining(ax), "MSPEED": lambda: ax.vp_speed,
            "DEMAND_EDGES": lambda: ax.demand, "ENCODER": lambda: ax.steps,
            "LINKAX": lambda: getattr(ax.current, "link", -1) if ax.current is not None else -1,
            "MOVES_BUFFERED": lambda: (ax.current is not None) + (ax.queued is not None),
            "DRIVE_STATUS": lambda: 0, "TRANS_DPOS": lambda: ax.dpos,
        }
        if key not in values:
            raise ConfigurationError(unknown_name(key))
        return Fraction(values[key]())


def _shown(value: Any) -> Any:
    return int(value) if isinstance(value, Fraction) and value.denominator == 1 else (
        float(value) if isinstance(value, Fraction) else value)
