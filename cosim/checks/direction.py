"""Direction setup time: the direction output is steady and right before every step pulse.

Polarity (the default): direction level 1 = positive = pulse ``dir`` 1, as a
:class:`~cosim.signals.PulseTrain` counts it. Hardware with the opposite wiring sets
``positive_level=0``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cosim import validate
from cosim.checks.base import TICKS, Check, Clock, Findings, fmt, pulse_chunks, record_chunks
from cosim.checks.result import MAX_REPORTED, Violation
from cosim.errors import ConfigurationError
from cosim.tracecursor import Held

if TYPE_CHECKING:
    from cosim.trace import Trace


@dataclass(frozen=True)
class DirectionSetup(Check):
    """The direction signal holds its level for at least ``setup`` before each step pulse, and agrees with it.

    Parameters
    ----------
    step : str
        The step pulse train, e.g. ``pokeys.x.step``.
    direction : str
        The direction output, a bit signal, e.g. ``pokeys.x.dir``.
    setup : int
        Shortest allowed time from the last direction change to a pulse [ticks], >= 0.
    positive_level : {1, 0}
        The direction level that means a positive pulse (``dir`` 1). Default 1.
    active_delay : int
        Ticks from a recorded pulse to its active edge, where the drive counts it (a Trio step
        output: the step pulse width); the set-up is measured to the active edge. Default 0.
    trailing : bool
        The drive counts each pulse at its trailing edge, as recorded: the pulse plus the width the
        trace declares for the train (a Trio step output, whose falling edge is the active one), in
        place of ``active_delay``. The check then follows the recorded width, not a number given
        for it.

    Notes
    -----
    The first record of the direction signal is its initial value, held since before the run: it
    is not a change. A change at the same tick as a pulse counts as 0 ns before it.

    One violation per offending pulse, at the pulse's ``t_ns``:

    * setup too short: ``value`` = time since the last direction change [ns], ``limit`` = setup [ns];
    * wrong direction only: ``value`` = the direction level, ``limit`` = the level the pulse needed;
    * no direction value yet (pulse before the first record): ``value`` 0, ``limit`` = setup [ns].

    Measured: ``min_setup_ns`` (over pulses with a change before them), ``setup_violations``,
    ``direction_mismatches``.
    """

    step: str
    direction: str
    setup: int
    positive_level: int = 1
    active_delay: int = 0
    trailing: bool = False

    def __post_init__(self) -> None:
        if self.trailing and self.active_delay:
            raise ConfigurationError(f"{self.where}: give active_delay or trailing, not both")
        validate.integer(self.setup, "setup", low=0, unit="ticks", kind=TICKS, where=self.where)
        validate.integer(self.active_delay, "active_delay", low=0, unit="ticks", kind=TICKS, where=self.where)
        validate.integer(self.positive_level, "positive_level", low=0, high=1, allowed="0, 1", kind="an integer",
                         where=self.where)

    @property
    def main_signal(self) -> str:
        return self.step

    def examine(self, trace: Trace, clock: Clock) -> Findings:
        held = Held(record_chunks(trace, self.direction, self))
        setup_ns = clock.ns(self.setup)
        found = Findings(self.step, description=f"{self.direction} steady for at least {fmt(setup_ns)} ns before "
                                                f"each {self.step} pulse and agreeing with it "
                                                f"(level {self.positive_level} = dir 1)")
        shortest: int | None = None
        setup_violations = mismatches = 0
        delay = self.active_delay
        if self.trailing:
            info = trace.info.get(self.step)
            delay = info.pulse_width if info is not None else 0
            found.description += f" (active edge: the trailing one, {fmt(clock.ns(delay))} ns after the leading)"
        for recorded, d in pulse_chunks(trace, self.step, self):
            t = recorded + delay
            value, defined, changed_at, changed = held.at(t)
            undefined = ~defined
            level = (value != 0).astype(np.int8)
            wanted = level if self.positive_level == 1 else 1 - level  # the pulse dir this level means
            mismatch = defined & (d != wanted)
            age = t - changed_at
            short = changed & (age < self.setup)
            bad = np.flatnonzero(undefined | short | mismatch)
            found.n_violations += bad.size
            for i in bad[:MAX_REPORTED - len(found.violations)]:
                found.violations.append(self._violation(i, found.checked, t, d, level, age, undefined, short,
                                                        mismatch, clock))
            found.checked += t.size
            if changed.any():
                least = int(age[changed].min())
                shortest = least if shortest is None else min(shortest, least)
            setup_violations += int(np.count_nonzero(short | undefined))
            mismatches += int(np.count_nonzero(mismatch))
        if shortest is not None:
            found.measured["min_setup_ns"] = clock.ns(shortest)
        found.measured["setup_violations"] = setup_violations
        found.measured["direction_mismatches"] = mismatches
        return found

    def _violation(self, i: int, base: int, t: np.ndarray, d: np.ndarray, level: np.ndarray, age: np.ndarray,
                   undefined: np.ndarray, short: np.ndarray, mismatch: np.ndarray, clock: Clock) -> Violation:
        t_ns, setup_ns = clock.t_ns(t[i]), clock.ns(self.setup)
        k = base + i  # the pulse's index in the train
        if undefined[i]:
            return Violation(t_ns, 0, setup_ns, f"pulse {k}: {self.direction} has no value yet", unit="ns")
        needed = int(d[i]) if self.positive_level == 1 else 1 - int(d[i])
        wrong = f"; pulse dir {d[i]} needs level {needed}, level is {level[i]}" if mismatch[i] else ""
        if short[i]:
            since = clock.ns(age[i])
            changed_at = clock.t_ns(t[i] - age[i])
            return Violation(t_ns, since, setup_ns,
                             f"pulse {k}: {self.direction} changed to {level[i]} at "
                             f"{changed_at} ns, only {fmt(since)} ns before{wrong}", unit="ns")
        return Violation(t_ns, int(level[i]), needed, f"pulse {k}: dir {d[i]} but {self.direction} is {level[i]}",
                         unit="")  # levels
