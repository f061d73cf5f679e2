"""When the servo cycle runs: explicit ticks, ticks skipped at rest, and moves in closed form.

The controller's servo cycle (:meth:`TrioController._tick`) runs at ``k * SERVO_PERIOD``. Running
it as a kernel event every period costs a Python pass per axis and per period, which for a job of
hours is most of the run (issue 29). :class:`ServoLoop` runs a tick as a kernel event (*explicit*)
only where the outcome can depend on something else; the others are *implicit*:

* **At rest** (:meth:`~TrioController.settled`: every axis at rest and recorded, nothing buffered,
  nothing waiting on the servo cycle) a tick changes nothing, so none runs until the first tick at or
  after the next event of the simulation (a program waking up, an input changing, a command between
  runs): whatever could change something comes from such an event, and the tick after it is
  explicit, exactly as before.
* **In a straight move** (``MOVE``, ``MOVEABS``, ``FORWARD``, ``REVERSE``, a CANCEL's stop) or an arc
  (``MOVECIRC``, its cosines and sines per cycle in integers; not towards a gate position) on axes
  whose outputs nobody listens to as they happen, or whose step pulses go only to plants that take
  them when they need them (a stepper coupling on the segments way, which *pulls* them before its
  plant steps: :attr:`cosim.signals.PulseTrain.pull`), the cycles up to the next event, the cycle in
  which the move ends, the cycle in which a gate position is reached, the cycle after which a run of
  pulses to a plant would end, or the cycle that would change a speed-linked PWM mark, are computed
  in closed form (:func:`materialize`): the same demand positions, step segments, MPOS, VP_SPEED and
  PWM_ENCODER counts, written with the instants they have, in one pass of integer arithmetic per
  axis, when they are needed. A pulled axis hands its segments to the plants as runs announced at
  their ticks (:meth:`~cosim.signals.PulseTrain.emit_run`); where the plant's rows fill up, it is
  stepped to the tick that filled them, as the explicit ticks would have.
* Programs **waiting** for move-buffer space, ``WAIT IDLE`` or ``WAIT LOADED`` are released only at a
  tick where a move ends (explicit); a ``WAIT UNTIL`` whose condition reads only memory (VR, TABLE,
  the program's variables: :class:`MemoryPoll`) stays false until a program writes memory, which
  is an event that bounds the window, so its checks at the ticks in between do not.

*Needed* means: before anything reads or changes the controller (every entry point calls
:meth:`ServoLoop.sync`, which brings the implicit ticks up to *now* up to date; a command or an input
change then makes the next tick explicit), at the next explicit tick, and when a run stops (the trace
is complete up to the instant reached). Events of the SAMPLE priority (recording plant outputs) do
not bound a window: by the kernel's convention they read plants, never a controller.

Why it is exact: an implicit tick is always strictly before the next event that could observe or
change the controller (a window ends at the first tick at or after that event's instant, and that tick
is explicit, ordered with the event by the kernel's priorities), and every output of an implicit tick
that something else consumes as it happens (step pulses to a plant that does not pull them, a change of
a speed-linked mark, a gate edge) either rules the window out or ends it; a plant that pulls gets every
segment before it steps (a plant with watched outputs, which looks ahead, rules pulling out). The
per-signal digests of every bundled run are unchanged.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from simpy.events import Event

from cosim.controllers.trio.paths import ArcPath
from cosim.controllers.trio.pwm import PwmMode
from cosim.kernel import At
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.controllers.trio.axis import Axis
    from cosim.controllers.trio.controller import TrioController
    from cosim.controllers.trio.counter import StepCounter
    from cosim.controllers.trio.motion import Move
    from cosim.signals import PulseTrain
    from cosim.trace import Trace

_HALF_WRAP = 1 << 27  # a window never spans this many counts (the gate's 29-bit wrap stays far)
_SCAN_CYCLES = 512  # a window with pulled axes or a speed-linked mark looks this many cycles ahead at most


class MemoryPoll(At):
    """A ``WAIT UNTIL`` check at a servo tick whose condition reads only memory (VR, TABLE, the program's own
    variables and constants): it cannot observe or change the controller, and it stays false until an
    event that writes memory (which bounds a window) has happened, so it does not bound a window."""


class ServoLoop:
    """Schedules the servo ticks of one controller (see the module doc).

    Parameters
    ----------
    controller : TrioController
    """

    #: Compute straight unobserved moves in closed form, and skip ticks at rest (False: every tick explicit,
    #: the reference the tests compare the trace with).
    shortcuts = True

    def __init__(self, controller: TrioController) -> None:
        self.controller = controller
        self.sim = controller.sim
        self.period = controller.period_ticks
        #: The last tick (index k, at k * period) that has run, explicitly or in closed form.
        self.k_done = -(-self.sim.now // self.period) - 1
        #: The next explicit tick and its kernel event.
        self.k_next = self.k_done + 1
        self._event: Event | None = None
        #: Moves computed in closed form for the ticks k_done + 1 .. k_next - 1 (empty: those ticks are no-ops).
        self._window: list[Move] = []
        self.implicit = 0  # ticks computed in closed form so far
        self.skipped = 0  # ticks at rest not run
        self._materializing = False
        # as a process started now would first run: after the events already due now (URGENT, like SimPy's)
        self.sim.call_at(self.sim.now, Priority.URGENT, lambda: self._schedule(self.k_next))
        self.sim.on_stop(lambda t: self.sync(t, at_now=False))

    # -- scheduling ---------------------------------------------------------------------------
    def _schedule(self, k: int) -> None:
        if self._event is not None:
            self.sim.cancel(self._event)
        self.k_next = k
        event = At(self.sim.env, k * self.period, Priority.SERVO)
        event.callbacks.append(self._on_tick)
        self._event = event

    def _on_tick(self, _event: Event) -> None:
        self._event = None
        sim, period, controller = self.sim, self.period, self.controller
        self.sync(sim.now, at_now=False)
        k = self.k_next
        while True:
            controller._tick()
            self.k_done = k
            k += 1
            if not self.shortcuts:
                self._schedule(k)
                return
            if controller.settled():  # the ticks up to the next event change nothing
                t_next = self._next_event_time()
                k_wake = max(k, -(-t_next // period)) if t_next is not None else k
                self.skipped += k_wake - k
                self._window = []
                self._schedule(k_wake)
                return
            window = self._lazy_moves()
            if window is not None:
                t_next = self._next_event_time()
                k_end = self._window_end(window, k, k + (1 << 40) if t_next is None else max(k, -(-t_next // period)))
                if k_end > k + 1:
                    self._window = window
                    self._schedule(k_end)
                    return
            if not sim.skip_to(k * period):
                self._schedule(k)
                return
            self.k_next = k

    def _next_event_time(self) -> int | None:
        """The instant of the earliest queued event that is not a plant sample (None: there is none)."""
        best = None
        for t, priority, _, event in self.sim.env._queue:
            if (priority != Priority.SAMPLE and not getattr(event, "cancelled", False) and event is not self._event
                    and type(event) is not MemoryPoll and (best is None or t < best)):
                best = t
        return None if best is None else int(best)

    def sync(self, now: int | None = None, *, at_now: bool = True) -> None:
        """Bring every implicit tick up to ``now`` (default: the current instant) up to date.

        With ``at_now`` a tick at ``now`` itself is included: whoever reads the controller inside a
        window does so from a plant sample (SAMPLE, after the servo at the same instant); a change of
        the controller (:meth:`wake`) and the end of a run come before it.
        """
        if self._materializing:
            return  # a coupled plant steps while the window's segments are handed over (its rows were full)
        if now is None:
            now = self.sim.now
        k_last = min(now // self.period if at_now else -(-now // self.period) - 1, self.k_next - 1)
        if k_last <= self.k_done:
            return
        if self._window:
            self._materializing = True
            try:
                materialize(self.controller, self._window, self.k_done + 1, k_last + 1)
            finally:
                self._materializing = False
            self.implicit += k_last - self.k_done
        self.k_done = k_last

    def wake(self) -> None:
        """Something changed the controller now: the next tick (the first one after the ticks run) is explicit."""
        self.sync(at_now=False)
        k = self.k_done + 1
        if k < self.k_next:
            self._window = []
            self._schedule(k)

    # -- closed-form windows ------------------------------------------------------------------
    def _lazy_moves(self) -> list[Move] | None:
        """The running moves, if the next ticks may be computed in closed form (see the module doc)."""
        controller = self.controller
        buffers = controller.buffers
        running = buffers._running
        if not running:  # programs waiting for buffer space, WAIT IDLE, WAIT LOADED: released only where a move ends
            return None
        moving: set[int] = set()
        for move in running:
            if ((move._straight is None and move._arc is None) or move.cancel_requested or move.modify_to is not None
                    or move.done or not move.monotonic):
                return None
            moving.update(move.axes)
        for move in buffers._queued:
            if not moving.issuperset(move.axes):
                return None
        for number, axis in controller.axes.items():
            if number in moving:
                if not (_unobserved(axis) or _pulled(axis)) or axis.supervised:
                    return None
            elif not axis.quiet:
                return None
        for gate in controller._gates:
            if gate.has_waiting:
                return None
        for pwm in controller._pwms:
            link = pwm.link
            if link is not None and link.link_axis in moving and not (
                    pwm.mode == PwmMode.LINKED and pwm.mark_out._wanted == pwm.mark == pwm.mark_out.signal.value):
                return None
        return running

    def _window_end(self, moves: list[Move], k: int, end: int) -> int:
        """The first tick from ``k`` on (``end`` at the latest: the next event) that must be explicit: a move's
        last cycle, a gate edge, a following error that might be reached, the end of a run of pulses a
        plant takes, a change of a speed-linked mark."""
        if end <= k + 1:
            return end
        axes = self.controller.axes
        for move in moves:
            cycle = move._cycle
            assert cycle is not None
            if cycle.k_end is not None:
                end = min(end, k + cycle.k_end - move.cycles - 1)  # the tick that runs cycle k_end
            for index, a in enumerate(move.axes):
                axis = axes[a]
                end = min(end, k + move.cycles_within_range(axis))
                if axis.stepper and not move.pulses_safe(axis, self.period):
                    return k
                if axis.params["SERVO"] and axis.stepper and not move.fe_safe(axis):
                    return k
                gate = axis.gate
                if gate is not None and axis.feeds_gate and gate.gating and gate.entries:
                    if move._straight is None:
                        return k  # an arc towards a gate position: explicit ticks
                    end = min(end, _gate_tick(move, index, gate, k, end))
        for move in moves:
            if end <= k + 1:
                break
            end = self._scan_end(move, k, end)
        return end

    def _scan_end(self, move: Move, k: int, end: int) -> int:
        """The window's end for a move whose pulses a plant takes (a pulled axis) or whose path speed sets a
        PWM mark: the tick of the first cycle after which a run of pulses would end (the tick after it
        announces the end, explicitly) or the mark would change; at most :data:`_SCAN_CYCLES` cycles on."""
        controller = self.controller
        straight, arc = move._straight, move._arc
        cycle = move._cycle
        assert cycle is not None
        period = self.period
        on_path = len(straight) if straight is not None else len(arc[1]) if arc is not None else 0
        pulled = [(i, axis) for i, axis in enumerate(move.axis_objects)
                  if i < on_path and axis.step is not None and axis.step._listeners and axis.stepper]
        marks = [pwm for pwm in controller._pwms if pwm.link is not None and pwm.link.link_axis in move.axes]
        if not pulled and not marks:
            return end
        last = min(end - k, _SCAN_CYCLES)
        c0, p_prev = move.cycles, move._p_prev
        tp, tq = move._period
        den_v = cycle.den * tp
        steps = [axis.steps_raw for _, axis in pulled]
        running = [axis.emitted_at == (k - 1) * period for _, axis in pulled]  # a run of pulses goes on
        for j in range(1, last + 1):
            p = cycle.numerator(c0 + j)
            cs = None
            if straight is None and pulled:
                assert arc is not None
                cs = ArcPath.cos_sin_at(p, arc[0])
                if cs is None:
                    return k + j - 1  # the arc's end (its last cycle runs explicitly anyway)
            for n, (i, _) in enumerate(pulled):
                if cs is None:
                    assert straight is not None
                    s, g, e = straight[i]
                    num = s + g * p
                else:
                    assert arc is not None
                    s, g, e = arc[1][i]
                    num = s + g * cs[i]
                was = steps[n]
                target = num // e if num >= was * e else -(-num // e)
                if target != was:
                    steps[n], running[n] = target, True
                elif running[n]:
                    return k + j - 1  # this cycle has no pulses after one that had: the tick that runs it
            if marks:
                v_num = (p - p_prev) * tq
                for pwm in marks:
                    assert pwm.link is not None
                    if pwm.linked_mark(pwm.link, v_num, den_v) != pwm.mark:
                        return k + j - 1
            p_prev = p
        return k + last


def _unobserved(axis: Axis) -> bool:
    """Nothing listens to the axis' outputs as they happen, and nothing is pending on it."""
    if axis.pending_shift:
        return False
    for signal in (axis.dpos_out, axis.mpos_out, axis.vp_out, axis.dir):
        if signal is not None and signal._listeners:
            return False
    return axis.step is None or not axis.step._listeners


def _pulled(axis: Axis) -> bool:
    """The axis' pulses go to plants that take them when they need them (:attr:`PulseTrain.pull`), and nothing
    else listens to its outputs as they happen."""
    step = axis.step
    if step is None or axis.pending_shift or axis.sim.env.look_aheads:
        return False
    for signal in (axis.dpos_out, axis.mpos_out, axis.vp_out, axis.dir):
        if signal is not None and signal._listeners:
            return False
    return step.pull is not None and step.takes_runs and 0 < len(step._listeners) == step.pulling


def _gate_tick(move: Move, index: int, gate: object, k: int, end: int) -> int:
    """The tick (from ``k``, before ``end``) whose cycle brings the axis' count onto the gate's head entry."""
    head = gate.entries[0]  # type: ignore[attr-defined]
    c0 = move.cycles
    last = c0 + (end - k)  # cycles c0+1 .. last run at ticks k .. end-1

    axis_steps, base = move_axis_steps(move, index)

    def count(c: int) -> int:
        return base + move.steps_after(index, c, axis_steps) - axis_steps

    if head.satisfied(count(c0)) or abs(count(last) - count(c0)) > _HALF_WRAP:
        return k
    if not head.satisfied(count(last)):
        return end
    lo, hi = c0 + 1, last  # the first cycle whose end count satisfies the head
    while lo < hi:
        mid = (lo + hi) // 2
        if head.satisfied(count(mid)):
            hi = mid
        else:
            lo = mid + 1
    return k + (lo - c0 - 1)


def move_axis_steps(move: Move, index: int) -> tuple[int, int]:
    """The axis' step count now and its gate's PWM_ENCODER count once every pulse fed has happened."""
    axis = move.axis_objects[index]
    gate = axis.gate
    assert gate is not None
    return axis.steps_raw, gate.encoder.end_value


def materialize(controller: TrioController, moves: list[Move], k_from: int, k_to: int) -> None:
    """Run the ticks ``k_from .. k_to - 1`` of ``moves`` in closed form (lines and arcs, see the module doc).

    The same values as :meth:`TrioController._tick` gives, written with their instants: DPOS, MPOS and
    VP_SPEED at each tick, the step segment and direction of each cycle, the feedback and PWM_ENCODER
    counts.
    """
    period = controller.period_ticks
    trace = controller.sim.trace
    n = k_to - k_from
    for move in moves:
        cycle = move._cycle
        assert cycle is not None
        c0 = move.cycles
        ps = [cycle.numerator(c) for c in range(c0 + 1, c0 + n + 1)]
        tp, tq = move._period
        den_v = cycle.den * tp
        p_prev = move._p_prev
        vps = []
        for p in ps:
            vps.append((p - p_prev) * tq)
            p_prev = p
        demands = _demands(move, ps)
        for index, a in enumerate(move.axes):
            nums, den = demands[index]
            _materialize_axis(controller.axes[a], trace, period, k_from, nums, den, vps, den_v)
        move.cycles = c0 + n
        move._p_prev = ps[-1]
        move.v_num, move.v_den = vps[-1], den_v
        move.nums = [nums[-1] for nums, _ in demands]
        move.dens = [den for _, den in demands]


def _demands(move: Move, ps: list[int]) -> list[tuple[list[int], int]]:
    """Each axis' demand numerators [counts] at the cycles whose path numerators are ``ps``, and their
    denominator: a straight move's ``(S + G P) / E``, an arc's ``(N + M x) / E`` (:meth:`Move.advance`)."""
    out: list[tuple[list[int], int]] = []
    if move._straight is not None:
        out = [([s + g * p for p in ps], e) for s, g, e in move._straight]
    else:
        assert move._arc is not None
        terms, coefficients = move._arc
        xs = [ArcPath.cos_sin_at(p, terms) for p in ps]
        for i, (s, g, e) in enumerate(coefficients):
            nums = []
            for x in xs:
                assert x is not None  # a window ends before the arc's last cycle
                nums.append(s + g * x[i])
            out.append((nums, e))
    out += [([start.numerator] * len(ps), start.denominator) for start in move.start_counts[len(out):]]
    return out


def _materialize_axis(axis: Axis, trace: Trace, period: int, k_from: int, nums: list[int], den: int,
                      vps: list[int], den_v: int) -> None:
    a_scale, b_scale, c_scale = axis._scales()
    dpos_out, mpos_out, vp_out = axis.dpos_out, axis.mpos_out, axis.vp_out
    dpos_last, mpos_last, vp_last = dpos_out.value, mpos_out.value, vp_out.value
    dpos_t: list[int] = []
    dpos_v: list[float] = []
    mpos_t: list[int] = []
    mpos_v: list[float] = []
    vp_t: list[int] = []
    vp_v: list[float] = []
    seg_t0: list[int] = []
    seg_n: list[int] = []
    seg_dir: list[int] = []
    dir_t: list[int] = []
    dir_v: list[int] = []
    stepper = axis.stepper
    feedback = axis.feedback
    counts = axis.counts_steps
    gate = axis.gate if axis.feeds_gate else None
    steps = axis.steps_raw
    step, direction = axis.step, axis.dir
    dir_value = int(direction.value) if direction is not None else 0
    dir_setup, width = axis.dir_setup, axis.pulse_width
    # the feedback counter's current segment, followed here without a call per cycle
    fb_before, fb_t0, fb_dur, fb_count, fb_sign = (feedback._before, feedback.t0, feedback.duration, feedback.count,
                                                   feedback.sign)
    enc_fed = 0
    mnum, mden = axis.mnum, axis.mden
    dnum, dden = axis.dnum, axis.dden
    t = k_from * period
    for i, num in enumerate(nums):
        if stepper:  # MPOS latched at the tick: the counted pulses (pulse k of a segment at t0 + k dur // n)
            happened = min(fb_count, -(-(t - fb_t0 + 1) * fb_count // fb_dur)) if fb_count and t >= fb_t0 else 0
            mnum, mden = fb_before + fb_sign * happened, 1
        else:
            mnum, mden = dnum, dden
        dnum, dden = num, den
        if stepper:
            target = num // den if num >= steps * den else -(-num // den)
            delta = target - steps
            if delta:
                if delta > 0:
                    count, sign, new_dir = delta, 1, 1
                else:
                    count, sign, new_dir = -delta, -1, 0
                if new_dir != dir_value:
                    dir_value = new_dir
                    dir_t.append(t)
                    dir_v.append(new_dir)
                leading = t + dir_setup
                seg_t0.append(leading)
                seg_n.append(count)
                seg_dir.append(new_dir)
                steps = target
                if counts:
                    fb_before += fb_sign * fb_count
                    fb_t0, fb_dur, fb_count, fb_sign = leading + width, period, count, sign
                enc_fed += delta
        dpos = (num * a_scale - b_scale * den) / (den * c_scale)
        if dpos != dpos_last:
            dpos_t.append(t)
            dpos_v.append(dpos)
            dpos_last = dpos
        mpos = (mnum * a_scale - b_scale * mden) / (mden * c_scale)
        if mpos != mpos_last:
            mpos_t.append(t)
            mpos_v.append(mpos)
            mpos_last = mpos
        vp = vps[i] / den_v
        if vp != vp_last:
            vp_t.append(t)
            vp_v.append(vp)
            vp_last = vp
        t += period
    for signal, times, values, last in ((dpos_out, dpos_t, dpos_v, dpos_last), (mpos_out, mpos_t, mpos_v, mpos_last),
                                        (vp_out, vp_t, vp_v, vp_last)):
        if times:
            trace.extend(signal.name, times, values)
            signal.value = last
    if direction is not None and dir_t:
        trace.extend(direction.name, dir_t, dir_v)
        direction.value = dir_value
    if step is not None and seg_t0:
        if step._listeners:  # a pulled axis (see _pulled): its plants take the runs of segments, as announced
            _emit_runs(axis, step, period, seg_t0, seg_n, seg_dir)
        else:
            trace.extend_segments(step.name, seg_t0, [period] * len(seg_t0), seg_n, seg_dir)
            step.position += steps - axis.steps_raw
    if counts:
        feedback._before, feedback.t0, feedback.duration, feedback.count, feedback.sign = (fb_before, fb_t0, fb_dur,
                                                                                           fb_count, fb_sign)
        feedback._times = None
    if gate is not None and enc_fed:
        _feed_total(gate.encoder, seg_t0[-1] + width, period, seg_n[-1], 1 if seg_dir[-1] else -1, enc_fed)
        gate._plan_id += 1
    axis.steps_raw = steps
    axis.mnum, axis.mden = mnum, mden
    axis.dnum, axis.dden = dnum, dden
    axis.vnum, axis.vden = vps[-1], den_v


def _emit_runs(axis: Axis, step: PulseTrain, period: int, seg_t0: list[int], seg_n: list[int],
               seg_dir: list[int]) -> None:
    """Hand the segments of the window's cycles to the train's listeners, as runs of contiguous segments of one
    direction, each announced (``lead`` = the direction set-up) at its servo tick, as the ticks would have."""
    first = 0
    for i in range(1, len(seg_t0) + 1):
        if i == len(seg_t0) or seg_t0[i] != seg_t0[i - 1] + period or seg_dir[i] != seg_dir[first]:
            step.emit_run(seg_t0[first], period, seg_n[first:i], seg_dir[first], axis.dir_setup)
            first = i
    axis.emitted_at = seg_t0[-1] - axis.dir_setup


def _feed_total(counter: StepCounter, t0: int, duration: int, count: int, sign: int, total: int) -> None:
    """Feed a counter ``total`` signed pulses of which the last segment is ``(t0, duration, count, sign)``."""
    end = counter.end_value + total
    counter.feed(t0, duration, count, sign)
    counter._before = end - sign * count
