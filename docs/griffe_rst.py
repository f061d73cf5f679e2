"""A griffe extension for the API reference: the reStructuredText bits of our docstrings, as Markdown.

The docstrings are numpydoc, which mkdocstrings reads, but their prose uses Sphinx roles
(``:func:`load```) and literal-block markers (``Example::``) that Markdown would show as they are.
This turns a role into inline code of its target and ``::`` at the end of a line into ``:``.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:func|meth|class|mod|data|attr|exc|obj|const|ref|term):`[~.]*([^`<]+?)`")
_LITERAL = re.compile(r"(\S)::$", re.MULTILINE)


class RstRoles(griffe.Extension):
    """Rewrite each docstring once, when griffe has loaded the object."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            text = _ROLE.sub(r"`\1`", obj.docstring.value)
            obj.docstring.value = _LITERAL.sub(r"\1:", text)
