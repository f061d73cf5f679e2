"""The co-simulation master: plants (FMUs) coupled to signals, advanced only when they must be.

A :class:`Plant` is advanced (one ``doStep`` from its own time to now) only

* when one of its inputs changes (:meth:`Plant.drive`): first advance to now with the old
  input, then set the new one;
* when one of its outputs is needed (:meth:`Plant.read`, or a requested sample from
  :meth:`Plant.record`);
* at an event it announces (:meth:`Plant.watch`): such plants get a kernel look-ahead and are
  stepped to the next instant at which anything else happens; an FMI 3.0 FMU that returns early
  at an event inside that step has its watched outputs published at the exact event tick.

An input whose values carry their own instants (a schedule, such as the Stepper's pulse-train
segments) does not advance the plant at all: it is written just before the plant's next step,
whatever asks for that step (:meth:`Plant.before_step`, :meth:`Plant.ahead_writer`).

Never on a fixed grid unless a scenario asks for sampling, so results do not depend on how many
samples are requested (beyond the FMU's own solver tolerance). Recorded outputs
(:meth:`Plant.record`) are sampled every period and also where the picture changes: at every
instant an input changes through :meth:`Plant.drive` or :meth:`Plant.set` (a gate, an enable, a
command), once per instant after everything else there, and at the plant's events (an early
return, a watched output changing). Inputs set on a coupling's hot path (:meth:`Plant.setter`,
:meth:`Plant.ahead_writer`: a stepper's rate or its per-slot pulse segments) add no samples. These
samples cost no FMU step: the plant is at that instant already. A grid sample costs one, unless the
plant takes samples inside its own steps (:mod:`cosim.sampleschedule`: the Laser does for power and
energy): then the samples ride inside the steps the plant makes anyway, bit-identical.

The calls are prepared once: a step is one ctypes call with arguments made at load
(:meth:`cosim.fmu.Fmu.stepper`), a sample one getter call per FMI type; samples taken in a row,
with nothing else due between them, are read into numpy blocks and handed to the trace when the
row ends (:class:`cosim.fmu.BlockSampler`). Such a row is stepped and read in C where a C compiler
is at hand (:mod:`cosim.gridloop`: one call from Python per row of up to a block of samples, the
same FMI calls with the same arguments, so the same values); elsewhere in Python.

Every FMI variable type can be read and set (:mod:`cosim.fmuvars`: arrays as numpy arrays);
numeric and Boolean outputs can be recorded (an array as one trace signal per element,
``<plant>.<variable>.<i>``) and scalar ones watched. A plant FMU that asks to end the simulation
raises :class:`~cosim.errors.PlantTerminated` at the tick of its request (for a watched plant the
run stops exactly there, before anything else happens at that tick); a terminated plant keeps its
last values for reads.

:class:`PlantLike` is the one plant protocol: what couplings (:mod:`cosim.couplings`) and
scenarios use of a plant. :class:`Plant` (an FMU) and the analytic plants of
:mod:`cosim.plants.analytic` implement it; a test double may too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from cosim import gridloop, sampleschedule
from cosim.errors import ConfigurationError, PlantTerminated
from cosim.fmu import Fmu, Value
from cosim.fmuvars import trace_names
from cosim.kernel import At, Simulation
from cosim.signals import Signal
from cosim.timebase import Priority


class PlantLike(Protocol):
    """What every plant offers the couplings: variables by name, read, set, driven and watched.

    Reading an output or setting an input brings the plant to the simulation's current time
    first; a watched output becomes a signal that changes at the plant's own events.
    """

    name: str
    sim: Simulation

    def variable_names(self) -> list[str]:
        """Every variable of the plant (inputs, outputs, parameters)."""
        ...

    def read(self, variable: str) -> Value:
        """Value of a variable now."""
        ...

    def set(self, values: Mapping[str, Value]) -> None:
        """Set inputs now."""
        ...

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        """A function setting these real inputs now, prepared once (for couplings' hot paths)."""
        ...

    def drive(self, variable: str, signal: Signal, *, convert: Callable[[float], Value] | None = None) -> None:
        """Let ``signal`` drive input ``variable`` from now on."""
        ...

    def watch(self, variable: str, *, signal: str | None = None, kind: str = "bit") -> Signal:
        """Publish an output as a signal that changes at the plant's own events."""
        ...


class Plant:
    """An FMU inside a :class:`~cosim.kernel.Simulation` (a :class:`PlantLike`).

    Parameters
    ----------
    sim : Simulation
    fmu : Fmu
        An initialised FMU at ``sim.now``; the plant closes it when the simulation closes.
    name : str
        Device name used as prefix of the plant's trace signals, e.g. ``laser``.
    """

    def __init__(self, sim: Simulation, fmu: Fmu, *, name: str) -> None:
        self.sim = sim
        self.fmu = fmu
        self.name = name
        self.steps = 0
        self._watched: dict[str, Signal] = {}
        self._pending: dict[str, float] = {}
        self._before_step: list[Callable[[int], None]] = []
        self._after_step: list[Callable[[int], None]] = []
        self._samplers: list[Callable[[int], None]] = []  # record the sampled outputs at the plant's tick
        self._sample_at = -1  # the tick of the latest sample asked for by an input change or an event
        self._step = fmu.stepper()
        for note in fmu.notes:
            sim.notes.add(note)
        sim.on_close(fmu.close)

    @classmethod
    def load(cls, sim: Simulation, model: str | Path, *, name: str, fmi_version: int = 3,
             parameters: Mapping[str, Value] | None = None) -> Plant:
        """Load a bundled plant by model name (built if missing or stale) or an FMU by path.

        Parameters
        ----------
        sim : Simulation
        model : str or path
            ``"Laser"`` (a model of ``fmu_src/``) or a path to a ``.fmu`` file.
        name : str
            Device name for trace signals.
        fmi_version : {2, 3}
            Which build of a bundled model to use.
        parameters : mapping, optional
            Parameter start values (e.g. a preset from ``models/``).
        """
        path = Path(model)
        if path.suffix != ".fmu":
            from cosim.fmubuild import ensure_fmu

            path = ensure_fmu(str(model), fmi_version)
        fmu = Fmu(path, timebase=sim.timebase, instance_name=name, parameters=parameters, start=sim.now)
        return cls(sim, fmu, name=name)

    def variable_names(self) -> list[str]:
        """Every variable of the FMU that the adapter can read or set."""
        return list(self.fmu.variables)

    # -- time -------------------------------------------------------------------------------
    def advance(self) -> None:
        """Bring the FMU to the current simulation time (no-op if it is there or has terminated)."""
        now = self.sim.now
        if self.fmu.t != now and self.fmu.terminated is None:
            self._advance_to(now)
            if self._watched:
                self._check_watched(now)

    def advance_ahead(self, t: int) -> None:
        """Bring the FMU to tick ``t`` at or after its own time, for a coupling acting on a run of segments.

        Only where nothing else can happen in the simulation before ``t`` (see
        :meth:`cosim.signals.PulseTrain.emit_run`): the step is the one :meth:`advance` would make with
        the clock at ``t``. ``t`` may be before now for segments a controller hands over late (a Trio's
        servo ticks in closed form, :attr:`cosim.signals.PulseTrain.pull`), never before the FMU's time.
        A watched plant (which has a look-ahead, so never sees runs) is refused.
        """
        if t < self.fmu.t or self._watched:
            raise ConfigurationError(f"{self.name}: advance_ahead to t={t} ticks (now {self.sim.now}, the FMU at "
                                     f"{self.fmu.t}) is allowed only at or after the FMU's time, for a plant "
                                     "without watched outputs")
        if self.fmu.t != t and self.fmu.terminated is None:
            self._advance_to(t)

    def _advance_to(self, t: int) -> None:
        for hook in self._before_step:
            hook(t)
        reached = self._step(t)
        self.steps += 1
        for hook in self._after_step:
            hook(reached)
        if reached < t:
            self._resume(t, reached)

    def _resume(self, t: int, reached: int) -> None:
        """The rest of a step to ``t`` that returned early at ``reached`` (an event of the plant's own)."""
        while reached < t:  # early return at an event: sample there, go on (watched plants never lag now)
            for take in self._samplers:
                take(reached)
            reached = self._step(t)
            self.steps += 1
            for hook in self._after_step:
                hook(reached)

    def _sample_soon(self, t: int) -> None:
        """Sample the recorded outputs at tick ``t`` (now or later), after everything else at that tick."""
        if self._samplers and t != self._sample_at:
            self._sample_at = t
            self.sim.call_at(t, Priority.SAMPLE, self._sample_here)

    def _sample_here(self) -> None:
        # the plant is at this tick already (an input set it there, or the look-ahead found an event
        # there), or at the instant it terminated: no step
        for take in self._samplers:
            take(self.fmu.t)

    # -- inputs -----------------------------------------------------------------------------
    def drive(self, variable: str, signal: Signal, *,
              convert: Callable[[float], Value] | None = None) -> None:
        """Let ``signal`` drive FMU input ``variable`` from now on (its value is set at once)."""
        var = self.fmu.variable(variable)
        if var.causality not in ("input", "parameter"):
            raise ConfigurationError(f"{self.name}.{variable} is an {var.causality}, not an input")
        to_fmu = convert or (lambda v: v)
        fmu = self.fmu
        # a float for a Float64 scalar needs no check (Variable.check would return it as it is): its prepared setter
        checked = not (var.kind.name == "Float64" and not var.shape)

        def on_change(sig: Signal) -> None:
            self.advance()
            value = to_fmu(sig.value)
            if checked or type(value) is not float:
                fmu.set(variable, value)
            else:
                var.set(value)
            if self._samplers:
                self._sample_soon(self.sim.now)

        self.fmu.set(variable, to_fmu(signal.value))
        signal.subscribe(on_change)

    def set(self, values: Mapping[str, Value]) -> None:
        """Set inputs now (advancing first), for scenario scripts without a signal.

        Any type: an array variable takes a sequence or numpy array of its shape (or flat), an
        Enumeration also its item name; integers are checked against their range first.
        """
        self.advance()
        for variable, value in values.items():
            self.fmu.set(variable, value)
        self._sample_soon(self.sim.now)

    def setter(self, variables: Sequence[str]) -> Callable[[Sequence[float]], None]:
        """A function that sets the Float64 inputs ``variables`` now (advancing first) in one FMI call.

        Same effect as :meth:`set` with a mapping, for couplings that change an input at every
        slot: names are resolved and the FMI arguments prepared once.
        """
        write = self.fmu.writer(list(variables))
        advance = self.advance

        def set_now(values: Sequence[float]) -> None:
            advance()
            write(values)

        return set_now

    def before_step(self, hook: Callable[[int], None]) -> None:
        """Call ``hook(t)`` just before every step of the FMU to tick ``t`` (whatever asks for the step).

        For inputs the master may set late (:meth:`ahead_writer`): a coupling collects them as they
        are announced and writes them in its hook, so the FMU is stepped only when an output is needed,
        another input changes or it announces an event, never for these inputs alone.
        """
        self._before_step.append(hook)

    def after_step(self, hook: Callable[[int], None]) -> None:
        """Call ``hook(t)`` just after every step of the FMU, with the tick ``t`` it reached.

        For inputs that follow a function of time (an input table's interpolated columns,
        :mod:`cosim.fmuinput`): the hook sets them to their value at ``t``, which the FMU then holds
        over its next step, and which an output read at ``t`` already sees. Such inputs add no samples.
        """
        self._after_step.append(hook)

    def ahead_writer(self, variable: str, values: np.ndarray) -> Callable[[], None]:
        """A function writing the contents of ``values`` to the Float64 array input ``variable``, without advancing.

        Only for inputs whose values carry their own instants (a schedule, such as the Stepper's
        ``step_segments``: each row says when its pulses fall), which the FMU applies at those
        instants: a value written while the FMU lags behind the simulation's time still holds
        everything the FMU has to place from its own time on. Call it from a :meth:`before_step`
        hook. ``values``: a C-contiguous float64 numpy array of the variable's size, filled by the
        caller before each call (FMI 3.0; the call is prepared once).
        """
        return self.fmu.array_writer(variable, values)

    # -- outputs ----------------------------------------------------------------------------
    def read(self, variable: str) -> Value:
        """Value of ``variable`` now (advances the FMU to now first)."""
        self.advance()
        return self.fmu.get(variable)

    def record(self, variables: Mapping[str, str] | Sequence[str], *, period: int,
               start: int | None = None, units: Mapping[str, str] | None = None,
               at_events: bool = True) -> Callable[[], None]:
        """Sample outputs every ``period`` ticks at ``start + k*period`` (priority SAMPLE), and at events.

        With ``at_events`` the outputs are also sampled at every instant an input changes through
        :meth:`drive` or :meth:`set` (once, after everything else there) and at the plant's own
        events (an early return, a watched output changing), without a step of their own.

        Numbers and Booleans of any FMI type are recorded as ``real`` signals (integers beyond 2^53
        lose precision there); an array as one signal per element, ``<name>.<i>`` (``<name>.<i>.<j>``
        for two dimensions). Strings and binaries cannot be recorded.

        Parameters
        ----------
        variables : sequence of str or mapping FMU variable -> trace signal name
            A plain list is recorded as ``<plant>.<variable>``, the name in the trace's scheme
            (lower case; see :func:`cosim.fmuvars.trace_names`).
        period : int
            Sample period [ticks] (> 0).
        start : int, optional
            First sample time [ticks] (default: now).
        units : mapping, optional
            Units for the trace (default: the FMU's declared units).
        at_events : bool
            Also sample at input changes and events (default); False keeps to the grid (as fmpy's
            ``simulate_fmu`` does).

        Returns
        -------
        callable
            Takes one more sample of the same signals now (e.g. at the end of a run, which the
            periodic samples never reach). If the FMU asks to end the simulation on its way to now,
            the sample is taken at the instant it stopped (its last values) and
            :class:`~cosim.errors.PlantTerminated` is raised.
        """
        self.sim.timebase.check_ticks(period, name="period", minimum=1)
        mapping = dict(variables) if isinstance(variables, Mapping) else trace_names(
            list(variables), self.name, order=list(self.fmu.variables))
        sinks: list[Callable[[int, Any], None]] = []
        blocks: list[Callable[[Any, Any], None]] = []  # trace.extend of each signal: for samples taken in blocks
        arrays = False
        for variable, trace_name in mapping.items():
            var = self.fmu.variable(variable)
            arrays = arrays or bool(var.shape)
            if not var.kind.is_numeric:
                raise ConfigurationError(f"{self.name}.{variable} is a {var.type} variable: the trace records "
                                         "numbers and Booleans only (read it with read())")
            unit = (units or {}).get(variable, var.unit)
            elements = [trace_name + "".join(f".{i}" for i in index) for index in np.ndindex(var.shape)]
            for name in elements:
                self.sim.trace.declare(name, "real", unit=unit, description=f"{self.name} {variable}")
            recorders = [self.sim.trace.recorder(name) for name in elements]
            sinks.append(partial(_record_elements, recorders) if var.shape else recorders[0])
            blocks.append(partial(self.sim.trace.extend, elements[0]))
        t0 = self.sim.now if start is None else start

        self.sim.timebase.check_ticks(t0, name="start", minimum=self.sim.now)
        fill = self.fmu.sampler(list(mapping), sinks)  # numbers and bools go to the trace as they come
        # in a row of samples without other events between them: read into blocks, handed to the trace
        # when the row ends (before anything else can look at the trace)
        block = self.fmu.block_sampler(list(mapping), blocks)
        sim, env, fmu = self.sim, self.sim.env, self.fmu
        peek, count_step, advance_to, step = env.peek, env.count_step, self._advance_to, self._step

        last = [-1]  # the tick of the latest sample

        def take(t: int) -> None:
            if last[0] == t:
                return  # sampled at this tick already (an input change or an event asked first)
            if block is not None and block.count:
                block.flush()
            fill(t)
            last[0] = t

        def take_in_row(t: int) -> None:
            if last[0] == t:
                return
            block.take(t)  # type: ignore[union-attr]
            last[0] = t

        in_row = take_in_row if block is not None else take
        flush = block.flush if block is not None else (lambda: None)
        # rows of samples stepped and read in C (cosim.gridloop), where it is available: the same FMI calls
        grid = fmu.grid_row(block) if block is not None else None

        def sample_now() -> None:
            try:
                self.advance()
            except PlantTerminated:
                take(fmu.t)  # the FMU asked to end the simulation on the way: its values at that instant
                raise
            take(fmu.t if fmu.terminated is not None else sim.now)  # a terminated plant: its last instant

        if not arrays and sampleschedule.capacity(self, list(mapping)):  # samples inside the plant's own steps
            sampleschedule.ScheduledSamples(self, list(mapping), blocks, take, t0=t0, period=period)
            if at_events:
                self._samplers.append(take)
            return sample_now

        def sample() -> object:
            # The hot loop of sampled runs. While nothing else is due before the next sample (no
            # queued event at or before it, no look-ahead and no watched output that could make
            # one), samples are taken in a row without a kernel event each: same instants, same
            # values, a fraction of the cost. A plant that ends the simulation on a sample's tick
            # still gives that sample (its outputs are valid at the instant it stopped).
            k = 0
            while True:
                t = t0 + k * period
                yield At(env, t, Priority.SAMPLE)
                try:
                    if fmu.t != t:
                        self.advance()
                    while True:
                        in_row(t)
                        k += 1
                        t = t0 + k * period
                        if env.look_aheads or self._watched or peek() <= t:  # sim.due_by(t)
                            break
                        if (grid is not None and not (self._before_step or self._after_step) and fmu.t < t
                                and t < gridloop.EXACT_TICKS):
                            # a row of instants stepped and sampled in C: t is then its last one, sampled (the
                            # loop's in_row(t) does nothing), or the step left pending, sampled after finishing
                            k, t = self._grid_rows(grid, block, last, t0=t0, period=period, k=k)
                            if grid.pending:  # the step to t was made and needs more than a sample
                                reached = grid.finish(t)
                                self.steps += 1
                                if reached < t:
                                    self._resume(t, reached)
                            continue
                        count_step(t)  # progress on long sampled runs, which run here without events
                        if self._before_step or self._after_step:
                            advance_to(t)
                        else:  # _advance_to without hooks, inline
                            reached = step(t)
                            self.steps += 1
                            if reached < t:
                                self._resume(t, reached)
                except PlantTerminated as ended:
                    flush()
                    if ended.t == t:
                        take(t)
                    raise
                finally:
                    flush()

        self.sim.process(sample())  # type: ignore[arg-type]
        if at_events:
            self._samplers.append(take)
        return sample_now

    def _grid_rows(self, grid: Any, block: Any, last: list[int], *, t0: int, period: int, k: int) -> tuple[int, int]:
        """One row of grid instants from ``t0 + k*period`` on, stepped and sampled in C: as many as are before the
        next queued event and fit in the block. Returns the ``(k, t)`` of the row's last instant, sampled, or
        of the step left :attr:`~cosim.gridloop.GridRow.pending`, not sampled yet."""
        env = self.sim.env
        n = block.rows - block.count
        due = env.peek()
        if due < math.inf:
            n = min(n, (int(due) - t0 - 1) // period - k + 1)  # instants t0 + m*period < due, m >= k
        n = min(n, (gridloop.EXACT_TICKS - 1 - t0) // period - k + 1)  # >= 1: t0 + k*period is below both
        done = grid.run(t0, period, k, n)
        passes = done + int(grid.pending)  # env.count_step for each, inline (progress reports)
        before = env._steps + env._skips
        env._skips += passes
        self.steps += done
        k += done if grid.pending else done - 1
        t = t0 + k * period
        if env._on_progress is not None and (before ^ (before + passes)) >> 12:
            env._on_progress(t)
        if done and not grid.pending:
            last[0] = t
        elif done:
            last[0] = t - period
        if block.count == block.rows:
            block.flush()
        return k, t

    def watch(self, variable: str, *, signal: str | None = None, kind: str = "bit") -> Signal:
        """Publish output ``variable`` as a signal that changes at the plant's own events.

        The plant gets a kernel look-ahead: before the clock moves it is advanced to the next
        instant, and a change found on the way (exactly located on FMI 3.0 with early return;
        at the end of the step on FMI 2.0) is published at its tick with priority PLANT_EVENT.
        """
        var = self.fmu.variable(variable)
        if not var.kind.is_numeric or var.shape:
            raise ConfigurationError(f"{self.name}.{variable} is a {var.type}{var.dimensions} variable: a watched "
                                     "output must be a number or a Boolean (a signal carries one)")
        name = signal or f"{self.name}.{variable}"
        out = Signal(self.sim, name, kind=kind, initial=_number(self.fmu.get(variable)), unit=var.unit,
                     description=f"{self.name} output {variable}")
        if not self._watched:
            self.sim.add_look_ahead(self._look_ahead)
        self._watched[variable] = out
        return out

    def _look_ahead(self, t_next: int) -> None:
        if self.fmu.t >= t_next or self.fmu.terminated is not None:
            return
        for hook in self._before_step:
            hook(t_next)
        try:
            reached = self.fmu.advance_to(t_next)
        except PlantTerminated as ended:
            # the clock has not moved yet: end the run at the plant's tick, before anything else there
            self.sim.call_at(max(ended.t, self.sim.now), Priority.PLANT_EVENT, partial(_raise, ended))
            return
        self.steps += 1
        for hook in self._after_step:
            hook(reached)
        self._pending = {v: _number(self.fmu.get(v)) for v in self._watched}
        if any(self._pending[v] != s.value for v, s in self._watched.items()):
            self.sim.call_at(reached, Priority.PLANT_EVENT, self._publish_pending)
            self._sample_soon(reached)
        elif reached < t_next:  # an event of the plant's own, no watched output changed
            self._sample_soon(reached)

    def _publish_pending(self) -> None:
        values, self._pending = self._pending, {}
        for variable, value in values.items():
            self._watched[variable].set(value)

    def _check_watched(self, now: int) -> None:
        changed = [out.set(_number(self.fmu.get(variable))) for variable, out in self._watched.items()]
        if any(changed):
            self._sample_soon(now)


def _number(value: Value) -> float:
    """A watched output's value (a number or a Boolean: :meth:`Plant.watch` checked its type)."""
    assert isinstance(value, int | float), value
    return value


def _raise(error: Exception) -> None:
    raise error


def _record_elements(recorders: list[Callable[[int, float], None]], t: int, value: Value) -> None:
    """Record an array output's elements, one signal each (row-major)."""
    for record, x in zip(recorders, np.ravel(value).tolist(), strict=True):
        record(t, x)
