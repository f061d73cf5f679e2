"""Step/direction outputs to a stepper plant (the Stepper FMU, or any plant with the same roles).

A controller announces every stretch of evenly spread pulses as one pulse-train segment
``(t0, duration, count, direction)`` whose pulse k is at ``t0 + (k * duration) // count`` (the
rule of :mod:`cosim.pulses`): a PoKeys slot, a Trio servo cycle. A stepper plant takes a signed
``step_rate`` held from an anchor with its ``step_phase`` and places pulse j at
``t_anchor + (j - phase) / |rate|``. :func:`couple_stepper` sets, at ``t0`` (plus the port's
``active_delay`` where the drive counts a pulse at its active edge, after the recorded instant),
``step_rate = +-count / duration`` (phase 0): the plant then puts exactly ``count`` pulses in
``[t0, t0 + duration)``, at ``t0 + k * duration / count``, which is the controller's instant plus
``(k * duration mod count) / count`` ticks: **less than one tick later**, never in another
segment::

    segment       |s                  |s+1                |s+2      (no segment)
    controller    |.  |  .  .  .  .   |.  |  .  .  .  .   |.  |
    step_rate     ____|‾‾ 5 kHz ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____   set at t0 of s, 0 at the end of s+1
                      ^ t0                                      (s+1 has the same rate: not set again)

The inputs are set at most once per segment (one plant step each, :meth:`PlantLike.setter`), and
not at all while the count and direction stay the same from one segment to the next (the plant
continues its train from the same anchor, so the pulses are the same). ``step_rate`` returns to 0
at the end of the last segment of a run of segments.

The rate's sign follows the direction *pin*, as a driver sees it: with a port whose pin is
``reversed`` relative to the count, the motor turns the other way (and counts ``-position``).

Roles (plant variables, with the Stepper FMU's names as defaults): ``step_rate`` [pulses/s] and
``step_phase`` [1] inputs; ``commanded_steps`` [steps] output (optional: recorded at the coupling
and wherever the axis stops, where it must equal the controller's count).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from weakref import WeakKeyDictionary

from cosim.couplings.roles import required, resolve
from cosim.kernel import Simulation
from cosim.master import PlantLike
from cosim.signals import PulseTrain, StepDirPort
from cosim.timebase import Priority, TimeBase

ROLES: dict[str, str | None] = {"step_rate": "step_rate", "step_phase": "step_phase",
                                "commanded_steps": "commanded_steps"}
"""Roles of the stepper coupling and the Stepper FMU's variables that play them."""


def segment_rate_hz(timebase: TimeBase, duration: int, count: int, sign: int) -> float:
    """``step_rate`` [pulses/s] that puts ``count`` pulses evenly into a segment of ``duration`` ticks.

    Examples
    --------
    >>> segment_rate_hz(TimeBase(), 1_000_000, 5, -1)
    -5000.0
    """
    return float(sign * count / (duration * timebase.resolution_s)) if count else 0.0


class _Wakeups:
    """One kernel event per instant at which some coupled axis may change its rate.

    Shared by every stepper coupling of a simulation, so an instant costs one event for all axes
    (at a PoKeys slot start + dir set-up), however many axes move.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.couplings: list[StepperCoupling] = []
        self._due: set[int] = set()

    def wake(self, t: int) -> None:
        if t not in self._due:
            self._due.add(t)
            # HOST: after the controller's slot or servo cycle at the same tick has announced its segments
            self.sim.call_at(t, Priority.HOST, partial(self._fire, t))

    def _fire(self, t: int) -> None:
        self._due.discard(t)
        for coupling in self.couplings:
            coupling.update(t)


_WAKEUPS: WeakKeyDictionary[Simulation, _Wakeups] = WeakKeyDictionary()


@dataclass
class StepperCoupling:
    """State of one step/direction output driving one stepper plant (made by :func:`couple_stepper`).

    Attributes
    ----------
    plant : PlantLike
    sign : int
        +1, or -1 when the port's direction pin is reversed relative to its count.
    commanded_signal : str or None
        Trace name of the plant's ``commanded_steps``, recorded at the coupling and whenever the
        axis stops (rate back to 0), where it must equal the controller's count; None when the
        plant has no such output.
    rate_hz : float
        The ``step_rate`` the plant has now [pulses/s].
    settings : int
        Input changes so far (each one plant step at most).
    """

    sim: Simulation
    plant: PlantLike
    sign: int
    commanded_signal: str | None
    commanded_variable: str | None = field(repr=False)
    wakeups: _Wakeups = field(repr=False)
    set_rate: Callable[[Sequence[float]], None] = field(repr=False)
    rate_hz: float = 0.0
    settings: int = 0
    _announced: dict[int, tuple[float, int]] = field(default_factory=dict, repr=False)  # t0 -> (rate, t_end)
    _t_end: int | None = field(default=None, repr=False)  # end of the running segment [ticks]

    def on_segment(self, _train: PulseTrain, t0: int, duration: int, count: int, direction: int) -> None:
        """Segment listener: the rate for ``[t0, t0 + duration)``, applied at ``t0``."""
        rate_hz = segment_rate_hz(self.sim.timebase, duration, count, self.sign if direction else -self.sign)
        self._announced[t0] = (rate_hz, t0 + duration)
        self.wakeups.wake(t0)

    def update(self, t: int) -> None:
        """At ``t``: start an announced segment, or return to rate 0 where the running one ends alone."""
        segment = self._announced.pop(t, None)
        if segment is not None:
            rate_hz, self._t_end = segment
            self._apply(rate_hz)
            self.wakeups.wake(self._t_end)  # merged with the next segment's wake-up when one follows
        elif self._t_end == t:
            self._t_end = None
            self._apply(0.0)

    def _apply(self, rate_hz: float) -> None:
        if rate_hz == self.rate_hz:
            return  # same rate from the same anchor: the plant continues the train by itself
        self.set_rate((rate_hz,))
        self.rate_hz = rate_hz
        self.settings += 1
        if rate_hz == 0.0 and self.commanded_signal is not None and self.commanded_variable is not None:
            self.sim.trace.record(self.commanded_signal, self.sim.now,
                                  _as_int(self.plant.read(self.commanded_variable)))


def couple_stepper(port: StepDirPort, plant: PlantLike, *,
                   variables: Mapping[str, str | None] | None = None) -> StepperCoupling:
    """Drive a stepper ``plant`` from a controller's step/direction ``port``.

    Parameters
    ----------
    port : StepDirPort
        E.g. ``engine.step_dir(0)`` (PoKeys axis x) or ``trio.step_dir(3)``.
    plant : PlantLike
        The Stepper FMU (or a plant with the roles of :data:`ROLES`).
    variables : mapping role -> variable, optional
        The plant's names for the roles, where they differ from the Stepper FMU's.

    Returns
    -------
    StepperCoupling
        Also records ``<plant>.commanded_steps`` [steps] now and whenever the axis stops (rate
        back to 0), so a check can compare it with the controller's count at the end of a job.

    Examples
    --------
    ::

        x = run.plant("Stepper", name="stepper_x", preset="nema17_17hs16_2004s1")
        couple_stepper(engine.step_dir(0), x)
    """
    names = resolve(plant, "stepper", ROLES, variables, optional=("commanded_steps",))
    sim = plant.sim
    plant.set({required(names, "step_rate"): 0.0, required(names, "step_phase"): 0.0})
    commanded = names["commanded_steps"]
    signal = None
    if commanded is not None:
        signal = f"{plant.name}.commanded_steps"
        sim.trace.declare(signal, "int", unit="steps",
                          description=f"{plant.name} {commanded}, read at the coupling and where "
                                      f"{port.step.name} stops")
        sim.trace.record(signal, sim.now, _as_int(plant.read(commanded)))
    wakeups = _WAKEUPS.get(sim)
    if wakeups is None:
        wakeups = _WAKEUPS[sim] = _Wakeups(sim)
    coupling = StepperCoupling(sim, plant, -1 if port.reversed else 1, signal, commanded, wakeups,
                               plant.setter((required(names, "step_rate"),)))
    wakeups.couplings.append(coupling)
    delay = port.active_delay
    port.step.subscribe(coupling.on_segment if not delay else  # the drive counts at the active edge
                        lambda train, t0, duration, count, direction:
                        coupling.on_segment(train, t0 + delay, duration, count, direction))
    return coupling


def _as_int(value: object) -> int:
    return int(value)  # type: ignore[call-overload]
