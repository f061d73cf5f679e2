"""Stable ids for Bokeh output: the same run gives the same page byte for byte.

Bokeh names each document and root element with a random uuid (``uuid4``). :func:`stable_ids`
replaces them, in order of first appearance, by uuids derived from a name (``uuid5``), keeping
every occurrence of one id the same across the texts given together (a page's script and div).
"""

from __future__ import annotations

import re
import uuid
from collections.abc import Sequence

_UUID = re.compile(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}")


def stable_ids(texts: Sequence[str], name: str) -> list[str]:
    """``texts`` with their uuids replaced by ones derived from ``name``.

    Examples
    --------
    >>> a, b = stable_ids(["id 0a6e2b4c-1f2d-4c3b-9a8e-7d6c5b4a3f2e", "0a6e2b4c-1f2d-4c3b-9a8e-7d6c5b4a3f2e"], "x")
    >>> a == "id " + b and b == str(uuid.uuid5(uuid.NAMESPACE_URL, "cosim-report/x/0"))
    True
    """
    ids: dict[str, str] = {}

    def stable(match: re.Match[str]) -> str:
        if match[0] not in ids:
            ids[match[0]] = str(uuid.uuid5(uuid.NAMESPACE_URL, f"cosim-report/{name}/{len(ids)}"))
        return ids[match[0]]

    return [_UUID.sub(stable, text) for text in texts]
