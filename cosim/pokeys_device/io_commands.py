"""Benign replies to the I/O commands host programs commonly call (6.1 of the protocol notes).

A benign reply makes the library call succeed with neutral values: ``[2..5]`` = 0 and a zero
payload, unless the command defines fields. A few commands store what the host writes and return
it on a read, because the library (or a host) compares them:

* 0xC0 pin configuration, 0xCB PWM configuration: stored and returned;
* 0xCD encoder values: the written groups are stored and returned;
* 0xDA PoExtBus: the 10 data bytes are stored and echoed (the library fails a write whose reply
  differs from what it sent);
* 0x30 / 0x40 single-pin get / set: ``[2]`` must be 0 (an echoed pin index reads as an error).

Inputs read as 0; there are no PoNET modules (0xDD module status calls then report an error, as
on a device without modules).
"""

from __future__ import annotations

from cosim.pokeys_device.packets import new_reply

PIN_CONFIG = slice(8, 63)
"""0xC0: pin functions of pins 0..54."""
PWM_CONFIG = slice(8, 37)
"""0xCB: enable bits, 6 duties, period."""
ENCODER_GROUP = slice(8, 60)
"""0xCD: 13 uint32 encoder values."""
POEXTBUS = slice(8, 18)
"""0xDA: 10 bytes."""


class IoCommands:
    """Stored I/O configuration and the benign reply for every other command."""

    def __init__(self) -> None:
        self.pin_functions = bytes(PIN_CONFIG.stop - PIN_CONFIG.start)
        self.counter_options = bytes(PIN_CONFIG.stop - PIN_CONFIG.start)
        self.pwm = bytes(PWM_CONFIG.stop - PWM_CONFIG.start)
        self.encoders = {0: bytes(ENCODER_GROUP.stop - ENCODER_GROUP.start),
                         1: bytes(ENCODER_GROUP.stop - ENCODER_GROUP.start)}
        self.poextbus = bytes(POEXTBUS.stop - POEXTBUS.start)

    def handle(self, request: bytes) -> tuple[bytearray, bool]:
        """Unsealed reply, and whether the command is one this module knows."""
        reply = new_reply(request)
        command, p1 = request[1], request[2]
        if command == 0xC0:
            self._pins(request, reply)
        elif command == 0xCB:
            if p1 == 1:
                self.pwm = bytes(request[PWM_CONFIG])
            reply[PWM_CONFIG] = self.pwm
        elif command == 0xCD:
            group = p1 % 10
            if group in self.encoders:
                if p1 >= 10:
                    self.encoders[group] = bytes(request[ENCODER_GROUP])
                reply[ENCODER_GROUP] = self.encoders[group]
        elif command == 0xDA:
            if p1 == 1:
                self.poextbus = bytes(request[POEXTBUS])
            reply[POEXTBUS] = self.poextbus
        elif command == 0x30:
            reply[3] = 0  # pin level: inputs read low
        else:
            return reply, command in KNOWN_BENIGN
        return reply, True

    def _pins(self, request: bytes, reply: bytearray) -> None:
        p1, p2 = request[2], request[3]
        if p1 == 1:
            self.pin_functions = bytes(request[PIN_CONFIG])
        elif p1 == 0 and p2 == 2:
            self.counter_options = bytes(request[PIN_CONFIG])
        reply[PIN_CONFIG] = self.counter_options if (p1, p2) in ((0, 1), (0, 2)) else self.pin_functions


KNOWN_BENIGN = frozenset((0x40, 0xC1, 0xC2, 0xC3, 0xD7, 0xCC, 0x3A, 0xC4, 0xC5, 0xC6, 0xC7, 0xCE, 0x1C, 0xD8, 0x1D,
                          0x50, 0x52, 0x81, 0x83, 0x84, 0xDD, 0xDB, 0xDC))
"""Commands of 6.1 answered with the plain benign reply (zeros)."""
