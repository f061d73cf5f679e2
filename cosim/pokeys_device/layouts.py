"""Field layouts of the pulse-engine packets: status blocks, parameter block, axis record.

Pure encode/decode pairs: the device writes these blocks, the client reads them, at the offsets of
the protocol notes (0-based ``[n]``). Positions are int32 LE; speeds float32 in pulses/ms,
accelerations float32 in pulses/ms^2.

================================  =========================================================
block                             where
================================  =========================================================
v1 status (:class:`StatusV1`)     0x80/0x00 reply from ``[8]``; 0x80/0x35 fill reply from ``[9]``
v1 motion parameters              0x80/0x10 reply and 0x80/0x11 request, ``[8..46]``
v2 status (:class:`StatusV2`)     0x85/0x00 reply and every v2 fill reply, ``[3..5]``, ``[8..62]``
v2 axis record (:class:`AxisRecord`)  0x85/0x10 reply and 0x85/0x11 request, ``[8..52]``
================================  =========================================================
"""

from __future__ import annotations

import struct
from dataclasses import astuple, dataclass

from cosim.controllers.pokeys import BUFFER_SLOTS, SLOT_NS, DeviceModel
from cosim.pokeys_device.packets import get_i32, put_i32

V1_AXES = 3
V2_AXES = 8
"""Axes of the pulse engine v2 status block (the 57 series supports 8)."""
ENGINE_INFO_V1 = bytes((3, 25, 128, 10))
"""0x80/0x30 ``[8..11]``: 3 axes, 25 kHz, 128 slots, slot time 10 x 100 us."""
ENGINE_INFO_V2 = bytes((V2_AXES, 25, 128, 10))
"""v2 status ``[56..59]``: 8 axes, 25 kHz (internal generator), 128 slots, 10 x 100 us."""


def engine_info(model: DeviceModel, *, axes: int) -> bytes:
    """Engine info bytes (v1 0x80/0x30 ``[8..11]``, v2 status ``[56..59]``) for ``model``.

    ``axes``, maximum frequency [kHz] = the model's pulses per 1 ms slot, buffer depth [slots],
    slot time [100 us]: ``(3, 25, 128, 10)`` for a 56E, ``(8, 125, 128, 10)`` for a 57CNC.
    """
    return bytes((axes, model.max_pulses_per_slot, BUFFER_SLOTS, SLOT_NS // 100_000))
STATUS_CHECK_OFFSET = 0x5A
"""v2 status reply ``[63]`` = (request ``[3]`` + 0x5A) mod 256."""


@dataclass(frozen=True)
class StatusV1:
    """Pulse engine v1 status (0x80/0x00 reply; fill reply shifted by one byte, without the last two).

    Attributes
    ----------
    positions : tuple of 3 int
        x, y, z [pulses].
    limit_pos, limit_neg, home : int
        Switch states, bit 0 = x, bit 1 = y, bit 2 = z.
    engine_state : int
        v1 engine state code.
    axis_states : tuple of 3 int
    enabled, charge_pump : int
        As set by 0x80/0x06 (status reply only).
    """

    positions: tuple[int, ...]
    limit_pos: int
    limit_neg: int
    home: int
    engine_state: int
    axis_states: tuple[int, ...]
    enabled: int = 0
    charge_pump: int = 0


def put_status_v1(frame: bytearray, status: StatusV1, *, offset: int = 8, with_enable: bool = True) -> None:
    """Write a v1 status block from ``[offset]`` (8 for the status reply, 9 for the fill reply)."""
    for a in range(V1_AXES):
        put_i32(frame, offset + 4 * a, status.positions[a])
    frame[offset + 12:offset + 16] = bytes((status.limit_pos, status.limit_neg, status.home, status.engine_state))
    frame[offset + 16:offset + 19] = bytes(status.axis_states[:V1_AXES])
    if with_enable:
        frame[offset + 19:offset + 21] = bytes((status.enabled, status.charge_pump))


def get_status_v1(frame: bytes | bytearray, *, offset: int = 8, with_enable: bool = True) -> StatusV1:
    """Read a v1 status block (the inverse of :func:`put_status_v1`)."""
    o = offset
    return StatusV1(tuple(get_i32(frame, o + 4 * a) for a in range(V1_AXES)), frame[o + 12], frame[o + 13],
                    frame[o + 14], frame[o + 15], tuple(frame[o + 16:o + 19]),
                    frame[o + 19] if with_enable else 0, frame[o + 20] if with_enable else 0)


# -- v1 motion parameters (0x10 / 0x11) ------------------------------------------------------------
_PARAMS_V1 = struct.Struct("<9f3B")
PARAMS_V1_SLICE = slice(8, 8 + _PARAMS_V1.size)
"""``[8..46]``: the block 0x80/0x10 returns exactly as 0x80/0x11 set it."""


@dataclass(frozen=True)
class ParamsV1:
    """v1 motion parameters on the wire.

    Attributes
    ----------
    max_speed : tuple of 3 float
        pulses/ms (25.0 = 25 kHz).
    accel, decel : tuple of 3 float
        pulses/ms^2 (0.1 = 100 000 pulses/s^2).
    homing_pct, homing_return_pct : int
        % of the maximum speed.
    emergency_polarity : int
        0: a high input means emergency; 1: a low input.
    """

    max_speed: tuple[float, ...]
    accel: tuple[float, ...]
    decel: tuple[float, ...]
    homing_pct: int
    homing_return_pct: int
    emergency_polarity: int

    def to_bytes(self) -> bytes:
        """The 39 bytes of ``[8..46]``."""
        return _PARAMS_V1.pack(*self.max_speed, *self.accel, *self.decel, self.homing_pct,
                               self.homing_return_pct, self.emergency_polarity)

    @classmethod
    def from_bytes(cls, block: bytes | bytearray) -> ParamsV1:
        """Decode the 39 bytes of ``[8..46]``."""
        v = _PARAMS_V1.unpack(bytes(block))
        return cls(tuple(v[0:3]), tuple(v[3:6]), tuple(v[6:9]), v[9], v[10], v[11])


# -- v2 status block ------------------------------------------------------------------------------
@dataclass(frozen=True)
class StatusV2:
    """Pulse engine v2 status block (5.3 of the protocol notes).

    Attributes
    ----------
    soft_limit, power_mask, limit_override : int
        ``[3]``, ``[4]``, ``[5]``.
    enabled_axes, activated, engine_state, charge_pump : int
        ``[8]``, ``[9]``, ``[10]``, ``[11]``.
    limit_pos, limit_neg, home : int
        ``[12]``, ``[13]``, ``[14]`` bit per axis.
    generator : int
        ``[15]``.
    axis_states : tuple of 8 int
        ``[16..23]``.
    positions : tuple of 8 int
        ``[24..55]`` [pulses].
    info : bytes
        ``[56..59]``: axes, kHz, buffer slots, slot time.
    emergency_polarity, driver_errors, misc_inputs : int
        ``[60]``, ``[61]``, ``[62]``.
    """

    soft_limit: int
    power_mask: int
    limit_override: int
    enabled_axes: int
    activated: int
    engine_state: int
    charge_pump: int
    limit_pos: int
    limit_neg: int
    home: int
    generator: int
    axis_states: tuple[int, ...]
    positions: tuple[int, ...]
    info: bytes = ENGINE_INFO_V2
    emergency_polarity: int = 0
    driver_errors: int = 0
    misc_inputs: int = 0


def put_status_v2(frame: bytearray, status: StatusV2) -> None:
    """Write the v2 status block (``[3..5]`` and ``[8..62]``; ``[2]`` and ``[63]`` are the caller's)."""
    frame[3:6] = bytes((status.soft_limit, status.power_mask, status.limit_override))
    frame[8:16] = bytes((status.enabled_axes, status.activated, status.engine_state, status.charge_pump,
                         status.limit_pos, status.limit_neg, status.home, status.generator))
    frame[16:24] = bytes(status.axis_states[:V2_AXES]).ljust(V2_AXES, b"\0")
    for a in range(V2_AXES):
        put_i32(frame, 24 + 4 * a, status.positions[a] if a < len(status.positions) else 0)
    frame[56:60] = status.info
    frame[60:63] = bytes((status.emergency_polarity, status.driver_errors, status.misc_inputs))


def get_status_v2(frame: bytes | bytearray) -> StatusV2:
    """Read the v2 status block (the inverse of :func:`put_status_v2`)."""
    f = frame
    return StatusV2(f[3], f[4], f[5], f[8], f[9], f[10], f[11], f[12], f[13], f[14], f[15], tuple(f[16:24]),
                    tuple(get_i32(frame, 24 + 4 * a) for a in range(V2_AXES)), bytes(frame[56:60]),
                    frame[60], frame[61], frame[62])


def status_check(request_check: int) -> int:
    """v2 status reply ``[63]`` for the request's check byte ``[3]``."""
    return (request_check + STATUS_CHECK_OFFSET) & 0xFF


# -- v2 axis record (0x10 / 0x11) ------------------------------------------------------------------
_RECORD = struct.Struct("<8B3f2ih7BIH2B")
RECORD_SLICE = slice(8, 8 + _RECORD.size)
"""``[8..52]``: the axis record, stored per axis and returned verbatim."""

# axis configuration byte [8]
CFG_ENABLED = 0x01
CFG_INVERT_DIRECTION = 0x02
CFG_INTERNAL_PLANNER = 0x04
CFG_POSITION_MODE = 0x08
CFG_INVERT_HOMING = 0x10
CFG_SOFT_LIMITS = 0x20
# axis switch byte [9]
SW_LIMIT_NEG = 0x01
SW_LIMIT_POS = 0x02
SW_HOME = 0x04
# signal options [51]
SIG_INVERT_DIRECTION = 0x02


@dataclass(frozen=True)
class AxisRecord:
    """One v2 axis record (5.5 of the protocol notes), in wire units.

    Attributes
    ----------
    config, switches : int
        Configuration bits ``[8]`` (``CFG_*``) and switch bits ``[9]`` (``SW_*``).
    max_speed : float
        pulses/ms ``[16..19]``.
    accel, decel : float
        pulses/ms^2 ``[20..27]``.
    soft_min, soft_max : int
        Soft limits [pulses] ``[28..35]``.
    """

    config: int = 0
    switches: int = 0
    home_pin: int = 0
    limit_neg_pin: int = 0
    limit_pos_pin: int = 0
    homing_speed_pct: int = 0
    homing_return_pct: int = 0
    mpg_encoder: int = 0
    max_speed: float = 0.0
    accel: float = 0.0
    decel: float = 0.0
    soft_min: int = 0
    soft_max: int = 0
    mpg_multiplier: int = 0
    enable_pin: int = 0
    invert_enable: int = 0
    limit_neg_filter: int = 0
    limit_pos_filter: int = 0
    home_filter: int = 0
    homing_algorithm: int = 0
    mpg_1x: int = 0
    home_backoff: int = 0
    mpg_divider: int = 0
    signal_options: int = 0
    probe_filter: int = 0

    def to_bytes(self) -> bytes:
        """The 45 bytes of ``[8..52]``."""
        return _RECORD.pack(*astuple(self))

    @classmethod
    def from_bytes(cls, block: bytes | bytearray) -> AxisRecord:
        """Decode the 45 bytes of ``[8..52]``."""
        return cls(*_RECORD.unpack(bytes(block)))
