"""The network side: asyncio UDP and TCP on port 20055, as the PoKeys library expects them.

* UDP: one datagram per request (64 bytes, 512 for the large fill); one 64-byte reply to the
  request's source. An empty datagram is a discovery probe: 14- or 19-byte reply.
* TCP: back-to-back 64-byte frames; each reply is one 64-byte write (``TCP_NODELAY``, so it leaves
  at once); the device never closes a connection and has no idle timeout. Bytes that do not start
  a frame (a request header 0xBB with a right header checksum) are skipped up to the next frame,
  so a stream that received stray bytes is answered again from its next request (``resync``
  counts them; a frame with a wrong header or checksum is such bytes on TCP).
* Trouble the event loop reports (a socket error, the file-descriptor limit) is counted in the
  packet log and reported once per kind and interval (:class:`~.logs.RateLimit`), without a
  traceback: a server that runs for hours never floods or blocks on its own log.
* Both sockets share one device. Every request is handled holding the pacer's lock, after it
  caught the simulation up with the wall clock, so a host sees the engine as of the current slot.
* Bound to 127.0.0.1 unless another address is given; a non-loopback address is refused unless
  ``allow_remote=True`` (the simulator has no authentication and accepts any host's commands).

:class:`BackgroundServer` runs a server on its own event loop in a thread (tests, examples, bench).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import socket
import threading
from typing import Any, cast

from cosim.errors import ConfigurationError
from cosim.pokeys_device.common import log
from cosim.pokeys_device.device import Device
from cosim.pokeys_device.logs import RateLimit
from cosim.pokeys_device.packets import FRAME_BYTES, HEADER_BYTES, PORT, REQUEST_HEADER, PartCollector, checksum
from cosim.pokeys_device.realtime import RealtimePacer

_PAIR_ATTEMPTS = 20  # port 0: UDP ports tried before TCP takes any free port


def check_address(host: str, *, allow_remote: bool) -> str:
    """Return ``host`` if it is a loopback address (or remote serving was asked for), else raise.

    Raises
    ------
    ConfigurationError
        Naming the address and how to allow it.
    """
    try:
        infos = socket.getaddrinfo(host, None, proto=socket.IPPROTO_UDP)
        addresses = {str(info[4][0]) for info in infos}
    except (OSError, UnicodeError) as exc:
        raise ConfigurationError.out_of_range("address", host, "an IP address or a resolvable host name") from exc
    remote = sorted(a for a in addresses if not ipaddress.ip_address(a.split("%")[0]).is_loopback)
    if remote and not allow_remote:
        raise ConfigurationError.out_of_range(
            "address", host,
            "a loopback address (127.0.0.0/8, ::1) unless remote serving is asked for explicitly "
            "(allow_remote=True / --allow-remote): the virtual device accepts commands from anyone who can reach it")
    return host


class _Udp(asyncio.DatagramProtocol):
    def __init__(self, server: DeviceServer) -> None:
        self.server = server
        self.transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: tuple[Any, ...]) -> None:
        server = self.server
        if not data:
            reply: bytes | None = server.device.discovery(device_ip=server.advertise_ip, host_ip=str(addr[0]))
        else:
            with server.current():
                reply = server.device.handle(data)
        if reply is not None and self.transport is not None:
            self.transport.sendto(reply, addr)

    def error_received(self, exc: Exception) -> None:
        self.server.device.log.count("socket_error", f"UDP: {exc}")


class _Tcp(asyncio.Protocol):
    def __init__(self, server: DeviceServer) -> None:
        self.server = server
        self.buffer = bytearray()
        self.parts = PartCollector()
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.server.device.log.count("tcp_connection")
        self.server.connections.add(self)

    def data_received(self, data: bytes) -> None:
        self.buffer += data
        self._resync()
        if len(self.buffer) < FRAME_BYTES:
            return
        with self.server.current():
            while len(self.buffer) >= FRAME_BYTES:
                frame = bytes(self.buffer[:FRAME_BYTES])
                del self.buffer[:FRAME_BYTES]
                reply = self.server.device.handle_stream_frame(frame, self.parts)
                if reply is not None and self.transport is not None:
                    self.transport.write(reply)
                self._resync()

    def _resync(self) -> None:
        """Drop bytes before the next frame start: 0xBB with a right header checksum ([7] = sum of [0..6])."""
        buffer = self.buffer
        skipped = 0
        while buffer:
            if buffer[0] == REQUEST_HEADER and (len(buffer) < HEADER_BYTES or checksum(buffer) == buffer[7]):
                break  # a frame starts here (or may: wait for its header)
            k = buffer.find(REQUEST_HEADER, 1)
            cut = len(buffer) if k < 0 else k
            del buffer[:cut]
            skipped += cut
        if skipped:
            self.server.device.log.count("resync", f"TCP: skipped {skipped} bytes that start no frame")

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None
        self.server.connections.discard(self)


class DeviceServer:
    """A :class:`Device` served on UDP and TCP.

    Parameters
    ----------
    device : Device
    pacer : RealtimePacer, optional
        Runs the simulation in real time while the server runs (None: time does not move).
    host : str
        Address to bind (127.0.0.1). Not loopback: refused unless ``allow_remote``.
    port : int
        UDP and TCP port (20055; 0 picks free ports, for tests).
    allow_remote : bool
        Allow a non-loopback ``host``.
    advertise_ip : str, optional
        Device address in discovery replies (the library connects to it); default: ``host`` if it
        is a specific IPv4 address, else 127.0.0.1.
    """

    def __init__(self, device: Device, *, pacer: RealtimePacer | None = None, host: str = "127.0.0.1",
                 port: int = PORT, allow_remote: bool = False, advertise_ip: str | None = None) -> None:
        self.device = device
        self.pacer = pacer
        self.host = check_address(host, allow_remote=allow_remote)
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise ConfigurationError.out_of_range("port", port, "0..65535")
        self.port = port
        self.advertise_ip = advertise_ip or _default_advertise(host)
        self.udp_port = 0
        self.tcp_port = 0
        self._udp: asyncio.DatagramTransport | None = None
        self._tcp: asyncio.Server | None = None
        self._stop = asyncio.Event()
        self._pacing: asyncio.Task[None] | None = None
        self.connections: set[_Tcp] = set()
        self.rate_limit = RateLimit()

    def current(self) -> contextlib.AbstractContextManager[None]:
        """Hold the simulation, caught up to the wall clock, while a request is handled."""
        return self.pacer.current() if self.pacer is not None else contextlib.nullcontext()

    def loop_trouble(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        """Event-loop exception handler: count the trouble, report it rate-limited, one line, no traceback."""
        exc = context.get("exception")
        message = str(context.get("message", "event loop error"))
        kind = f"{message}: {type(exc).__name__}" if exc is not None else message
        self.device.log.count("socket_error", f"{kind}: {exc}" if exc is not None else kind)
        report, held = self.rate_limit.allow(kind)
        if report:
            more = f" ({held} more since the last report)" if held else ""
            log.warning("%s%s%s", kind, f" ({exc})" if exc is not None else "", more)

    async def start(self) -> None:
        """Bind both sockets and start pacing."""
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(self.loop_trouble)
        self._stop = asyncio.Event()
        # Like the real device, one port number for both: with port 0 the system picks the UDP port,
        # and where that number is taken for TCP, another pair is tried (then any TCP port).
        for attempt in range(_PAIR_ATTEMPTS):
            transport, _ = await loop.create_datagram_endpoint(lambda: _Udp(self),
                                                               local_addr=(self.host, self.port))
            self.udp_port = transport.get_extra_info("sockname")[1]
            try:
                self._tcp = await loop.create_server(lambda: _Tcp(self), self.host, self.port or self.udp_port,
                                                     reuse_address=True)
                break
            except OSError:
                if self.port:
                    transport.close()
                    raise
                if attempt == _PAIR_ATTEMPTS - 1:
                    self._tcp = await loop.create_server(lambda: _Tcp(self), self.host, 0, reuse_address=True)
                    break
                transport.close()
        self._udp = transport
        assert self._tcp is not None  # every way out of the loop above set it or raised
        self.tcp_port = self._tcp.sockets[0].getsockname()[1]
        if self.pacer is not None:
            self._pacing = asyncio.create_task(self.pacer.run(self._stop))

    async def stop(self) -> None:
        """Stop pacing (after a last catch-up) and close the sockets."""
        self._stop.set()
        if self._pacing is not None:
            await self._pacing
            self._pacing = None
        if self._udp is not None:
            self._udp.close()
        if self._tcp is not None:
            self._tcp.close()
            for connection in list(self.connections):  # shutting down: the only time the device closes one
                if connection.transport is not None:
                    connection.transport.close()
            await self._tcp.wait_closed()

    async def serve(self, stop: asyncio.Event) -> None:
        """Start, serve until ``stop`` is set, stop."""
        await self.start()
        try:
            await stop.wait()
        finally:
            await self.stop()


def _default_advertise(host: str) -> str:
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return "127.0.0.1"
    return host if address.version == 4 and not address.is_unspecified else "127.0.0.1"


class BackgroundServer:
    """A :class:`DeviceServer` on its own event loop in a daemon thread.

    While it runs, the simulation belongs to the server and the pacer (under ``pacer.lock``); read
    it after :meth:`stop`. Use as a context manager::

        with BackgroundServer(DeviceServer(rig.device, pacer=rig.pacer, port=0)) as running:
            client = PoKeysClient("127.0.0.1", running.server.udp_port)
    """

    def __init__(self, server: DeviceServer) -> None:
        self.server = server
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._main, name="pokeys-device-server", daemon=True)

    def _main(self) -> None:
        async def body() -> None:
            self._loop = asyncio.get_running_loop()
            self._stop = asyncio.Event()
            try:
                await self.server.start()
            except BaseException as exc:
                self._error = exc
                self._ready.set()
                return
            self._ready.set()
            try:
                await self._stop.wait()
            finally:
                await self.server.stop()

        asyncio.run(body())

    def start(self, *, timeout_s: float = 5.0) -> BackgroundServer:
        """Start the thread and wait until the sockets are bound (raises what binding raised)."""
        self._thread.start()
        if not self._ready.wait(timeout_s):
            raise TimeoutError(f"the device server did not start within {timeout_s} s")
        if self._error is not None:
            raise self._error
        return self

    def stop(self, *, timeout_s: float = 5.0) -> None:
        """Stop serving and wait for the thread."""
        if self._loop is not None and self._stop is not None and self._thread.is_alive():
            with contextlib.suppress(RuntimeError):
                self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(timeout_s)

    def __enter__(self) -> BackgroundServer:
        return self.start() if not self._thread.is_alive() else self

    def __exit__(self, *exc: object) -> None:
        self.stop()
