"""Notes of a run: what a user should know that is neither a check nor a figure.

Two kinds, both kept on the simulation (``sim.notes``) so that controllers, which know the
simulation but not the run, can add them:

* plain notes: one line each ("G64 P0.05 blends corners within 0.05 mm"); a note with a ``key``
  replaces an earlier note of the same key (a count that grows during the run);
* settings that were **set, not modelled**: a program or a machine file set something the
  controller documents (a Trio gain, a PMAC I-variable, a G-code override) whose effect on timing
  the model does not implement. The value is stored and readable back; here it is listed, once per
  device and name with its last value and where it was set, so that nothing is silently dropped.

The runner copies both into ``result.json`` (``notes``, ``not_modelled``) and the table.

Examples
--------
>>> notes = Notes()
>>> notes.not_modelled("trio", "P_GAIN(axis 0)", 1.5, where="line.bas:4")
>>> notes.not_modelled("trio", "P_GAIN(axis 0)", 2.0, where="line.bas:9")
>>> notes.add("the gate is off after the job")
>>> notes.texts()
['the gate is off after the job', 'trio: set, not modelled (1): P_GAIN(axis 0) = 2.0']
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: How many names a device's summary line spells out before "and N more".
SUMMARY_NAMES = 12


@dataclass(frozen=True)
class NotModelled:
    """A setting that was accepted and stored but does not act in the model."""

    device: str
    name: str
    value: Any
    where: str = ""

    def to_dict(self) -> dict[str, Any]:
        value = self.value if isinstance(self.value, int | float | str | bool) else str(self.value)
        return {"device": self.device, "name": self.name, "value": value, "where": self.where}


class Notes:
    """The notes of one simulation (see the module doc)."""

    def __init__(self) -> None:
        self._plain: dict[str, str] = {}
        self._unmodelled: dict[tuple[str, str], NotModelled] = {}

    def add(self, text: str, *, key: str | None = None) -> None:
        """Add a note; with ``key``, replace the earlier note of that key (keeping its place)."""
        text = str(text)
        self._plain[text if key is None else f"\0{key}"] = text

    def not_modelled(self, device: str, name: str, value: Any, *, where: str = "") -> None:
        """Record that ``name`` of ``device`` was set to ``value`` (at ``where``: file:line) and does not act."""
        key = (str(device), str(name))
        self._unmodelled.pop(key, None)  # the last setting wins, listed in the order last set
        self._unmodelled[key] = NotModelled(key[0], key[1], value, str(where))

    def unmodelled(self) -> list[NotModelled]:
        """Every setting set, not modelled, in the order last set."""
        return list(self._unmodelled.values())

    def texts(self) -> list[str]:
        """The plain notes, then one summary line per device of the settings set, not modelled."""
        lines = list(self._plain.values())
        by_device: dict[str, list[NotModelled]] = {}
        for item in self._unmodelled.values():
            by_device.setdefault(item.device, []).append(item)
        for device, items in by_device.items():
            named = ", ".join(f"{i.name} = {i.value}" for i in items[:SUMMARY_NAMES])
            more = f" and {len(items) - SUMMARY_NAMES} more (result.json: not_modelled)" \
                if len(items) > SUMMARY_NAMES else ""
            lines.append(f"{device}: set, not modelled ({len(items)}): {named}{more}")
        return lines

    def __len__(self) -> int:
        return len(self._plain) + len(self._unmodelled)
