"""Controller families of machine files: how ``[controller]``, ``[[program]]`` and the family's own
tables become a controller, its ports and its programs (see :class:`Family`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol

from cosim.machine.document import Table
from cosim.scenario import Run


class Family(Protocol):
    """What the machine builder needs of a controller family."""

    name: str
    #: Top-level tables of the machine file the family reads itself (besides ``controller`` and ``program``).
    tables: tuple[str, ...]

    def controller(self, run: Run, table: Table, *, base: Path) -> Any:
        """Build the controller from ``[controller]`` (the family key is read already)."""
        ...

    def port(self, controller: Any, kind: str, table: Table) -> Any:
        """The controller port a coupling of ``kind`` joins (``stepper``, ``laser``, ``switches``)."""
        ...

    def start(self, run: Run, controller: Any, programs: list[Table], document: Table, *, base: Path) -> None:
        """Load and start the programs (and the family's own tables), and declare its figures."""
        ...


def families() -> dict[str, Family]:
    """Every family, by its ``family`` key."""
    from cosim.machine.families.pokeys import PoKeysFamily
    from cosim.machine.families.trio import TrioFamily

    return {f.name: f for f in (TrioFamily(), PoKeysFamily())}
