"""``cosim params MACHINE.toml``: every key of a machine file with its value, unit and allowed values.

The builder's typed getters say what each key takes as they read it (:class:`~cosim.machine.document.KeySpec`);
what they read as raw values and hand on is described here: the loader's ``[machine]`` keys, a
Trio axis parameter by its vendor name (its unit and range from :mod:`cosim.controllers.trio.params`),
a plant's FMU parameters (unit and range from the FMU's model description), a check's parameters
(from the check's annotations; times with their unit).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from cosim.machine.document import KeySpec, Table, leaves

#: The ``[machine]`` keys the loader reads.
LOADER = {"name": ("", "text (default: the file's name)"),
          "description": ("", "text (cosim list shows its first line)"),
          "until": ("time", "a time with a unit, e.g. \"2 s\""),
          "resolution": ("time", "a time with a unit, ps..s (default \"1 ns\")")}


#: What family keys take where the family reads them without saying (``family: {key: (unit, allowed)}``;
#: ``*`` stands for one table of an array or an axis).
FAMILY_KEYS: dict[str, dict[str, tuple[str, str]]] = {
    "trio": {"controller.servo_period_us": ("us", "250, 500, 1000, 2000 (SERVO_PERIOD)"),
             "controller.n_axes": ("", "4..64"), "controller.table_size": ("entries", ">= 1"),
             "controller.encoder_at_atype": ("", "0..536870911 (raw PWM_ENCODER after ATYPE=35)"),
             "program[*].base": ("", "a list of axis numbers, e.g. [3, 2]")},
    "pokeys": {"controller.model": ("", "56E, 56U, 57E, 57CNC"),
               "controller.dir_setup": ("time", "a time with a unit, e.g. \"5 us\""),
               "controller.pulse_width": ("time", "a time with a unit, e.g. \"5 us\""),
               "controller.axis.*.max_speed_hz": ("Hz", "> 0, at most the model's rate (25 kHz on a 56E)"),
               "controller.axis.*.accel": ("pulses/s^2", "> 0"), "controller.axis.*.decel": ("pulses/s^2", "> 0"),
               "move[*].target": ("pulses", "a list of pulse counts, one per axis"),
               "move[*].speed_hz": ("Hz", "> 0 (optional)"),
               "plant.*.stepper.axis": ("", "an axis name (x, y, z, ...) or its index"),
               "plant.*.switches.axis": ("", "an axis name (x, y, z, ...) or its index")},
    "pmac": {"controller.setup": ("", "a PMAC file or a list of them, relative to the machine file")},
}
_GENERIC = ("", "text", "any integer", "a number")


def loader_keys(document: Table) -> list[KeySpec]:
    """The ``[machine]`` keys, as the loader reads them."""
    machine = document.data.get("machine", {})
    return [KeySpec(f"machine.{key}", machine.get(key), key in machine, unit, allowed)
            for key, (unit, allowed) in LOADER.items()]


def describe(data: Mapping[str, Any], specs: list[KeySpec], *, plants: Mapping[str, Any]) -> list[KeySpec]:
    """``specs`` and, for every key of ``data`` they do not describe, what is known of it, in file order first."""
    name = str(data.get("controller", {}).get("family"))
    family = FAMILY_KEYS.get(name, {})
    known = {spec.key: _family(spec, family) for spec in specs}
    out: list[KeySpec] = []
    for key, value in leaves(data):
        spec = known.pop(key, None) or _family(_described(key, value, data, plants), family)
        if not spec.allowed and key.startswith("controller."):
            spec = KeySpec(spec.key, spec.value, spec.given, spec.unit, f"read by the {name} family")
        out.append(spec)
    # keys the file does not give, with their defaults (an array table's optional keys without one are left out)
    return out + [spec for spec in known.values() if spec.value is not None or "[" not in spec.key]


def _family(spec: KeySpec, family: Mapping[str, tuple[str, str]]) -> KeySpec:
    """``spec`` with the family's own description where the builder's says nothing particular."""
    if spec.allowed not in _GENERIC:
        return spec
    pattern = re.sub(r"\[\d+\]", "[*]", spec.key)
    pattern = re.sub(r"^controller\.axis\.[^.]+\.", "controller.axis.*.", pattern)
    pattern = re.sub(r"^plant\.[^.]+\.", "plant.*.", pattern)
    found = family.get(pattern)
    return spec if found is None else KeySpec(spec.key, spec.value, spec.given, found[0] or spec.unit, found[1])


def _described(key: str, value: Any, data: Mapping[str, Any], plants: Mapping[str, Any]) -> KeySpec:
    parts = key.split(".")
    family = data.get("controller", {}).get("family")
    if family == "trio" and len(parts) == 4 and parts[:2] == ["controller", "axis"]:
        from cosim.controllers.trio.params import AXIS_PARAMS

        spec = AXIS_PARAMS.get(parts[3].upper())
        if spec is not None:
            return KeySpec(key, value, True, spec.unit, f"{spec.allowed} (default {spec.default}): {spec.doc}")
    if len(parts) == 4 and parts[0] == "plant" and parts[2] == "parameters" and parts[1] in plants:
        fmu = getattr(plants[parts[1]], "fmu", None)
        variable = fmu.variables.get(parts[3]) if fmu is not None else None
        if variable is not None:
            return KeySpec(key, value, True, variable.unit, f"{variable.allowed()} (FMU parameter)")
    return KeySpec(key, value, True, "", "")
