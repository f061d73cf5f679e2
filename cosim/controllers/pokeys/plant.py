"""Coupling of the pulse engine's step/direction outputs and switch inputs to stepper plants.

The engine announces every slot of an axis with pulses as one pulse-train segment
``(t0 = slot_start + dir_setup_ns, 1 ms, count, direction)`` and places pulse k at
``t0 + (k * 1 ms) // count``. A stepper plant (the Stepper FMU) takes a signed ``step_rate`` held
from an anchor with its ``step_phase`` and places pulse j at ``t_anchor + (j - phase) / |rate|``.
:func:`couple_stepper` sets, at ``t0``, ``step_rate = +-count / 1 ms`` (phase 0): the FMU then puts
exactly ``count`` pulses in ``[t0, t0 + 1 ms)``, at ``t0 + k * 1 ms / count``, which is the engine's
instant plus ``(k * 1e6 mod count) / count`` ns: **less than 1 ns later**, never in another slot::

    slot          |s                  |s+1                |s+2      (no segment)
    engine        |.  |  .  .  .  .   |.  |  .  .  .  .   |.  |
    step_rate     ____|‾‾ 5 kHz ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|____   set at t0 of s, 0 at the end of s+1
                      ^ t0 = slot start + dir_setup_ns         (s+1 has the same rate: not set again)

The inputs are set at most once per slot (one FMU step each, :meth:`~cosim.master.Plant.setter`),
and not at all while the count and direction stay the same from one slot to the next (the FMU
continues its train from the same anchor, so the pulses are the same). ``step_rate`` returns to 0
at the end of the last segment of a run of slots.

The rate's sign follows the direction *pin*, as a driver sees it: pin low (the engine's positive
direction, not inverted) = positive rotation. With ``invert_direction`` on an axis the motor turns
the other way and counts ``-position``.

:func:`couple_switches` publishes the plant's switch outputs (1 = tripped, normally-closed
wiring, as the engine's inputs) as signals at the plant's own events and copies them to the
engine's limit and home inputs; the engine sees a change at its next slot start.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol
from weakref import WeakKeyDictionary

from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.limits import AXES, check_axis
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.stepper import segment_inputs
from cosim.signals import PulseTrain, Signal
from cosim.timebase import Priority


class StepperPlant(Protocol):
    """What the coupling needs of a plant: a :class:`~cosim.master.Plant` of the Stepper FMU, or a test double."""

    name: str

    def set(self, values: Mapping[str, float]) -> None:
        """Set inputs now (advancing the plant to now first)."""

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        """A function setting these inputs now (advancing first), prepared once for the hot path."""

    def read(self, variable: str) -> object:
        """Value of an output now."""

    def watch(self, variable: str) -> Signal:
        """Publish an output as a signal that changes at the plant's own events."""


SWITCH_OUTPUTS = ("limit_pos", "limit_neg", "home")
"""Stepper FMU outputs wired by :func:`couple_switches` (same names as the engine's inputs)."""


class _Wakeups:
    """One kernel event per instant at which some coupled axis of an engine may change its rate.

    Shared by the couplings of one engine, so a slot costs one event for all three axes (at
    ``slot_start + dir_setup_ns``), however many axes move.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.couplings: list[StepperCoupling] = []
        self._due: set[int] = set()

    def wake(self, t: int) -> None:
        if t not in self._due:
            self._due.add(t)
            # HOST: after the engine's slot at the same tick (dir_setup_ns = 0) has announced its segments
            self.sim.call_at(t, Priority.HOST, partial(self._fire, t))

    def _fire(self, t: int) -> None:
        self._due.discard(t)
        for coupling in self.couplings:
            coupling.update(t)


_WAKEUPS: WeakKeyDictionary[PulseEngine, _Wakeups] = WeakKeyDictionary()


@dataclass
class StepperCoupling:
    """State of one engine axis driving one stepper plant (made by :func:`couple_stepper`).

    Attributes
    ----------
    plant : StepperPlant
    axis : int
        Engine axis 0..2.
    sign : int
        +1, or -1 when the axis' direction output is inverted.
    commanded_signal : str
        Trace name of the plant's ``commanded_steps``, recorded at the coupling and whenever the
        axis stops (rate back to 0), where it must equal the engine's position counter.
    rate_hz : float
        The ``step_rate`` the plant has now [pulses/s].
    settings : int
        Input changes so far (each one FMU step at most).
    """

    sim: Simulation
    plant: StepperPlant
    axis: int
    sign: int
    commanded_signal: str
    wakeups: _Wakeups = field(repr=False)
    set_rate: Callable[[Sequence[float]], None] = field(repr=False)
    rate_hz: float = 0.0
    settings: int = 0
    _announced: dict[int, tuple[float, int]] = field(default_factory=dict, repr=False)  # t0 -> (rate, t_end)
    _t_end_ns: int | None = field(default=None, repr=False)  # end of the running segment

    def on_segment(self, _train: PulseTrain, t0: int, duration: int, count: int, direction: int) -> None:
        """Segment listener: the rate for ``[t0, t0 + duration)``, applied at ``t0``."""
        rate_hz = segment_inputs(duration, count, self.sign if direction else -self.sign)[0]
        self._announced[t0] = (rate_hz, t0 + duration)
        self.wakeups.wake(t0)

    def update(self, t: int) -> None:
        """At ``t``: start an announced segment, or return to rate 0 where the running one ends alone."""
        segment = self._announced.pop(t, None)
        if segment is not None:
            rate_hz, self._t_end_ns = segment
            self._apply(rate_hz)
            self.wakeups.wake(self._t_end_ns)  # merged with the next slot's wake-up when one follows
        elif self._t_end_ns == t:
            self._t_end_ns = None
            self._apply(0.0)

    def _apply(self, rate_hz: float) -> None:
        if rate_hz == self.rate_hz:
            return  # same rate from the same anchor: the FMU continues the train by itself
        self.set_rate((rate_hz,))
        self.rate_hz = rate_hz
        self.settings += 1
        if rate_hz == 0.0:
            self.sim.trace.record(self.commanded_signal, self.sim.now, _as_int(self.plant.read("commanded_steps")))


def couple_stepper(sim: Simulation, engine: PulseEngine, axis: int, plant: StepperPlant) -> StepperCoupling:
    """Drive ``plant`` (a Stepper FMU or a stand-in with the same inputs) from engine axis ``axis``.

    Parameters
    ----------
    sim : Simulation
    engine : PulseEngine
    axis : int
        0..2 (x, y, z).
    plant : StepperPlant
        A :class:`~cosim.master.Plant` of the Stepper FMU (or a stand-in): inputs ``step_rate``
        [pulses/s] and ``step_phase`` [1], output ``commanded_steps`` [steps].

    Returns
    -------
    StepperCoupling
        Also records ``<plant>.commanded_steps`` [steps] now and whenever the axis stops (rate
        back to 0), so a check can compare it with ``pokeys.<axis>.position`` at the end of a job.

    Examples
    --------
    ::

        x = run.plant("Stepper", name="stepper_x", preset="nema17_17hs16_2004s1")
        couple_stepper(run.sim, engine, 0, x)
    """
    check_axis(axis, where="couple_stepper")
    plant.set({"step_rate": 0.0, "step_phase": 0.0})
    sign = -1 if engine.config.axes[axis].invert_direction else 1
    name = f"{plant.name}.commanded_steps"
    sim.trace.declare(name, "int", unit="steps",
                      description=f"{plant.name} commanded_steps, read at the coupling and where pokeys axis "
                                  f"{AXES[axis]} stops")
    sim.trace.record(name, sim.now, _as_int(plant.read("commanded_steps")))
    wakeups = _WAKEUPS.get(engine)
    if wakeups is None:
        wakeups = _WAKEUPS[engine] = _Wakeups(sim)
    coupling = StepperCoupling(sim, plant, axis, sign, name, wakeups, plant.setter(("step_rate",)))
    wakeups.couplings.append(coupling)
    engine.steps[axis].subscribe(coupling.on_segment)
    return coupling


def couple_switches(plant: StepperPlant, engine: PulseEngine, axis: int,
                    outputs: tuple[str, ...] = SWITCH_OUTPUTS) -> list[Signal]:
    """Feed the engine's switch inputs of ``axis`` from the plant's switch outputs.

    Parameters
    ----------
    plant : StepperPlant
        Boolean outputs ``limit_pos``, ``limit_neg``, ``home`` (true = tripped).
    engine : PulseEngine
    axis : int
        0..2.
    outputs : tuple of str
        Which of the three to wire.

    Returns
    -------
    list of Signal
        The watched plant outputs (``<plant>.<output>``), in the order of ``outputs``.
    """
    check_axis(axis, where="couple_switches")
    inputs = {"limit_pos": engine.switches.limit_pos, "limit_neg": engine.switches.limit_neg,
              "home": engine.switches.home}
    watched = []
    for output in outputs:
        if output not in inputs:
            raise ConfigurationError.out_of_range("switch output", output, ", ".join(SWITCH_OUTPUTS),
                                                  where="couple_switches")
        source = plant.watch(output)
        target = inputs[output][axis]
        target.set(int(bool(source.value)))
        source.subscribe(partial(_copy_level, target))
        watched.append(source)
    return watched


def _copy_level(target: Signal, source: Signal) -> None:
    target.set(int(bool(source.value)))


def _as_int(value: object) -> int:
    return int(value)  # type: ignore[call-overload]
