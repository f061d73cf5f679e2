"""Periodic samples a plant FMU takes inside its own steps, so that a sample does not cost a doStep.

A plant that offers it (an FMI 3.0 FMU with a Float64 input ``sample_schedule`` of shape ``[N, 2]``,
an Int32 output ``samples_taken[1]`` and, for each sampled output ``x``, a Float64 output
``x_samples[N]``: the bundled Laser has them for ``power`` and ``energy``) is told, before each
step, the sample instants inside that step; it stops at each of them as separate doSteps would,
with the same floating-point operations (row k of the schedule holds the end of the step before
the instant, ``t + h``, and the start of the step after it, the next ``t``, as the master would
pass them), and keeps the outputs there. The master reads them after the step and records them at
their ticks: the same values as one doStep per sample, bit for bit.

The plant is still stepped wherever it was before (an input change, a read, its events); the
samples between those steps ride along. So that a schedule never holds more than ``N`` instants, a
sample every ``N`` instants is taken the ordinary way (a step to it); when a run stops, the samples
up to that instant are delivered (a step to the last of them). A sample whose instant is where the
plant is stepped anyway is read there, after everything else at that instant, as before.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from cosim.errors import FmuError
from cosim.kernel import At
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.master import Plant

SCHEDULE, TAKEN, SUFFIX = "sample_schedule", "samples_taken", "_samples"


def capacity(plant: Plant, variables: Sequence[str]) -> int:
    """How many samples per step the plant takes for ``variables`` (0: it cannot; sample the ordinary way)."""
    fmu = plant.fmu
    schedule, taken = fmu.variables.get(SCHEDULE), fmu.variables.get(TAKEN)
    resolution = fmu.timebase.resolution_s
    if resolution.numerator != 1 or resolution.denominator >= 2**53:  # ticks / N is then what the master passes
        return 0
    if fmu.fmi_version != 3 or schedule is None or taken is None or len(schedule.shape) != 2:
        return 0
    n = schedule.shape[0]
    if schedule.shape[1] != 2 or schedule.kind.name != "Float64" or taken.shape != (1,):
        return 0
    for name in variables:
        samples = fmu.variables.get(name + SUFFIX)
        if samples is None or samples.shape != (n,) or samples.kind.name != "Float64" or fmu.variable(name).shape:
            return 0
    return n


class ScheduledSamples:
    """The samples of ``variables`` every ``period`` ticks from ``t0``, taken inside the plant's steps.

    Parameters
    ----------
    plant : Plant
    variables : sequence of str
        The outputs sampled (each has ``<name>_samples``).
    sinks : sequence of callable
        ``sinks[i](t, values)``: record the samples of variable ``i`` (ticks and values, numpy arrays).
    take : callable
        ``take(t)``: read and record every variable now (the plant is at ``t``), as an ordinary sample.
    t0, period : int
        The grid [ticks].
    """

    def __init__(self, plant: Plant, variables: Sequence[str], sinks: Sequence[Callable[[Any, Any], None]],
                 take: Callable[[int], None], *, t0: int, period: int) -> None:
        self.plant, self.sinks, self.take = plant, list(sinks), take
        self.t0, self.period = t0, period
        fmu = plant.fmu
        self.n = capacity(plant, variables)
        self.schedule = np.zeros((self.n, 2), dtype=np.float64)
        self.write = fmu.array_writer(SCHEDULE, self.schedule)
        self.samples = [np.zeros(self.n, dtype=np.float64) for _ in variables]
        self.readers = [fmu.array_reader(name + SUFFIX, out) for name, out in zip(variables, self.samples, strict=True)]
        self.taken = np.zeros(1, dtype=np.int32)
        self.read_taken = fmu.array_reader(TAKEN, self.taken)
        self.next_k = 0  # the first sample not taken yet
        self.rows: list[int] = []  # the ticks of the schedule written for the step under way
        per_second = float(fmu.timebase.resolution_s.denominator)  # capacity(): a resolution of 1/N s
        self.seconds_of: Callable[[Any], Any] = lambda ticks: ticks / per_second  # exact below 2**53 ticks
        plant.before_step(self.before)
        plant.after_step(self.after)
        plant.sim.on_stop(self.deliver)
        plant.sim.process(self.wake())

    def instant(self, k: int) -> int:
        return self.t0 + k * self.period

    # -- the steps ---------------------------------------------------------------------------------
    def before(self, target: int) -> None:
        """Tell the plant the sample instants strictly inside its step to ``target``."""
        t = self.plant.fmu.t
        first = max(self.next_k, -((self.t0 - t - 1) // self.period) if t >= self.t0 else 0)  # first instant > t
        last = -((self.t0 - target) // self.period) - 1  # last instant < target
        count = last - first + 1
        if count <= 0:
            self.rows = []
            return
        if count > self.n:
            raise FmuError(f"{self.plant.name}: {count} samples inside one step, the plant takes at most "
                           f"{self.n} (a step of the master that no sample bounded)")
        ticks = self.t0 + np.arange(first, last + 1, dtype=np.int64) * self.period
        before = np.empty_like(ticks)
        before[0] = t
        before[1:] = ticks[:-1]
        # as the master's doSteps would pass them: t + h ends the step before the instant, the next t begins
        # the step after it (int64 / int is the correctly rounded quotient, as Python's int / int)
        self.schedule[:count, 0] = self.seconds_of(before) + self.seconds_of(ticks - before)
        self.schedule[:count, 1] = self.seconds_of(ticks)
        if count < self.n:
            self.schedule[count] = 0.0  # the end of the list
        self.write()
        self.rows = ticks.tolist()

    def after(self, reached: int) -> None:
        """Record the samples the step took; then the sample at the instant reached, if one is due there."""
        if self.rows:
            ticks, self.rows = self.rows, []
            self.read_taken()
            taken = int(self.taken[0])
            if taken != len(ticks):
                raise FmuError(f"{self.plant.name}: the plant took {taken} of the {len(ticks)} samples asked for "
                               f"inside its step to t={reached} ticks", self.plant.fmu.log)
            times = np.array(ticks, dtype=np.int64)
            for sink, read, values in zip(self.sinks, self.readers, self.samples, strict=True):
                read()
                sink(times, values[:taken].copy())
            self.next_k = (ticks[-1] - self.t0) // self.period + 1
        if reached >= self.t0 and self.instant(self.next_k) == reached:
            sim = self.plant.sim
            if reached >= sim.now:  # read it at that instant, after everything else there
                sim.call_at(reached, Priority.SAMPLE, lambda: self.take_grid(reached))
            else:  # the plant caught up with an instant already past: nothing else happened to it there
                self.take_grid(reached)

    def take_grid(self, t: int) -> None:
        """The ordinary sample at grid instant ``t``, where the plant is (once)."""
        k = (t - self.t0) // self.period
        if k < self.next_k or self.plant.fmu.t != t:
            return
        self.take(t)
        self.next_k = k + 1

    # -- bounds ----------------------------------------------------------------------------------------
    def wake(self) -> Any:
        """Every ``n`` samples, one taken the ordinary way (a step to it), so that a schedule stays within ``n``."""
        env = self.plant.sim.env
        while True:
            k = self.next_k + self.n - 1 if self.next_k else 0
            t = self.instant(k)
            yield At(env, t, Priority.SAMPLE)
            for _ in range(self.n if k else 1):  # progress counts samples (a long sampled run shows it moving)
                env.count_step(t)
            if self.next_k > k:
                continue  # taken meanwhile
            if self.plant.fmu.terminated is None:
                self.plant.advance()
            self.take_grid(t)

    def deliver(self, now: int) -> None:
        """The run stopped at ``now``: the samples before it that the plant has not delivered yet."""
        plant = self.plant
        if plant.fmu.terminated is not None or plant.fmu._ended is not None:
            return
        last = (now - 1 - self.t0) // self.period
        if now <= self.t0 or last < self.next_k:
            return
        t = self.instant(last)
        if t <= plant.fmu.t:
            return
        try:
            plant._advance_to(t)
        except Exception:  # the run stops with its own error; this keeps what it can
            return
