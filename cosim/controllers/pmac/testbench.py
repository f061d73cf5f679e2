"""Pure-Python stand-ins for the plants, so the PMAC model is testable without FMUs.

* :class:`AnalyticConveyor` -- the master: position an exact function of time (piecewise
  constant acceleration, :class:`~fractions.Fraction` arithmetic), an incremental encoder with
  ``count = floor(position)`` and exact edge timestamps (the first ns tick at which the count
  is reached), and registration marks as a bit signal. It is an :class:`EncoderSource`.
* :class:`DcMotorStandIn` -- the slave: a DC motor driven by the DAC signal,
  ``G(s) = K / (s (tau s + 1))``, advanced with its exact solution between DAC changes.

Before t = 0 the conveyor is taken to have run at its initial speed, so the first servo
cycles already see valid edge timestamps. The conveyor only moves forward (speed >= 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Generator, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING, Any, TypeVar

from cosim import validate
from cosim.controllers.pmac.encoder import EncoderSample
from cosim.controllers.pmac.servo import MotorModel
from cosim.controllers.pmac.units import ServoClock
from cosim.errors import ConfigurationError
from cosim.signals import Signal
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.kernel import Simulation

Number = int | Fraction
T = TypeVar("T")

#: A default slave axis: 6 counts/s per DAC bit (about 197 counts/ms at full DAC), tau = 10 ms.
SERVO_AXIS = MotorModel(gain_counts_per_s_per_bit=6.0, tau_s=0.01)
_NS_PER_MS = 10**6


def _ceil(x: Fraction) -> int:
    return -((-x.numerator) // x.denominator)


class AnalyticConveyor:
    """A conveyor whose position is an exact function of time.

    Parameters
    ----------
    sim : Simulation
    speed_counts_per_ms : int or Fraction
        Speed at t = 0 (and before) [counts/ms], >= 0.
    phases : sequence of (duration_ns, accel_counts_per_ms2)
        Consecutive phases of constant acceleration from t = 0; afterwards the speed stays.
    position_counts : int or Fraction
        Position at t = 0 [counts].
    marks : sequence of int or Fraction
        Registration-mark positions [counts], each > ``position_counts``.
    mark_width_counts : int or Fraction
        Length of a mark [counts]: the sensor is high from ``m`` to ``m + width``.
    name : str
        Trace prefix: the mark sensor is ``<name>.mark``.

    Examples
    --------
    >>> from cosim.kernel import Simulation
    >>> belt = AnalyticConveyor(Simulation(), speed_counts_per_ms=64)
    >>> belt.position(15_625), belt.time_at(3)
    (Fraction(1, 1), 46875)
    """

    def __init__(self, sim: Simulation, *, speed_counts_per_ms: Number = 0,
                 phases: Sequence[tuple[int, Number]] = (), position_counts: Number = 0,
                 marks: Sequence[Number] = (), mark_width_counts: Number = 1, name: str = "conveyor") -> None:
        self.sim = sim
        v = validate.positive(speed_counts_per_ms, "speed_counts_per_ms", zero=True,
                              allowed=">= 0 (forward only)") / _NS_PER_MS
        p = self._p0 = validate.exact(position_counts, "position_counts")
        self._v0 = v
        t = 0
        self._phases: list[tuple[int, Fraction, Fraction, Fraction]] = []  # (t_start, p, v [counts/ns], a)
        for duration_ns, accel in phases:
            validate.integer(duration_ns, "phase duration_ns", low=1, allowed="integers > 0 ns")
            a = validate.exact(accel, "phase acceleration") / _NS_PER_MS**2
            self._phases.append((t, p, v, a))
            p, v = p + v * duration_ns + a * duration_ns * duration_ns / 2, v + a * duration_ns
            t += duration_ns
            if v < 0:
                raise ConfigurationError.out_of_range(
                    f"acceleration of the phase ending at {t} ns", accel,
                    "values that keep the speed >= 0 (the stand-in conveyor only moves forward)")
        self._phases.append((t, p, v, Fraction(0)))
        self._cache: dict[Fraction, int | None] = {}
        self.mark = Signal(sim, f"{name}.mark", kind="bit", description="registration-mark sensor")
        self.mark_times: list[tuple[int, int]] = []
        width = validate.positive(mark_width_counts, "mark_width_counts", unit="counts")
        for m in marks:
            mark = validate.in_range(m, "mark position", low=self._p0, low_open=True,
                                     allowed=f"> position_counts = {position_counts}")
            rise, fall = self.time_at(mark), self.time_at(mark + width)
            if rise is not None:
                self.mark_times.append((rise, fall if fall is not None else -1))
                sim.call_at(rise, Priority.PLANT_EVENT, self._mark_on)
            if fall is not None:
                sim.call_at(fall, Priority.PLANT_EVENT, self._mark_off)

    def _mark_on(self) -> None:
        self.mark.set(1)

    def _mark_off(self) -> None:
        self.mark.set(0)

    def _phase(self, t_ns: int) -> tuple[int, Fraction, Fraction, Fraction]:
        if t_ns < 0:
            return 0, self._p0, self._v0, Fraction(0)
        for phase in reversed(self._phases):
            if t_ns >= phase[0]:
                return phase
        return self._phases[0]

    def position(self, t_ns: int) -> Fraction:
        """Exact position at ``t_ns`` [counts]."""
        t0, p, v, a = self._phase(t_ns)
        tau = t_ns - t0
        return p + v * tau + a * tau * tau / 2

    def speed_counts_per_ms(self, t_ns: int) -> Fraction:
        """Exact speed at ``t_ns`` [counts/ms]."""
        t0, _p, v, a = self._phase(t_ns)
        return (v + a * (t_ns - t0)) * _NS_PER_MS

    def time_at(self, x: Number) -> int | None:
        """First integer ns at which the position is >= ``x`` (None if never)."""
        x = Fraction(x)
        if x in self._cache:
            return self._cache[x]
        result = self._time_at(x)
        if len(self._cache) > 8192:
            self._cache.clear()
        self._cache[x] = result
        return result

    def _time_at(self, x: Fraction) -> int | None:
        if x <= self._p0:
            return _ceil((x - self._p0) / self._v0) if self._v0 > 0 else None
        bounds = [*(ph[0] for ph in self._phases[1:]), None]
        for (t0, p, v, a), t_end in zip(self._phases, bounds, strict=True):
            end_p = self.position(t_end) if t_end is not None else None
            if end_p is not None and end_p < x:
                continue
            if a == 0 and v == 0:
                return None if t_end is None else t0
            d = float(x - p)
            fv, fa = float(v), float(a)
            guess = 2 * d / (fv + math.sqrt(max(fv * fv + 2 * fa * d, 0.0))) if fv > 0 or fa > 0 else 0.0
            t = t0 + max(0, math.ceil(guess))
            if t_end is not None:
                t = min(t, t_end)
            while self.position(t) < x:
                t += 1
            while t - 1 >= t0 and self.position(t - 1) >= x:
                t -= 1
            return t
        return None

    def sample(self, t_ns: int) -> EncoderSample:
        """Encoder state at ``t_ns``: count = floor(position) and its last two edge instants."""
        count = math.floor(self.position(t_ns))
        return EncoderSample(count, self.time_at(count), self.time_at(count - 1), 1)


class DcMotorStandIn:
    """The slave axis: a DC motor, amplifier and encoder driven by a DAC signal.

    Parameters
    ----------
    sim : Simulation
    dac : Signal
        DAC output [bits] of the position loop.
    model : MotorModel
        ``K`` [counts/s per bit] and ``tau`` [s].
    """

    def __init__(self, sim: Simulation, dac: Signal, model: MotorModel) -> None:
        self.sim = sim
        self.model = model
        self._t = sim.now
        self._u = float(dac.value)
        self.position_counts = 0.0
        self.speed_counts_per_s = 0.0
        dac.subscribe(self._on_dac)

    def _advance(self, t_ns: int) -> None:
        dt = self.sim.timebase.seconds(t_ns - self._t)
        if dt <= 0:
            return
        tau = self.model.tau_s
        v_end = self.model.gain_counts_per_s_per_bit * self._u
        decay = math.exp(-dt / tau)
        self.position_counts += v_end * dt + (self.speed_counts_per_s - v_end) * tau * (1 - decay)
        self.speed_counts_per_s = v_end + (self.speed_counts_per_s - v_end) * decay
        self._t = t_ns

    def _on_dac(self, signal: Signal) -> None:
        self._advance(self.sim.now)
        self._u = float(signal.value)

    def encoder_count(self) -> int:
        """Encoder count now: ``floor(position)`` [counts]."""
        self._advance(self.sim.now)
        return math.floor(self.position_counts)


def record_each_cycle(sim: Simulation, clock: ServoClock, probe: Callable[[int, int], T], *,
                      cycles: int) -> list[T]:
    """Call ``probe(k, t_ns)`` after servo cycle ``k`` (priority SAMPLE) for ``k < cycles``.

    Returns the list the results are appended to (filled as the simulation runs).
    """
    results: list[T] = []

    def sample() -> Generator[Any, Any, None]:
        for k in range(clock.first_cycle_at_or_after(sim.now), cycles):
            t = clock.t_ns(k)
            yield sim.at(t, Priority.SAMPLE)
            results.append(probe(k, t))

    sim.process(sample())
    return results
