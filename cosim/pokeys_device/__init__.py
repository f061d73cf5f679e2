"""Virtual PoKeys device: the simulated pulse engine served on 127.0.0.1:20055 with the device's own protocol.

Host software written for a PoKeys56E (pulse engine v1) or PoKeys57E / PoKeys57CNC (pulse engine
v2) talks UDP or TCP to this server as to the real device; the engine model of
:mod:`cosim.controllers.pokeys` runs behind it in real time (one 1 ms slot per millisecond of wall
clock), and everything it does is recorded in the normal trace. See ``docs/pokeys-device.md``.

Modules: :mod:`.packets` (framing, checksum), :mod:`.layouts` (field layouts), :mod:`.identity`
(discovery, handshake), :mod:`.commands_v1` / :mod:`.commands_v2` (pulse engine commands),
:mod:`.io_commands` (benign I/O replies), :mod:`.adapter` (the engine interface), :mod:`.device`
(request in, reply out), :mod:`.realtime` (wall-clock pacing, lag report), :mod:`.server`
(asyncio UDP/TCP), :mod:`.rig` (everything assembled), :mod:`.cli`. A client written from the
protocol notes, for tests and examples, is :mod:`cosim.testing.pokeys_client`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from cosim.pokeys_device.adapter import EngineAdapter, PulseEngineAdapter
    from cosim.pokeys_device.device import Device
    from cosim.pokeys_device.identity import DeviceIdentity
    from cosim.pokeys_device.packets import PORT

_EXPORTS = {
    "PORT": "packets", "Device": "device", "DeviceIdentity": "identity", "EngineAdapter": "adapter",
    "PulseEngineAdapter": "adapter",
}
__all__ = ["PORT", "Device", "DeviceIdentity", "EngineAdapter", "PulseEngineAdapter"]


def __getattr__(name: str) -> Any:
    """Import on first use, so ``cosim --help`` does not load the engine (PEP 562)."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
