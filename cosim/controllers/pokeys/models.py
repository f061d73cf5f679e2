"""Device models: what one PoKeys pulse engine can emit, and how its slot entries are written.

The per-slot pulse limit, the number of axes the pulse generator drives and the entry formats are
properties of the device, not of the engine model: the same :class:`~.engine.PulseEngine` runs
every model, and refuses a fill entry above its model's limit on every route (Python API and
the virtual device's fill replies alike).

=========  ======  =====  ==========  ==============  ======================================================
model      engine  axes   pulses per  slot entries    source
                          slot (kHz)
=========  ======  =====  ==========  ==============  ======================================================
``56E``    v1      3      25 (25)     3 x 8 bit       vendor document "PoKeys Pulse engine" (2012): "up to
``56U``                                               25 pulses per 1 millisecond time slot", 3 axes, 3 bytes
                                                      per slot, 7-bit count and a direction MSB; protocol
                                                      notes 4.1 and 4.5 (the x byte 0xFF is reserved)
``57E``    v2      3      25 (25)     N x 8 or 16     protocol notes 5.1: the internal generator has 3
                                      bit             channels at 25 kHz (25 per slot); 5.3: status ``[57]``
                                                      reports 25 kHz at power-on (the notes' preset)
``57CNC``  v2      8      125 (125)   N x 8 or 16     protocol notes 5.1: the external generator has 8
                                      bit             channels at 125 kHz (125 per slot). The 57CNC drives 8
                                                      step/direction axes, which only that generator has
=========  ======  =====  ==========  ==============  ======================================================

Pulse engine v2 keeps 2 bytes per axis in its buffer and takes 8- or 16-bit entries on the wire;
no model emits more than 125 pulses per slot, so the engine's one-byte axis entries (7-bit
count, direction MSB) hold every count any model accepts.

Pulse width and direction set-up are not in the vendor documents: the model's defaults keep
``dir_setup_ns + pulse_width_ns`` within the pulse spacing at full rate (40 us at 25 kHz, 8 us
at 125 kHz), so no pulse crosses a slot boundary.
"""

from __future__ import annotations

from dataclasses import dataclass

from cosim.controllers.pokeys.limits import AXIS_NAMES, SLOT_NS, SLOTS_PER_S
from cosim.validate import choice


@dataclass(frozen=True)
class DeviceModel:
    """The figures of one PoKeys model's pulse engine.

    Parameters
    ----------
    name : str
        Preset name (``56E``, ``56U``, ``57E``, ``57CNC``).
    pulse_engine : {1, 2}
        Pulse engine version (the protocol's command 0x80 or 0x85).
    axes : int
        Axes the pulse generator drives [1].
    max_pulses_per_slot : int
        Most pulses per axis and 1 ms slot [pulses]; a fill entry above it is refused.
    entry_bits : tuple of int
        Widths of an axis entry on the wire [bits]: 8 (7-bit count, direction MSB), 16 (15-bit count).
    reserved_x_byte : int or None
        An x byte value the vendor reserves for a "special command" (v1: 0xFF), refused as a count.
    pulse_width_ns, dir_setup_ns : int
        Default step pulse width and direction set-up [ns] (choices, see the module text).
    source : str
        Where the figures come from.
    """

    name: str
    pulse_engine: int
    axes: int
    max_pulses_per_slot: int
    entry_bits: tuple[int, ...]
    reserved_x_byte: int | None
    pulse_width_ns: int
    dir_setup_ns: int
    source: str

    @property
    def max_rate_hz(self) -> int:
        """Highest pulse frequency [pulses/s]."""
        return self.max_pulses_per_slot * SLOTS_PER_S

    @property
    def min_spacing_ns(self) -> int:
        """Pulse spacing at the highest frequency [ns] (40000 at 25 kHz)."""
        return SLOT_NS // self.max_pulses_per_slot

    @property
    def axis_names(self) -> tuple[str, ...]:
        """Names of the axes, index 0 first (x, y, z, ...)."""
        return AXIS_NAMES[:self.axes]


_V1 = ("vendor document 'PoKeys Pulse engine' (v1, 2012): 25 pulses per 1 ms slot, 3 axes, 3-byte entries; "
       "protocol notes 4.1, 4.5")
MODELS: dict[str, DeviceModel] = {
    "56E": DeviceModel("56E", 1, 3, 25, (8,), 0xFF, 5_000, 5_000, _V1),
    "56U": DeviceModel("56U", 1, 3, 25, (8,), 0xFF, 5_000, 5_000, _V1),
    "57E": DeviceModel("57E", 2, 3, 25, (8, 16), None, 5_000, 5_000,
                       "protocol notes 5.1 (internal generator: 3 channels, 25 kHz) and 5.3 (status [57] = 25)"),
    "57CNC": DeviceModel("57CNC", 2, 8, 125, (8, 16), None, 2_000, 2_000,
                         "protocol notes 5.1 (external generator: 8 channels, 125 kHz); the 57CNC has 8 axes"),
}
"""The presets by name."""


def device_model(name: str, *, where: str = "") -> DeviceModel:
    """The preset ``name`` (one of :data:`MODELS`)."""
    return MODELS[choice(name, "model", tuple(MODELS), where=where)]
