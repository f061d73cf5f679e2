"""Who the virtual device says it is: discovery replies and the identification handshake.

Two presets, as the protocol notes propose:

* ``56E``: a PoKeys56E with pulse engine v1 (classic device data, FW 3.0.60, serial 20123);
  the hosts that drive it use the PEv1-era library, which sends 0x00, 0x03, 0xE0, 0x06, 0x04 x3,
  0x8F and then 0x80/0x30 (engine info) at connect;
* ``57E`` / ``57CNC``: a PoKeys57E or PoKeys57CNC with pulse engine v2 (extended device data
  "PKEx", FW 4.7.15, serial 32123, hardware type 31 or 32).

The same module decodes both as the library does (for the client and the tests): type, serial,
firmware and the pulse-engine flags come from exactly the bytes the library reads.
"""

from __future__ import annotations

import ipaddress
from dataclasses import dataclass

from cosim.errors import ConfigurationError
from cosim.pokeys_device.packets import new_reply, put_text

MODELS = ("56E", "57E", "57CNC")
TYPE_POKEYS56E = 11
HW_TYPE = {"57E": 31, "57CNC": 32}
TYPE_NAMES = {TYPE_POKEYS56E: "PoKeys56E", 29: "PoKeys57E", 31: "PoKeys57E", 32: "PoKeys57CNC",
              33: "PoKeys57CNCpro4x25"}
EXTENDED_TAGS = (b"PKEx", b"PK58")
DISCOVERY_CLASSIC_BYTES = 14
DISCOVERY_EXTENDED_BYTES = 19
IDENTITY_COMMANDS = frozenset((0x00, 0x03, 0x04, 0x06, 0x8F, 0xE0))
"""Commands of the identification handshake answered here."""
TCP_IDLE_TIMEOUT_100MS = 30
"""0xE0 ``[17..18]``: the vendor default idle timeout (3 s); the simulator never drops a connection."""


@dataclass(frozen=True)
class DeviceIdentity:
    """Model, serial number and firmware the virtual device reports.

    Parameters
    ----------
    model : {'56E', '57E', '57CNC'}
        PoKeys56E (pulse engine v1) or PoKeys57E / PoKeys57CNC (pulse engine v2).
    serial : int
        Serial number: 20000..65534 for the 56E (the library's classic range), 1..4294967295 for
        the 57 series. Never 0: plain enumeration searches for serial 0.
    fw_major, fw_minor : int
        Firmware bytes ``M``, ``m``: version ``(1 + (M >> 4)).(M & 0x0F).m``. A 56E needs
        ``M`` = 0x20 and ``m`` = 59..65 for pulse engine v1.
    user_id : int
        0..255.
    name : str
        Device name, at most 10 ASCII characters.
    build_date : str
        11 ASCII characters, e.g. ``"Mar 14 2025"``.
    """

    model: str = "57E"
    serial: int = 32123
    fw_major: int = 0x37
    fw_minor: int = 15
    user_id: int = 0
    name: str = "SimPoKeys"
    build_date: str = "Mar 14 2025"

    @classmethod
    def preset(cls, model: str, *, serial: int | None = None) -> DeviceIdentity:
        """The protocol notes' preset (a) for ``56E`` or (b) for ``57E`` / ``57CNC``."""
        if model == "56E":
            return cls("56E", 20123 if serial is None else serial, 0x20, 60)
        return cls(model, 32123 if serial is None else serial, 0x37, 15)

    def __post_init__(self) -> None:
        if self.model not in MODELS:
            raise ConfigurationError.out_of_range("model", self.model, ", ".join(MODELS))
        low, high = (20000, 65534) if self.model == "56E" else (1, 0xFFFFFFFF)
        if isinstance(self.serial, bool) or not isinstance(self.serial, int) or not low <= self.serial <= high:
            raise ConfigurationError.out_of_range(f"serial of a PoKeys{self.model}", self.serial, f"{low}..{high}")
        for field_name, value in (("fw_major", self.fw_major), ("fw_minor", self.fw_minor),
                                  ("user_id", self.user_id)):
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 255:
                raise ConfigurationError.out_of_range(field_name, value, "0..255")
        if self.model == "56E" and (self.fw_major != 0x20 or not 59 <= self.fw_minor <= 65):
            raise ConfigurationError.out_of_range(
                "firmware of a PoKeys56E with pulse engine v1", f"0x{self.fw_major:02X}/{self.fw_minor}",
                "fw_major 0x20 and fw_minor 59..65 (FW 3.0.59-3.0.65)")
        if not self.name.isascii() or len(self.name) > 10:
            raise ConfigurationError.out_of_range("name", self.name, "at most 10 ASCII characters")
        if not self.build_date.isascii() or len(self.build_date) != 11:
            raise ConfigurationError.out_of_range("build_date", self.build_date, "11 ASCII characters")

    @property
    def extended(self) -> bool:
        """True for the 57 series (extended device data "PKEx", 19-byte discovery reply)."""
        return self.model != "56E"

    @property
    def pulse_engine(self) -> int:
        """Pulse engine version: 1 for the 56E preset, 2 for the 57 series."""
        return 2 if self.extended else 1

    @property
    def type_id(self) -> int:
        """Device type as the library records it (11 PoKeys56E, 31 PoKeys57E, 32 PoKeys57CNC)."""
        return HW_TYPE.get(self.model, TYPE_POKEYS56E)


# -- discovery --------------------------------------------------------------------------------------
def discovery_reply(identity: DeviceIdentity, *, device_ip: str = "127.0.0.1", host_ip: str = "127.0.0.1") -> bytes:
    """Reply to an empty UDP datagram: 14 bytes (56 series) or 19 bytes (57 series).

    ``device_ip`` is the address the library then connects to.
    """
    common = bytes((identity.fw_major, identity.fw_minor)) + _ip(device_ip) + b"\0" + _ip(host_ip)
    if not identity.extended:
        return bytes((identity.user_id,)) + identity.serial.to_bytes(2, "big") + common
    return (bytes((identity.user_id, 0, 0)) + common + identity.serial.to_bytes(4, "little")
            + bytes((identity.type_id,)))


@dataclass(frozen=True)
class Discovered:
    """A discovery reply as the library reads it (hardware type 0 for a 14-byte reply)."""

    serial: int
    hw_type: int
    fw_major: int
    fw_minor: int
    device_ip: str
    user_id: int


def decode_discovery(data: bytes) -> Discovered | None:
    """Decode a discovery reply; None for any length but 14 or 19 (the library ignores those)."""
    if len(data) == DISCOVERY_CLASSIC_BYTES:
        serial, hw_type = data[1] << 8 | data[2], 0
    elif len(data) == DISCOVERY_EXTENDED_BYTES:
        serial, hw_type = int.from_bytes(data[14:18], "little"), data[18]
    else:
        return None
    return Discovered(serial, hw_type, data[3], data[4], str(ipaddress.IPv4Address(bytes(data[5:9]))), data[0])


def _ip(address: str) -> bytes:
    try:
        return ipaddress.IPv4Address(address).packed
    except ValueError:
        return bytes((127, 0, 0, 1))


# -- the handshake commands ---------------------------------------------------------------------------
def identity_reply(identity: DeviceIdentity, request: bytes) -> bytearray:
    """Unsealed reply to one of :data:`IDENTITY_COMMANDS`."""
    reply = new_reply(request)
    command = request[1]
    if command == 0x00:
        _device_data(identity, reply)
    elif command == 0x03:
        reply[2] = identity.user_id  # [3] = 0: configuration unlocked
    elif command == 0xE0:
        loopback = bytes((127, 0, 0, 1))
        reply[9:13] = reply[13:17] = loopback
        reply[17:19] = TCP_IDLE_TIMEOUT_100MS.to_bytes(2, "little")
        reply[23:27] = bytes((255, 0, 0, 0))
    elif command == 0x06:
        put_text(reply, 8, identity.name, 10)
        put_text(reply, 35, identity.name, 20)
    elif command == 0x04:
        part = request[2]
        chunk = identity.build_date[4 * part:4 * part + 4] if part <= 2 else ""
        put_text(reply, 2, chunk, 4)
    # 0x8F: [8] = 0, no extra options (pulse engine v1 comes from FW 3.0.59+ anyway)
    return reply


def _device_data(identity: DeviceIdentity, reply: bytearray) -> None:
    if not identity.extended:
        reply[2:6] = identity.serial.to_bytes(2, "big") + bytes((identity.fw_major, identity.fw_minor))
        return
    reply[2:6] = (identity.serial & 0xFFFF).to_bytes(2, "big") + bytes((identity.fw_major, identity.fw_minor))
    reply[8:12] = EXTENDED_TAGS[0]
    reply[12:16] = identity.serial.to_bytes(4, "little")
    reply[16:20] = bytes((identity.fw_major, identity.fw_minor, identity.type_id, identity.user_id))
    put_text(reply, 20, identity.build_date, 11)
    put_text(reply, 31, identity.name, 10)
    # [41] firmware type 0 (standard), [42..43] secondary firmware 0, [57] product ID 0, [61] bootloader 0


@dataclass(frozen=True)
class DeviceData:
    """The 0x00 reply decoded by the library's rules (3.4 of the protocol notes).

    Attributes
    ----------
    type_id : int
        11 PoKeys56E, 31 PoKeys57E, 32 PoKeys57CNC, ...; 0 when the library would not accept it.
    serial : int
    fw_major, fw_minor : int
    pe_v1, pe_v2 : bool
        Pulse engine v1 / v2 present.
    """

    type_id: int
    serial: int
    fw_major: int
    fw_minor: int
    pe_v1: bool
    pe_v2: bool

    @property
    def type_name(self) -> str:
        """``"PoKeys56E"``, ``"PoKeys57E"``, ... (``"unknown"`` for anything else)."""
        return TYPE_NAMES.get(self.type_id, "unknown")

    @property
    def firmware(self) -> str:
        """Firmware version ``(1 + (M >> 4)).(M & 0x0F).m``."""
        return f"{1 + (self.fw_major >> 4)}.{self.fw_major & 0x0F}.{self.fw_minor}"


def decode_device_data(reply: bytes, *, options: int = 0) -> DeviceData:
    """Decode a 0x00 reply as the library does; ``options`` is the 0x8F reply's ``[8]``."""
    major, minor = reply[4], reply[5]
    if bytes(reply[8:12]) in EXTENDED_TAGS:
        return DeviceData(reply[18], int.from_bytes(reply[12:16], "little"), major, minor, False, True)
    serial = reply[2] << 8 | reply[3]
    if not 20000 <= serial <= 65534 or major & 0x80 or major == 0x40:
        return DeviceData(0, serial, major, minor, False, False)
    pe_v1 = major == 0x20 and (minor >= 59 or bool(options & 1))
    return DeviceData(TYPE_POKEYS56E, serial, major, minor, pe_v1, major == 0x21)
