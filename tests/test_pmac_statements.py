"""Nothing the Turbo PMAC reference documents as program or on-line command syntax is a syntax error (issue 27).

``tests/data/pmac_statements.txt`` lists statements written from the Turbo PMAC/PMAC2 Software Reference's
command syntax (on-line commands, motion and PLC program commands), one per line as ``online|...`` or
``program|...``. Each is parsed in its context; a command the model does not act on is still accepted (and
listed as "set, not modelled" when it runs), never refused.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cosim.controllers.pmac.nodes import Other
from cosim.controllers.pmac.syntax import parse_line

LIST = Path(__file__).parent / "data" / "pmac_statements.txt"
STATEMENTS = [tuple(line.split("|", 1)) for line in LIST.read_text().splitlines()
              if line.strip() and not line.startswith("#")]


def test_the_list_walks_at_least_150_statements_of_both_contexts() -> None:
    contexts = [context for context, _text in STATEMENTS]
    assert len(STATEMENTS) >= 150
    assert contexts.count("online") >= 100 and contexts.count("program") >= 100


@pytest.mark.parametrize(("context", "text"), STATEMENTS, ids=[f"{c}:{t}" for c, t in STATEMENTS])
def test_the_reference_statement_parses(context: str, text: str) -> None:
    statements = parse_line(text, context=context, source="reference.pmc", line=1)
    assert statements, text


def test_commands_the_model_does_not_act_on_are_kept_as_written() -> None:
    (gather,) = parse_line("DEFINE GATHER 1000", context="online", source="s", line=1)
    assert isinstance(gather, Other) and (gather.keyword, gather.text) == ("DEFINE", "DEFINE GATHER 1000")
    (macro,) = parse_line("MS0,MI910=$F", context="online", source="s", line=1)
    assert isinstance(macro, Other) and macro.keyword == "MS"
