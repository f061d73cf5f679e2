"""PID position loop at the servo rate, with gains designed by python-control.

The slave axis (DC motor, amplifier and encoder) is modelled for design as seen from the DAC::

    G(s) = K / (s * (tau * s + 1))      [counts per DAC bit]

sampled with a zero-order hold at the servo period (the DAC holds its value for a cycle). The
controller is a PID with a filtered derivative, in series form::

    C(s) = Kc * (tau * s + 1) / (s / w_f + 1) * (s + w_i) / s

whose derivative zero cancels the motor pole, with ``w_i = w_c / 10`` and
``w_f = min(10 * w_c, Nyquist / 2)``. It is discretised with the Tustin rule and ``Kc`` is
scaled so that the *discrete* loop crosses 0 dB exactly at the requested bandwidth ``w_c``.
The design reports the crossover, the closed-loop -3 dB bandwidth, the gain and phase margins
and the largest closed-loop pole radius (stable at the servo rate if below 1).

The DAC output is a 16-bit value (+-32767, about +-10 V); the controller state keeps running
when the output saturates (no anti-windup).

python-control (which pulls in scipy and matplotlib) is imported inside the functions that design a
loop, never at module level: a run that designs no loop does not pay for it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from cosim import validate

#: Largest DAC output [bits] of a 16-bit DAC.
DAC_MAX = 32767
#: DAC output voltage per bit [V]: a 16-bit DAC whose 32768 bits are 10 V (+-32767 = +-9.9997 V).
DAC_VOLTS_PER_BIT = Fraction(10, 32768)


@dataclass(frozen=True)
class MotorModel:
    """Slave axis as seen from the DAC: ``G(s) = K / (s (tau s + 1))``.

    Parameters
    ----------
    gain_counts_per_s_per_bit : float
        K, steady speed per DAC bit [counts/s per bit], > 0.
    tau_s : float
        Mechanical time constant [s], > 0.
    """

    gain_counts_per_s_per_bit: float
    tau_s: float

    def __post_init__(self) -> None:
        validate.positive(self.gain_counts_per_s_per_bit, "gain_counts_per_s_per_bit")
        validate.positive(self.tau_s, "tau_s")

    def transfer_function(self) -> Any:
        """The continuous plant ``G(s)`` as a python-control transfer function."""
        import control  # python-control (with scipy and matplotlib) only where a loop is designed

        return control.tf([self.gain_counts_per_s_per_bit], [self.tau_s, 1.0, 0.0])


@dataclass(frozen=True)
class PidDesign:
    """A designed PID position loop and its figures.

    Attributes
    ----------
    period_s : float
        Servo period [s].
    kp : float
        Proportional gain [DAC bits per count].
    ki : float
        Integral gain [DAC bits per count per s].
    kd : float
        Derivative gain [DAC bits per count/s].
    derivative_filter_hz : float
        Corner of the derivative filter [Hz].
    crossover_hz : float
        Open-loop 0 dB crossover (the requested bandwidth) [Hz].
    bandwidth_hz : float
        Closed-loop -3 dB bandwidth [Hz].
    gain_margin_db : float
        Gain margin [dB] (inf if the phase never crosses -180 deg).
    phase_margin_deg : float
        Phase margin [deg].
    max_pole_radius : float
        Largest |z| of the closed-loop poles (< 1: stable at the servo rate).
    a, b, c, d : tuple
        Discrete controller state space (error [counts] in, DAC [bits] out).
    """

    period_s: float
    kp: float
    ki: float
    kd: float
    derivative_filter_hz: float
    crossover_hz: float
    bandwidth_hz: float
    gain_margin_db: float
    phase_margin_deg: float
    max_pole_radius: float
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    c: tuple[float, ...]
    d: float

    @property
    def stable(self) -> bool:
        """True if every closed-loop pole is inside the unit circle."""
        return self.max_pole_radius < 1.0

    def summary(self) -> str:
        """Human-readable design report (bandwidth, margins, gains)."""
        return (
            f"PID position loop at {1 / self.period_s:.1f} Hz servo rate: "
            f"crossover {self.crossover_hz:.1f} Hz, closed-loop bandwidth {self.bandwidth_hz:.1f} Hz, "
            f"phase margin {self.phase_margin_deg:.1f} deg, gain margin {self.gain_margin_db:.1f} dB, "
            f"largest closed-loop pole |z| = {self.max_pole_radius:.4f} "
            f"({'stable' if self.stable else 'UNSTABLE'}); "
            f"Kp = {self.kp:.4g} bits/count, Ki = {self.ki:.4g} bits/(count s), Kd = {self.kd:.4g} bits s/count"
        )

    def __str__(self) -> str:
        return self.summary()


def _closed_loop_bandwidth_hz(closed: Any, period_s: float) -> float:
    """First frequency where the discrete closed loop falls 3 dB below its DC gain [Hz]."""
    nyquist = math.pi / period_s
    dc = abs(complex(closed(1.0)))
    target = dc / math.sqrt(2.0)

    def gain(w: float) -> float:
        return abs(complex(closed(np.exp(1j * w * period_s))))

    grid = np.logspace(-1, math.log10(nyquist * 0.999), 2000)
    below = [w for w in grid if gain(w) < target]
    if not below:
        return nyquist / (2 * math.pi)
    hi = below[0]
    lo = grid[max(0, int(np.searchsorted(grid, hi)) - 1)]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gain(mid) >= target else (lo, mid)
    return 0.5 * (lo + hi) / (2 * math.pi)


#: Revision of the design method: a change of :func:`design_pid` or :func:`cosim.couplings.servo.full_model_margins`
#: that changes their numbers raises it, so designs kept on disk from before are not used.
DESIGN_REVISION = 1


def cached_design(kind: str, inputs: dict[str, Any], compute: Callable[[], dict[str, Any]]) -> dict[str, Any]:
    """``compute()`` (a JSON-able dict of floats), kept on disk by its inputs: a loop is designed once per machine.

    Designing imports python-control (scipy, matplotlib: a second or more of start-up); a design is
    a deterministic function of its inputs, so it is stored in the user cache folder
    (``platformdirs``; the key holds the inputs, :data:`DESIGN_REVISION` and python-control's
    version) and read back bit for bit (JSON keeps floats exactly). A cache that cannot be read or
    written is ignored.
    """
    import hashlib
    import json
    from importlib.metadata import version

    key = json.dumps({"kind": kind, "inputs": inputs, "revision": DESIGN_REVISION,
                      "control": version("control")}, sort_keys=True)
    path = _cache_folder() / f"{kind}-{hashlib.sha256(key.encode()).hexdigest()[:32]}.json"
    try:
        stored = json.loads(path.read_text())
        if stored.get("key") == key:
            return dict(stored["value"])
    except (OSError, ValueError, KeyError, TypeError):
        pass
    value = compute()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(json.dumps({"key": key, "value": value}))
        temporary.replace(path)
    except OSError:
        pass
    return value


def _cache_folder() -> Path:
    from platformdirs import user_cache_path

    from cosim import __version__

    return user_cache_path("cosim", appauthor=False, version=__version__) / "servo-designs"


def design_pid(motor: MotorModel, *, period_s: float, bandwidth_hz: float, integral_ratio: float = 10.0,
               derivative_filter_ratio: float = 10.0) -> PidDesign:
    """Design the PID position loop for a stated bandwidth (kept on disk: :func:`cached_design`).

    Parameters
    ----------
    motor : MotorModel
    period_s : float
        Servo period [s] (``ServoClock.period_s``).
    bandwidth_hz : float
        Open-loop crossover to place [Hz], 0 < bandwidth <= servo rate / 10.
    integral_ratio : float
        ``w_c / w_i`` (> 1).
    derivative_filter_ratio : float
        ``w_f / w_c`` (> 1; capped at half the Nyquist frequency).

    Returns
    -------
    PidDesign
    """
    validate.positive(period_s, "period_s", unit="s")
    inputs = {"gain": float(motor.gain_counts_per_s_per_bit), "tau_s": float(motor.tau_s),
              "period_s": float(period_s), "bandwidth_hz": float(bandwidth_hz),
              "integral_ratio": float(integral_ratio), "derivative_filter_ratio": float(derivative_filter_ratio)}
    rate_hz = 1.0 / period_s
    validate.in_range(bandwidth_hz, "bandwidth_hz", low=0, low_open=True, high=rate_hz / 10,
                      allowed=f"0 < bandwidth <= servo rate / 10 = {rate_hz / 10:.1f} Hz")
    validate.in_range(integral_ratio, "integral_ratio", low=1, low_open=True)
    validate.in_range(derivative_filter_ratio, "derivative_filter_ratio", low=1, low_open=True)
    value = cached_design("pid", inputs, lambda: _design(motor, period_s=period_s, bandwidth_hz=bandwidth_hz,
                                                         integral_ratio=integral_ratio,
                                                         derivative_filter_ratio=derivative_filter_ratio))
    value["a"] = tuple(tuple(row) for row in value["a"])
    value["b"], value["c"] = tuple(value["b"]), tuple(value["c"])
    return PidDesign(**value)


def _design(motor: MotorModel, *, period_s: float, bandwidth_hz: float, integral_ratio: float,
            derivative_filter_ratio: float) -> dict[str, Any]:
    """The design itself, with python-control (see :func:`design_pid`)."""
    import control  # python-control (with scipy and matplotlib) only where a loop is designed

    wc = 2 * math.pi * bandwidth_hz
    wi = wc / integral_ratio
    wf = min(derivative_filter_ratio * wc, math.pi / period_s / 2)
    tau = motor.tau_s
    shape = control.tf([tau, 1.0], [1.0 / wf, 1.0]) * control.tf([1.0, wi], [1.0, 0.0])
    plant_d = control.sample_system(motor.transfer_function(), period_s, method="zoh")
    shape_d = control.sample_system(shape, period_s, method="tustin")
    kc = 1.0 / abs(complex((plant_d * shape_d)(np.exp(1j * wc * period_s))))
    controller = shape_d * kc
    loop = plant_d * controller
    gm, pm, _sm, _wpc, _wgc, _wms = control.stability_margins(loop, method="frd")
    closed = control.feedback(loop, 1)
    radius = float(np.max(np.abs(control.poles(closed))))
    ss = control.ss(controller)
    ki = kc * wi
    kp = kc * (1 + tau * wi) - ki / wf
    kd = kc * tau - kp / wf
    return dict(
        period_s=period_s, kp=kp, ki=ki, kd=kd, derivative_filter_hz=wf / (2 * math.pi), crossover_hz=bandwidth_hz,
        bandwidth_hz=_closed_loop_bandwidth_hz(closed, period_s),
        gain_margin_db=float(20 * math.log10(gm)) if np.isfinite(gm) and gm > 0 else math.inf,
        phase_margin_deg=float(pm), max_pole_radius=radius,
        a=[[float(v) for v in row] for row in np.asarray(ss.A)],
        b=[float(v) for v in np.asarray(ss.B).ravel()],
        c=[float(v) for v in np.asarray(ss.C).ravel()],
        d=float(np.asarray(ss.D).ravel()[0]),
    )


class PidLoop:
    """The running PID: one update per servo cycle, DAC output in 16-bit bits.

    Parameters
    ----------
    design : PidDesign
    """

    def __init__(self, design: PidDesign) -> None:
        self.design = design
        self._x = [0.0] * len(design.b)
        self._rows = tuple(zip(design.a, design.b, strict=True))

    def update(self, error_counts: float) -> int:
        """Following error [counts] in, DAC value [bits] out (clamped to +-32767).

        ``u = C x + D e`` and ``x <- A x + B e``, each sum taken left to right from 0 (the same
        floats in the same order whatever the state's size).
        """
        d = self.design
        x = self._x
        if len(x) == 2:  # the designed PID's order: the same sums, unrolled
            x0, x1 = x
            (a00, a01), b0 = self._rows[0]
            (a10, a11), b1 = self._rows[1]
            c0, c1 = d.c
            u = 0.0 + c0 * x0 + c1 * x1 + d.d * error_counts
            self._x = [0.0 + a00 * x0 + a01 * x1 + b0 * error_counts, 0.0 + a10 * x0 + a11 * x1 + b1 * error_counts]
            return max(-DAC_MAX, min(DAC_MAX, round(u)))
        u = 0.0
        for ci, xi in zip(d.c, x, strict=True):
            u += ci * xi
        u += d.d * error_counts
        new = []
        for row, bi in self._rows:
            acc = 0.0
            for aij, xj in zip(row, x, strict=True):
                acc += aij * xj
            new.append(acc + bi * error_counts)
        self._x = new
        return max(-DAC_MAX, min(DAC_MAX, round(u)))
