"""Start-up (issue 29): a run imports only what it uses, and the grammars are built once.

The figures (CPU seconds) are measured by ``bench/bench_startup.py``; these tests pin the causes:
which modules a run loads, and that a built parser is read back from the per-user cache.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from lark import Lark, Tree

import cosim
from cosim.controllers import grammars
from cosim.controllers.grammars import cache_key, lark_parser
from cosim.controllers.pmac.grammar import GRAMMAR as PMAC_GRAMMAR
from cosim.controllers.pokeys.gcode.grammar import GRAMMAR as GCODE_GRAMMAR
from cosim.controllers.pokeys.gcode.syntax import normalize
from cosim.controllers.trio.grammar import GRAMMAR as TRIO_GRAMMAR
from cosim.controllers.trio.grammar import normalise_lines

ROOT = Path(__file__).resolve().parent.parent
TINY = 'start: WORD+\n%import common.WORD\n%import common.WS\n%ignore WS\n'

#: Loaded by python-control, the PMAC runtime or the table writers: a Trio or PoKeys run needs none of them.
NOT_FOR_TRIO_OR_POKEYS = ("control", "scipy", "matplotlib", "pandas", "asyncio", "cosim.controllers.pmac",
                          "cosim.couplings.servo")


def test_importing_the_package_imports_none_of_its_modules() -> None:
    code = "import sys, cosim; print(sorted(m for m in sys.modules if m.startswith('cosim')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['cosim']"
    assert cosim.TimeBase.__module__ == "cosim.timebase" and cosim.Priority.SLOT == 20


@pytest.mark.fmu
def test_a_trio_and_a_pokeys_machine_run_without_control_scipy_pandas_or_the_pmac_runtime(tmp_path: Path) -> None:
    code = (
        "import sys\n"
        "from cosim.catalog import load\n"
        "from cosim.runner import run_scenario\n"
        "out, machines = sys.argv[1], sys.argv[2:]\n"
        "for k, name in enumerate(machines):\n"
        "    result = run_scenario(load(name), until='1 ms', out=f'{out}/{k}')\n"
        "    assert result.error is None, result.error\n"
        f"print(sorted(m for m in {NOT_FOR_TRIO_OR_POKEYS!r} if m in sys.modules))\n"
    )
    machines = ["examples/trio_engraver/engraver.toml", "examples/pokeys_router/router.toml"]
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path), *machines], cwd=ROOT, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]"


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty grammar cache, and no parser built yet in this process."""
    monkeypatch.setenv("COSIM_GRAMMARS", str(tmp_path / "grammars"))
    monkeypatch.setattr(grammars, "_BUILT", {})
    return tmp_path / "grammars"


def _builds(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Count the parsers built from grammar text (not loaded) from now on."""
    built: list[str] = []

    class Counting(Lark):
        def __init__(self, grammar: str, **options: object) -> None:
            built.append(grammar)
            super().__init__(grammar, **options)

    monkeypatch.setattr(grammars, "Lark", Counting)
    return built


def test_a_parser_is_built_once_per_process_and_then_read_from_the_cache(
        cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    built = _builds(monkeypatch)
    first = lark_parser(TINY, parser="lalr")
    assert lark_parser(TINY, parser="lalr") is first  # the same process: the same parser
    key = cache_key(TINY, {"parser": "lalr"})
    assert len(built) == 1 and [p.name for p in cache.iterdir()] == [f"lark-{key[:32]}.bin"]
    monkeypatch.setattr(grammars, "_BUILT", {})  # as a new process
    again = lark_parser(TINY, parser="lalr")
    assert len(built) == 1 and again is not first
    assert again.parse("two words") == Tree("start", ["two", "words"])


def test_another_grammar_or_other_options_are_another_file(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    built = _builds(monkeypatch)
    lark_parser(TINY, parser="lalr")
    lark_parser(TINY, parser="lalr", propagate_positions=True)
    lark_parser(TINY.replace("WORD+", "WORD*"), parser="lalr")
    assert len(built) == 3 and len(list(cache.iterdir())) == 3


def test_a_damaged_cache_file_is_built_anew_and_replaced(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    lark_parser(TINY, parser="lalr")
    (path,) = cache.iterdir()
    path.write_bytes(path.read_bytes()[:100])  # cut short
    monkeypatch.setattr(grammars, "_BUILT", {})
    built = _builds(monkeypatch)
    assert lark_parser(TINY, parser="lalr").parse("a b") == Tree("start", ["a", "b"])
    assert len(built) == 1
    monkeypatch.setattr(grammars, "_BUILT", {})
    lark_parser(TINY, parser="lalr")
    assert len(built) == 1  # the replaced file reads


def test_a_cache_folder_that_cannot_be_written_costs_only_the_build(cache: Path) -> None:
    cache.parent.mkdir(exist_ok=True)
    cache.write_text("a file where the folder should be")
    assert lark_parser(TINY, parser="lalr").parse("a") == Tree("start", ["a"])


def _nodes(tree: Tree) -> list[tuple[str, int, int, int, int]]:
    return [(t.data, t.meta.line, t.meta.column, t.meta.end_line, t.meta.end_column)
            for t in tree.iter_subtrees() if not t.meta.empty]


@pytest.mark.parametrize(("grammar", "options", "text", "start"), [
    (TRIO_GRAMMAR, {"propagate_positions": True, "maybe_placeholders": True},
     normalise_lines((ROOT / "examples/trio_engraver/engrave.bas").read_text()), None),
    (PMAC_GRAMMAR, {"start": ["online_line", "program_line"], "propagate_positions": True,
                    "maybe_placeholders": True}, "P1=P2*3+I130 X(P1) Y20 F100", "program_line"),
    (GCODE_GRAMMAR, {"lexer": "contextual"}, normalize("N10 G2 X10.5 Y-3 I5 J0 F300 (cut)")[0], None),
])
def test_a_cached_parser_reads_as_a_freshly_built_one(
        cache: Path, grammar: str, options: dict[str, object], text: str, start: str | None) -> None:
    fresh = Lark(grammar, parser="lalr", **options)  # type: ignore[arg-type]
    lark_parser(grammar, parser="lalr", **options)
    grammars._BUILT.clear()
    cached = lark_parser(grammar, parser="lalr", **options)
    expected, got = fresh.parse(text, start=start), cached.parse(text, start=start)
    assert got == expected
    if options.get("propagate_positions"):
        assert _nodes(got) == _nodes(expected) and len(_nodes(got)) > 5


def test_a_trace_that_spills_to_disk_and_is_read_back_does_not_load_pandas() -> None:
    code = ("import sys\n"
            "from cosim.trace import Trace\n"
            "trace = Trace(spill_rows=3)\n"
            "trace.declare('dev.n', 'int')\n"
            "trace.declare('dev.step', 'pulse')\n"
            "for k in range(10):\n"
            "    trace.record('dev.n', 10 * k, k)\n"
            "    trace.record_segment('dev.step', 100 * k, 100, 3, k % 2)\n"
            "t, v = trace.edges('dev.n')\n"
            "p, d = trace.pulses('dev.step')\n"
            "assert trace.spilled_rows() > 0\n"
            "print(t.tolist()[-2:], v.tolist()[-2:], p.tolist()[:4], d.tolist()[:4], 'pandas' in sys.modules)\n"
            "trace.discard_spill()\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[80, 90] [8.0, 9.0] [0, 33, 66, 100] [0, 0, 0, 1] False"
