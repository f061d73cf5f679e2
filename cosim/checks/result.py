"""What a timing check reports: the verdict, what was checked, the first violations, key figures.

The runner stores :meth:`CheckResult.to_dict` in ``result.json``; its shape is fixed::

    {"name": str, "outcome": "PASS" | "FAIL" | "UNCHECKED", "passed": bool, "checked": int,
     "n_violations": int,
     "violations": [{"t_ns": int, "value": number, "limit": number | str, "detail": str, "unit": str}, ...],
     "measured": {figure: number, ...}, "signal": str, "description": str, "nothing_checked": str}

The outcome: ``FAIL`` when there was a violation, else ``UNCHECKED`` when the check examined
nothing (``checked == 0``) and was not told that this is fine (``allow_empty``), else ``PASS``.
An ``UNCHECKED`` check neither passed nor failed (``passed`` is false, ``n_violations`` 0);
``nothing_checked`` says why (e.g. ``signal pokeys.x.step had no data: nothing was checked``).

``violations`` holds the first :data:`MAX_REPORTED` violations in time order; ``n_violations``
counts all of them. A violation's ``unit`` is the unit of its value and of a number limit (``ns``
for a time or a duration, ``Hz``, ``pulses``, the unit of the signal whose value it is; ``""``
for a bare number or a state); a check that does not say leaves it out.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: How many violations a result lists (``n_violations`` counts all of them).
MAX_REPORTED = 20

Number = int | float


def plain(x: object) -> Any:
    """A numpy scalar as the Python int/float that JSON understands (other values unchanged)."""
    if isinstance(x, bool | np.bool_):
        return bool(x)
    if isinstance(x, int | np.integer):
        return int(x)
    if isinstance(x, float | np.floating):
        return float(x)
    return x


@dataclass(frozen=True)
class Violation:
    """One broken rule at one instant.

    Parameters
    ----------
    t_ns : int
        When it happened [ns].
    value : int or float
        What was measured there (the check says in what unit: ns, Hz, counts, signal value).
    limit : int, float or str
        What was allowed (a number in the same unit, or a short rule such as ``'never < 1'``).
    detail : str
        One line for humans.
    unit : str, optional
        The unit of ``value`` and of a number ``limit`` (``"ns"``, ``"Hz"``, ``"pulses"``, the
        signal's unit; ``""``: a bare number or a state). None: not said (left out of the dict).
    """

    t_ns: int
    value: Number
    limit: Number | str
    detail: str = ""
    unit: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """The violation as a JSON-ready dict."""
        out = {"t_ns": int(self.t_ns), "value": plain(self.value), "limit": plain(self.limit), "detail": self.detail}
        if self.unit is not None:
            out["unit"] = self.unit
        return out


@dataclass(frozen=True)
class CheckResult:
    """The outcome of one check on one trace.

    Parameters
    ----------
    name : str
        Name of the check (given by the user or made from its type and signal).
    passed : bool
        True when something was checked (or ``allow_empty``) and nothing broke the rule.
    checked : int
        How many items were examined (pulses, edges, samples, intervals...).
    n_violations : int
        How many violations there were in all.
    violations : tuple of Violation
        The first :data:`MAX_REPORTED` of them, in time order.
    measured : mapping of str to number
        Key figures (worst spacing, highest rate...); units are in the names (``_ns``, ``_hz``).
    signal : str
        The main signal the check reads.
    description : str
        The rule in one line.
    nothing_checked : str
        Why the check examined nothing, when it did and that is not fine for it (outcome
        ``UNCHECKED``); empty otherwise.
    """

    name: str
    passed: bool
    checked: int
    n_violations: int
    violations: tuple[Violation, ...] = ()
    measured: Mapping[str, Number] = field(default_factory=dict)
    signal: str = ""
    description: str = ""
    nothing_checked: str = ""

    @property
    def outcome(self) -> str:
        """``PASS``, ``FAIL`` (a violation) or ``UNCHECKED`` (examined nothing, and that is not fine here)."""
        if self.n_violations:
            return "FAIL"
        return "UNCHECKED" if self.nothing_checked else "PASS"

    def to_dict(self) -> dict[str, Any]:
        """The result as the runner stores it in ``result.json``."""
        return {
            "name": self.name,
            "outcome": self.outcome,
            "passed": bool(self.passed),
            "checked": int(self.checked),
            "n_violations": int(self.n_violations),
            "violations": [v.to_dict() for v in self.violations[:MAX_REPORTED]],
            "measured": {k: plain(v) for k, v in self.measured.items()},
            "signal": self.signal,
            "description": self.description,
            "nothing_checked": self.nothing_checked,
        }

    def summary(self) -> str:
        """One line: verdict, name, counts and the first violation.

        Examples
        --------
        >>> CheckResult("spacing", False, 3, 1, (Violation(1200, 200, 500, "too close"),)).summary()
        'FAIL spacing: 3 checked, 1 violation; first at t=1200 ns: 200 vs limit 500 (too close)'
        >>> CheckResult("spacing", False, 0, 0, nothing_checked="no pulses").summary()
        'UNCHECKED spacing: 0 checked (no pulses)'
        """
        if self.outcome == "UNCHECKED":
            return f"UNCHECKED {self.name}: 0 checked ({self.nothing_checked})"
        if self.checked == 0 and not self.n_violations:  # allow_empty: a pass, but say that nothing was examined
            return f"PASS {self.name}: 0 checked (nothing to examine; allowed for this check)"
        verdict = self.outcome
        plural = "" if self.n_violations == 1 else "s"
        line = f"{verdict} {self.name}: {self.checked} checked, {self.n_violations} violation{plural}"
        if self.violations:
            first = self.violations[0]
            line += f"; first at t={first.t_ns} ns: {plain(first.value)} vs limit {plain(first.limit)}"
            if first.detail:
                line += f" ({first.detail})"
        return line
