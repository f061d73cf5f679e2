"""The PMAC's connectors for couplings: an encoder input (with its capture trigger) and a servo motor.

A coupling (``cosim.couplings.encoder.couple_encoder``, ``cosim.couplings.servo.couple_servo``)
joins a port to a plant; the port knows only the controller's side.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from cosim.controllers.pmac.encoder import EncoderChannel
from cosim.controllers.pmac.motor import Motor
from cosim.controllers.pmac.servo import MotorModel, PidDesign, PidLoop, design_pid
from cosim.encoders import EncoderSource
from cosim.signals import Signal

if TYPE_CHECKING:
    from cosim.controllers.pmac.machine import Pmac


@dataclass(frozen=True)
class EncoderPort:
    """Encoder channel input at ``address`` (e.g. $078018), optionally with a capture trigger.

    Attributes
    ----------
    pmac : Pmac
    address : int
        Channel address as conversion-table entries name it; its capture register is at +3.
    trigger : str or None
        The plant output that is the capture trigger (a registration sensor), or None.
    trigger_level : int
        Active level of the trigger (1 = high).
    name : str
        Signal name part of the channel (``pmac.<name>.capture_flag``).
    """

    pmac: Pmac
    address: int
    trigger: str | None = None
    trigger_level: int = 1
    name: str | None = None

    def connect(self, encoder: EncoderSource, trigger: Signal | None) -> EncoderChannel:
        """Add the channel: ``encoder`` as its position, ``trigger`` as its capture input."""
        return self.pmac.add_channel(self.address, encoder, trigger=trigger, trigger_level=self.trigger_level,
                                     name=self.name)


@dataclass(frozen=True)
class ServoPort:
    """A motor's position loop, to be closed around a plant with a PID designed for ``bandwidth_hz``.

    Attributes
    ----------
    motor : Motor
    period_s : float
        Servo period [s] (the PID's sample time).
    bandwidth_hz : float
        Loop crossover the PID is designed for [Hz].
    model : MotorModel or None
        Design model given by the user (else the coupling derives it from the plant).
    """

    motor: Motor
    period_s: float
    bandwidth_hz: float
    model: MotorModel | None = None

    def close_loop(self, model: MotorModel) -> PidDesign:
        """Design the PID for ``model`` (unless the port names its own) and give it to the motor."""
        design = design_pid(self.model or model, period_s=self.period_s, bandwidth_hz=self.bandwidth_hz)
        self.motor.loop = PidLoop(design)
        return design
