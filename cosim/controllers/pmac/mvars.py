"""Variables of PMAC programs: P, Q, M and I, read and written, directly or indirectly.

* ``Pn`` (0..8191): a 48-bit word of user memory, the same from every context, 0 at power-up.
* ``Qn`` (0..8191): user memory per coordinate system. The 8192 Q words are shared: coordinate
  system s sees its ``Q0`` at word ``offset(s)``, with the offsets of the PMAC User Manual's
  Q-variable memory map (the bits of s - 1 reversed, times 512 on the Turbo PMAC's 8192 words:
  &1 at 0, &2 at 4096, &3 at 2048, &4 at 6144, ...), so ``Q0`` of &2 is ``Q4096`` of &1 and
  every coordinate system may use Q0..Q511 without overlap. Online commands use the Q-variables
  of the host's ``&n``, a motion program those of its coordinate system, a PLC those of its
  ``ADDRESS &n`` (&1 until it says otherwise).
* ``In``: every I-variable (through the controller, with its range: :mod:`.ivartable`).
* ``Mn``: definitions of every form (``X:``, ``Y:`` bit fields; ``D:``, ``DP:``, ``L:``, ``F:`` wide
  words; ``TWS:``/``TWB:``/``TWD:``/``TWR:`` thumbwheels; ``->*`` plain memory). On a register the
  model has (:mod:`.machine`: encoder channels X:+0 count and X:+3 capture -- **reading the capture
  re-arms it** --, conversion-table lines, ``%`` registers) an M-variable reads and writes that
  register; on any other address it is memory of its own (what was last written through the
  definition, 0 at first), and the definition is listed as "set, not modelled". Writing rounds to
  the nearest integer (halves away from zero) and keeps the field's bits.
* Indirect forms ``P(expr)``, ``Q(expr)``, ``M(expr)``, ``I(expr)``: the number is computed when the
  statement runs (0..8191, else an error naming it).

Every write that changes a value, and every definition, is counted (:attr:`Memory.changes`) and
reported to :attr:`Memory.on_change` (the PLC background scans wake on it); a read of something that
changes by itself (an encoder register, a timer) marks :attr:`Memory.volatile`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from fractions import Fraction

from cosim.controllers.pmac import arith
from cosim.controllers.pmac.bus import Registers, Value
from cosim.controllers.pmac.nodes import MDefine, MThumb, MWide, MWord, Pos, located
from cosim.errors import ConfigurationError

#: Variables of each kind: 0..8191.
VARIABLES = 8192
#: Q words per coordinate system without overlap (8192 shared by 16).
Q_BLOCK = 512


def round_half_away(value: Value) -> int:
    """Nearest integer, halves away from zero."""
    if type(value) is int:
        return value
    return math.floor(value + Fraction(1, 2)) if value >= 0 else -math.floor(-value + Fraction(1, 2))


def field_value(word: int, offset: int, width: int, signed: bool) -> int:
    """Bits ``offset .. offset+width-1`` of ``word``, two's complement if ``signed``."""
    bits = (word >> offset) & ((1 << width) - 1)
    if signed and bits >> (width - 1):
        bits -= 1 << width
    return bits


def q_offset(cs: int) -> int:
    """Word of ``Q0`` of coordinate system ``cs`` (1..16): the bits of cs - 1 reversed, times 512."""
    index = cs - 1
    reversed_bits = ((index & 1) << 3) | ((index & 2) << 1) | ((index & 4) >> 1) | ((index & 8) >> 3)
    return reversed_bits * Q_BLOCK


class Memory:
    """P-, Q- and M-variables of one controller, and reads and writes of every variable kind.

    Parameters
    ----------
    registers : Registers
        The controller whose I-variables and registers the variables reach.
    """

    def __init__(self, registers: Registers) -> None:
        self.registers = registers
        self.p: list[Value] = [0] * VARIABLES
        self.q: list[Value] = [0] * VARIABLES
        self.definitions: dict[int, MDefine] = {}
        self.words: dict[int, Value] = {}
        self.own: dict[tuple[str, int], Value] = {}  # registers the model does not have: memory of their own
        self.changes = 0
        self.volatile = False
        self.on_change: Callable[[], None] | None = None
        self.on_unmodelled: Callable[[str, object, str], None] | None = None

    # -- bookkeeping -----------------------------------------------------------------------
    def changed(self) -> None:
        """Something a program can read has changed (counted, and the PLC background woken)."""
        self.changes += 1
        if self.on_change is not None:
            self.on_change()

    # -- M-variable definitions --------------------------------------------------------------
    def define(self, stmt: MDefine) -> None:
        """``Mn->...`` (or a range of them): (re)define M-variables."""
        for number in stmt.numbers():
            self.definitions[number] = stmt if stmt.last is None else MDefine(stmt.pos, number, stmt.target)
        self.changed()
        if self.registers.started:
            self.check_definition(stmt)

    def modelled(self, target: MWord | MWide | MThumb | None) -> bool:
        """True if ``target`` is a register the model has (reads and writes act on it)."""
        return isinstance(target, MWord) and self.registers.has_register(target.space, target.address)

    def check_definition(self, stmt: MDefine) -> None:
        """List a definition on a register the model does not have as "set, not modelled"."""
        target = stmt.target
        if target is None or self.modelled(target):
            return
        if self.on_unmodelled is not None:
            numbers = f"M{stmt.number}" + (f"..{stmt.last}" if stmt.last is not None else "")
            self.on_unmodelled(f"{numbers}->", str(target), str(stmt.pos))

    def _definition(self, number: int, pos: Pos) -> MDefine:
        stmt = self.definitions.get(number)
        if stmt is None:
            raise pos.error(f"M{number} is not defined (define it first, e.g. M{number}->X:$07800B,0,24,S)")
        return stmt

    # -- reads -------------------------------------------------------------------------------
    def read(self, kind: str, number: int, cs: int, pos: Pos) -> Value:
        """The value of ``kind`` ``number`` now (Q of coordinate system ``cs``)."""
        if kind == "P":
            return self.p[number]
        if kind == "Q":
            return self.q[(q_offset(cs) + number) % VARIABLES]
        if kind == "I":
            registers = self.registers
            if registers.ivar_is_volatile(number):
                self.volatile = True
            with located(pos):
                return registers.get_ivar(number)
        return self.read_m(number, pos)

    def read_m(self, number: int, pos: Pos) -> Value:
        stmt = self._definition(number, pos)
        target = stmt.target
        if target is None:
            return self.words.get(number, 0)
        if not self.modelled(target):
            return self._read_own(target)
        assert isinstance(target, MWord)
        registers = self.registers
        if registers.register_is_volatile(target.space, target.address):
            self.volatile = True
        with located(pos):
            word = registers.read_word(target.space, target.address)
        return field_value(word, target.offset, target.width, target.signed)

    def _read_own(self, target: MWord | MWide | MThumb) -> Value:
        if isinstance(target, MWord):
            word = int(self.own.get((target.space, target.address), 0))
            return field_value(word, target.offset, target.width, target.signed)
        if isinstance(target, MWide):
            return self.own.get((target.kind, target.address), 0)
        return self.own.get((target.kind, target.args[0] if target.args else 0), 0)

    # -- writes ------------------------------------------------------------------------------
    def write(self, kind: str, number: int, value: Value, cs: int, pos: Pos) -> None:
        """``kind number = value`` (checked against the variable's range; raises naming ``pos``)."""
        if kind == "P" or kind == "Q":
            fitted = arith.fit(value, what=f"{kind}{number}", where=str(pos))
            store = self.p if kind == "P" else self.q
            index = number if kind == "P" else (q_offset(cs) + number) % VARIABLES
            if store[index] != fitted:
                store[index] = fitted
                self.changed()
            return
        if kind == "I":
            self.registers.set_ivar(number, value, where=str(pos))
            self.changed()
            return
        self.write_m(number, value, pos)

    def write_m(self, number: int, value: Value, pos: Pos, op: str = "=") -> None:
        stmt = self._definition(number, pos)
        target = stmt.target
        if target is None:
            fitted = arith.fit(value, what=f"M{number}", where=str(pos))
            if op != "=":
                fitted = _combine(op, int(self.words.get(number, 0)), round_half_away(fitted))
            if self.words.get(number, 0) != fitted:
                self.words[number] = fitted
                self.changed()
            return
        if not self.modelled(target):
            self._write_own(target, value, op)
            return
        assert isinstance(target, MWord)
        if target.space == "X":
            raise pos.error(f"M{number}->{target}: X registers are read-only in this model "
                            "(encoder position and capture, table results)")
        mask = ((1 << target.width) - 1) << target.offset
        with located(pos):
            word = self.registers.read_word(target.space, target.address)
            old = field_value(word, target.offset, target.width, False)
            new = _combine(op, old, round_half_away(value)) if op != "=" else round_half_away(value)
            bits = (new << target.offset) & mask
            self.registers.write_word(target.space, target.address, (word & ~mask) | bits, where=str(pos))
        self.changed()

    def _write_own(self, target: MWord | MWide | MThumb, value: Value, op: str) -> None:
        if isinstance(target, MWord):
            key = (target.space, target.address)
            word = int(self.own.get(key, 0))
            mask = ((1 << target.width) - 1) << target.offset
            old = field_value(word, target.offset, target.width, False)
            new = _combine(op, old, round_half_away(value)) if op != "=" else round_half_away(value)
            stored: Value = (word & ~mask) | ((new << target.offset) & mask)
        else:
            key = (target.kind, target.address if isinstance(target, MWide) else (target.args or (0,))[0])
            stored = arith.fit(value) if op == "=" else _combine(op, int(self.own.get(key, 0)), round_half_away(value))
        if self.own.get(key) != stored:
            self.own[key] = stored
            self.changed()


def _combine(op: str, old: int, value: int) -> int:
    """``M==``, ``M&=``, ``M|=``, ``M^=``: the synchronous assignment stores the value, the others combine bits."""
    if op == "&=":
        return old & value
    if op == "|=":
        return old | value
    if op == "^=":
        return old ^ value
    return value


def check_number(kind: str, number: Value, pos: Pos) -> int:
    """An indirect variable's computed number: a whole number 0..8191."""
    if number != int(number) or not 0 <= number < VARIABLES:
        raise ConfigurationError(f"{pos}: {kind}({number}) is not allowed (allowed: {kind}0..{kind}{VARIABLES - 1})")
    return int(number)
