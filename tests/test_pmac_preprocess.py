"""The download preprocessor: #define, #include, #undefine, #ifdef, comments and $(NAME) template macros.

A project's files reach the controller through its download tool's C-like preprocessor; these are the
forms real projects use (issue 27, item 1), each with the place it came from kept for messages.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosim.controllers.pmac import Pmac
from cosim.controllers.pmac.preprocess import TemplateMacroError, preprocess
from cosim.controllers.pmac.program import parse_text
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation


def _texts(text: str, **kwargs: object) -> list[str]:
    return [line.text.strip() for line in preprocess(text, source="p.pmc", **kwargs) if line.text.strip()]  # type: ignore[arg-type]


def test_define_substitutes_whole_words_in_the_lines_after_it() -> None:
    text = "#define Counter P100\n#define ON 1 ; the value ends before the comment\nCounter=Counter+ON P1000=ON1\n"
    assert _texts(text) == ["P100=P100+1 P1000=ON1"]  # ON1 is another word


def test_macros_may_use_macros_and_undefine_forgets_one() -> None:
    text = "#define BASE 200\n#define ADDR (BASE+10)\nP(ADDR)=1\n#undefine BASE\nP1=BASE\n#undef ADDR\nP2=ADDR\n"
    assert _texts(text) == ["P((200+10))=1", "P1=BASE", "P2=ADDR"]


def test_a_macro_defined_through_itself_stops_with_an_error() -> None:
    with pytest.raises(ConfigurationError, match=r"^p.pmc:2:1: macros are still substituted after 32 rounds"):
        preprocess("#define LOOP LOOP+1\nP1=LOOP\n", source="p.pmc")


def test_comments_of_three_kinds_and_banner_lines_go_away_strings_stay() -> None:
    text = ('####################\nP1=1 ; semicolon\nP2=2 // slashes\nP3=/* a\nblock */3\nCMD"I130=1 ; kept"\n'
            "#####\n")
    lines = preprocess(text, source="p.pmc")
    assert [(line.line, line.text.strip()) for line in lines if line.text.strip()] == [
        (2, "P1=1"), (3, "P2=2"), (4, "P3="), (5, "3"), (6, 'CMD"I130=1 ; kept"')]


def test_ifdef_ifndef_else_endif() -> None:
    text = "#define SIM\n#ifdef SIM\nP1=1\n#else\nP1=2\n#endif\n#ifndef SIM\nP2=1\n#endif\n"
    assert _texts(text) == ["P1=1"]


def test_include_is_relative_to_the_including_file_then_the_search_path(tmp_path: Path) -> None:
    (tmp_path / "cell").mkdir()
    (tmp_path / "lib").mkdir()
    (tmp_path / "cell" / "local.pmc").write_text("#define SPEED 64\n")
    (tmp_path / "lib" / "shared.pmc").write_text('#include "gains.pmc"\n')
    (tmp_path / "lib" / "gains.pmc").write_text("#define GAIN 2000\n")  # relative to shared.pmc, in lib
    main = tmp_path / "cell" / "main.pmc"
    main.write_text('#include "local.pmc"\n#include <shared.pmc>\nI122=SPEED I130=GAIN\n')
    with pytest.raises(ConfigurationError, match=r"main.pmc:2:1: #include 'shared.pmc': file not found"):
        preprocess(main.read_text(), source="main.pmc", path=main)
    lines = preprocess(main.read_text(), source="main.pmc", path=main, search=[tmp_path / "lib"])
    assert [line.text for line in lines if line.text.strip()] == ["I122=64 I130=2000"]
    assert lines[-1].source == "main.pmc" and lines[-1].line == 3


def test_a_file_including_itself_is_refused(tmp_path: Path) -> None:
    loop = tmp_path / "loop.pmc"
    loop.write_text('#include "loop.pmc"\n')
    with pytest.raises(ConfigurationError, match="includes itself"):
        preprocess(loop.read_text(), source="loop.pmc", path=loop)


def test_template_macros_take_their_values_from_the_machine_file() -> None:
    text = "OPEN PLC $(PLC) CLEAR\nP1=$(GAIN)\nCLOSE\n"
    (buffer,) = parse_text(text, source="t.pmc", defines={"PLC": "3", "GAIN": "2.5"}).buffers()
    assert (buffer.kind, buffer.number) == ("PLC", 3)


def test_a_template_macro_left_without_a_value_names_the_construct() -> None:
    """The issue's first refusal: ``OPEN PLC $(PLC)`` gave "nothing may follow OPEN PROG n [CLEAR]"."""
    with pytest.raises(TemplateMacroError, match=r"^t.pmc:1:10: `\$\(PLC\)`: template macro with no value; give it "
                                                 r"in \[controller.defines\] \(given: GAIN\)$"):
        parse_text("OPEN PLC $(PLC) CLEAR\nCLOSE\n", source="t.pmc", defines={"GAIN": "1"})


def test_unknown_directives_are_named() -> None:
    with pytest.raises(ConfigurationError, match=r"^p.pmc:1:1: #pragma: unknown preprocessor directive"):
        preprocess("#pragma once\n", source="p.pmc")


def test_motor_addressing_is_not_a_directive(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load("#define SCALE 1000\n&1 #1->SCALE X #2->-SCALE Y\n#1->\n", source="m.pmc")
    assert pmac.motors[1].counts_per_unit == 1000 and pmac.motors[2].counts_per_unit == -1000
