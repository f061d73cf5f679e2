"""Which plant variable plays which role in a coupling: the one place a plant's names are mapped.

Every coupling declares its *roles* (what it needs of a plant, e.g. the laser coupling's
``period_clocks``) with the variable names of the bundled FMU as defaults. A user's FMU with
other names is coupled by a mapping ``{role: variable}`` (in Python, or in a machine file's
``variables`` table); a role mapped to ``None`` is left unconnected where the coupling allows it.
:func:`resolve` checks every name against the plant before anything runs.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from typing import Protocol

from cosim.errors import ConfigurationError


class Named(Protocol):
    """What :func:`resolve` needs of a plant: its name and its variables."""

    name: str

    def variable_names(self) -> list[str]:
        """Every variable the plant has."""
        ...


def resolve(plant: Named, coupling: str, defaults: Mapping[str, str | None],
            variables: Mapping[str, str | None] | None = None, *,
            optional: Iterable[str] = ()) -> dict[str, str | None]:
    """The plant variable of each role: ``defaults`` with the user's ``variables`` over them.

    Parameters
    ----------
    plant : Named
        The plant being coupled.
    coupling : str
        Name of the coupling, for messages (``"laser"``).
    defaults : mapping role -> variable
        The bundled FMU's names.
    variables : mapping role -> variable or None, optional
        The user's mapping; ``None`` leaves a role unconnected (only for ``optional`` roles).
    optional : iterable of str
        Roles that may be unconnected, and that are dropped silently when the plant lacks their
        default variable.

    Raises
    ------
    ConfigurationError
        An unknown role, a required role mapped to None, or a variable the plant does not have
        (the message names the role, the variable and the closest names the plant has).
    """
    optional = frozenset(optional)
    mapping = dict(defaults)
    for role, variable in (variables or {}).items():
        if role not in defaults:
            raise ConfigurationError.out_of_range(f"{coupling} coupling role", role, ", ".join(defaults),
                                                  where=f"variables of {plant.name}")
        mapping[role] = variable
    known = plant.variable_names()
    for role, variable in mapping.items():
        user_given = variables is not None and role in variables
        if variable is None:
            if role not in optional:
                raise ConfigurationError(f"{coupling} coupling of {plant.name}: role {role!r} is required and "
                                         "cannot be left unconnected")
        elif variable not in known:
            if role in optional and not user_given:
                mapping[role] = None
                continue
            close = difflib.get_close_matches(variable, known, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f" (its variables: {', '.join(known)})"
            raise ConfigurationError(f"{coupling} coupling of {plant.name}: role {role!r} is mapped to "
                                     f"{variable!r}, which {plant.name} does not have{hint}")
    return mapping


def required(mapping: Mapping[str, str | None], role: str) -> str:
    """The variable of a role that :func:`resolve` guaranteed to be connected."""
    variable = mapping[role]
    assert variable is not None, role
    return variable
