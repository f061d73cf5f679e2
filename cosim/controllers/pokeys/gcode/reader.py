"""Reading G-code text into blocks of words, every unsupported word refused with its file and line.

Each line is parsed with the grammar of :mod:`.grammar` into words with exact values (``X-2.5``
is ``Fraction(-5, 2)``), then checked against the subset:

=========================  ==================================================================
word                       meaning
=========================  ==================================================================
``G0`` ``G1``              rapid and feed moves (straight lines)
``G2`` ``G3``              clockwise and counter-clockwise arcs in the XY plane (IJ or R form)
``G4 P``                   dwell for P seconds
``G17``                    XY plane (the only plane)
``G20`` ``G21``            inches, millimetres
``G90`` ``G91``            absolute, incremental distances
``G92``                    set the current position (a coordinate offset; axis words required)
``G40 G49 G54 G80 G94``    accepted without effect: they select the state cosim always has
                           (no cutter or tool-length compensation, the first work offset, no
                           canned cycle, feed in units per minute), as CAM headers write them
``M2`` ``M30``             program end (the rest of the file is not read)
``M3`` ``M4`` ``M5``       spindle (or laser) on clockwise, counter-clockwise, off
``X Y Z``                  axis words; ``I J`` arc centre offsets (always incremental); ``R`` arc radius
``F`` ``S`` ``P``          feed [units/min], spindle speed, dwell time [s]
``N``                      line number (ignored)
=========================  ==================================================================

Comments are ``( ... )`` and ``;``; a line holding only ``%`` (the tape delimiter) is skipped.
A letter appears at most once per line, except ``G`` and ``M`` words of different modal groups
(``G90 G21 G17`` is one line). Anything else is an error naming the file, the line and the word,
before the program runs; with ``allow_unsupported`` an unsupported word skips its line instead,
and the skipped lines are listed (:attr:`Blocks.skipped`).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from cosim.controllers.grammars import lark_parser
from cosim.controllers.pokeys.gcode.grammar import GRAMMAR
from cosim.errors import ConfigurationError

_PARSER = lark_parser(GRAMMAR, parser="lalr")

#: Supported G codes by modal group (two of one group on a line is an error, as in RS274/NGC).
G_GROUPS: dict[str, tuple[int, ...]] = {
    "motion": (0, 1, 2, 3),
    "non-modal": (4, 92),
    "plane": (17,),
    "units": (20, 21),
    "distance": (90, 91),
    "cutter compensation": (40,),
    "tool length": (49,),
    "work offset": (54,),
    "canned cycle": (80,),
    "feed mode": (94,),
}
#: Supported M codes by modal group.
M_GROUPS: dict[str, tuple[int, ...]] = {"spindle": (3, 4, 5), "stop": (2, 30)}
#: Letters with a value of their own (``G`` and ``M`` are codes).
VALUE_LETTERS = frozenset("XYZIJRFSPN")
SUPPORTED_G = ", ".join(f"G{g}" for group in G_GROUPS.values() for g in group)
SUPPORTED_M = ", ".join(f"M{m}" for group in M_GROUPS.values() for m in group)


@dataclass(frozen=True)
class Word:
    """One word: its letter (upper case), its exact value and the text as written."""

    letter: str
    value: Fraction
    text: str


@dataclass(frozen=True)
class Block:
    """The words of one line (line numbers from 1), comments dropped."""

    line: int
    words: tuple[Word, ...]

    def get(self, letter: str) -> Fraction | None:
        """The value of the value word ``letter``, or None."""
        for word in self.words:
            if word.letter == letter:
                return word.value
        return None

    def codes(self, letter: str) -> list[Fraction]:
        """The values of every ``G`` (or ``M``) word, in order."""
        return [w.value for w in self.words if w.letter == letter]


@dataclass(frozen=True)
class Blocks:
    """A program's blocks, with the lines skipped under ``allow_unsupported``."""

    source: str
    blocks: tuple[Block, ...]
    skipped: tuple[str, ...] = ()


def read_file(path: str | Path, *, allow_unsupported: bool = False) -> Blocks:
    """Read a G-code file (:func:`read_text`); an unreadable or non-text file is refused."""
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"{path}:{_line_of(exc.object, exc.start)}: not G-code: not a UTF-8 text file "
                                 f"(byte 0x{exc.object[exc.start]:02x} at offset {exc.start})") from None
    except OSError as exc:
        raise ConfigurationError(f"{path}: cannot read the G-code file ({exc.strerror})") from None
    return read_text(text, source=str(path), allow_unsupported=allow_unsupported)


def read_text(text: str, *, source: str = "program.nc", allow_unsupported: bool = False) -> Blocks:
    """Parse G-code ``text`` into checked blocks.

    Raises
    ------
    ConfigurationError
        ``SOURCE:LINE: reason`` for text that is not G-code, an unsupported word (unless
        ``allow_unsupported``), a letter given twice or two codes of one modal group.
    """
    blocks: list[Block] = []
    skipped: list[str] = []
    if "\x00" in text:
        raise ConfigurationError(f"{source}:{text[:text.index(chr(0))].count(chr(10)) + 1}: not G-code: "
                                 "the file holds NUL bytes (a binary file?)")
    for number, raw in enumerate(text.splitlines(), start=1):
        if raw.strip() == "%":
            continue
        words = _parse_line(raw, number, source)
        if not words:
            continue
        problem = _unsupported(words)
        if problem is not None:
            if not allow_unsupported:
                raise ConfigurationError(f"{source}:{number}: {problem}")
            skipped.append(f"{source}:{number}: {problem}; line skipped")
            continue
        _check_repeats(words, number, source)
        blocks.append(Block(number, tuple(words)))
    return Blocks(source, tuple(blocks), tuple(skipped))


def _parse_line(raw: str, number: int, source: str) -> list[Word]:
    try:
        tree = _PARSER.parse(raw)
    except UnexpectedInput as exc:
        raise ConfigurationError(f"{source}:{number}: not G-code: {_syntax(exc, raw)}") from None
    words = []
    for child in tree.children:
        if isinstance(child, Token):  # a comment
            continue
        letter, number_text = (str(t) for t in child.children)
        words.append(Word(letter.upper(), Fraction(number_text), f"{letter.upper()}{number_text}"))
    return words


def _syntax(exc: UnexpectedInput, raw: str) -> str:
    column = getattr(exc, "column", 0) or 0
    if isinstance(exc, UnexpectedCharacters):
        char = raw[column - 1] if 0 < column <= len(raw) else "?"
        hint = {"#": "parameters are not supported", "[": "expressions are not supported",
                "/": "block delete is not supported", "(": "a comment is not closed on its line",
                ")": "a comment closes that was never opened"}.get(char, "a word is a letter and a number, "
                                                                          "e.g. G1 or X-2.5")
        return f"unexpected {char!r} at column {column} ({hint})"
    if isinstance(exc, UnexpectedToken | UnexpectedEOF):
        token = getattr(exc, "token", None)
        at_end = token is None or token.type == "$END"
        before = raw.rstrip() if at_end or not column else raw[:column - 1].rstrip()
        letter = before[-1:] if before else ""
        if letter.isalpha():
            found = "the end of the line" if at_end else repr(str(token))
            return f"the letter {letter.upper()!r} at column {len(before)} is followed by {found}, not a number " \
                   "(a word is a letter and a number, e.g. G1 or X-2.5)"
        return f"{str(token)!r} at column {column} is not a word (a word is a letter and a number, e.g. G1 or X-2.5)"
    return "cannot be read"  # pragma: no cover - lark raises only the kinds above


def _code(value: Fraction) -> str:
    return str(value.numerator) if value.denominator == 1 else str(float(value))


def _unsupported(words: list[Word]) -> str | None:
    """Why a line is outside the subset (the first offending word), or None."""
    groups = {"G": G_GROUPS, "M": M_GROUPS}
    for word in words:
        if word.letter in groups:
            known = [c for group in groups[word.letter].values() for c in group]
            if word.value.denominator != 1 or word.value.numerator not in known:
                listed = SUPPORTED_G if word.letter == "G" else SUPPORTED_M
                return f"{word.letter}{_code(word.value)} is not supported (supported: {listed})"
        elif word.letter == "K":
            return f"{word.text} is not supported (arcs are in the XY plane, G17: I and J give the centre)"
        elif word.letter not in VALUE_LETTERS:
            return (f"the word {word.text} is not supported (letters: G, M, X, Y, Z, I, J, R, F, S, P, N; "
                    "no tools, coolant, other axes or parameters)")
    return None


def _check_repeats(words: list[Word], number: int, source: str) -> None:
    seen: dict[str, str] = {}
    for word in words:
        if word.letter in ("G", "M"):
            table = G_GROUPS if word.letter == "G" else M_GROUPS
            group = next(name for name, codes in table.items() if word.value.numerator in codes)
            key = f"{word.letter}:{group}"
            if key in seen:
                raise ConfigurationError(f"{source}:{number}: {seen[key]} and {word.text} are both {group} codes: "
                                         "one per line")
            seen[key] = word.text
        elif word.letter in seen:
            raise ConfigurationError(f"{source}:{number}: {word.letter} appears twice ({seen[word.letter]} and "
                                     f"{word.text}): one word per letter per line")
        else:
            seen[word.letter] = word.text


def _line_of(data: bytes, offset: int) -> int:
    return data[:offset].count(b"\n") + 1
