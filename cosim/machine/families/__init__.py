"""Controller families of machine files: how ``[controller]``, ``[[program]]`` and the family's own
tables become a controller, its ports and its programs (see :class:`Family`)."""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping
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


#: Each family's module and class, by its ``family`` key: imported when a machine of that family is built
#: (the PMAC family's servo models import python-control, and with it scipy and matplotlib: seconds of
#: start-up, and tens of MB in an exported FMU, that a Trio or PoKeys machine does not need).
MODULES = {"trio": ("cosim.machine.families.trio", "TrioFamily"),
           "pokeys": ("cosim.machine.families.pokeys", "PoKeysFamily"),
           "pmac": ("cosim.machine.families.pmac", "PmacFamily")}


class _Families(Mapping[str, Family]):
    """The families by name, each imported when it is looked up."""

    def __getitem__(self, name: str) -> Family:
        module, cls = MODULES[name]
        family: Family = getattr(importlib.import_module(module), cls)()
        return family

    def __iter__(self) -> Iterator[str]:
        return iter(MODULES)

    def __len__(self) -> int:
        return len(MODULES)


def families() -> Mapping[str, Family]:
    """Every family, by its ``family`` key (the one looked up is imported then)."""
    return _Families()
