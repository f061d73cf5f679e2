"""Parameter presets of real devices, kept as TOML files in ``models/presets/``.

An installed cosim carries the same files inside the package (``cosim/_data/presets/``); ``PRESETS``
is whichever of the two this copy of cosim has (see :func:`cosim.fmubuild.data_dir`).

A preset file names the model it is for, cites its sources, and lists FMU parameter values in
SI units::

    model = "Laser"
    description = "40 W sealed CO2 laser tube"
    sources = ["datasheet ..."]
    [parameters]
    peak_power = 40.0
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from cosim.errors import ConfigurationError
from cosim.fmubuild import data_dir

#: The preset folder: ``models/presets`` of the source checkout, or the copy inside the installed package.
PRESETS: Path = data_dir("models/presets", "presets")


def available() -> list[str]:
    """Names of the presets in :data:`PRESETS`."""
    return sorted(p.stem for p in PRESETS.glob("*.toml"))


def read_preset(name: str) -> dict[str, Any]:
    """The whole preset file ``name`` (without ``.toml``) as a dict."""
    path = PRESETS / f"{name}.toml"
    if not path.exists():
        raise ConfigurationError(
            f"no preset named {name!r} in {PRESETS} (available: {', '.join(available()) or 'none'})"
        )
    with path.open("rb") as stream:
        return tomllib.load(stream)


def load_preset(name: str) -> dict[str, float | int | bool]:
    """FMU parameter values of preset ``name``."""
    return dict(read_preset(name).get("parameters", {}))
