"""PMAC units: the servo clock (I10) and time-base values in 2^-23 ms, in exact integers.

PMAC measures time in units of 2^-23 ms (8,388,608 units = 1 ms). I10 is the servo interrupt
time in those units; a coordinate system's time-base value is in the same units per servo cycle,
so 100 % is a time-base value equal to I10.

Servo interrupt instants
------------------------
I10 is rarely a whole number of nanoseconds (the default 3,713,707 is 442,708.37 ns). The model
never rounds the period and never accumulates it: servo interrupt ``k`` is at the first tick of
the simulation's resolution at or before its exact instant::

    t_k = t0 + floor(k * I10 * 10**6 / (2**23 * ns_per_tick))   [ticks]

computed exactly from ``k``. At the default 1 ns resolution consecutive interrupts are therefore
442,708 or 442,709 ns apart with the default I10, and their average is exactly
I10 * 10**6 / 2**23 ns: the interrupt count never drifts from the real-time clock by more than
one tick.

Examples
--------
>>> clock = ServoClock()
>>> [clock.t(k) for k in range(4)]
[0, 442708, 885416, 1328125]
>>> ServoClock.from_period_ns(250_000).i10
2097152
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim import validate
from cosim.errors import ConfigurationError

#: Time units per millisecond (time-base values and I10 are in 2^-23 ms).
UNITS_PER_MS = 1 << 23
#: Largest value of a signed 24-bit PMAC register (I10, Ix94, time-base values).
REG_MAX = (1 << 23) - 1
#: Smallest value of a signed 24-bit PMAC register.
REG_MIN = -(1 << 23)
#: Mask of a 24-bit register.
REG_MASK = (1 << 24) - 1
#: Default servo interrupt time (I10), about 442.7 us.
I10_DEFAULT = 3_713_707
#: Default Ix94 (time-base slew per servo cycle): 0 -> 100 % in about one second.
IX94_DEFAULT = 1644
#: Largest Ix94.
IX94_MAX = REG_MAX
#: Nanoseconds per millisecond.
NS_PER_MS = 10**6
#: Allowed values of I10, of Ix94 and of a 24-bit setup word, as messages say them.
I10_ALLOWED = f"integers 1..{REG_MAX} (2^-23 ms)"
IX94_ALLOWED = f"integers 0..{IX94_MAX} (2^-23 ms per servo cycle)"
WORD_ALLOWED = f"integers 0..{REG_MASK}"


def hexaddr(value: int, digits: int = 4) -> str:
    """PMAC-style hex text of an address or register value, e.g. ``$0729``."""
    return f"${value:0{digits}X}"


class Reg(int):
    """An int shown as PMAC hex and decimal in error messages: ``$0729 (1833)``.

    Examples
    --------
    >>> Reg(1833)
    $0729 (1833)
    >>> Reg(0xC, digits=1)
    $C
    """

    digits: int
    decimal: bool

    def __new__(cls, value: int, digits: int = 4, *, decimal: bool | None = None) -> Reg:
        obj = super().__new__(cls, value)
        obj.digits = digits
        obj.decimal = digits > 1 if decimal is None else decimal
        return obj

    def __repr__(self) -> str:
        text = hexaddr(int(self), self.digits)
        return f"{text} ({int(self)})" if self.decimal else text


def wrap24(value: int) -> int:
    """Sign-extend the low 24 bits of ``value`` (what a 24-bit register difference gives)."""
    return ((value + (1 << 23)) & REG_MASK) - (1 << 23)


def saturate24(value: int) -> int:
    """Clamp ``value`` to the signed 24-bit range ``-2^23 .. 2^23-1``."""
    return max(REG_MIN, min(REG_MAX, value))


@dataclass(frozen=True)
class ServoClock:
    """The servo interrupt clock defined by I10.

    Parameters
    ----------
    i10 : int
        Servo interrupt time, I10 [2^-23 ms], 1..8,388,607 (0 would stop the clock).
    t0 : int
        Instant of servo interrupt 0 [ticks].
    ns_per_tick : Fraction
        The simulation's resolution [ns per tick] (1 by default; ``Pmac`` passes its own).
    """

    i10: int = I10_DEFAULT
    t0: int = 0
    ns_per_tick: Fraction = Fraction(1)

    def __post_init__(self) -> None:
        validate.integer(self.i10, "I10 (servo interrupt time)", low=1, high=REG_MAX, allowed=I10_ALLOWED)
        validate.integer(self.t0, "t0", low=0, high=1 << 62, allowed=f"integers 0..{1 << 62} ticks")
        validate.positive(self.ns_per_tick, "ns_per_tick")
        period = self.period_ticks  # t(k) in integers: t0 + (k * numerator) // denominator
        object.__setattr__(self, "_period_num", period.numerator)
        object.__setattr__(self, "_period_den", period.denominator)

    @classmethod
    def from_period_ns(cls, period_ns: int, *, t0: int = 0, ns_per_tick: Fraction = Fraction(1)) -> ServoClock:
        """The clock whose period is exactly ``period_ns`` (a multiple of 15,625 ns).

        Raises
        ------
        ConfigurationError
            If no integer I10 gives that period exactly (I10 = period_ns * 2^23 / 10^6).
        """
        i10 = Fraction(period_ns * UNITS_PER_MS, NS_PER_MS)
        if i10.denominator != 1:
            raise ConfigurationError.out_of_range(
                "servo period_ns", period_ns,
                "multiples of 15625 ns (I10 = period_ns * 2^23 / 10^6 must be an integer); "
                "use ServoClock(i10=...) for other periods")
        return cls(int(i10), t0, ns_per_tick)

    @property
    def period_ns(self) -> Fraction:
        """Exact servo period [ns] (usually not an integer)."""
        return Fraction(self.i10 * NS_PER_MS, UNITS_PER_MS)

    @property
    def period_ticks(self) -> Fraction:
        """Exact servo period [ticks] (usually not an integer)."""
        return self.period_ns / self.ns_per_tick

    @property
    def rate_hz(self) -> Fraction:
        """Exact servo interrupt rate [Hz]."""
        return Fraction(10**9) / self.period_ns

    @property
    def period_s(self) -> float:
        """Servo period [s] as a float: for controller design only, never for time keeping."""
        return float(self.period_ns) / 1e9

    def t(self, k: int) -> int:
        """Instant of servo interrupt ``k`` [ticks]: ``t0 + floor(k * period_ticks)``."""
        return self.t0 + k * self._period_num // self._period_den  # type: ignore[attr-defined]

    def first_cycle_at_or_after(self, t: int) -> int:
        """Smallest ``k`` with ``t(k) >= t`` (``t`` in ticks)."""
        if t <= self.t0:
            return 0
        period = self.period_ticks
        k = int((t - self.t0) / period)
        while self.t(k) < t:
            k += 1
        return k


def percent(timebase: int | Fraction, i10: int) -> Fraction:
    """Time-base value as a feedrate-override percentage: ``100 * value / I10`` (exact).

    For an integer value the float of it is ``100 * value / i10`` (Python's correctly rounded
    integer division), without building the fraction: what the servo cycle records.
    """
    return Fraction(100) * timebase / i10


def timebase_for_percent(pct: int | Fraction, i10: int) -> Fraction:
    """Time-base value (2^-23 ms per servo cycle) of ``pct`` percent: ``pct * I10 / 100``."""
    return Fraction(pct) * i10 / 100


def scale_factor_for(rtif_counts_per_ms: int | Fraction, *, triggered: bool = False) -> int:
    """SCALE_FACTOR of a time-base entry for a real-time input frequency (RTIF).

    Parameters
    ----------
    rtif_counts_per_ms : int or Fraction
        Master count rate [counts/ms] at which the time base is 100 %.
    triggered : bool
        True for the Turbo triggered entry (1/256 count: SF = 2^14 / RTIF); False for the
        untriggered entry on a 1/T source (1/32 count: SF = 2^17 / RTIF).

    Raises
    ------
    ConfigurationError
        If the scale factor is not an integer (choose RTIF as a power of two).

    Examples
    --------
    >>> scale_factor_for(64)
    2048
    >>> scale_factor_for(256, triggered=True)
    64
    """
    numerator = 1 << (14 if triggered else 17)
    rtif = validate.positive(rtif_counts_per_ms, "real-time input frequency", unit="counts/ms")
    return validate.integer(
        numerator / rtif, "SCALE_FACTOR", low=1, high=REG_MAX, whole=True, allowed=(
            f"integers 1..{REG_MAX}: {numerator} / RTIF must be whole, "
            "so choose the real-time input frequency as a power of two in counts/ms"))


def formula_percent(scale_factor: int, input_freq_counts_per_ms: int | Fraction, *,
                    triggered: bool = False) -> Fraction:
    """The manual's time-base formula: ``% = 100 * SF * INPUT_FREQ / 2^17`` (2^14 triggered)."""
    return Fraction(100 * scale_factor) * Fraction(input_freq_counts_per_ms) / (1 << (14 if triggered else 17))
