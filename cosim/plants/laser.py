"""Laser plant: closed-form PWM energy and the small-signal linear model.

The Laser FMU (``fmu_src/Laser``) follows its modulation with a first-order lag::

    dP/dt = (P_target - P) / tau,   tau = tau_rise while P_target > P else tau_fall

With a piecewise-constant target the solution is exact per segment::

    P(t) = Pt + (P0 - Pt) exp(-t/tau)
    E    = Pt*dt + (P0 - Pt) * tau * (1 - exp(-dt/tau))

:func:`pwm_energy` walks the carrier edges and sums that closed form; scenarios and tests use it
as the reference the FMU must match.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any


def carrier_segments(t0_s: Fraction, t1_s: Fraction, *, period: int, on: int, clock_hz: Fraction,
                     phase: int = 0) -> list[tuple[Fraction, Fraction, bool]]:
    """Exact ``(start_s, end_s, on)`` segments of the PWM carrier over ``[t0_s, t1_s)``.

    Parameters
    ----------
    t0_s, t1_s : Fraction
        Interval [s], exact.
    period, on : int
        PWM period and on-time [clock ticks]; ``on >= period`` is continuously on, ``on == 0`` off.
    clock_hz : Fraction
        Modulation clock [Hz].
    phase : int
        Clock tick at which a carrier period starts.
    """
    if t1_s <= t0_s:
        return []
    if on <= 0:
        return [(t0_s, t1_s, False)]
    if on >= period:
        return [(t0_s, t1_s, True)]
    tick = 1 / clock_hz
    k = math.floor((t0_s * clock_hz - phase) / period)
    segments = []
    while True:
        start = (phase + k * period) * tick
        rise, fall, end = start, start + on * tick, start + period * tick
        for a, b, level in ((rise, fall, True), (fall, end, False)):
            lo, hi = max(a, t0_s), min(b, t1_s)
            if hi > lo:
                segments.append((lo, hi, level))
        if end >= t1_s:
            return segments
        k += 1


def first_order(p0: float, target: float, dt: float, tau: float) -> tuple[float, float]:
    """Power at the end and energy over ``dt`` of a first-order approach to ``target``."""
    decay = math.exp(-dt / tau)
    power = target + (p0 - target) * decay
    energy = target * dt + (p0 - target) * tau * (1.0 - decay)
    return power, energy


def pwm_energy(windows: list[tuple[Fraction, Fraction]], *, period: int, on: int, peak_power: float,
               tau_rise: float, tau_fall: float, clock_hz: Fraction = Fraction(20_000_000),
               duty_threshold: float = 0.0, t_end: Fraction | None = None) -> tuple[float, float]:
    """Energy [J] and final power [W] for a laser gated on during ``windows`` (closed form).

    Parameters
    ----------
    windows : list of (start_s, end_s)
        Intervals in which enable and gate are both on, sorted, not overlapping.
    period, on : int
        PWM period and on-time [clock ticks].
    peak_power : float
        [W]
    tau_rise, tau_fall : float
        Time constants [s].
    t_end : Fraction, optional
        End of the evaluation [s] (default: end of the last window); decay after it is included.
    """
    lasing = on > 0 and (on >= period or Fraction(on, period) >= Fraction(duty_threshold))
    power, energy = 0.0, 0.0
    t = Fraction(0)
    stop = t_end if t_end is not None else (windows[-1][1] if windows else Fraction(0))
    for start, end in [*windows, (stop, stop)]:
        for seg_start, seg_end, level in [(t, start, False)] + (
                carrier_segments(start, end, period=period, on=on, clock_hz=clock_hz) if end > start else []):
            target = peak_power if level and lasing else 0.0
            tau = tau_rise if target > power else tau_fall
            power, e = first_order(power, target, float(seg_end - seg_start), tau)
            energy += e
        t = end
    return energy, power


def linear_model(*, tau_s: float, peak_power: float) -> Any:
    """Small-signal model of optical power against duty: ``peak / (tau s + 1)`` (python-control).

    Averaged over a carrier period much shorter than ``tau``, the power follows the duty cycle
    through this first-order lag (one time constant; rise and fall equal for small signals).
    """
    import control

    return control.tf([peak_power], [tau_s, 1.0])
