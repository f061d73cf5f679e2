"""How the report shows a verdict: one colour and one sentence per verdict of ``result.json``.

A verdict the report does not know (a newer ``result.json``) is shown as its text in black.
"""

from __future__ import annotations

import html

#: verdict -> (colour, what it means), in the order the summary's legend lists them.
VERDICTS: dict[str, tuple[str, str]] = {
    "PASS": ("#2a9d3f", "every check passed"),
    "HAZARD SHOWN": ("#c77c00", "the hazard this scenario exists to demonstrate happened, as expected"),
    "HAZARD MISSED": ("#7b3fb0", "the hazard this scenario exists to demonstrate did not happen"),
    "FAIL": ("#d62728", "a check failed"),
    "UNCHECKED": ("#5b6b7b", "no check examined anything: nothing was verified"),
    "ERROR": ("#7a1010", "the run broke, or a check or figure could not be evaluated"),
    "TERMINATED": ("#8c564b", "a plant ended the run early; the checks passed up to then"),
    "INTERRUPTED": ("#444444", "Ctrl-C or SIGTERM stopped the run; what it simulated is checked"),
}


def colour(verdict: str) -> str:
    """The colour of a verdict (black for one this report does not know)."""
    return VERDICTS.get(verdict, ("#000000", ""))[0]


def meaning(verdict: str) -> str:
    """The sentence that says what a verdict means (empty for one this report does not know)."""
    return VERDICTS.get(verdict, ("", ""))[1]


def badge(verdict: str) -> str:
    """The verdict as an HTML badge (white on its colour, its meaning as the tooltip)."""
    return (f'<span class="verdict" data-verdict="{html.escape(verdict)}" title="{html.escape(meaning(verdict))}" '
            f'style="background:{colour(verdict)}">{html.escape(verdict)}</span>')
