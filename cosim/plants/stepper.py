"""Stepper plant: pulse placement rule, small-signal linear model and pull-out estimates.

The Stepper FMU (``fmu_src/Stepper``) is a two-phase hybrid stepper with a microstepping driver::

    T = -Kt ia sin(Nr theta) + Kt ib cos(Nr theta) - Td sin(4 Nr theta)
    J dw/dt = T - B w - T_load - T_friction,      Nr = steps_per_rev / 4

with the commanded phase currents ``I (cos, sin)(n pi / (2 microsteps))`` after ``n`` pulses.

Pulses come as a signed rate held over a communication step with its phase (see
:func:`pulse_instants`), so a controller holding its frequency over a slot is coupled exactly with
one FMU step per slot. Around a full-step position the motor is a spring-mass system of stiffness
``Nr (Kt I + 4 Td)``; :func:`linear_model` gives its transfer function with python-control.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from fractions import Fraction
from functools import cache
from typing import Any, Protocol

from cosim import validate
from cosim.errors import ConfigurationError
from cosim.timebase import TimeBase

SUPPORTED_MICROSTEPS = (1, 2, 4, 8, 16, 32, 64, 128, 256)


@cache
def _fmu_defaults() -> dict[str, Any]:
    """Start values of the FMU's parameters, read from ``fmu_src/Stepper/model.toml``."""
    from cosim import fmubuild, fmudesc

    spec = fmudesc.load_spec(fmubuild.SOURCE_DIR / "Stepper")
    return {v.name: v.start for v in spec.variables if v.causality == "parameter"}


@dataclass(frozen=True)
class StepperParameters:
    """The parameters of the Stepper FMU that its small-signal behaviour depends on (SI units).

    Build one with :meth:`from_parameters` to take the FMU's defaults for what is not given.

    Parameters
    ----------
    steps_per_rev : int
        Full steps per revolution (a positive multiple of 4).
    microsteps : int
        Microsteps per full step (1..256, a power of two).
    torque_constant : float
        Kt [N.m/A].
    current : float
        Amplitude of the commanded current vector [A].
    detent_torque : float
        Td [N.m].
    rotor_inertia, load_inertia : float
        [kg.m2].
    viscous_damping : float
        B [N.m.s/rad].
    screw_lead : float
        Carriage travel per revolution [m/rev] (0: no screw).
    carriage_mass : float
        [kg], reflected as ``m (lead / 2 pi)^2``.
    phase_inductance : float
        [H]; 0 for an ideal current source.
    current_tau : float
        Current-loop time constant [s] (used when ``phase_inductance > 0``).
    """

    steps_per_rev: int = 200
    microsteps: int = 16
    torque_constant: float = 0.159
    current: float = 2.0
    detent_torque: float = 0.0
    rotor_inertia: float = 5.4e-6
    load_inertia: float = 0.0
    viscous_damping: float = 3.0e-4
    screw_lead: float = 0.008
    carriage_mass: float = 0.0
    phase_inductance: float = 0.0
    current_tau: float = 20.0e-6

    def __post_init__(self) -> None:
        where, multiple = "StepperParameters", "a positive multiple of 4"
        if validate.integer(self.steps_per_rev, "steps_per_rev", low=4, allowed=multiple, where=where, whole=True) % 4:
            raise ConfigurationError.out_of_range("steps_per_rev", self.steps_per_rev, multiple, where=where)
        validate.choice(self.microsteps, "microsteps", SUPPORTED_MICROSTEPS, where=where)
        validate.positive(self.rotor_inertia, "rotor_inertia", unit="kg.m2", where=where)
        for f in fields(self):
            if f.type == "float":
                validate.finite(getattr(self, f.name), f.name, where=where)

    @classmethod
    def from_parameters(cls, parameters: Mapping[str, Any] | None = None) -> StepperParameters:
        """The parameters of an FMU instance given ``parameters`` (e.g. a preset); FMU defaults otherwise."""
        known = {f.name for f in fields(cls)}
        defaults = _fmu_defaults()
        values = {name: defaults[name] for name in known if name in defaults}
        values.update({k: v for k, v in (parameters or {}).items() if k in known})
        return replace(cls(), **values)

    @property
    def rotor_teeth(self) -> int:
        """Nr: teeth of the rotor (a tooth pitch is 4 full steps)."""
        return self.steps_per_rev // 4

    @property
    def microstep_angle_rad(self) -> float:
        """Rotor angle of one step pulse [rad]."""
        return 2 * math.pi / (self.steps_per_rev * self.microsteps)

    @property
    def inertia(self) -> float:
        """Total inertia on the shaft [kg.m2], carriage mass included."""
        r = self.screw_lead / (2 * math.pi)
        return self.rotor_inertia + self.load_inertia + self.carriage_mass * r * r

    @property
    def torque_amplitude(self) -> float:
        """Kt I: the pull-in/holding torque of the current vector [N.m]."""
        return self.torque_constant * self.current

    @property
    def stiffness(self) -> float:
        """Small-signal torque per rotor angle at a full-step position [N.m/rad]: Nr (Kt I + 4 Td)."""
        return self.rotor_teeth * (self.torque_amplitude + 4 * self.detent_torque)

    @property
    def natural_frequency_rad_s(self) -> float:
        """Undamped small-signal natural frequency sqrt(stiffness / J) [rad/s]."""
        return math.sqrt(self.stiffness / self.inertia)

    @property
    def damping_ratio(self) -> float:
        """B / (2 sqrt(stiffness J)) of the mechanical part."""
        return self.viscous_damping / (2 * math.sqrt(self.stiffness * self.inertia))


def linear_model(params: StepperParameters | Mapping[str, Any] | None = None) -> Any:
    """Small-signal transfer function from commanded to actual rotor angle [rad/rad] (python-control).

    Around a full-step position the torque is linear in the angle errors::

        J s^2 theta + B s theta + Nr (Kt I + 4 Td) theta = Nr Kt I theta_cmd_i

    where ``theta_cmd_i`` is the commanded angle seen through the current loop: ``1 / (tau s + 1)``
    with ``tau = current_tau`` when ``phase_inductance > 0`` (an unsaturated current loop), and 1 for
    an ideal current source. Its DC gain is ``Kt I / (Kt I + 4 Td)``: the detent pulls the rotor
    back towards the full-step position.

    Parameters
    ----------
    params : StepperParameters or mapping, optional
        The motor; a mapping (e.g. a preset's parameters) is completed with the FMU's defaults.

    Examples
    --------
    >>> g = linear_model({"detent_torque": 0.0})
    >>> round(float(g.dcgain()), 12)
    1.0
    """
    import control

    p = params if isinstance(params, StepperParameters) else StepperParameters.from_parameters(params)
    mechanics = control.tf([p.rotor_teeth * p.torque_amplitude], [p.inertia, p.viscous_damping, p.stiffness])
    if p.phase_inductance > 0:
        return mechanics * control.tf([1.0], [p.current_tau, 1.0])
    return mechanics


def max_acceleration_rad_s2(params: StepperParameters, *, load_torque: float = 0.0) -> float:
    """Largest rotor acceleration the motor can force [rad/s2] (at low speed, torque Kt I).

    A profile that asks for more loses steps; real motors fall below this as speed rises.
    """
    return max(0.0, params.torque_amplitude - abs(load_torque)) / params.inertia


# -- pulse placement ------------------------------------------------------------------------------
def pulse_instants(t_start_s: Fraction, t_end_s: Fraction, *, rate_hz: Fraction,
                   phase: Fraction) -> list[Fraction]:
    """Instants [s] of the step pulses the FMU places in one step ``[t_start_s, t_end_s)``.

    The rule (the same as inside the FMU)::

        t_j = t_start + (j - phase) / |rate|,   j = 0, 1, 2, ...,   t_start <= t_j < t_end

    ``phase`` in [0, 1) is the fraction of a pulse period already elapsed at ``t_start``; phase 0
    puts a pulse at ``t_start``. A pulse at ``t_end`` belongs to the next step.

    Parameters
    ----------
    t_start_s, t_end_s : Fraction
        The step [s].
    rate_hz : Fraction
        Signed pulse rate [pulses/s]; only its magnitude places pulses.
    phase : Fraction
        In [0, 1).

    Examples
    --------
    >>> [str(t) for t in pulse_instants(Fraction(0), Fraction(1, 1000), rate_hz=Fraction(3000), phase=Fraction(1, 2))]
    ['1/6000', '1/2000', '1/1200']
    """
    validate.in_range(phase, "phase", low=0, high=1, high_open=True, allowed="0 <= phase < 1")
    if rate_hz == 0 or t_end_s <= t_start_s:
        return []
    period = 1 / abs(rate_hz)
    j = 0 if phase == 0 else 1
    out = []
    while (t := t_start_s + (j - phase) * period) < t_end_s:
        out.append(t)
        j += 1
    return out


def phase_after(duration_s: Fraction, *, rate_hz: Fraction, phase: Fraction) -> Fraction:
    """The ``step_phase`` that continues a pulse train exactly after ``duration_s`` [s].

    Examples
    --------
    >>> phase_after(Fraction(1, 1000), rate_hz=Fraction(1500), phase=Fraction(0))
    Fraction(1, 2)
    """
    if rate_hz == 0:
        return phase
    elapsed = phase + duration_s * abs(rate_hz)
    return elapsed - math.floor(elapsed)


# -- driving the FMU on its own -------------------------------------------------------------------
class _SteppedFmu(Protocol):
    t: int
    timebase: TimeBase

    def set(self, name: str, value: float) -> None: ...

    def advance_to(self, t: int) -> int: ...


def trapezoid_rates(top_hz: int, *, ramp_slots: int, hold_slots: int,
                    down: bool = True) -> list[Fraction]:
    """Step rates per slot [pulses/s] of a trapezoid: ``ramp_slots`` up to ``top_hz``, held, and back.

    Examples
    --------
    >>> [int(r) for r in trapezoid_rates(3000, ramp_slots=3, hold_slots=2)]
    [1000, 2000, 3000, 3000, 3000, 2000, 1000]
    """
    validate.integer(ramp_slots, "ramp_slots", low=1)
    validate.integer(hold_slots, "hold_slots", low=0)
    up = [Fraction(top_hz * (k + 1), ramp_slots) for k in range(ramp_slots)]
    return up + [Fraction(top_hz)] * hold_slots + (up[::-1][1:] if down else [])


def drive_slots(fmu: _SteppedFmu, rates_hz: Sequence[Fraction], *, slot_ns: int = 1_000_000,
                stop: bool = True) -> int:
    """Drive a Stepper FMU slot by slot from its current time, the way a slot-based controller does.

    At the start of slot k the held rate ``rates_hz[k]`` and the exact phase that continues the
    train (:func:`phase_after`) are set; the FMU then advances to the slot's end, through any
    early returns at switch events. Times are integer ticks of the FMU's time base.

    Parameters
    ----------
    fmu : cosim.fmu.Fmu
        A Stepper FMU (standalone, not in a :class:`~cosim.kernel.Simulation`).
    rates_hz : sequence of Fraction
        Signed step rate per slot [pulses/s].
    slot_ns : int
        Slot length [ticks of the FMU's time base] (1 ms at the default 1 ns).
    stop : bool
        Set ``step_rate = 0`` after the last slot.

    Returns
    -------
    int
        Pulses commanded, counted by the pulse rule (:func:`pulse_instants`), signed.

    Examples
    --------
    ::

        with Fmu(ensure_fmu("Stepper"), parameters=load_preset("nema17_17hs16_2004s1")) as fmu:
            pulses = drive_slots(fmu, trapezoid_rates(16_000, ramp_slots=100, hold_slots=50))
            print(pulses, fmu.get("lost_full_steps"))
    """
    validate.integer(slot_ns, "slot_ns", low=1, unit="tick")
    t0, slot_s = fmu.t, slot_ns * fmu.timebase.resolution_s
    phase, count = Fraction(0), 0
    for k, rate in enumerate(rates_hz):
        fmu.set("step_rate", float(rate))
        fmu.set("step_phase", float(phase))
        t_end = t0 + (k + 1) * slot_ns
        while fmu.advance_to(t_end) < t_end:
            pass
        pulses = len(pulse_instants(Fraction(0), slot_s, rate_hz=rate, phase=phase))
        count += pulses if rate > 0 else -pulses
        phase = phase_after(slot_s, rate_hz=rate, phase=phase)
    if stop:
        fmu.set("step_rate", 0.0)
    return count
