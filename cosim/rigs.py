"""Ready-made PMAC machines for scenarios and tests (written as the setup text a user keeps).

* :func:`external_time_base` -- Turbo table with a 1/T entry on the master channel and an
  untriggered time-base entry; CS1 follows it (``I5193=@I8002``).
* :func:`triggered_time_base` -- a Turbo triggered time-base entry on the master channel with the
  registration sensor as capture trigger; CS1 follows it.

Both put motor 1 on axis X of CS1: ideal (act = cmd) by default; with ``slave=MotorModel(...)``
a PID designed for ``bandwidth_hz`` closes the loop around a :class:`~cosim.plants.analytic.DcMotor`
(gain per DAC bit); with ``loop=`` a given loop is used and the caller connects
``rig.motor.feedback`` (for a Servo plant: :func:`cosim.couplings.servo.connect_servo`).
The master is any :class:`~cosim.encoders.EncoderSource`: an
:class:`~cosim.plants.analytic.IdealConveyor` or a :class:`~cosim.couplings.encoder.PlantEncoder`.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from cosim.controllers.pmac.coord import CoordinateSystem
from cosim.controllers.pmac.ect import ARMED, FROZEN, RUNNING, TimeBaseEntry, TriggeredTimeBaseEntry
from cosim.controllers.pmac.encoder import EncoderChannel
from cosim.controllers.pmac.machine import Pmac
from cosim.controllers.pmac.motion import Item, LinearMove
from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.servo import MotorModel, PidDesign, PidLoop, design_pid
from cosim.controllers.pmac.units import I10_DEFAULT, IX94_MAX
from cosim.encoders import EncoderSource
from cosim.plants.analytic import DcMotor, IdealConveyor
from cosim.signals import Signal
from cosim.timebase import Priority

if TYPE_CHECKING:
    from cosim.kernel import Simulation

#: Master encoder channel used by the rigs (Turbo Servo IC 0, as in the manual's I8010=$978008).
MASTER_CHANNEL = 0x078008
#: Its capture register (dummy-read address): channel + 3.
MASTER_CAPTURE = MASTER_CHANNEL + 3
#: A default slave axis: 6 counts/s per DAC bit (about 197 counts/ms at full DAC), tau = 10 ms.
SERVO_AXIS = MotorModel(gain_counts_per_s_per_bit=6.0, tau_s=0.01)


E = TypeVar("E", TimeBaseEntry, TriggeredTimeBaseEntry)


@dataclass
class Rig(Generic[E]):
    """What a rig built: the controller and the parts a test or scenario looks at."""

    pmac: Pmac
    cs: CoordinateSystem
    motor: Motor
    channel: EncoderChannel
    entry: E
    setup: str
    design: PidDesign | None = None
    plant: DcMotor | None = None


def _finish(sim: Simulation, pmac: Pmac, setup: str, master: EncoderSource, trigger: Signal | None,
            loop: PidLoop | None, slave: MotorModel | None, bandwidth_hz: float
            ) -> tuple[CoordinateSystem, Motor, EncoderChannel, PidDesign | None, DcMotor | None]:
    channel = pmac.add_channel(MASTER_CHANNEL, master, trigger=trigger, name="master")
    pmac.load_setup(setup, source="rig setup")
    cs = pmac.coordinate_system(1)
    design = design_pid(slave, period_s=pmac.clock.period_s, bandwidth_hz=bandwidth_hz) if slave else None
    motor = pmac.add_motor(1, cs=1, loop=PidLoop(design) if design is not None else loop)
    plant = None
    if slave is not None:
        slave_plant = plant = DcMotor(sim, gain=slave.gain_counts_per_s_per_bit, tau_s=slave.tau_s)
        slave_plant.drive("command", motor.dac)
        motor.feedback = lambda: slave_plant.read("encoder_count")
    return cs, motor, channel, design, plant


def external_time_base(sim: Simulation, master: EncoderSource, *, scale_factor: int, ix94: int = IX94_MAX,
                       i10: int = I10_DEFAULT, loop: PidLoop | None = None, slave: MotorModel | None = None,
                       bandwidth_hz: float = 50.0) -> Rig[TimeBaseEntry]:
    """Untriggered external time base from the 1/T position of ``master`` (not started)."""
    setup = (f"I10={i10}\n"
             f"I8000=${MASTER_CHANNEL:06X}        ; 1/T extension of the master channel (1/32 count)\n"
             "I8001=$403501         ; time base ($4) from the 1/T result at $3501\n"
             f"I8002={scale_factor}  ; SCALE_FACTOR = 131072 / real-time input frequency\n"
             "I5193=@I8002          ; CS1 time base = result of the time-base entry ($3503)\n"
             f"I5194={ix94}         ; time-base slew limit\n")
    pmac = Pmac(sim, i10=i10)
    cs, motor, channel, design, plant = _finish(sim, pmac, setup, master, None, loop, slave, bandwidth_hz)
    entry = pmac.table.entry_at(0x3502)
    assert isinstance(entry, TimeBaseEntry)
    return Rig(pmac, cs, motor, channel, entry, setup, design, plant)


def triggered_time_base(sim: Simulation, master: EncoderSource, trigger: Signal, *, scale_factor: int,
                        method: int = FROZEN, ix94: int = IX94_MAX, i10: int = I10_DEFAULT,
                        loop: PidLoop | None = None, slave: MotorModel | None = None,
                        bandwidth_hz: float = 50.0) -> Rig[TriggeredTimeBaseEntry]:
    """Turbo triggered time base on ``master`` with ``trigger`` as capture input (not started)."""
    setup = (f"I10={i10}\n"
             f"I8000=${method:X}{MASTER_CHANNEL:05X}     ; triggered time base: $9 frozen, $B armed, $A running\n"
             f"I8001={scale_factor}  ; SCALE_FACTOR = 16384 / real-time input frequency\n"
             "I5193=@I8001          ; CS1 time base = result of the triggered entry ($3502)\n"
             f"I5194={ix94}\n")
    pmac = Pmac(sim, i10=i10)
    cs, motor, channel, design, plant = _finish(sim, pmac, setup, master, trigger, loop, slave, bandwidth_hz)
    entry = pmac.table.entry_at(0x3501)
    assert isinstance(entry, TriggeredTimeBaseEntry)
    return Rig(pmac, cs, motor, channel, entry, setup, design, plant)


def freeze_then_arm(sim: Simulation, rig: Rig[TriggeredTimeBaseEntry], program: list[Item], *, t_freeze: int,
                    arm_after: int, dummy_read: bool) -> None:
    """The manual's triggered-move recipe, as host actions (priority HOST).

    At ``t_freeze`` the motion program freezes the entry (``I8000=$978008``), optionally does
    the dummy read of the capture register (``X:$07800B``), and starts ``program``. After
    ``arm_after`` the PLC arms the entry if it is still frozen (``IF (I8000=$978008)
    I8000=$B78008``). If both fall between the same two servo interrupts and there is no dummy
    read, no servo cycle sees the entry frozen: the stale-capture hazard.
    """
    frozen = (FROZEN << 20) | MASTER_CHANNEL
    armed = (ARMED << 20) | MASTER_CHANNEL

    def motion_program_and_plc() -> Generator[Any, Any, None]:
        yield sim.at(t_freeze, Priority.HOST)
        rig.pmac.set_ivar(8000, frozen)
        if dummy_read:
            rig.pmac.read_x(MASTER_CAPTURE)
        rig.cs.run_program(program)
        yield sim.at(t_freeze + arm_after, Priority.HOST)
        if rig.pmac.get_ivar(8000) == frozen:
            rig.pmac.set_ivar(8000, armed)

    sim.process(motion_program_and_plc())


def stale_capture(sim: Simulation, *, t_freeze: int, arm_after: int,
                  dummy_read: bool) -> tuple[IdealConveyor, Rig[TriggeredTimeBaseEntry]]:
    """The stale-capture set-up of the manual's warning, started.

    A 64 counts/ms belt with marks at 500 and 1500 counts; the triggered entry is left running,
    so mark 1's capture is never read. The motion program freezes the entry 1 us after the first
    servo interrupt at or after ``t_freeze`` and the PLC arms it ``arm_after`` later
    (:func:`freeze_then_arm`); with ``dummy_read`` the program reads the capture register.
    """
    belt = IdealConveyor(sim, speed_counts_per_ms=64, marks=[500, 1500], mark_width_counts=5)
    rig = triggered_time_base(sim, belt, belt.mark, scale_factor=256, method=RUNNING)
    clock = rig.pmac.clock
    t_freeze = clock.t(clock.first_cycle_at_or_after(t_freeze)) + sim.ticks(1, "us")
    freeze_then_arm(sim, rig, [LinearMove(3000, 64_000, 10)], t_freeze=t_freeze, arm_after=arm_after,
                    dummy_read=dummy_read)
    rig.pmac.start()
    return belt, rig
