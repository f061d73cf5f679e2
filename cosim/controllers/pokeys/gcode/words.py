"""The words of a line, evaluated and checked: codes by modal group, one word per letter, what uses what.

:func:`evaluate_line` computes every word's value with the parameters as they are when the line is
read, and checks the line as LinuxCNC's ``check_items`` does: G codes x 10 and M codes known, one
of each modal group, at most four M codes, one word per letter, and no word that nothing on the
line (or the modal motion) uses. It returns a :class:`Words`. Each error names the word and its
column.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cosim.controllers.pokeys.gcode.params import LARGEST, EvalError, Number, Parameters, integer, show
from cosim.controllers.pokeys.gcode.syntax import SourceLine, Word

#: G codes x 10 by modal group (LinuxCNC 2.9).
G_GROUPS: dict[int, tuple[int, ...]] = {
    0: (40, 100, 280, 281, 300, 301, 520, 530, 920, 921, 922, 923),
    1: (0, 10, 20, 30, 50, 51, 52, 53, 330, 331, 382, 383, 384, 385, 730, 740, 760, 800, 810, 820, 830, 840, 850,
        860, 870, 880, 890),
    2: (170, 171, 180, 181, 190, 191),
    3: (900, 910),
    4: (901, 911),
    5: (930, 940, 950),
    6: (200, 210),
    7: (400, 410, 411, 420, 421),
    8: (430, 431, 432, 490),
    10: (980, 990),
    12: (540, 550, 560, 570, 580, 590, 591, 592, 593),
    13: (610, 611, 640),
    14: (960, 970),
    15: (70, 80),
}
G_GROUP = {code: group for group, codes in G_GROUPS.items() for code in codes}
M_GROUPS: dict[int, tuple[int, ...]] = {
    4: (0, 1, 2, 30, 60),
    5: (62, 63, 64, 65, 66, 67, 68),
    6: (6, 61),
    7: (3, 4, 5, 19),
    8: (7, 8, 9),
    9: (48, 49, 50, 51, 52, 53),
    10: tuple(range(100, 200)),
    11: (70, 71, 72, 73),
}
M_GROUP = {code: group for group, codes in M_GROUPS.items() for code in codes}
G_NAMES = {"motion": 1, "plane": 2, "distance": 3, "arc distance": 4, "feed mode": 5, "units": 6,
           "cutter compensation": 7, "tool length": 8, "retract": 10, "coordinate system": 12, "path control": 13,
           "spindle mode": 14, "lathe diameter": 15, "non-modal": 0}
GROUP_NAME = {v: k for k, v in G_NAMES.items()}
AXIS_LETTERS = "XYZABCUVW"
#: Group-0 codes that take the axis words (the motion mode does not use them on that line).
AXIS_USERS_0 = (100, 280, 300, 520, 920)


class WordError(Exception):
    """A word that is wrong on its line: ``reason`` at ``column``."""

    def __init__(self, reason: str, column: int = 0) -> None:
        super().__init__(reason)
        self.reason = reason
        self.column = column


def code_name(letter: str, code10: int) -> str:
    """``G61.1``, ``G0``, ``M3``."""
    if letter == "M":
        return f"M{code10}"
    return f"G{code10 // 10}" if code10 % 10 == 0 else f"G{code10 // 10}.{code10 % 10}"


@dataclass
class Words:
    """A line's words, evaluated: ``g`` and ``m`` codes (G x 10), the value of each other letter."""

    g: dict[int, int] = field(default_factory=dict)  # group -> code x 10
    m: dict[int, int] = field(default_factory=dict)  # group -> code
    values: dict[str, Number] = field(default_factory=dict)
    columns: dict[str, int] = field(default_factory=dict)
    g_columns: dict[int, int] = field(default_factory=dict)
    m_columns: dict[int, int] = field(default_factory=dict)

    def has(self, letter: str) -> bool:
        return letter in self.values

    def get(self, letter: str) -> Number | None:
        return self.values.get(letter)

    def axes(self) -> dict[str, Number]:
        return {a: v for a in AXIS_LETTERS if (v := self.values.get(a)) is not None}

    def column(self, letter: str) -> int:
        return self.columns.get(letter, 0)


def evaluate_line(line: SourceLine, params: Parameters) -> Words:
    """The words of ``line`` with their values now; raises :class:`WordError`."""
    words = Words()
    m_count = 0
    for word in line.words:
        try:
            value = params.evaluate(word.expr)
        except EvalError as exc:
            raise WordError(f"{word.letter} word: {exc}", word.column) from None
        if abs(value) > LARGEST:  # type: ignore[operator]
            raise WordError(f"{word.letter} word: {float(value):.6g} is out of range (at most {LARGEST:.0e} in size)",
                            word.column)
        if word.letter == "G":
            _g(words, word, value)
        elif word.letter == "M":
            m_count += 1
            if m_count > 4:
                raise WordError("Too many M codes on line (at most 4)", word.column)
            _m(words, word, value)
        else:
            if word.letter in words.values:
                raise WordError(f"Multiple {word.letter} words on one line", word.column)
            words.values[word.letter] = value
            words.columns[word.letter] = word.column
    return words


#: G codes of LinuxCNC 2.9 that are not simulated here, by name.
NOT_SIMULATED = {700: "G70 (lathe finishing cycle)", 710: "G71 (lathe roughing cycle)",
                 711: "G71.1 (lathe roughing cycle)", 712: "G71.2 (lathe roughing cycle)",
                 720: "G72 (lathe facing cycle)", 721: "G72.1 (lathe facing cycle)", 722: "G72.2 (lathe facing cycle)"}


def _g(words: Words, word: Word, value: Number) -> None:
    code = integer(value * 10)
    if code in NOT_SIMULATED:
        raise WordError(f"{NOT_SIMULATED[code]} is not supported: the host of a PoKeys mill or router runs no lathe "
                        "cycles", word.column)
    if code is None or code not in G_GROUP:
        text = f"G{show(value)}"
        raise WordError(f"Unknown G code used: {text}" if value < 100 else f"G code out of range: {text}", word.column)
    group = G_GROUP[code]
    if group in words.g and not (group == 0 and words.g[group] == code):
        raise WordError(f"{code_name('G', words.g[group])} and {code_name('G', code)}: two G codes from the same "
                        f"modal group ({GROUP_NAME.get(group, group)}) on one line", word.column)
    if group == 0 and 0 in words.g:
        raise WordError(f"{code_name('G', words.g[0])} and {code_name('G', code)}: two non-modal G codes on one "
                        "line", word.column)
    words.g[group] = code
    words.g_columns[group] = word.column


def _m(words: Words, word: Word, value: Number) -> None:
    code = integer(value)
    if code is None or code < 0:
        raise WordError(f"Unknown M code used: M{show(value)}", word.column)
    if code > 199:
        raise WordError(f"M code greater than 199: M{code}", word.column)
    group = M_GROUP.get(code)
    if group is None:
        raise WordError(f"Unknown M code used: M{code}", word.column)
    if group in words.m:
        raise WordError(f"M{words.m[group]} and M{code}: two M codes from the same modal group on one line",
                        word.column)
    words.m[group] = code
    words.m_columns[group] = word.column


def check_uses(words: Words, motion: int) -> None:
    """Refuse words that nothing on the line uses (LinuxCNC's ``check_other_codes``)."""
    g = words.g
    line_motion = g.get(1, motion)
    g0 = g.get(0)
    axis_user_0 = g0 in AXIS_USERS_0 or (g0 in (281, 301) and False)
    if g0 in AXIS_USERS_0 and 1 in g and g[1] != 800 and words.axes():
        raise WordError(f"{code_name('G', g0)} and {code_name('G', g[1])} both use the axis words: one per line",
                        words.g_columns[0])
    m = set(words.m.values())
    arcs = line_motion in (20, 30)
    cycles = 730 <= line_motion <= 890 and line_motion != 800
    checks = {
        "I": arcs or line_motion in (50, 51, 331, 760, 870) or g0 == 100,
        "J": arcs or line_motion in (50, 51, 760, 870) or g0 == 100,
        "K": arcs or line_motion in (331, 330, 760, 870) or g0 == 100,
        "R": arcs or cycles or g0 == 100 or line_motion == 760 or 19 in m,
        "P": (arcs or g0 in (40, 100) or g.get(13) == 640 or line_motion in (50, 52, 760, 820, 860, 880, 890, 740,
                                                                            840)
              or bool(m & {19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 67, 68}) or bool(m & set(range(100, 200)))
              or (line_motion == 830 and False)),
        "Q": (line_motion in (50, 52, 730, 760, 830) or g.get(13) == 640 or g0 == 100
              or bool(m & {19, 66, 67, 68, 61}) or bool(m & set(range(100, 200)))),
        "L": g0 == 100 or cycles or line_motion in (52, 760) or bool(m & {66}),
        "E": line_motion == 760 or bool(m & {66, 67, 68}),
        "H": g.get(8) in (430, 432) or line_motion == 760,
        "D": g.get(7) in (410, 420, 411, 421) or g.get(14) == 960,
    }
    for letter, used in checks.items():
        if words.has(letter) and not used:
            raise WordError(f"{letter} word with nothing on the line that uses it", words.column(letter))
    if words.axes() and line_motion == 800 and not axis_user_0 and g0 not in AXIS_USERS_0 and g.get(8) != 431:
        first = min(words.columns[a] for a in words.axes())
        raise WordError("Cannot use axis values without a G code that uses them (the motion mode is G80: give "
                        "G0, G1, G2 or G3)", first)
