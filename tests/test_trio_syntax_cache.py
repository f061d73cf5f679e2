"""A machine's Trio BASIC programs are parsed once: their syntax trees are kept in the per-user cache.

:func:`cosim.controllers.trio.syntax.parse_cached` (used for the program files of a machine) keeps each
tree under the SHA-256 of the grammar and the text, so the next run of the machine loads it instead of
building the parser and parsing (issue 29, start-up).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosim.controllers.trio import syntax
from cosim.controllers.trio.basic import BasicProgram
from cosim.errors import ConfigurationError

PROGRAM = "BASE(3)\nATYPE = 35\nUNITS = 16\nMOVEABS(300)\nWAIT UNTIL VR(1) = 2\nPRINT \"done\"\n"


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("COSIM_GRAMMARS", str(tmp_path / "grammars"))
    return tmp_path / "grammars"


def _parses(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Count the texts parsed (not loaded) from now on."""
    parsed: list[str] = []
    parse = syntax.parse

    def counting(text: str, name: str) -> object:
        parsed.append(name)
        return parse(text, name)

    monkeypatch.setattr(syntax, "parse", counting)
    return parsed


def test_a_program_is_parsed_once_then_its_tree_is_read_from_the_cache(
        cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    expected = syntax.parse(PROGRAM, "a.bas")
    parsed = _parses(monkeypatch)
    first = syntax.parse_cached(PROGRAM, "a.bas")
    again = syntax.parse_cached(PROGRAM, "b.bas")  # the same text under another name: the same tree
    assert parsed == ["a.bas"] and again == first == expected
    assert len(list(cache.glob("trio-tree-*.pickle"))) == 1
    syntax.parse_cached(PROGRAM + "x = 1\n", "c.bas")  # a changed program is a new tree
    assert parsed == ["a.bas", "c.bas"] and len(list(cache.glob("trio-tree-*.pickle"))) == 2


def test_a_cut_short_tree_is_parsed_anew_and_replaced(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    syntax.parse_cached(PROGRAM, "a.bas")
    (path,) = cache.glob("trio-tree-*.pickle")
    path.write_bytes(path.read_bytes()[:40])
    expected = syntax.parse(PROGRAM, "a.bas")
    parsed = _parses(monkeypatch)
    assert syntax.parse_cached(PROGRAM, "a.bas") == expected
    assert parsed == ["a.bas"]
    parsed.clear()
    syntax.parse_cached(PROGRAM, "a.bas")
    assert parsed == []  # replaced by a whole one


def test_a_syntax_error_is_reported_every_time_and_never_kept(cache: Path) -> None:
    for _ in range(2):
        with pytest.raises(ConfigurationError, match=r"bad\.bas line 2"):
            syntax.parse_cached("BASE(3)\nMOVE(1,,\n", "bad.bas")
    assert not list(cache.glob("trio-tree-*.pickle"))


def test_at_most_the_newest_trees_are_kept(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(syntax, "CACHED_TREES", 3)
    for k in range(5):
        syntax.parse_cached(f"VR({k}) = 1\n", "p.bas")
    assert len(list(cache.glob("trio-tree-*.pickle"))) == 3


def test_an_unwritable_cache_only_costs_the_parse(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("COSIM_GRAMMARS", str(blocker / "grammars"))
    assert syntax.parse_cached(PROGRAM, "a.bas") == syntax.parse(PROGRAM, "a.bas")


def test_a_machines_program_files_go_through_the_cache(cache: Path, tmp_path: Path) -> None:
    (tmp_path / "main.bas").write_text(PROGRAM)
    (tmp_path / "other.bas").write_text("VR(1) = 2\n")
    programs = BasicProgram.load_all([tmp_path / "main.bas", tmp_path / "other.bas"])
    assert [p.key for p in programs] == ["MAIN", "OTHER"]
    assert len(list(cache.glob("trio-tree-*.pickle"))) == 2
    again = BasicProgram.load_all([tmp_path / "main.bas", tmp_path / "other.bas"])
    assert [p.compiled.sources for p in again] == [p.compiled.sources for p in programs]
