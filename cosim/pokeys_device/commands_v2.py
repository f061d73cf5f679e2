"""Pulse engine v2 (command 0x85 and the large fill 0xB0, PoKeys57 series): sub-commands to engine calls.

Replies echo the sub-command in ``[2]`` (fills put the accepted count there) with ``[3..5]`` = 0
unless the sub-command defines them. The status block (:class:`~.layouts.StatusV2`) is in the
0x00 reply and in every fill reply; the 0x00 reply's ``[63]`` is the request's check byte + 0x5A.

Modelled: 0x00 status, 0x01 setup, 0x02 state, 0x03 positions, 0x05 reboot, 0x06 additional
parameters, 0x04 external outputs, 0x08 status 2, 0x10/0x11 axis records, 0x20 move, 0x21/0x22
homing, 0xF0 clear, 0xFF/0xFE fills, 0xB0 large fill; 0x0A, 0x0B, 0x18, 0x19 stored and echoed.
Every other sub-command gets the benign reply (sub-command echo, zeros).

The engine model drives ``adapter.axes`` axes (3 on a 57E, 8 on a 57CNC); the status block has 8.
Axes beyond the model keep their records and positions (set by 0x03) but never move. A fill slot
the model cannot emit (more pulses than its per-slot limit: 25 on a 57E, 125 on a 57CNC; an
8-bit 0xFF is -127, a 16-bit entry can hold 32767) refuses the whole fill, as the engine's API
does: ``[2]`` = 0 accepted, counted as ``rejected``.
"""

from __future__ import annotations

from dataclasses import replace

from cosim.controllers.pokeys import MODELS, DeviceModel, EngineState
from cosim.pokeys_device.adapter import EngineAdapter
from cosim.pokeys_device.common import PacketLog, accel_hz2, bits, percent, reported_axis_state, speed_hz
from cosim.pokeys_device.layouts import (
    CFG_ENABLED,
    CFG_INTERNAL_PLANNER,
    CFG_INVERT_DIRECTION,
    CFG_INVERT_HOMING,
    CFG_POSITION_MODE,
    RECORD_SLICE,
    SIG_INVERT_DIRECTION,
    SW_HOME,
    SW_LIMIT_NEG,
    SW_LIMIT_POS,
    V2_AXES,
    AxisRecord,
    StatusV2,
    engine_info,
    put_status_v2,
    status_check,
)
from cosim.pokeys_device.packets import (
    MULTIPART_COMMAND,
    LargeFill,
    get_i32,
    new_reply,
    signed_entries,
)

COMMAND = 0x85
RUNNING = 3
"""v2 engine state "running": buffer mode (or the internal planner) in the engine model."""
FILL_8BIT, FILL_16BIT = 0xFF, 0xFE
ENTRY_WIDTH = {FILL_8BIT: 1, FILL_16BIT: 2}
SETUP = slice(8, 14)
"""Setup ``[8..13]``: enabled axes, charge pump, generator, buffer size, E-stop polarity, power mask."""
ECHOED = {0x0A: slice(8, 16), 0x0B: slice(8, 16), 0x18: slice(8, 16), 0x19: slice(8, 16)}
"""Sub-commands whose fields are stored on a write and echoed."""


def v2_state(engine_state: int) -> int:
    """v2 engine state for an engine (v1-coded) state: internal and buffer are both "running"."""
    return RUNNING if engine_state in (EngineState.INTERNAL, EngineState.BUFFER) else engine_state


class PulseEngineV2:
    """Handlers of command 0x85 (and 0xB0) over an :class:`EngineAdapter`.

    Parameters
    ----------
    adapter : EngineAdapter
    notes : PacketLog
    model : DeviceModel
        The device's figures (default the 57E's).
    """

    def __init__(self, adapter: EngineAdapter, notes: PacketLog, *, model: DeviceModel = MODELS["57E"]) -> None:
        self.adapter = adapter
        self.notes = notes
        self.model = model
        self.setup = bytes(6)
        self.records = [AxisRecord() for _ in range(V2_AXES)]
        self.raw_records = [bytes(RECORD_SLICE.stop - RECORD_SLICE.start)] * V2_AXES
        self.limit_override = 0
        self.output_mask = 0
        self.emergency_pin = 0
        self.outputs = (0, 0)
        self.home_offsets = [0] * V2_AXES
        self.extra_positions = [0] * V2_AXES
        self.echoed = {sub: bytes(s.stop - s.start) for sub, s in ECHOED.items()}
        self._references: list[int] | None = None
        self._configured: set[int] = set()
        adapter.set_enabled(True)
        self._handlers = {
            0x00: self._status, 0x01: self._setup, 0x02: self._set_state, 0x03: self._set_positions,
            0x04: self._external_outputs, 0x05: self._reboot, 0x06: self._additional, 0x08: self._status2,
            0x10: self._get_axis, 0x11: self._set_axis, 0x20: self._move, 0x21: self._start_homing,
            0x22: self._finish_homing, 0xF0: self._clear, FILL_8BIT: self._fill, FILL_16BIT: self._fill,
        }

    def handle(self, request: bytes) -> bytearray:
        """Unsealed reply to a checked 0x85 request."""
        reply = new_reply(request)
        sub = request[2]
        reply[2] = sub
        handler = self._handlers.get(sub)
        if handler is not None:
            handler(request, reply)
        elif sub in ECHOED:
            self._echo(request, reply)
        else:
            self.notes.count("unknown_subcommand", f"0x85/0x{sub:02X}")
        return reply

    def large_fill(self, fill: LargeFill) -> bytearray:
        """Unsealed reply to a reassembled 0xB0 request: ``[1]`` = 0xB0, ID of part 7."""
        reply = new_reply(bytes((0, MULTIPART_COMMAND, 0, 0, 0, 0, fill.last_id)))
        width = ENTRY_WIDTH.get(fill.entry_format)
        if width is None:
            self.notes.count("ignored_value", f"0xB0 entry format [3] = 0x{fill.entry_format:02X} (allowed: FF, FE)")
            put_status_v2(reply, self.status())
            return reply
        reply[2] = self._queue(fill.data, fill.offered_slots, fill.axes_per_slot, width)
        put_status_v2(reply, self.status())
        return reply

    # -- status -----------------------------------------------------------------------------------
    def status(self) -> StatusV2:
        """The status block now."""
        s = self.adapter.status()
        state = v2_state(s.engine_state)
        queued = s.queued_slots > 0
        axis_states = []
        positions = list(self.extra_positions)
        for a in range(V2_AXES):
            enabled = bool(self.records[a].config & CFG_ENABLED) and state != EngineState.STOPPED
            if a < self.adapter.axes:
                axis_states.append(reported_axis_state(s.axis_states[a], enabled=enabled, queued=queued))
                positions[a] = s.positions[a]
            else:
                axis_states.append(0)
        setup = self.setup
        return StatusV2(0, setup[5], self.limit_override, setup[0], 1, state, setup[1], s.limit_pos & 0xFF,
                        s.limit_neg & 0xFF, s.home & 0xFF, setup[2], tuple(axis_states), tuple(positions),
                        info=engine_info(self.model, axes=V2_AXES), emergency_polarity=setup[4])

    def _status(self, request: bytes, reply: bytearray) -> None:
        put_status_v2(reply, self.status())
        reply[2] = 0
        reply[63] = status_check(request[3])

    def _status2(self, request: bytes, reply: bytearray) -> None:
        s = self.adapter.status()
        reply[8:11] = bytes((s.limit_neg & 0xFF, s.limit_pos & 0xFF, s.home & 0xFF))
        reply[63] = status_check(request[3])

    # -- setup and state --------------------------------------------------------------------------
    def _setup(self, request: bytes, reply: bytearray) -> None:
        self.setup = bytes(request[SETUP])
        polarity = self.setup[4]
        if polarity not in (0, 1):
            self.notes.count("ignored_value", f"0x85/0x01 emergency polarity [12] = {polarity} (allowed: 0, 1)")
            polarity = self.adapter.settings().emergency_polarity
        with self.notes.rejecting("0x85/0x01 setup"):
            self.adapter.configure(replace(self.adapter.settings(), emergency_polarity=polarity))
        reply[3] = 0  # result: OK

    def _set_state(self, request: bytes, reply: bytearray) -> None:
        self.limit_override, self.output_mask = request[4], request[5]
        self._apply_axes()
        self._enter(request[3], "0x85/0x02 set state")

    def _enter(self, state: int, what: str) -> None:
        with self.notes.rejecting(what):
            if state == RUNNING:
                planner = self._planner_axes()
                self.adapter.set_state(EngineState.INTERNAL if planner else EngineState.BUFFER)
                if planner:
                    self._apply_references()
            else:
                self.adapter.set_state(state)

    def _reboot(self, request: bytes, reply: bytearray) -> None:
        self.adapter.set_state(EngineState.STOPPED)
        self.adapter.clear_buffer()

    def _set_positions(self, request: bytes, reply: bytearray) -> None:
        for a in bits(request[3], V2_AXES):
            value = get_i32(request, 8 + 4 * a)
            if a < self.adapter.axes:
                self.adapter.set_position(a, value)
            else:
                self.extra_positions[a] = value

    def _additional(self, request: bytes, reply: bytearray) -> None:
        if request[3] == 1:
            self.emergency_pin = request[8]
        reply[8] = self.emergency_pin

    def _external_outputs(self, request: bytes, reply: bytearray) -> None:
        if request[5] != 1:
            self.outputs = (request[3], request[4])
        reply[3:5] = bytes(self.outputs)

    def _echo(self, request: bytes, reply: bytearray) -> None:
        sub, fields = request[2], ECHOED[request[2]]
        self.echoed[sub] = bytes(request[fields])
        reply[fields] = self.echoed[sub]

    # -- axis records -----------------------------------------------------------------------------
    def _get_axis(self, request: bytes, reply: bytearray) -> None:
        axis = request[3]
        if axis >= V2_AXES:
            self.notes.count("ignored_value", f"0x85/0x10 axis [3] = {axis} (allowed: 0..7)")
            return
        reply[RECORD_SLICE] = self.raw_records[axis]

    def _set_axis(self, request: bytes, reply: bytearray) -> None:
        axis = request[3]
        if axis >= V2_AXES:
            self.notes.count("ignored_value", f"0x85/0x11 axis [3] = {axis} (allowed: 0..7)")
            return
        self.raw_records[axis] = bytes(request[RECORD_SLICE])
        self.records[axis] = AxisRecord.from_bytes(self.raw_records[axis])
        self._configured.add(axis)
        self._apply_axes(changed=axis)

    def _apply_axes(self, *, changed: int | None = None) -> None:
        """Give the engine the records' speeds, switch enables (minus the limit override) and inversions.

        Only axes whose record the host has set: until then the engine keeps its own configuration.
        """
        old = self.adapter.settings()
        axes = list(old.axes)
        homing, back = old.homing_speed_pct, old.homing_return_pct
        for a in sorted(self._configured):
            if a >= min(self.adapter.axes, len(axes)):
                continue
            r, where = self.records[a], f"0x85/0x11 axis {a}"
            override = bool(self.limit_override >> a & 1)
            axes[a] = replace(
                axes[a],
                limit_pos_enabled=bool(r.switches & SW_LIMIT_POS) and not override,
                limit_neg_enabled=bool(r.switches & SW_LIMIT_NEG) and not override,
                home_enabled=bool(r.switches & SW_HOME),
                invert_direction=bool(r.config & CFG_INVERT_DIRECTION) != bool(r.signal_options & SIG_INVERT_DIRECTION),
                invert_homing=bool(r.config & CFG_INVERT_HOMING))
            if a == changed:
                axes[a] = replace(
                    axes[a],
                    max_speed_hz=speed_hz(r.max_speed, axes[a].max_speed_hz, what=f"{where} max speed",
                                          notes=self.notes, high=self.model.max_rate_hz),
                    accel=accel_hz2(r.accel, axes[a].accel, what=f"{where} acceleration", notes=self.notes),
                    decel=accel_hz2(r.decel, axes[a].decel, what=f"{where} deceleration", notes=self.notes))
                if r.homing_speed_pct:
                    homing = percent(r.homing_speed_pct, homing, what=f"{where} homing speed [13]", notes=self.notes)
                    back = max(1, homing * min(r.homing_return_pct or 10, 100) // 100)
        with self.notes.rejecting("0x85/0x11 axis configuration"):
            self.adapter.configure(replace(old, axes=tuple(axes), homing_speed_pct=homing, homing_return_pct=back))

    def _planner_axes(self) -> list[int]:
        return [a for a in range(min(self.adapter.axes, V2_AXES))
                if self.records[a].config & CFG_ENABLED and self.records[a].config & CFG_INTERNAL_PLANNER]

    # -- motion -----------------------------------------------------------------------------------
    def _move(self, request: bytes, reply: bytearray) -> None:
        self._references = [get_i32(request, 8 + 4 * a) for a in range(V2_AXES)]
        if not self._planner_axes():
            self.notes.count("ignored_value", "0x85/0x20 move: no axis uses the internal planner")
            return
        if v2_state(self.adapter.status().engine_state) == RUNNING:
            with self.notes.rejecting("0x85/0x20 move"):
                if self.adapter.status().engine_state != EngineState.INTERNAL:
                    self.adapter.set_state(EngineState.INTERNAL)
                self._apply_references()

    def _apply_references(self) -> None:
        """Position or speed references to the planner axes (the engine runs them in its internal mode)."""
        if self._references is None:
            return
        n = self.adapter.axes
        targets: list[int | None] = [None] * n
        speeds: list[int | None] = [None] * n
        for a in self._planner_axes():
            if self.records[a].config & CFG_POSITION_MODE:
                targets[a] = self._references[a]
            else:
                speeds[a] = self._references[a]
        if any(t is not None for t in targets):
            self.adapter.move_to(targets)
        if any(v is not None for v in speeds):
            self.adapter.run_at(speeds)

    def _start_homing(self, request: bytes, reply: bytearray) -> None:
        axes = bits(request[3], V2_AXES)
        for a in axes:
            self.home_offsets[a] = get_i32(request, 8 + 4 * a)
        modelled = [a for a in axes if a < self.adapter.axes]
        if modelled:
            with self.notes.rejecting("0x85/0x21 start homing"):
                self.adapter.start_homing(modelled)

    def _finish_homing(self, request: bytes, reply: bytearray) -> None:
        if request[4] == 0:
            self._enter(request[3], "0x85/0x22 finish homing")

    # -- buffer -----------------------------------------------------------------------------------
    def _clear(self, request: bytes, reply: bytearray) -> None:
        self.adapter.clear_buffer()

    def _fill(self, request: bytes, reply: bytearray) -> None:
        accepted = self._queue(request[8:], request[3], request[4], ENTRY_WIDTH[request[2]])
        put_status_v2(reply, self.status())
        reply[2] = accepted

    def _queue(self, data: bytes, offered: int, axes_per_slot: int, width: int) -> int:
        """Decode slot-major entries, keep the buffer-mode axes' counts, queue as many as fit."""
        if axes_per_slot == 0:
            return 0
        capacity = len(data) // (axes_per_slot * width)
        slots = signed_entries(data, min(offered, capacity), axes_per_slot, width=width)
        n = self.adapter.axes
        driven = [a for a in range(min(n, axes_per_slot))
                  if self.records[a].config & CFG_ENABLED and not self.records[a].config & CFG_INTERNAL_PLANNER]
        counts = []
        for slot in slots:
            row = [0] * n
            for a in driven:
                row[a] = slot[a]
            counts.append(row)
        accepted = 0
        with self.notes.rejecting(f"{width * 8}-bit fill"):
            accepted = self.adapter.fill(counts)
        return accepted

