"""Turbo PMAC triggered time base on the Conveyor FMU: the Servo FMU starts its move at a registration mark.

The master is the Conveyor FMU (FMI 3.0, preset ``conveyor_web_200mm_wheel``, 50,000 counts/m)
running at constant speed from t = 0: 0.64 m/s = 32 counts/ms = the real-time input frequency,
so SCALE_FACTOR = 16384 / 32 = 512 and the running time base is 100 %. Its encoder (edge instants
ceiled to ns) feeds the triggered entry I8000=$978008 and its mark sensor (an FMI 3.0 event) is
the capture trigger. The slave is the Servo FMU (preset ``servo_maxon_re40_24v``, with Coulomb
friction) under a PID at the servo rate, gains from python-control for ``bandwidth_hz``; the
DAC drives ``u_cmd`` (10 V = 32768 bits), the feedback is its 1/T position (1/32 count)::

    conveyor.mark   ____________________________|‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|________   mark_offset (1000.355 counts)
    pmac.ect.method $9 |$B‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾|$A‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾   armed at t_arm, running at the mark
    timebase %      0  0  0  0  0  0  0  0  0  0 |100 ‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾
    slave cmd       0 ........................... /‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾‾\\___ 2000 counts (X2000 F64000 TA20)
                    0  t_arm                     ~31.26 ms                    100 ms

Checks: the mark is published within 1 ns of its closed-form instant; time zero equals the
conveyor's position at the mark edge within 1/256 count; the entry runs within one servo period
of the mark; the slave's command is still 0 at the mark; 100 % within one 1/256-count quantum;
the sync error (master-derived command - actual) stays within ``sync_limit``; the slave ends
within ``end_tol`` of its target.
"""

from __future__ import annotations

from collections.abc import Generator
from fractions import Fraction
from typing import Any

from cosim import rigs
from cosim.checks import Bound, Duration, EdgeRef, ValueAt
from cosim.controllers.pmac import ARMED, FROZEN, I10_DEFAULT, RUNNING, LinearMove, PidLoop, ServoClock, design_pid
from cosim.couplings.encoder import PlantEncoder, watch_mark
from cosim.couplings.servo import connect_servo, full_model_margins, servo_motor_model
from cosim.plants.conveyor import ConveyorParameters, mark_edge_times
from cosim.plants.servo import ServoParameters
from cosim.presets import load_preset
from cosim.scenario import Param, Run
from cosim.timebase import Priority

PARAMETERS = (
    Param("rtif", 32, "counts/ms", (1, 256), "conveyor speed = real-time input frequency (a power of two)"),
    Param("mark_offset_m", 0.0200071, "m", (0.001, 0.1), "position of the first mark's leading edge"),
    Param("t_arm_ms", 2.0, "ms", (0.5, 10.0), "when the PLC arms the entry"),
    Param("move_counts", 2000, "counts", (1, 100_000), "slave move length (X, 1 count per unit)"),
    Param("feedrate", 64_000, "counts/s", (1, 200_000), "slave feedrate F at 100 %"),
    Param("ta_ms", 20, "ms", (1, 1000), "acceleration time TA"),
    Param("bandwidth_hz", 100.0, "Hz", (1.0, 225.0), "position-loop crossover of the PID design"),
    Param("sync_limit", 65.0, "counts", (0.0, 1e6), "largest allowed |sync error|"),
    Param("end_tol", 0.5, "counts", (0.0, 1e6), "allowed final position error of the slave"),
)
UNTIL = "160 ms"


def scenario(run: Run) -> None:
    sim, p = run.sim, run.p
    preset = load_preset("conveyor_web_200mm_wheel")
    speed_m_s = p.rtif * 1000 / preset["counts_per_metre"]
    belt = ConveyorParameters.from_mapping({**preset, "mark_offset": p.mark_offset_m, "speed_start": speed_m_s})
    conveyor = run.plant("Conveyor", name="conveyor", parameters=belt.as_fmu_parameters())
    conveyor.set({"speed_cmd": speed_m_s})
    motor_params = ServoParameters.from_mapping(load_preset("servo_maxon_re40_24v"))
    servo = run.plant("Servo", name="servo", preset="servo_maxon_re40_24v")

    mark = watch_mark(conveyor)
    design = design_pid(servo_motor_model(motor_params), period_s=ServoClock(I10_DEFAULT).period_s,
                        bandwidth_hz=p.bandwidth_hz)
    scale_factor = 16384 // p.rtif
    rig = rigs.triggered_time_base(sim, PlantEncoder(conveyor), mark, scale_factor=scale_factor, method=FROZEN,
                                   loop=PidLoop(design))
    connect_servo(rig.motor, servo)
    rig.cs.run_program([LinearMove(p.move_counts, p.feedrate, p.ta_ms)])

    def plc() -> Generator[Any, Any, None]:
        yield sim.at(sim.ticks(p.t_arm_ms, "ms"), Priority.HOST)
        rig.pmac.set_ivar(8000, (ARMED << 20) | rigs.MASTER_CHANNEL)

    sim.process(plc())
    rig.pmac.start()

    times_s, _rising = mark_edge_times(belt, speed_cmd=speed_m_s, t_end_s=sim.timebase.seconds(run.until))
    t_mark = sim.timebase.ticks_from_seconds_ceil(float(times_s[0]))
    mark_pos = p.mark_offset_m * belt.counts_per_metre  # the belt position at the mark's leading edge
    period = -(-rig.pmac.clock.period_ticks // 1)
    quantum = 100 * 2 * scale_factor / rig.pmac.i10  # one 1/256 count per cycle, in %
    run.check(ValueAt("conveyor.mark", t_mark - 2, 0, name="mark off 2 ns before its closed-form instant"))
    run.check(ValueAt("conveyor.mark", t_mark + 1, 1, name="mark on within 1 ns of its closed-form instant"))
    run.check(ValueAt("pmac.ect.time_zero_pos", None, mark_pos, tol=1 / 256,
                      name="time zero = conveyor position at the mark edge (1/256 count)"))
    run.check(Duration(EdgeRef("conveyor.mark", 1), EdgeRef("pmac.ect.method", RUNNING), max=int(period),
                       name="running within one servo period of the mark"))
    run.check(ValueAt("pmac.motor1.cmd_pos", t_mark, 0, name="slave command still 0 at the mark"))
    run.check(ValueAt("pmac.cs1.timebase_pct", t_mark + sim.ticks("10 ms"), 100, tol=quantum,
                      name="100 % at the real-time input frequency (one 1/256-count quantum)"))
    run.check(Bound("pmac.motor1.sync_error", lower=-p.sync_limit, upper=p.sync_limit,
                    name="sync error within sync_limit"))
    run.check(ValueAt("pmac.motor1.act_pos", None, p.move_counts, tol=p.end_tol, name="slave ends at its target"))

    def start_error() -> float:
        starts = rig.entry.starts
        return float(Fraction(starts[0].time_zero_pos256, 256) - Fraction(mark_pos)) if starts else float("nan")

    def max_sync_error() -> float:
        _t, values = sim.trace.edges("pmac.motor1.sync_error")
        return float(abs(values).max()) if len(values) else float("nan")

    gm_full, pm_full, radius_full = full_model_margins(design, motor_params)
    run.figure("start_error_counts", start_error, "counts")
    run.figure("mark_time_ms", t_mark / 1e6, "ms")
    run.figure("max_abs_sync_error", max_sync_error, "counts")
    run.figure("phase_margin", design.phase_margin_deg, "deg")
    run.figure("gain_margin", design.gain_margin_db, "dB")
    run.figure("closed_loop_bandwidth", design.bandwidth_hz, "Hz")
    run.figure("phase_margin_full_model", pm_full, "deg")
    run.figure("gain_margin_full_model", gm_full, "dB")
    run.figure("max_pole_radius_full_model", radius_full)
    run.figure("final_position_error", lambda: rig.motor.act - p.move_counts, "counts")
    run.figure("servo_fmu_steps", lambda: float(servo.steps))
