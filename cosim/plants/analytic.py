"""Plants written in Python with exact or closed-form solutions, for machines without an FMU.

* :class:`IdealConveyor` -- a master conveyor whose position is an exact function of time
  (piecewise constant acceleration, :class:`~fractions.Fraction` arithmetic), an incremental
  encoder with ``count = floor(position)`` and exact edge instants (the first tick at which the
  count is reached), and registration marks as a bit signal. Besides its variables it is an
  :class:`~cosim.encoders.EncoderSource`, so a controller can read its edges exactly.
* :class:`DcMotor` -- a DC motor with its amplifier and encoder, ``G(s) = K / (s (tau s + 1))``
  from its command input to its position [counts], advanced with its exact solution between
  command changes.

Both offer the one plant protocol (:class:`cosim.master.PlantLike`): variables by name, read,
driven and watched like an FMU behind :class:`cosim.master.Plant`.

Before t = 0 the conveyor is taken to have run at its initial speed, so the first servo cycles
already see valid edge instants. The conveyor only moves forward (speed >= 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.encoders import EncoderSample
from cosim.errors import ConfigurationError
from cosim.signals import Signal
from cosim.timebase import Priority
from cosim.validate import exact, integer, positive

if TYPE_CHECKING:
    from cosim.kernel import Simulation

Number = int | Fraction
Value = float | int | bool


def _ceil(x: Fraction) -> int:
    return -((-x.numerator) // x.denominator)


class AnalyticPlant:
    """What every Python plant shares: variables by name (the :class:`~cosim.master.PlantLike` protocol).

    Subclasses register their outputs (a function giving the value now), inputs (a function
    taking the new value) and watchable outputs (a signal the plant sets at its own events).
    """

    def __init__(self, sim: Simulation, name: str) -> None:
        self.sim = sim
        self.name = name
        self._outputs: dict[str, Callable[[], Value]] = {}
        self._inputs: dict[str, Callable[[float], None]] = {}
        self._events: dict[str, Signal] = {}

    def variable_names(self) -> list[str]:
        """Every variable: inputs, then outputs."""
        return [*self._inputs, *self._outputs]

    def _unknown(self, variable: str, what: str, names: Sequence[str]) -> ConfigurationError:
        return ConfigurationError.out_of_range(f"{what} of {self.name}", variable, ", ".join(names) or "none")

    def read(self, variable: str) -> Value:
        """Value of an output now."""
        if variable not in self._outputs:
            raise self._unknown(variable, "output", list(self._outputs))
        return self._outputs[variable]()

    def set(self, values: Mapping[str, Value]) -> None:
        """Set inputs now."""
        for variable, value in values.items():
            if variable not in self._inputs:
                raise self._unknown(variable, "input", list(self._inputs))
            self._inputs[variable](float(value))

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        """A function setting ``variables`` now."""
        names = list(variables)
        for variable in names:
            if variable not in self._inputs:
                raise self._unknown(variable, "input", list(self._inputs))

        def set_now(values: Sequence[float]) -> None:
            self.set(dict(zip(names, values, strict=True)))

        return set_now

    def drive(self, variable: str, signal: Signal, *, convert: Callable[[float], Value] | None = None) -> None:
        """Let ``signal`` drive input ``variable`` from now on (its value is set at once)."""
        to_plant = convert or (lambda v: v)
        self.set({variable: to_plant(signal.value)})
        signal.subscribe(lambda sig: self.set({variable: to_plant(sig.value)}))

    def watch(self, variable: str, *, signal: str | None = None, kind: str = "bit") -> Signal:
        """The signal the plant sets at its own events for ``variable`` (its name is fixed: ``<plant>.<variable>``)."""
        if variable not in self._events:
            raise self._unknown(variable, "watchable output", list(self._events))
        out = self._events[variable]
        if signal is not None and signal != out.name:
            raise ConfigurationError.out_of_range(f"signal name of {self.name}.{variable}", signal, out.name)
        return out


class IdealConveyor(AnalyticPlant):
    """A conveyor whose position is an exact function of time.

    Parameters
    ----------
    sim : Simulation
    speed_counts_per_ms : int or Fraction
        Speed at t = 0 (and before) [counts/ms], >= 0.
    phases : sequence of (duration_ticks, accel_counts_per_ms2)
        Consecutive phases of constant acceleration from t = 0; afterwards the speed stays.
    position_counts : int or Fraction
        Position at t = 0 [counts].
    marks : sequence of int or Fraction
        Registration-mark positions [counts], each > ``position_counts``.
    mark_width_counts : int or Fraction
        Length of a mark [counts]: the sensor is high from ``m`` to ``m + width``.
    name : str
        Plant name: the mark sensor is the signal ``<name>.mark``.

    Notes
    -----
    Variables: ``position`` [counts], ``encoder_count`` [counts], ``edge_direction`` (+1),
    ``t_last_edge`` and ``t_prev_edge`` [s] (the start time before there were edges), ``mark``
    (watchable), the same names as the Conveyor FMU's.

    Examples
    --------
    >>> from cosim.kernel import Simulation
    >>> belt = IdealConveyor(Simulation(), speed_counts_per_ms=64)
    >>> belt.position(15_625), belt.time_at(3)
    (Fraction(1, 1), 46875)
    """

    def __init__(self, sim: Simulation, *, speed_counts_per_ms: Number = 0,
                 phases: Sequence[tuple[int, Number]] = (), position_counts: Number = 0,
                 marks: Sequence[Number] = (), mark_width_counts: Number = 1, name: str = "conveyor") -> None:
        super().__init__(sim, name)
        ticks_per_ms = sim.ticks(1, "ms")
        v = positive(speed_counts_per_ms, "speed_counts_per_ms", unit="counts/ms (forward only)", zero=True)
        v /= ticks_per_ms
        p = exact(position_counts, "position_counts")
        t = 0
        self._phases: list[tuple[int, Fraction, Fraction, Fraction]] = []  # (t_start, p, v [counts/tick], a)
        for duration, accel in phases:
            integer(duration, "phase duration_ticks", low=1, unit="ticks")
            a = exact(accel, "accel_counts_per_ms2") / ticks_per_ms**2
            self._phases.append((t, p, v, a))
            p += v * duration + a * duration * duration / 2
            v += a * duration
            t += duration
            if v < 0:
                raise ConfigurationError.out_of_range(
                    f"acceleration of the phase ending at tick {t}", accel,
                    "values that keep the speed >= 0 (the ideal conveyor only moves forward)")
        self._phases.append((t, p, v, Fraction(0)))
        self._p0, self._v0 = self._phases[0][1], self._phases[0][2]
        self._cache: dict[Fraction, int | None] = {}
        self.mark = Signal(sim, f"{name}.mark", kind="bit", description="registration-mark sensor")
        self.mark_times: list[tuple[int, int]] = []
        width = positive(mark_width_counts, "mark_width_counts", unit="counts")
        for m in marks:
            if exact(m, "mark position") <= self._p0:
                raise ConfigurationError.out_of_range("mark position", m, f"> position_counts = {position_counts}")
            rise, fall = self.time_at(Fraction(m)), self.time_at(Fraction(m) + width)
            if rise is not None:
                self.mark_times.append((rise, fall if fall is not None else -1))
                sim.call_at(rise, Priority.PLANT_EVENT, self._mark_on)
            if fall is not None:
                sim.call_at(fall, Priority.PLANT_EVENT, self._mark_off)
        seconds = sim.timebase.seconds
        start = sim.now

        def edge_s(count_offset: int) -> float:
            t_edge = self.time_at(math.floor(self.position(sim.now)) + count_offset)
            return seconds(start if t_edge is None or t_edge <= start else t_edge)

        self._outputs.update({
            "position": lambda: float(self.position(sim.now)),
            "encoder_count": lambda: math.floor(self.position(sim.now)),
            "edge_direction": lambda: 1,
            "t_last_edge": lambda: edge_s(0),
            "t_prev_edge": lambda: edge_s(-1),
            "mark": lambda: self.mark.value,
        })
        self._events["mark"] = self.mark

    def _mark_on(self) -> None:
        self.mark.set(1)

    def _mark_off(self) -> None:
        self.mark.set(0)

    def _phase(self, t: int) -> tuple[int, Fraction, Fraction, Fraction]:
        if t < 0:
            return 0, self._p0, self._v0, Fraction(0)
        for phase in reversed(self._phases):
            if t >= phase[0]:
                return phase
        return self._phases[0]

    def position(self, t: int) -> Fraction:
        """Exact position at tick ``t`` [counts]."""
        t0, p, v, a = self._phase(t)
        tau = t - t0
        return p + v * tau + a * tau * tau / 2

    def speed_counts_per_ms(self, t: int) -> Fraction:
        """Exact speed at tick ``t`` [counts/ms]."""
        t0, _p, v, a = self._phase(t)
        return (v + a * (t - t0)) * self.sim.ticks(1, "ms")

    def time_at(self, x: Number) -> int | None:
        """First tick at which the position is >= ``x`` (None if never)."""
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

    def sample(self, t: int) -> EncoderSample:
        """Encoder state at tick ``t``: count = floor(position) and its last two edge instants."""
        count = math.floor(self.position(t))
        return EncoderSample(count, self.time_at(count), self.time_at(count - 1), 1)


class DcMotor(AnalyticPlant):
    """A DC motor, amplifier and encoder: ``K / (s (tau s + 1))`` from ``command`` to position.

    Parameters
    ----------
    sim : Simulation
    gain : float
        ``K`` [counts/s per command unit] (per DAC bit when a DAC drives it).
    tau_s : float
        Mechanical time constant ``tau`` [s], > 0.
    name : str
        Plant name.

    Notes
    -----
    Variables: input ``command`` [command units]; outputs ``position`` [counts] (float),
    ``speed`` [counts/s], ``encoder_count`` = ``floor(position)`` [counts].
    """

    def __init__(self, sim: Simulation, *, gain: float, tau_s: float, name: str = "slave") -> None:
        super().__init__(sim, name)
        self.gain = float(exact(gain, "gain"))
        self.tau_s = float(positive(tau_s, "tau_s", unit="s"))
        self._t = sim.now
        self._u = 0.0
        self.position_counts = 0.0
        self.speed_counts_per_s = 0.0
        self._inputs["command"] = self._on_command
        self._outputs.update({
            "position": self._position,
            "speed": self._speed,
            "encoder_count": lambda: math.floor(self._position()),
        })

    def _position(self) -> float:
        self._advance(self.sim.now)
        return self.position_counts

    def _speed(self) -> float:
        self._advance(self.sim.now)
        return self.speed_counts_per_s

    def _advance(self, t: int) -> None:
        dt = self.sim.timebase.seconds(t - self._t)
        if dt <= 0:
            return
        tau = self.tau_s
        v_end = self.gain * self._u
        decay = math.exp(-dt / tau)
        self.position_counts += v_end * dt + (self.speed_counts_per_s - v_end) * tau * (1 - decay)
        self.speed_counts_per_s = v_end + (self.speed_counts_per_s - v_end) * decay
        self._t = t

    def _on_command(self, value: float) -> None:
        self._advance(self.sim.now)
        self._u = float(value)
