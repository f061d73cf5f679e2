"""Variables of PMAC programs: P-variables, and M-variables that read and write the model's registers.

* ``Pn`` (0..8191): a 48-bit word of user memory, 0 at power-up; values fitted by
  :func:`cosim.controllers.pmac.arith.fit`.
* ``In``: the I-variables the model knows (through :meth:`Pmac.get_ivar`/:meth:`Pmac.set_ivar`,
  with their ranges; a value that is not an integer where the variable needs one is an error).
* ``Mn->X:address,offset,width,format`` (``Y:`` likewise): a bit field of a 24-bit register;
  ``S`` reads it as two's complement, ``U`` (default) as unsigned. ``Mn->*`` is a plain 48-bit
  word of memory. The modelled registers:

  ======================  ======  =====================================================
  address                 access  what
  ======================  ======  =====================================================
  X: channel + 0          read    encoder count (24 bits), e.g. X:$078008
  X: channel + 3          read    capture register (whole counts); **reading re-arms**
                                  the capture, as a read of X:$07800B does on the card
  X: table line           read    conversion-table result word (e.g. X:$3502)
  Y: table line           r/w     conversion-table setup word = I8000 + line (Y:$3501 is
                                  I8000); a write is an I-variable write (method digit or
                                  SCALE_FACTOR only, as for I-variables)
  ======================  ======  =====================================================

  Writing a non-integer rounds it to the nearest integer (halves away from zero), then keeps
  the low ``width`` bits, as the hardware's bit field does. Other addresses are refused when the
  controller starts (naming the definition's file, line and column); writing an X register is
  refused when it happens.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING

from cosim.controllers.pmac import arith
from cosim.controllers.pmac.nodes import (
    MDefine,
    Pos,
    Var,
    located,
)

if TYPE_CHECKING:
    from cosim.controllers.pmac.machine import Pmac


def round_half_away(value: Fraction) -> int:
    """Nearest integer, halves away from zero."""
    return math.floor(value + Fraction(1, 2)) if value >= 0 else -math.floor(-value + Fraction(1, 2))


def field_value(word: int, offset: int, width: int, signed: bool) -> int:
    """Bits ``offset .. offset+width-1`` of ``word``, two's complement if ``signed``."""
    bits = (word >> offset) & ((1 << width) - 1)
    if signed and bits >> (width - 1):
        bits -= 1 << width
    return bits


class Memory:
    """P- and M-variables of one controller, and the reads and writes of every variable kind.

    Parameters
    ----------
    pmac : Pmac
        The controller whose I-variables and registers the variables reach.
    """

    def __init__(self, pmac: Pmac) -> None:
        self.pmac = pmac
        self.p: dict[int, Fraction] = {}
        self.definitions: dict[int, MDefine] = {}
        self.words: dict[int, Fraction] = {}

    def define(self, stmt: MDefine) -> None:
        """``Mn->...``: (re)define an M-variable (its register is checked when the controller starts)."""
        self.definitions[stmt.number] = stmt
        if self.pmac.started:
            self.check_definition(stmt)

    def check_definition(self, stmt: MDefine) -> None:
        """Refuse a definition whose register the model does not have."""
        target = stmt.target
        if target is None:
            return
        if not self.pmac.has_register(target.space, target.address):
            raise stmt.pos.error(f"M{stmt.number}->{target}: the model has no register {target.space}:"
                                 f"${target.address:06X} (modelled: {self.pmac.describe_registers()})")

    def _definition(self, var: Var) -> MDefine:
        stmt = self.definitions.get(var.number)
        if stmt is None:
            raise var.pos.error(f"M{var.number} is not defined (define it first, e.g. "
                                f"M{var.number}->X:$07800B,0,24,S)")
        return stmt

    def read(self, var: Var) -> Fraction:
        """The value of ``var`` now (an M-variable on a capture register re-arms the capture)."""
        if var.kind == "P":
            return self.p.get(var.number, Fraction(0))
        if var.kind == "I":
            return Fraction(self.pmac.get_ivar(var.number))
        stmt = self._definition(var)
        target = stmt.target
        if target is None:
            return self.words.get(var.number, Fraction(0))
        with located(var.pos):
            word = self.pmac.read_word(target.space, target.address)
        return Fraction(field_value(word, target.offset, target.width, target.signed))

    def write(self, var: Var, value: Fraction, pos: Pos) -> None:
        """``var = value`` (checked against the variable's range; raises naming ``pos``)."""
        if var.kind == "P":
            self.p[var.number] = arith.fit(value, what=str(var), where=str(pos))
            return
        if var.kind == "I":
            number = value.numerator if value.denominator == 1 else value
            self.pmac.set_ivar(var.number, number, where=str(pos))
            return
        stmt = self._definition(var)
        target = stmt.target
        if target is None:
            self.words[var.number] = arith.fit(value, what=str(var), where=str(pos))
            return
        if target.space == "X":
            raise pos.error(f"M{var.number}->{target}: X registers are read-only in this model "
                            "(encoder position and capture, table results)")
        mask = ((1 << target.width) - 1) << target.offset
        with located(pos):
            word = self.pmac.read_word(target.space, target.address)
            bits = (round_half_away(value) << target.offset) & mask
            self.pmac.write_word(target.space, target.address, (word & ~mask) | bits, where=str(pos))
