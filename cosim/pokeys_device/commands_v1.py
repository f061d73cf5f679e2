"""Pulse engine v1 (command 0x80, PoKeys56E FW 3.0.59-3.0.65): sub-commands to engine calls.

Every reply echoes the sub-command in ``[2]`` with ``[3..5]`` = 0; the library checks nothing
else in a v1 reply and copies fields at fixed offsets (:mod:`.layouts`).

Sub-commands (library call: device behaviour):

* 0x30 ``PK_PEInfoGet``: 3 axes, the model's kHz (25), 128 slots, 1 ms;
* 0x00 ``PK_PEStatusGet``: positions, switches, state, axis states, enabled, charge pump;
* 0x06 ``PK_PEStatusSet``: ``[3]`` engine enabled (disabled: nothing moves), ``[4]`` charge pump;
* 0x01 ``PK_PECurrentPositionSet``: the x, y, z position counters;
* 0x02 ``PK_PEStateSet``: ``[8]`` state 0 / 1 / 2 / 10;
* 0x05 ``PK_PEMove``: references of the internal controller (state 1), positions or speeds;
* 0x10 / 0x11 ``PK_PEParametersGet`` / ``Set``: ``[8..46]`` returned exactly as set; applied as
  max speed, acceleration, deceleration, homing speeds and emergency polarity;
* 0x12 / 0x13 ``PK_PEAxisConfigurationGet`` / ``Set``: switch enables, direction and homing
  direction inversion;
* 0x14 / 0x15 kbd48CNC use, 0x03 MPG jog configuration: stored and returned;
* 0x20 ``PK_PEHomingStart``: ``[8..10]`` = 1 homes that axis;
* 0x35 ``PK_PEBufferFill``: at most 18 slots of 3 bytes; accepted count in ``[8]``, status from ``[9]``.
  A slot the model cannot emit (more than 25 pulses, or the reserved x byte 0xFF) refuses the
  whole fill, as the engine's API does: ``[8]`` = 0, counted as ``rejected`` (0xFF also as
  ``special_entry``);
* 0x36 ``PK_PEBufferFlush``: clear the buffer; 0x37 ``PK_PEBufferFreeSizeGet``: ``[8]`` free slots.
"""

from __future__ import annotations

from dataclasses import replace

from cosim.controllers.pokeys import MODELS, DeviceModel, EngineConfig, EngineState
from cosim.pokeys_device.adapter import EngineAdapter
from cosim.pokeys_device.common import PacketLog, accel_hz2, percent, reported_axis_state, speed_hz
from cosim.pokeys_device.layouts import (
    PARAMS_V1_SLICE,
    V1_AXES,
    ParamsV1,
    StatusV1,
    engine_info,
    put_status_v1,
)
from cosim.pokeys_device.packets import get_i32, new_reply

COMMAND = 0x80
FILL_SLOTS_MAX = 18
"""Slots one v1 fill carries (54 of the 56 payload bytes)."""
SPECIAL_X_BYTE = 0xFF
"""The vendor's reserved "special command" value of the x byte: never a count; the engine refuses the fill."""
SWITCH_CONFIG = slice(8, 13)
MPG_CONFIG = slice(8, 24)


class PulseEngineV1:
    """Handlers of command 0x80 over an :class:`EngineAdapter`.

    Parameters
    ----------
    adapter : EngineAdapter
        The engine (at least 3 axes). It is disabled at power-on: the host enables it (0x06).
    notes : PacketLog
        Where refused commands and ignored values are counted.
    model : DeviceModel
        The device's figures (default the 56E's).
    """

    def __init__(self, adapter: EngineAdapter, notes: PacketLog, *, model: DeviceModel = MODELS["56E"]) -> None:
        self.adapter = adapter
        self.notes = notes
        self.model = model
        self.charge_pump = 0
        settings = adapter.settings()
        self.params = _params_block(settings)
        self.switch_config = _switch_block(settings)
        self.keyboard = 0
        self.mpg = bytes(MPG_CONFIG.stop - MPG_CONFIG.start)
        self._reference: tuple[int, tuple[int, ...]] | None = None
        adapter.set_enabled(False)
        self._handlers = {
            0x30: self._info, 0x00: self._status, 0x06: self._enable, 0x01: self._set_positions,
            0x02: self._set_state, 0x05: self._move, 0x10: self._get_params, 0x11: self._set_params,
            0x12: self._get_switches, 0x13: self._set_switches, 0x14: self._get_keyboard,
            0x15: self._set_keyboard, 0x20: self._homing, 0x03: self._mpg, 0x35: self._fill,
            0x36: self._clear, 0x37: self._free,
        }

    def handle(self, request: bytes) -> bytearray:
        """Unsealed reply to a checked 0x80 request (unknown sub-commands: the benign reply)."""
        reply = new_reply(request)
        reply[2] = request[2]
        handler = self._handlers.get(request[2])
        if handler is None:
            self.notes.count("unknown_subcommand", f"0x80/0x{request[2]:02X}")
        else:
            handler(request, reply)
        return reply

    # -- status -----------------------------------------------------------------------------------
    def status(self) -> StatusV1:
        """The status block as a 0x00 reply reports it."""
        s = self.adapter.status()
        enabled = self.adapter.enabled
        queued = s.queued_slots > 0
        axis_states = tuple(reported_axis_state(s.axis_states[a], enabled=enabled, queued=queued)
                            for a in range(V1_AXES))
        return StatusV1(s.positions[:V1_AXES], s.limit_pos & 7, s.limit_neg & 7, s.home & 7, int(s.engine_state),
                        axis_states, int(enabled), int(bool(self.charge_pump)))

    def _info(self, request: bytes, reply: bytearray) -> None:
        reply[8:12] = engine_info(self.model, axes=V1_AXES)

    def _status(self, request: bytes, reply: bytearray) -> None:
        put_status_v1(reply, self.status())

    def _free(self, request: bytes, reply: bytearray) -> None:
        reply[8] = self.adapter.status().free_slots & 0xFF

    # -- state ------------------------------------------------------------------------------------
    def _enable(self, request: bytes, reply: bytearray) -> None:
        self.charge_pump = request[4]
        self.adapter.set_enabled(bool(request[3]))
        if self.adapter.enabled and self.adapter.status().engine_state == EngineState.INTERNAL:
            self._apply_reference()

    def _set_state(self, request: bytes, reply: bytearray) -> None:
        with self.notes.rejecting("0x80/0x02 set state"):
            self.adapter.set_state(request[8])
            if request[8] == EngineState.INTERNAL:
                self._apply_reference()

    def _set_positions(self, request: bytes, reply: bytearray) -> None:
        for a in range(V1_AXES):
            self.adapter.set_position(a, get_i32(request, 8 + 4 * a))

    def _move(self, request: bytes, reply: bytearray) -> None:
        mode = request[3]
        if mode not in (0, 10):
            self.notes.count("ignored_value", f"0x80/0x05 mode [3] = {mode} (allowed: 0 position, 10 speed)")
            return
        self._reference = (mode, tuple(get_i32(request, 8 + 4 * a) for a in range(V1_AXES)))
        if self.adapter.enabled and self.adapter.status().engine_state == EngineState.INTERNAL:
            self._apply_reference()

    def _apply_reference(self) -> None:
        """Start the internal controller towards the last 0x05 references (once per reference)."""
        if self._reference is None:
            return
        mode, values = self._reference
        self._reference = None
        with self.notes.rejecting("0x80/0x05 move"):
            if mode == 0:
                self.adapter.move_to(list(values))
            else:
                self.adapter.run_at(list(values))

    def _homing(self, request: bytes, reply: bytearray) -> None:
        axes = [a for a in range(V1_AXES) if request[8 + a]]
        if axes:
            with self.notes.rejecting("0x80/0x20 start homing"):
                self.adapter.start_homing(axes)

    # -- configuration ----------------------------------------------------------------------------
    def _get_params(self, request: bytes, reply: bytearray) -> None:
        reply[PARAMS_V1_SLICE] = self.params

    def _set_params(self, request: bytes, reply: bytearray) -> None:
        self.params = bytes(request[PARAMS_V1_SLICE])
        wire = ParamsV1.from_bytes(self.params)
        old = self.adapter.settings()
        axes = list(old.axes)
        for a in range(V1_AXES):
            where = f"0x80/0x11 axis {a}"
            axes[a] = replace(
                axes[a],
                max_speed_hz=speed_hz(wire.max_speed[a], axes[a].max_speed_hz, what=f"{where} max speed",
                                      notes=self.notes, high=self.model.max_rate_hz),
                accel=accel_hz2(wire.accel[a], axes[a].accel, what=f"{where} acceleration", notes=self.notes),
                decel=accel_hz2(wire.decel[a], axes[a].decel, what=f"{where} deceleration", notes=self.notes))
        polarity = wire.emergency_polarity
        if polarity not in (0, 1):
            self.notes.count("ignored_value", f"0x80/0x11 emergency polarity [46] = {polarity} (allowed: 0, 1)")
            polarity = old.emergency_polarity
        self._configure(replace(
            old, axes=tuple(axes), emergency_polarity=polarity,
            homing_speed_pct=percent(wire.homing_pct, old.homing_speed_pct, what="0x80/0x11 homing speed [44]",
                                     notes=self.notes),
            homing_return_pct=percent(wire.homing_return_pct, old.homing_return_pct,
                                      what="0x80/0x11 homing return speed [45]", notes=self.notes)))

    def _get_switches(self, request: bytes, reply: bytearray) -> None:
        reply[SWITCH_CONFIG] = self.switch_config

    def _set_switches(self, request: bytes, reply: bytearray) -> None:
        self.switch_config = bytes(request[SWITCH_CONFIG])
        limit_pos, limit_neg, home, invert, invert_homing = self.switch_config
        old = self.adapter.settings()
        axes = list(old.axes)
        for a in range(V1_AXES):
            axes[a] = replace(axes[a], limit_pos_enabled=bool(limit_pos >> a & 1),
                              limit_neg_enabled=bool(limit_neg >> a & 1), home_enabled=bool(home >> a & 1),
                              invert_direction=bool(invert >> a & 1), invert_homing=bool(invert_homing >> a & 1))
        self._configure(replace(old, axes=tuple(axes)))

    def _configure(self, config: EngineConfig) -> None:
        with self.notes.rejecting("configuration"):
            self.adapter.configure(config)

    def _get_keyboard(self, request: bytes, reply: bytearray) -> None:
        reply[8] = self.keyboard

    def _set_keyboard(self, request: bytes, reply: bytearray) -> None:
        self.keyboard = request[8]

    def _mpg(self, request: bytes, reply: bytearray) -> None:
        if request[3] == 10:
            self.mpg = bytes(request[MPG_CONFIG])
        reply[MPG_CONFIG] = self.mpg

    # -- buffer -----------------------------------------------------------------------------------
    def _fill(self, request: bytes, reply: bytearray) -> None:
        offered = min(request[3], FILL_SLOTS_MAX)
        pad = bytes(self.adapter.axes - V1_AXES)
        slots = [bytes(request[8 + V1_AXES * s:8 + V1_AXES * (s + 1)]) + pad for s in range(offered)]
        for s, slot in enumerate(slots):
            if slot[0] == SPECIAL_X_BYTE:
                self.notes.count("special_entry", f"0x80/0x35 slot {s}: x byte 0xFF, the reserved special command")
        accepted = 0
        with self.notes.rejecting("0x80/0x35 fill"):
            accepted = self.adapter.fill(slots)
        reply[8] = accepted
        put_status_v1(reply, self.status(), offset=9, with_enable=False)

    def _clear(self, request: bytes, reply: bytearray) -> None:
        self.adapter.clear_buffer()


def _params_block(settings: EngineConfig) -> bytes:
    axes = settings.axes[:V1_AXES]
    return ParamsV1(tuple(float(a.max_speed_hz) / 1000 for a in axes), tuple(float(a.accel) / 1e6 for a in axes),
                    tuple(float(a.decel) / 1e6 for a in axes), settings.homing_speed_pct, settings.homing_return_pct,
                    settings.emergency_polarity).to_bytes()


def _switch_block(settings: EngineConfig) -> bytes:
    axes = settings.axes[:V1_AXES]

    def mask(flag: str) -> int:
        return sum(1 << a for a, axis in enumerate(axes) if getattr(axis, flag))

    return bytes(mask(f) for f in ("limit_pos_enabled", "limit_neg_enabled", "home_enabled", "invert_direction",
                                   "invert_homing"))
