"""The encoder conversion table (ECT): 1/T position entries and time-base entries.

The table runs at the start of every servo cycle, top to bottom (in address order), before the
coordinate systems and servo loops. Each entry occupies consecutive addresses ("lines"); its
setup words are the Y words (on Turbo PMAC the I-variables I8000..I8191 at $3501..$35C0), its
results the X words at the same addresses. An entry that reads the result of a later entry
sees last cycle's value.

Entries (method digit = bits 20-23 of the first setup line):

* :class:`OneOverTEntry` ($0): the 1/T-extended position of an encoder channel in 1/32 count.
* :class:`TimeBaseEntry` ($4, two lines: source address, SCALE_FACTOR): each cycle
  ``result = 2 * SF * (new source - old source)``; with a 1/32-count source that is
  ``64 * SF`` per count, so ``% = 100 * SF * f[counts/ms] / 2^17``.
* :class:`TriggeredTimeBaseEntry` ($9 frozen, $B armed, $A running; two lines: channel
  address, SCALE_FACTOR): its own 1/T extension to 1/256 count (first line X word, the
  undifferentiated master position); ``result = 2 * SF * delta`` in 1/256 count, i.e.
  ``512 * SF`` per count, ``SF = 2^14 / RTIF``.

Register arithmetic: positions are differenced as 24-bit registers (``wrap24``) and results
saturate at the signed 24-bit range. Positions are also kept unwrapped (as the firmware extends
them) for the master-position signal.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from cosim import validate
from cosim.controllers.pmac.encoder import ONE_OVER_T_BITS, TRIGGERED_BITS, EncoderChannel
from cosim.controllers.pmac.units import REG_MASK, REG_MAX, Reg, hexaddr, saturate24, wrap24
from cosim.errors import ConfigurationError

#: First line of the Turbo PMAC table (I8000 is Y:$3501).
TURBO_ECT_BASE = 0x3501
#: First line of the (non-Turbo) PMAC default table; its time-base result is at $0729 = 1833.
PMAC_ECT_BASE = 0x0720
#: Number of Turbo table lines (I8000..I8191).
TURBO_ECT_LINES = 192

METHOD_ONE_OVER_T = 0x0
METHOD_TIME_BASE = 0x4
FROZEN, RUNNING, ARMED = 0x9, 0xA, 0xB
TRIGGERED_METHODS = {FROZEN: "frozen", RUNNING: "running", ARMED: "armed"}
_ADDRESS_MASK = 0x7FFFF  # bits 0-18: source address; bit 19: PMAC2-style flag (kept, not modelled)
_FLAG_BIT = 1 << 19


def _method_text() -> str:
    return ", ".join(f"${m:X} ({n})" for m, n in sorted(TRIGGERED_METHODS.items()))


def check_scale_factor(value: object, *, name: str = "SCALE_FACTOR", where: str = "") -> int:
    """A SCALE_FACTOR must be an integer 1..8,388,607 (a positive 24-bit word)."""
    return validate.integer(value, name, low=1, high=REG_MAX, where=where, allowed=f"integers 1..{REG_MAX}")


class Entry:
    """Base of conversion-table entries.

    Attributes
    ----------
    address : int
        Address of the first line (set when added to a table).
    lines : int
        Number of lines.
    origin : str
        How the user wrote it (e.g. ``I8010``), for error messages.
    """

    lines = 1
    #: Fraction bits of the position this entry's first-line X word holds (None: not a position).
    position_bits: int | None = None

    def __init__(self, *, origin: str = "") -> None:
        self.address = -1
        self.origin = origin

    @property
    def result_address(self) -> int:
        """Address of the final result (the X word of the last line)."""
        return self.address + self.lines - 1

    @property
    def is_time_base(self) -> bool:
        """True if the final result is a time-base value (usable by Ix93)."""
        return False

    def x_word(self, offset: int) -> int:
        """X word of line ``offset`` as a 24-bit register value."""
        raise NotImplementedError

    def y_word(self, offset: int) -> int:
        """Setup (Y) word of line ``offset``."""
        raise NotImplementedError

    def bind(self, table: ConversionTable, channels: Mapping[int, EncoderChannel]) -> None:
        """Resolve source addresses before the first cycle (raises if they point at nothing)."""

    def convert(self, t: int, table: ConversionTable) -> None:
        """Run this entry for the servo cycle at ``t``."""
        raise NotImplementedError

    def label(self) -> str:
        return f"{type(self).__name__} at {hexaddr(self.address)}"

    def _channel(self, channels: Mapping[int, EncoderChannel], address: int, what: str) -> EncoderChannel:
        if address not in channels:
            known = ", ".join(f"${a:06X}" for a in sorted(channels)) or "none added"
            raise ConfigurationError.out_of_range(
                f"{what} of the {self.label()}" + (f" ({self.origin})" if self.origin else ""), Reg(address),
                f"addresses of encoder channels: {known}")
        return channels[address]


class OneOverTEntry(Entry):
    """Method $0: 1/T-extended position of an encoder channel, in 1/32 count.

    Parameters
    ----------
    channel_address : int
        Address of the encoder channel (e.g. ``0x078000``).
    """

    position_bits = ONE_OVER_T_BITS

    def __init__(self, channel_address: int, *, origin: str = "") -> None:
        super().__init__(origin=origin)
        self.channel_address = channel_address & _ADDRESS_MASK
        self.flags = channel_address & _FLAG_BIT
        self.position = 0
        self.unconnected = False
        self._channel_obj: EncoderChannel | None = None

    def bind(self, table: ConversionTable, channels: Mapping[int, EncoderChannel]) -> None:
        """Its encoder channel must exist -- unless the table lets it stay unconnected (then it reads 0)."""
        self._channel_obj = channels.get(self.channel_address)
        self.unconnected = self._channel_obj is None
        if self.unconnected and not table.allow_unconnected(self):
            self._channel(channels, self.channel_address, "channel address")  # raises, naming the channels

    def convert(self, t: int, table: ConversionTable) -> None:
        if self._channel_obj is not None:
            self.position = self._channel_obj.position(t, ONE_OVER_T_BITS)

    def x_word(self, offset: int) -> int:
        return self.position & REG_MASK

    def y_word(self, offset: int) -> int:
        return (METHOD_ONE_OVER_T << 20) | self.flags | self.channel_address


class DifferentiatingEntry(Entry):
    """Shared part of the two time-base entries: SF, previous position, result."""

    lines = 2

    def __init__(self, scale_factor: int, *, origin: str = "") -> None:
        super().__init__(origin=origin)
        self.scale_factor = check_scale_factor(scale_factor, name=self._sf_name(origin))
        self.result = 0
        self.saturated_cycles: list[int] = []
        self._prev: int | None = None
        self._cycle = -1

    @staticmethod
    def _sf_name(origin: str) -> str:
        if origin.startswith("I") and origin[1:].isdigit():
            return f"SCALE_FACTOR (I{int(origin[1:]) + 1})"
        return "SCALE_FACTOR"

    @property
    def is_time_base(self) -> bool:
        return True

    @property
    def units_per_count(self) -> int:
        """Time-base units (2^-23 ms) per master count moved in one servo cycle."""
        raise NotImplementedError

    def set_scale_factor(self, value: object, *, where: str = "") -> None:
        """Change SCALE_FACTOR (second line) while running."""
        self.scale_factor = check_scale_factor(value, name=self._sf_name(self.origin), where=where)

    def _differentiate(self, position: int) -> int:
        """``2 * SF * (position - previous)`` with 24-bit difference and saturation."""
        if self._prev is None:
            self._prev = position
        raw = 2 * self.scale_factor * wrap24(position - self._prev)
        self._prev = position
        value = saturate24(raw)
        if value != raw:
            self.saturated_cycles.append(self._cycle)
        return value


class TimeBaseEntry(DifferentiatingEntry):
    """Method $4: untriggered time base from a position register of the table.

    Parameters
    ----------
    source_address : int
        Address of the position register (normally a 1/T entry, 1/32 count).
    scale_factor : int
        SCALE_FACTOR = 2^17 / real-time input frequency [counts/ms] for a 1/32-count source.

    Notes
    -----
    The first cycle only stores the source position (result 0).
    """

    def __init__(self, source_address: int, scale_factor: int, *, origin: str = "") -> None:
        super().__init__(scale_factor, origin=origin)
        self.source_address = source_address & _ADDRESS_MASK
        self._source: Entry | None = None
        self.position = 0

    @property
    def units_per_count(self) -> int:
        bits = self._source.position_bits if self._source is not None else ONE_OVER_T_BITS
        return 2 * self.scale_factor << (bits or 0)

    def bind(self, table: ConversionTable, channels: Mapping[int, EncoderChannel]) -> None:
        source = table.entry_at(self.source_address)
        if source is None or source.position_bits is None or source.address != self.source_address:
            known = ", ".join(hexaddr(e.address) for e in table.entries if e.position_bits is not None)
            raise ConfigurationError.out_of_range(
                f"source address of the {self.label()}" + (f" ({self.origin})" if self.origin else ""),
                Reg(self.source_address), f"position registers of the table: {known or 'none'}")
        self._source = source

    def convert(self, t: int, table: ConversionTable) -> None:
        assert self._source is not None
        self._cycle = table.cycle
        self.position = self._source.x_word(0)  # the 24-bit register, as the hardware reads it
        self.result = self._differentiate(self.position)

    def x_word(self, offset: int) -> int:
        return (self.position if offset == 0 else self.result) & REG_MASK

    def y_word(self, offset: int) -> int:
        if offset == 0:
            return (METHOD_TIME_BASE << 20) | self.source_address
        return self.scale_factor


@dataclass(frozen=True)
class TriggerStart:
    """A triggered start: the armed entry saw the capture flag and started running.

    Attributes
    ----------
    cycle : int
        Servo cycle in which the entry saw the trigger.
    t : int
        Instant of that servo cycle [ticks].
    time_zero_pos256 : int
        Captured position used as time zero [1/256 count].
    capture_t : int or None
        Instant the capture latched [ticks] (None if the register was never latched).
    stale : bool
        True if the capture latched before the entry was last frozen (by a write of $9): the
        trigger logic was not reset since, so time zero is an old position (the stale-capture
        hazard of the Turbo manual).
    """

    cycle: int
    t: int
    time_zero_pos256: int
    capture_t: int | None
    stale: bool = False


class TriggeredTimeBaseEntry(DifferentiatingEntry):
    """Turbo triggered time base: method digit $9 frozen, $B armed, $A running.

    Parameters
    ----------
    channel_address : int
        Encoder channel address (e.g. ``0x078008``); its capture register is at +3.
    scale_factor : int
        SCALE_FACTOR = 2^14 / real-time input frequency [counts/ms] (1/256-count source).
    method : int
        Initial method digit: 0x9, 0xA or 0xB.

    Notes
    -----
    * Frozen: result 0; the capture register is read every cycle (which re-arms the capture).
    * Armed: result 0; every cycle the capture flag is checked. When set, the captured position
      becomes time zero, the method digit turns to $A, and the same cycle already outputs
      ``2 * SF * (position - captured)``.
    * Running: ``2 * SF * (position - previous)``; the capture register is not read. Entering
      $A by a write (not by a trigger) takes the first running cycle's position as time zero.
    """

    position_bits = TRIGGERED_BITS

    def __init__(self, channel_address: int, scale_factor: int, *, method: int = FROZEN, origin: str = "") -> None:
        super().__init__(scale_factor, origin=origin)
        self.channel_address = channel_address & _ADDRESS_MASK
        self.flags = channel_address & _FLAG_BIT
        self.method = self._check_method(method)
        self.position = 0
        self.starts: list[TriggerStart] = []
        self.method_changes: list[tuple[int, int]] = []
        self.frozen_t: int | None = None
        self._channel_obj: EncoderChannel | None = None

    def _check_method(self, method: int, *, where: str = "", line_value: int | None = None) -> int:
        if method in TRIGGERED_METHODS:
            return method
        allowed = _method_text()
        if line_value is None:
            name = "method digit of the triggered time-base entry" + (f" ({self.origin})" if self.origin else "")
            raise ConfigurationError.out_of_range(name, Reg(method, digits=1), allowed, where=where)
        name = f"{self.origin or 'first line'} (method digit ${method:X})"
        raise ConfigurationError.out_of_range(name, Reg(line_value, digits=6, decimal=False), allowed, where=where)

    @property
    def state(self) -> str:
        """``frozen``, ``armed`` or ``running``."""
        return TRIGGERED_METHODS[self.method]

    @property
    def units_per_count(self) -> int:
        return 2 * self.scale_factor << TRIGGERED_BITS

    def set_method(self, method: int, *, t: int = 0) -> None:
        """Change the method digit (a write of the first line: ``I8010=$B78008``)."""
        self.method = self._check_method(method)
        self.method_changes.append((t, self.method))
        if method == FROZEN:
            self.frozen_t = t
        if method == RUNNING:
            self._prev = None  # time zero = first running cycle's position

    def write_first_line(self, value: int, *, where: str = "", t: int = 0) -> None:
        """Write the whole first setup line; only the method digit may change while running."""
        method = (value >> 20) & 0xF
        self._check_method(method, where=where, line_value=value)
        if (value & (_ADDRESS_MASK | _FLAG_BIT)) != (self.channel_address | self.flags):
            raise ConfigurationError.out_of_range(
                f"{self.origin or 'first line'} (source address)", Reg(value, digits=6, decimal=False),
                f"the entry's own source ${self.channel_address | self.flags:05X} with method digit "
                f"{_method_text()} (changing the source while running is not modelled)", where=where)
        self.set_method(method, t=t)

    def bind(self, table: ConversionTable, channels: Mapping[int, EncoderChannel]) -> None:
        self._channel_obj = self._channel(channels, self.channel_address, "channel address")

    @property
    def channel(self) -> EncoderChannel:
        assert self._channel_obj is not None, "entry not bound to a channel"
        return self._channel_obj

    def convert(self, t: int, table: ConversionTable) -> None:
        channel = self.channel
        self._cycle = table.cycle
        self.position = channel.position(t, TRIGGERED_BITS)
        if self.method == FROZEN:
            channel.read_capture()
            self.result = 0
        elif self.method == ARMED:
            if channel.capture_flag:
                capture_t = channel.capture_t
                time_zero = channel.read_capture()
                stale = capture_t is not None and self.frozen_t is not None and capture_t < self.frozen_t
                self.starts.append(TriggerStart(table.cycle, t, time_zero, capture_t, stale))
                self.method = RUNNING
                self.method_changes.append((t, RUNNING))
                self._prev = time_zero
                self.result = self._differentiate(self.position)
            else:
                self.result = 0
        else:
            self.result = self._differentiate(self.position)

    def x_word(self, offset: int) -> int:
        return (self.position if offset == 0 else self.result) & REG_MASK

    def y_word(self, offset: int) -> int:
        if offset == 0:
            return (self.method << 20) | self.flags | self.channel_address
        return self.scale_factor


class ConversionTable:
    """The encoder conversion table: entries at addresses, run top to bottom each servo cycle.

    Parameters
    ----------
    base_address : int
        Address of the first line: :data:`TURBO_ECT_BASE` ($3501) or :data:`PMAC_ECT_BASE` ($0720).
    """

    def __init__(self, base_address: int = TURBO_ECT_BASE) -> None:
        self.base_address = base_address
        self.entries: list[Entry] = []
        self.cycle = -1
        #: Let 1/T entries that no time-base entry reads stay without an encoder (a motor the model does not couple).
        self.lenient = False
        self._by_address: dict[int, Entry] = {}

    def add(self, entry: Entry, *, at: int | None = None) -> Entry:
        """Place ``entry`` at address ``at`` (default: after the last line); returns it."""
        address = at if at is not None else (
            self.entries[-1].address + self.entries[-1].lines if self.entries else self.base_address)
        lines = range(address, address + entry.lines)
        taken = [a for a in lines if a in self._by_address]
        if address < self.base_address or taken:
            raise ConfigurationError.out_of_range(
                f"address of the {type(entry).__name__}", Reg(address),
                f"free lines at or after {hexaddr(self.base_address)}" + (
                    f"; {hexaddr(taken[0])} is taken by the {self._by_address[taken[0]].label()}" if taken else ""))
        entry.address = address
        for a in lines:
            self._by_address[a] = entry
        self.entries.append(entry)
        self.entries.sort(key=lambda e: e.address)
        return entry

    def entry_at(self, address: int) -> Entry | None:
        """The entry occupying ``address`` (None if no line is there)."""
        return self._by_address.get(address)

    def x_word(self, address: int) -> int:
        """X word (result) at ``address``."""
        entry = self._by_address[address]
        return entry.x_word(address - entry.address)

    def time_base_entries(self) -> list[DifferentiatingEntry]:
        """Entries whose final result is a time-base value."""
        return [e for e in self.entries if isinstance(e, DifferentiatingEntry)]

    def allow_unconnected(self, entry: Entry) -> bool:
        """True if ``entry`` may have no encoder: the table is lenient and no time-base entry takes it as source."""
        return self.lenient and not any(isinstance(e, TimeBaseEntry) and e.source_address == entry.address
                                        for e in self.entries)

    def bind(self, channels: Mapping[int, EncoderChannel]) -> None:
        """Resolve every entry's sources; raises ConfigurationError naming the bad one."""
        for entry in self.entries:
            entry.bind(self, channels)

    def run(self, t: int, cycle: int) -> None:
        """Run every entry, top to bottom, for servo cycle ``cycle`` at ``t``."""
        self.cycle = cycle
        for entry in self.entries:
            entry.convert(t, self)

    @classmethod
    def from_lines(cls, lines: Mapping[int, int], *, base_address: int = TURBO_ECT_BASE, first_ivar: int = 8000,
                   where: Mapping[int, str] | None = None) -> ConversionTable:
        """Build a table from setup lines ``{line index: value}`` (I8000 + index on Turbo).

        Lines are parsed in order; an explicit ``$000000`` line ends the table; unset lines are
        skipped (the model has no factory-default entries).
        """
        where = where or {}
        table = cls(base_address)
        indices = sorted(lines)
        skip: set[int] = set()
        for index in indices:
            if index in skip:
                continue
            value = lines[index]
            name = f"I{first_ivar + index}"
            at = base_address + index
            method = (value >> 20) & 0xF
            if value == 0:
                break
            if method == METHOD_ONE_OVER_T:
                table.add(OneOverTEntry(value & 0xFFFFF, origin=name), at=at)
            elif method in (METHOD_TIME_BASE, *TRIGGERED_METHODS):
                if index + 1 not in lines:
                    raise ConfigurationError(
                        f"{where.get(index, name)}: {name} = {hexaddr(value, 6)} starts a two-line time-base "
                        f"entry, but its SCALE_FACTOR line I{first_ivar + index + 1} is not set")
                sf = lines[index + 1]
                skip.add(index + 1)
                sf_where = where.get(index + 1, "")
                check_scale_factor(sf, name=f"SCALE_FACTOR (I{first_ivar + index + 1})", where=sf_where)
                if method == METHOD_TIME_BASE:
                    table.add(TimeBaseEntry(value & 0xFFFFF, sf, origin=name), at=at)
                else:
                    table.add(TriggeredTimeBaseEntry(value & 0xFFFFF, sf, method=method, origin=name), at=at)
            else:
                raise ConfigurationError.out_of_range(
                    f"{name} (method digit ${method:X})", Reg(value, digits=6, decimal=False),
                    f"method digits $0 (1/T), $4 (time base), {_method_text()} (triggered time base)",
                    where=where.get(index, ""))
        return table


def pmac_default_table(channel_address: int, scale_factor: int) -> ConversionTable:
    """A (non-Turbo) PMAC-style table: 1/T of a channel at $0720, time base at $0728-$0729.

    The time-base result is then at X:$0729 (= 1833), the address the manual gives for Ix93.
    The other default 1/T entries ($0721-$0727) are not modelled.
    """
    table = ConversionTable(PMAC_ECT_BASE)
    table.add(OneOverTEntry(channel_address), at=PMAC_ECT_BASE)
    table.add(TimeBaseEntry(PMAC_ECT_BASE, scale_factor), at=PMAC_ECT_BASE + 8)
    return table
