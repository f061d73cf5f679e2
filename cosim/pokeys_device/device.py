"""The virtual device as one pure function: request bytes in, reply bytes (or silence) out.

:meth:`Device.handle` is what both sockets call, and what the fuzz tests call in-process:

* a request that cannot be framed (length, header 0xBB, checksum, large-fill parts) gets no reply
  and is counted (``bad_length``, ``bad_header``, ``bad_checksum``, ``bad_multipart``);
* every framed request gets exactly one 64-byte reply: the command's own, or the benign reply
  (``[2..5]`` = 0, zero payload; for 0x80 / 0x85 ``[2]`` = the sub-command) for commands that
  are not modelled, counted as ``unknown_command`` / ``unknown_subcommand``;
* a fault inside a handler is a bug: it is counted as ``internal_error`` and still answered with
  the benign reply, so the host's session stays in step.
"""

from __future__ import annotations

from cosim.controllers.pokeys import device_model
from cosim.pokeys_device.adapter import EngineAdapter
from cosim.pokeys_device.commands_v1 import PulseEngineV1
from cosim.pokeys_device.commands_v2 import PulseEngineV2
from cosim.pokeys_device.common import PacketLog, log
from cosim.pokeys_device.identity import IDENTITY_COMMANDS, DeviceIdentity, discovery_reply, identity_reply
from cosim.pokeys_device.io_commands import IoCommands
from cosim.pokeys_device.packets import (
    FRAME_BYTES,
    MULTIPART_BYTES,
    MULTIPART_COMMAND,
    REQUEST_HEADER,
    BadMultipart,
    PacketError,
    PartCollector,
    check_frame,
    checksum,
    new_reply,
    parse_large_fill,
    seal,
)


class Device:
    """One simulated PoKeys: identity, pulse engine handlers, I/O replies and the packet log.

    Parameters
    ----------
    identity : DeviceIdentity
        56E (pulse engine v1, command 0x80) or 57E / 57CNC (pulse engine v2, 0x85 and 0xB0).
    adapter : EngineAdapter
        The engine behind the handlers (built for the same model:
        ``EngineConfig.for_model(identity.model)``, which :class:`~.rig.VirtualPoKeys` does).

    Attributes
    ----------
    model : DeviceModel
        The model's figures the device reports (engine info, maximum frequency).
    """

    def __init__(self, identity: DeviceIdentity, adapter: EngineAdapter) -> None:
        self.identity = identity
        self.adapter = adapter
        self.model = device_model(identity.model)
        self.log = PacketLog()
        self.io = IoCommands()
        self.v1 = PulseEngineV1(adapter, self.log, model=self.model) if identity.pulse_engine == 1 else None
        self.v2 = PulseEngineV2(adapter, self.log, model=self.model) if identity.pulse_engine == 2 else None

    def discovery(self, *, device_ip: str = "127.0.0.1", host_ip: str = "127.0.0.1") -> bytes:
        """Reply to an empty UDP datagram (14 or 19 bytes)."""
        self.log.count("discovery")
        return discovery_reply(self.identity, device_ip=device_ip, host_ip=host_ip)

    def handle(self, request: bytes) -> bytes | None:
        """The reply to one request (64 bytes, or 512 for a large fill), or None for silence."""
        try:
            if len(request) == MULTIPART_BYTES:
                return self._large_fill(request)
            frame = check_frame(request)
            if frame[1] == MULTIPART_COMMAND:
                raise BadMultipart("a lone 64-byte 0xB0 part (a large fill is 8 parts in one 512-byte request)")
        except PacketError as exc:
            self.log.count(exc.reason, str(exc))
            return None
        self.log.count("request")
        try:
            return seal(self._reply(frame))
        except Exception as exc:  # a bug: keep the session in step, count it loudly
            log.exception("internal error on request %s", frame[:8].hex(" "))
            self.log.count("internal_error", f"{type(exc).__name__}: {exc} on {frame[:8].hex(' ')}")
            return seal(_benign(frame))

    def handle_stream_frame(self, frame: bytes, parts: PartCollector) -> bytes | None:
        """One 64-byte frame from a TCP stream; large-fill parts are collected in ``parts`` first."""
        if (len(frame) == FRAME_BYTES and frame[0] == REQUEST_HEADER and frame[1] == MULTIPART_COMMAND
                and frame[7] == checksum(frame)):
            try:
                whole = parts.add(frame)
            except BadMultipart as exc:
                self.log.count(exc.reason, str(exc))
                return None
            return None if whole is None else self.handle(whole)
        return self.handle(frame)

    def _reply(self, frame: bytes) -> bytearray:
        command = frame[1]
        if command in IDENTITY_COMMANDS:
            return identity_reply(self.identity, frame)
        if command == 0x80 and self.v1 is not None:
            return self.v1.handle(frame)
        if command == 0x85 and self.v2 is not None:
            return self.v2.handle(frame)
        if command in (0x80, 0x85):
            self.log.count("unknown_command", f"0x{command:02X}: not this device's pulse engine")
            return _benign(frame)
        reply, known = self.io.handle(frame)
        if not known:
            self.log.count("unknown_command", f"0x{command:02X}")
        return reply

    def _large_fill(self, request: bytes) -> bytes | None:
        fill = parse_large_fill(request)
        self.log.count("request")
        if self.v2 is None:
            self.log.count("unknown_command", "0xB0 large fill on a pulse engine v1 device")
            return seal(new_reply(bytes((0, MULTIPART_COMMAND, 0, 0, 0, 0, fill.last_id))))
        try:
            return seal(self.v2.large_fill(fill))
        except Exception as exc:
            log.exception("internal error on a large fill")
            self.log.count("internal_error", f"{type(exc).__name__}: {exc} on a large fill")
            return seal(new_reply(bytes((0, MULTIPART_COMMAND, 0, 0, 0, 0, fill.last_id))))


def _benign(frame: bytes) -> bytearray:
    """``[2..5]`` = 0 and zeros; for 0x80 / 0x85 the sub-command stays in ``[2]``."""
    reply = new_reply(frame)
    if frame[1] in (0x80, 0x85):
        reply[2] = frame[2]
    return reply
