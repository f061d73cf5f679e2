"""I-variable setup text: the assignments users keep in their PMAC setup files, read with the PMAC grammar.

Accepted syntax, one or more assignments per line, case-insensitive::

    I10=3713707            ; decimal
    I8010=$978008 I8011=64 ; hex with $, several on a line
    I5193=@I8011           ; @In = address of a conversion-table line (I8000..I8191)

``;`` starts a comment. The text is parsed by :func:`cosim.controllers.pmac.program.parse_text`
(the grammar of every PMAC text), and each statement must be an assignment of a constant to an
I-variable of the Turbo PMAC (:mod:`.ivartable`), within its range; anything else is an error naming
``file:line:column``. A full PMAC file (M-variables, motors, programs) is read by
:meth:`cosim.controllers.pmac.machine.Pmac.load`.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from cosim.controllers.pmac import ivartable
from cosim.controllers.pmac.nodes import Assign, Var, constant
from cosim.controllers.pmac.program import Buffer, parse_text


@dataclass(frozen=True)
class Assignment:
    """One ``In=value`` of a setup file.

    Attributes
    ----------
    number : int
        I-variable number n.
    value : int or Fraction
        Parsed value (a Fraction only for Ix89 and Ixx22).
    line : int
        Line number (1-based).
    source : str
        File name (or a label) for messages.
    column : int
        Column of the assignment (1-based).
    """

    number: int
    value: int | Fraction
    line: int
    source: str
    column: int = 1

    @property
    def where(self) -> str:
        """``file:line:column`` for error messages."""
        return f"{self.source}:{self.line}:{self.column}"


def parse_setup(text: str, *, source: str = "setup") -> tuple[Assignment, ...]:
    """Parse setup text into assignments (in file order), checking every name and range.

    Parameters
    ----------
    text : str
        The setup file's content.
    source : str
        File name for messages.

    Raises
    ------
    ConfigurationError
        ``<source>:<line>:<column>: ...`` for unknown variables, bad syntax or values out of range.
    """
    assignments: list[Assignment] = []
    for item in parse_text(text, source=source).items:
        value = constant(item.expr) if (isinstance(item, Assign) and isinstance(item.var, Var) and item.var.kind == "I"
                                        and item.expr is not None) else None
        if value is None or not isinstance(item, Assign) or not isinstance(item.var, Var):
            pos = item.pos
            line = text.removeprefix("\ufeff").splitlines()[pos.line - 1]
            word = "OPEN" if isinstance(item, Buffer) else (line[pos.column - 1:].split() or ["?"])[0]
            raise pos.error(f"{word!r} is not an I-variable assignment (this loader reads assignments like "
                            "I10=3713707 or I8010=$978008)")
        number = item.var.number
        exact = value.numerator if value.denominator == 1 else value
        checked = ivartable.check(number, exact, where=str(item.pos))
        assignments.append(Assignment(number, checked, item.pos.line, source,
                                      item.pos.column))
    return tuple(assignments)
