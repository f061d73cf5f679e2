"""The machine-file loader under generated and mutated input: it may only raise cosim's own errors.

A longer run of the same properties (bench/fuzz_machine.py) covers about a million inputs.
"""

from __future__ import annotations

import contextlib
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cosim.errors import CosimError
from cosim.machine import load_machine
from cosim.machine.check import check_machine

SEED = """[machine]
description = "fuzz seed"
until = "5 ms"

[controller]
family = "pokeys"
model = "56E"
[controller.axis.x]
max_speed_hz = 20000
accel = 200000

[host]
link = "usb"
prefill = 16

[[move]]
target = [40, 0, 0]

[[check]]
type = "PulsesPerWindow"
signal = "pokeys.x.step"
max_count = 25
window = "1 ms"

[[figure]]
name = "peak"
signal = "pokeys.buffer_level"
reduce = "max"
"""

KEYS = ["machine", "controller", "family", "model", "axis", "x", "max_speed_hz", "accel", "host", "link",
        "prefill", "move", "target", "check", "type", "signal", "window", "figure", "reduce", "until", "plant",
        "stepper", "variables", "record", "period", "stimulus", "at", "values", "program", "file", "export"]
VALUES = st.one_of(st.integers(-(2**70), 2**70), st.floats(allow_nan=True, allow_infinity=True),
                   st.text(max_size=12), st.booleans(), st.lists(st.integers(-5, 5), max_size=4),
                   st.sampled_from(["1 ms", "-1 s", "0 s", "1e9 s", "abc", "pokeys", "trio", "usb", "x", "max"]))


def _try(path: Path) -> None:
    with contextlib.suppress(CosimError):
        check_machine(load_machine(path))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_machine_text_raises_only_cosim_errors(tmp_path: Path, data: st.DataObject) -> None:
    text = bytearray(SEED.encode())
    for _ in range(data.draw(st.integers(1, 4))):
        k = data.draw(st.integers(0, len(text) - 1))
        op = data.draw(st.sampled_from(["replace", "delete", "insert"]))
        byte = data.draw(st.integers(0, 255))
        if op == "replace":
            text[k] = byte
        elif op == "delete":
            del text[k]
        else:
            text.insert(k, byte)
    path = tmp_path / "machine.toml"
    path.write_bytes(bytes(text))
    _try(path)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(path_=st.lists(st.sampled_from(KEYS), min_size=1, max_size=3), value=VALUES)
def test_any_key_set_to_any_value_raises_only_cosim_errors(tmp_path: Path, path_: list[str], value: object) -> None:
    document = tomllib.loads(SEED)
    node = document
    for part in path_[:-1]:
        child = node.get(part)
        if not isinstance(child, dict):
            child = node[part] = {}
        node = child
    node[path_[-1]] = value
    machine = load_machine_from(document, tmp_path)
    if machine is not None:
        _try(machine)


def load_machine_from(document: dict[str, object], folder: Path) -> Path | None:
    """The document as a machine file (None when it cannot be written as TOML, e.g. a NaN in a list)."""
    import math

    def toml(value: object) -> str:
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, float):
            if math.isnan(value):
                return "nan"
            return ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
        if isinstance(value, str):
            return '"' + value.replace("\\", "\\\\").replace('"', '\\"').encode("unicode_escape").decode() + '"'
        if isinstance(value, list):
            return "[" + ", ".join(toml(v) for v in value) + "]"
        if isinstance(value, dict):
            return "{" + ", ".join(f'"{k}" = {toml(v)}' for k, v in value.items()) + "}"
        return str(value)

    lines = []
    for key, value in document.items():
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                lines.append(f"[[{key}]]")
                lines += [f'"{k}" = {toml(v)}' for k, v in item.items()]
        else:
            lines.append(f'"{key}" = {toml(value)}')
    path = folder / "machine.toml"
    path.write_text("\n".join(lines) + "\n")
    try:
        tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError:
        return None
    return path


@pytest.mark.parametrize("text", ["", "\x00\x01", "[machine]\nuntil = 5\n", "[[machine]]\n", "machine = 3\n",
                                  "[machine]\nuntil = \"1 ms\"\n[controller]\nfamily = 3\n"])
def test_degenerate_machine_files_raise_only_cosim_errors(tmp_path: Path, text: str) -> None:
    path = tmp_path / "machine.toml"
    path.write_text(text)
    with pytest.raises(CosimError):
        check_machine(load_machine(path))
