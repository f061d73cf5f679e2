"""PoKeys pulse engine model (PoKeys56U/56E pulse engine v1, PoKeys57 series v2): 1 ms slots, 128-slot buffer.

Public API::

    from cosim.controllers.pokeys import PulseEngine, EngineConfig, AxisConfig, EngineState
    engine = PulseEngine(sim, EngineConfig())             # a PoKeys56E: 3 axes, 25 pulses per slot
    engine = PulseEngine(sim, EngineConfig.for_model("57CNC"))   # 8 axes, 125 pulses per slot
    engine.fill_buffer([encode_entry((10, -5, 25))]); engine.set_state(EngineState.BUFFER)
    couple_stepper(engine.step_dir(0), plant)   # cosim.couplings.stepper: a Stepper FMU on axis x

See ``docs/pokeys.md`` for the rules and the choices where the vendor document is silent.
"""

from cosim.controllers.pokeys.buffer import (
    SlotBuffer,
    decode_axis,
    decode_entry,
    encode_axis,
    encode_entry,
    signed_count,
)
from cosim.controllers.pokeys.config import AxisConfig, EngineConfig, uniform_axes
from cosim.controllers.pokeys.engine import PulseEngine
from cosim.controllers.pokeys.limits import (
    AXES,
    AXIS_NAMES,
    BUFFER_SLOTS,
    MAX_PULSES_PER_SLOT,
    MAX_RATE_HZ,
    PINS,
    SLOT_NS,
    SLOTS_PER_S,
)
from cosim.controllers.pokeys.models import MODELS, DeviceModel, device_model
from cosim.controllers.pokeys.profile import AxisMotion, SlotLimits
from cosim.controllers.pokeys.records import FillReply, Refusal, Register, Status, Underrun
from cosim.controllers.pokeys.states import AxisState, EngineState
from cosim.controllers.pokeys.switches import TRIPPED, SwitchInputs, SwitchSample

__all__ = [
    "AXES",
    "AXIS_NAMES",
    "BUFFER_SLOTS",
    "MAX_PULSES_PER_SLOT",
    "MAX_RATE_HZ",
    "MODELS",
    "PINS",
    "SLOTS_PER_S",
    "SLOT_NS",
    "TRIPPED",
    "AxisConfig",
    "AxisMotion",
    "AxisState",
    "DeviceModel",
    "EngineConfig",
    "EngineState",
    "FillReply",
    "PulseEngine",
    "Refusal",
    "Register",
    "SlotBuffer",
    "SlotLimits",
    "Status",
    "SwitchInputs",
    "SwitchSample",
    "Underrun",
    "decode_axis",
    "decode_entry",
    "device_model",
    "encode_axis",
    "encode_entry",
    "signed_count",
    "uniform_axes",
]
