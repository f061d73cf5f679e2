"""Controller families of machine files: how ``[controller]``, ``[[program]]`` and the family's own
tables become a controller, its ports and its programs (see :class:`Family`)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from importlib import import_module
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
        """The controller port a coupling of ``kind`` joins (``stepper``, ``laser``, ``switches``, ``encoder``,
        ``servo``)."""
        ...

    def start(self, run: Run, controller: Any, programs: list[Table], document: Table, *, base: Path) -> None:
        """Load and start the programs (and the family's own tables), and declare its figures."""
        ...


#: Every family by its ``family`` key: the module and class that implement it (imported when a machine
#: names it, so that a Trio machine does not load the PMAC runtime).
FAMILIES = {"trio": "cosim.machine.families.trio:TrioFamily", "pokeys": "cosim.machine.families.pokeys:PoKeysFamily",
            "pmac": "cosim.machine.families.pmac:PmacFamily"}


class _Families(Mapping[str, Family]):
    """The families by key; a family's module is imported when it is looked up."""

    def __getitem__(self, name: str) -> Family:
        module, cls = FAMILIES[name].split(":")
        family: Family = getattr(import_module(module), cls)()
        return family

    def __iter__(self) -> Iterator[str]:
        return iter(FAMILIES)

    def __len__(self) -> int:
        return len(FAMILIES)


def families() -> Mapping[str, Family]:
    """Every family, by its ``family`` key (its module is imported when it is looked up)."""
    return _Families()
