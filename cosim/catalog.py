"""What can be run: bundled scenarios, scenario scripts, machine files and the example machines.

:func:`load` takes a bundled scenario name, a ``.py`` scenario script or a ``.toml`` machine file
and returns what the runner runs; :func:`description` gives the one-line description of any of
them without running anything (``cosim list`` costs milliseconds); :func:`examples` lists the
example machines shipped with cosim.
"""

from __future__ import annotations

from pathlib import Path

from cosim import scenario
from cosim.scenario import ScenarioFile

MACHINE_SUFFIX = ".toml"


def examples() -> list[Path]:
    """The example machine files (``examples/**/*.toml`` of the checkout, or the installed copy), sorted."""
    from cosim.fmubuild import data_dir

    folder = data_dir("examples", "examples")
    return sorted(folder.glob("**/*.toml")) if folder.is_dir() else []


def shown(path: Path) -> str:
    """A path as ``cosim list`` shows it: relative to the current folder when it is inside it."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def load(name_or_path: str | Path) -> ScenarioFile:
    """A bundled scenario by name, a scenario script (``.py``) or a machine file (``.toml``)."""
    if Path(name_or_path).suffix == MACHINE_SUFFIX:
        from cosim.machine import load_machine

        return load_machine(name_or_path)
    return scenario.load(name_or_path)


def description(name_or_path: str | Path) -> str:
    """The one-line description of a scenario or machine file, read without running it."""
    if Path(name_or_path).suffix == MACHINE_SUFFIX:
        from cosim.machine.document import machine_description

        return machine_description(Path(name_or_path))
    return scenario.description(name_or_path)
