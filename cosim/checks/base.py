"""What every check shares: naming, the examined-nothing rule, reading signals (parameters: :mod:`cosim.validate`).

A check is a frozen dataclass whose :meth:`Check.evaluate` reads a :class:`~cosim.trace.Trace`
and nothing else. Parameters are integer ticks of the trace's time base; results report instants
and durations in ns (see :class:`Clock`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field, fields
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from cosim.checks.result import CheckResult, Number, Violation
from cosim.errors import ConfigurationError
from cosim.timebase import TimeBase

if TYPE_CHECKING:
    from cosim.trace import Trace

Ints = npt.NDArray[np.int64]
Floats = npt.NDArray[np.float64]
VALUE_KINDS = ("bit", "int", "real")
#: What a tick parameter must be, as messages say it (``cosim.validate.integer(..., kind=TICKS)``).
TICKS = "an integer number of ticks"
#: Parameters of a check that name a signal (besides ``signal`` and ``*_signal``), and lists of them.
SIGNAL_FIELDS = ("signal", "step", "direction", "gate")
SIGNAL_LISTS = ("positions",)


@dataclass(frozen=True)
class Clock:
    """Ticks of a trace's time base as the nanoseconds a result reports.

    With the default 1 ns resolution a tick is a nanosecond. With a coarser resolution that is a
    whole number of ns the conversion is exact; with a finer one (ps) instants are rounded down to
    whole ns and durations are given as float ns.
    """

    timebase: TimeBase

    @property
    def ns_per_tick(self) -> Fraction:
        return self.timebase.resolution_s * 10**9

    def t_ns(self, ticks: int | np.integer) -> int:
        """An instant [ticks] in whole ns (rounded down if the resolution is finer than 1 ns)."""
        exact = int(ticks) * self.ns_per_tick
        return exact.numerator // exact.denominator

    def ns(self, ticks: int | np.integer) -> Number:
        """A duration [ticks] in ns: an int when exact, else a float."""
        exact = int(ticks) * self.ns_per_tick
        return exact.numerator if exact.denominator == 1 else float(exact)


@dataclass
class Findings:
    """What a check found, before the common rules (empty signal, verdict) are applied."""

    signal: str
    checked: int = 0
    n_violations: int = 0
    violations: list[Violation] = field(default_factory=list)
    measured: dict[str, Number] = field(default_factory=dict)
    description: str = ""
    empty_detail: str = ""


@dataclass(frozen=True)
class Check:
    """Base of all check specs: the keyword-only options every check has.

    Parameters
    ----------
    name : str, optional
        Name in reports; default ``Type(signal)``.
    allow_empty : bool
        Pass when there was nothing to check (for a check where that is fine, e.g. an axis the
        job may not move). By default a check that examined nothing neither passes nor fails: its
        outcome is ``UNCHECKED``, with the reason in ``nothing_checked``; a pass must mean
        something was checked.
    """

    name: str | None = field(default=None, kw_only=True)
    allow_empty: bool = field(default=False, kw_only=True)

    @property
    def main_signal(self) -> str:
        """The signal named in the default name and in results."""
        return str(getattr(self, "signal", ""))

    @property
    def label(self) -> str:
        """The name used in results and error messages."""
        return self.name or f"{type(self).__name__}({self.main_signal})"

    def signals(self) -> dict[str, object]:
        """The signals the check reads, by the parameter that names each (to check them before a run).

        A parameter names a signal when it is called ``signal``, ``*_signal``, ``step``,
        ``direction`` or ``gate`` (a list: ``positions``), or is an event reference (``start``,
        ``end``: :class:`~cosim.checks.EdgeRef`, :class:`~cosim.checks.PulseRef`). A value that is
        not a name (a list where one name goes, a name where a list goes) is returned as it is, for
        the caller to refuse.
        """
        out: dict[str, object] = {}
        for item in fields(self):
            value = getattr(self, item.name)
            if isinstance(getattr(value, "signal", None), str):
                out[f"{item.name}.signal"] = value.signal
            elif item.name in SIGNAL_FIELDS or item.name.endswith("_signal"):
                if value is not None:  # an optional one not given
                    out[item.name] = value
            elif item.name in SIGNAL_LISTS:
                if isinstance(value, list | tuple):
                    out.update({f"{item.name}[{i}]": v for i, v in enumerate(value)})
                else:
                    out[item.name] = value
        return out

    def evaluate(self, trace: Trace) -> CheckResult:
        """Evaluate the check on ``trace``.

        Raises
        ------
        KeyError
            A signal is not in the trace (the message names it and suggests close names).
        ConfigurationError
            A signal is of the wrong kind for this check.
        """
        try:
            found = self.examine(trace, Clock(trace.timebase))
        except KeyError as exc:
            raise KeyError(f"{self.label}: {exc.args[0] if exc.args else exc}") from None
        violations = sorted(found.violations, key=lambda v: v.t_ns)
        nothing = ""
        if found.checked == 0 and found.n_violations == 0 and not self.allow_empty:
            nothing = found.empty_detail or f"signal {found.signal} had no data: nothing was checked"
        return CheckResult(
            name=self.label, passed=found.n_violations == 0 and not nothing, checked=found.checked,
            n_violations=found.n_violations, violations=tuple(violations), measured=dict(found.measured),
            signal=found.signal, description=found.description, nothing_checked=nothing,
        )

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        """Find the violations (each check implements this)."""
        raise NotImplementedError

    @property
    def where(self) -> str:
        """Location prefix for configuration errors."""
        return self.label


# -- reading signals ---------------------------------------------------------------------------
def _require_kind(trace: Trace, name: str, kinds: tuple[str, ...], check: Check) -> None:
    info = trace.info.get(name)
    if info is not None and info.kind not in kinds:
        raise ConfigurationError(
            f"{check.label}: signal {name} is a {info.kind} signal; this check needs a "
            f"{' or '.join(kinds)} signal"
        )


def pulse_chunks(trace: Trace, name: str, check: Check) -> Iterator[tuple[Ints, npt.NDArray[np.int8]]]:
    """``(t, dir)`` of every pulse of a pulse train, in time order, chunk by chunk (an unknown name
    raises KeyError when read)."""
    _require_kind(trace, name, ("pulse",), check)
    return trace.pulse_chunks(name)


def record_chunks(trace: Trace, name: str, check: Check) -> Iterator[tuple[Ints, Floats]]:
    """``(t, value)`` of a bit/int/real signal, every record in time order, chunk by chunk."""
    _require_kind(trace, name, VALUE_KINDS, check)
    return trace.edge_chunks(name)


def records(trace: Trace, name: str, check: Check) -> tuple[Ints, Floats]:
    """``(t, value)`` of a bit/int/real signal: every recorded change or sample."""
    _require_kind(trace, name, VALUE_KINDS, check)
    return trace.edges(name)


def unit_of(trace: Trace, name: str) -> str:
    """The unit ``name`` was declared with (``""`` when it has none or is not in the trace)."""
    info = trace.info.get(name)
    return info.unit if info is not None else ""


def changes(t: Ints, v: Floats) -> tuple[Ints, Floats]:
    """The records where the value differs from the one before (the first record is the initial value)."""
    moved = np.flatnonzero(v[1:] != v[:-1]) + 1
    return t[moved], v[moved]


def held_index(t_records: Ints, t_query: Ints) -> Ints:
    """Index of the record holding the value at each query instant (-1 before the first record).

    A record at exactly the query instant counts: the value is the one after it.
    """
    return np.searchsorted(t_records, t_query, side="right").astype(np.int64) - 1


def signed_position(direction: npt.NDArray[np.int8]) -> Ints:
    """Signed pulse count after each pulse (dir 1 = +1, dir 0 = -1)."""
    return np.cumsum(direction.astype(np.int64) * 2 - 1)


def trace_end(trace: Trace, *times: Ints) -> int:
    """The end of the trace: its recorded end or the last recorded instant, whichever is later."""
    last = [int(t[-1]) for t in times if t.size]
    return max([trace.end_t, *last])


def as_number(x: float | np.integer | np.floating) -> Number:
    """A value as an int when it is whole (counts, levels), else a float."""
    f = float(x)
    return int(f) if f.is_integer() else f


def fmt(x: Number | np.integer | np.floating) -> str:
    """A number for a detail line: integers without a decimal point."""
    f = float(x)
    return str(int(f)) if f.is_integer() else f"{f:g}"
