"""PoKeys 3-axis buffered job near 25 kHz: the host keeps the 128-slot buffer filled over USB or Ethernet.

The host plans straight 3-axis moves (out and back, ``moves`` times) into per-slot pulse counts
and streams them with fill-buffer commands over the link; the engine emits one segment per slot
and axis::

    slot         |0 ms |1 ms |2 ms | ...           1 ms slots, frequency constant inside a slot
    x.step       |.....|.....|.....| ...           at most 25 pulses per slot
    buffer_level  ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾\\__       kept at ``prefill`` slots, no underrun

With ``steppers`` (default) each axis drives a Stepper FMU (NEMA 17 preset, FMI 3.0) through
:func:`~cosim.couplings.stepper.couple_stepper`: the slots' segments reach it as rows of its
``step_segments`` input, and it is stepped once per 64 slots or so (figure ``fmu_steps``).

Checks: at most 25 pulses per slot on every axis, pulses at least 40 us apart, the direction set
up before every pulse, no underrun, and each position counter equal to the pulses emitted, to
the planned end position and (with ``steppers``) to the stepper's ``commanded_steps``.
"""

from __future__ import annotations

from cosim.checks import DirectionSetup, IntervalsAbove, MinPulseSpacing, PulsesPerWindow, ValueAt
from cosim.controllers.pokeys import AXES, EngineConfig, PulseEngine, uniform_axes
from cosim.controllers.pokeys.host import HostApp
from cosim.controllers.pokeys.planner import Move, plan, to_entries
from cosim.couplings.stepper import couple_stepper
from cosim.scenario import Param, Run

PARAMETERS = (
    Param("max_speed_hz", 24_000, "Hz", (1, 25_000), "maximum speed of every axis"),
    Param("accel", 400_000, "pulses/s^2", (1, 100_000_000), "acceleration and deceleration of every axis"),
    Param("distance", 12_000, "pulses", (1, 1_000_000), "x travel of one move (y: -3/4, z: 1/2 of it)"),
    Param("moves", 3, "", (1, 100), "moves (out and back alternately)"),
    Param("link", "usb", "", ("usb", "ethernet"), "host link profile"),
    Param("prefill", 64, "slots", (1, 128), "slots queued before the start, and the level the host keeps"),
    Param("steppers", True, "", None, "drive a Stepper FMU (NEMA 17 preset) on every axis"),
)
UNTIL = "2 s"
PRESET = "nema17_17hs16_2004s1"


def scenario(run: Run) -> None:
    p = run.p
    config = EngineConfig(axes=uniform_axes(max_speed_hz=p.max_speed_hz, accel=p.accel, decel=p.accel))
    engine = PulseEngine(run.sim, config)
    far = (p.distance, -(3 * p.distance) // 4, p.distance // 2)
    targets = [far if k % 2 == 0 else (0, 0, 0) for k in range(p.moves)]
    counts = plan([Move(t) for t in targets], config.axes)
    host = HostApp(run.sim, engine, to_entries(counts), link=p.link, prefill_slots=p.prefill)
    plants = [run.plant("Stepper", name=f"stepper_{axis}", preset=PRESET) for axis in AXES] if p.steppers else []
    couplings = [couple_stepper(engine.step_dir(a), plant) for a, plant in enumerate(plants)]

    end = targets[-1]
    for a, axis in enumerate(AXES):
        step, direction = f"pokeys.{axis}.step", f"pokeys.{axis}.dir"
        run.check(PulsesPerWindow(step, 25, engine.slot_ticks, name=f"{axis}: at most 25 pulses per 1 ms slot"))
        run.check(MinPulseSpacing(step, run.sim.ticks("40 us"), name=f"{axis}: pulses at least 40 us apart"))
        run.check(DirectionSetup(step, direction, engine.dir_setup_ticks, positive_level=0,
                                 name=f"{axis}: direction set up {config.dir_setup_ns} ns before each pulse"))
        run.check(ValueAt(step, None, end[a], name=f"{axis}: pulses emitted add up to {end[a]}"))
        run.check(ValueAt(f"pokeys.{axis}.position", None, end[a], name=f"{axis}: position counter = {end[a]}"))
        if p.steppers:
            run.check(ValueAt(f"{plants[a].name}.commanded_steps", None, end[a],
                              name=f"{axis}: stepper commanded_steps = position counter = {end[a]}"))
    run.check(IntervalsAbove("pokeys.underrun", 0, name="no buffer underrun"))
    run.figure("slots", len(counts))
    run.figure("pulses", sum(abs(c) for slot in counts for c in slot))
    run.figure("fill_commands", lambda: len(host.fills))
    if p.steppers:
        run.figure("fmu_steps", lambda: sum(plant.steps for plant in plants))
        run.figure("step_rate_changes", lambda: sum(c.settings for c in couplings))
    run.figure("job_done_ms", lambda: (host.t_buffer_mode or 0) / engine.slot_ticks + len(counts), "ms")
