"""Scenario scripts and the runner: parameters, errors with file and line, results on disk."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.errors import ConfigurationError, ScenarioError
from cosim.runner import run_scenario
from cosim.scenario import Param, load

BLINK = '''
"""Blink a gate: on for on_us, off for off_us, n times."""
from cosim.scenario import Param, Run
from cosim.signals import Signal

PARAMETERS = (
    Param("on_us", 100, "us", (1, 1000), "gate-on time"),
    Param("n", 3, "", (1, 10), "number of blinks"),
    Param("limit_us", 150, "us", (1, 1000), "longest allowed gate-on time"),
)
UNTIL = "2 ms"


@dataclass_free
class LongestHigh:
    signal: str
    limit_ns: int

    def evaluate(self, trace):
        from types import SimpleNamespace
        t, v = trace.edges(self.signal)
        widths = [int(b - a) for a, b, level in zip(t[:-1], t[1:], v[:-1]) if level]
        bad = [w for w in widths if w > self.limit_ns]
        return SimpleNamespace(to_dict=lambda: {
            "name": f"{self.signal} high at most {self.limit_ns} ns", "passed": not bad,
            "checked": len(widths), "n_violations": len(bad),
            "violations": [{"t_ns": 0, "value": w, "limit": self.limit_ns, "detail": ""} for w in bad],
            "measured": {"max_high_ns": max(widths, default=0)}})


def scenario(run: Run) -> None:
    sim = run.sim
    gate = Signal(sim, "blink.gate")
    on = sim.ticks(run.p.on_us, "us")

    def blink():
        for k in range(run.p.n):
            yield sim.at(k * 500_000)
            gate.set(1)
            yield sim.at(k * 500_000 + on)
            gate.set(0)

    sim.process(blink())
    run.check(LongestHigh("blink.gate", sim.ticks(run.p.limit_us, "us")))
    run.figure("blinks", run.p.n)
'''.replace("@dataclass_free", "from dataclasses import dataclass\n@dataclass")


def _script(tmp_path: Path, text: str, name: str = "blink.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


@pytest.mark.parametrize(
    ("param", "text", "expected"),
    [
        (Param("n", 3, "", (1, 10)), "7", 7),
        (Param("n", 3, "", (1, 10)), "0x0A", 10),
        (Param("x", 1.0, "W", (0.0, 5.0)), "2.5", 2.5),
        (Param("on", False), "on", True),
        (Param("mode", "usb", "", ("usb", "ethernet")), "ethernet", "ethernet"),
        (Param("n", 3, "", (1, 10)), "11", r"parameter n = 11 is not allowed \(allowed: 1..10\)"),
        (Param("n", 3, "", (1, 10)), "2.5", r"parameter n = '2.5' is not an integer \(allowed: 1..10\)"),
        (Param("x", 1.0, "W", (0.0, 5.0)), "lots", r"parameter x = 'lots' is not a number \(allowed"),
        (Param("x", 1.0, "W", (0.0, 5.0)), "9", r"parameter x = 9.0 is not allowed \(allowed: 0.0..5.0 W\)"),
        (Param("mode", "usb", "", ("usb", "ethernet")), "can", r"allowed: usb, ethernet"),
        (Param("on", False), "maybe", r"parameter on = 'maybe' is not a flag \(true/false, on/off"),
    ],
)
def test_param_parse_table(param: Param, text: str, expected: object) -> None:
    if isinstance(expected, str) and ("allowed" in expected or "is not a" in expected):
        with pytest.raises(ConfigurationError, match=str(expected)):
            param.parse(text)
    else:
        assert param.parse(text) == expected


def test_run_passes_and_writes_results(tmp_path: Path) -> None:
    scenario = load(_script(tmp_path, BLINK))
    assert scenario.description == "Blink a gate: on for on_us, off for off_us, n times."
    result = run_scenario(scenario, out=tmp_path / "out")
    assert result.verdict == "PASS"
    data = json.loads((tmp_path / "out" / "result.json").read_text())
    assert data["parameters"] == {"on_us": 100, "n": 3, "limit_us": 150}
    assert data["summary"] == {"checks": 1, "passed": 1, "failed": 0, "unchecked": 0, "hazards": 0,
                               "hazards_shown": 0}
    assert data["hazards"] == [] and data["checks"][0]["verdict"] == "PASS" and data["checks"][0]["hazard"] is None
    assert data["checks"][0]["measured"] == {"max_high_ns": 100_000}
    assert (tmp_path / "out" / "trace.vcd").exists() and (tmp_path / "out" / "edges.parquet").exists()


def test_set_changes_the_result(tmp_path: Path) -> None:
    scenario = load(_script(tmp_path, BLINK))
    result = run_scenario(scenario, overrides={"on_us": "200"})
    assert result.verdict == "FAIL"
    assert result.checks[0]["n_violations"] == 3
    assert result.checks[0]["violations"][0]["value"] == 200_000


def test_unknown_and_out_of_range_parameters(tmp_path: Path) -> None:
    scenario = load(_script(tmp_path, BLINK))
    with pytest.raises(ConfigurationError, match=r"has no parameter 'of_us' .*on_us, n, limit_us"):
        scenario.resolve({"of_us": "1"})
    with pytest.raises(ConfigurationError, match=r"parameter n = 42 is not allowed \(allowed: 1..10\)"):
        scenario.resolve({"n": "42"})


def test_syntax_error_names_file_and_line(tmp_path: Path) -> None:
    path = _script(tmp_path, BLINK.replace("gate.set(1)", "gate.set(1", 1))
    with pytest.raises(ScenarioError, match=rf"{path}:\d+: syntax error"):
        load(path)


def test_missing_parameter_names_file_and_line(tmp_path: Path) -> None:
    text = BLINK.replace("range(run.p.n)", "range(run.p.count)")
    path = _script(tmp_path, text)
    line = next(i for i, s in enumerate(textwrap.dedent(text).splitlines(), 1) if "run.p.count" in s)
    result = run_scenario(load(path), out=tmp_path / "out")
    assert result.verdict == "ERROR"
    assert result.error is not None
    assert result.error.startswith(f"{path}:{line}: the scenario uses parameter 'count'")
    assert "declared: on_us, n, limit_us" in result.error
    assert (tmp_path / "out" / "trace.vcd").exists()  # nothing recorded is lost


def test_failure_mid_run_keeps_the_trace(tmp_path: Path) -> None:
    text = BLINK.replace("            gate.set(0)\n", "            gate.set(0)\n            1 / (k - 1)\n")
    path = _script(tmp_path, text)
    result = run_scenario(load(path), out=tmp_path / "out")
    assert result.verdict == "ERROR" and "ZeroDivisionError" in (result.error or "")
    from cosim.export import read_trace

    back = read_trace(tmp_path / "out")
    assert back.edges("blink.gate")[0].tolist() == [0, 0, 100_000, 500_000, 600_000]


def test_cli_exit_codes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = str(_script(tmp_path, BLINK))
    assert main(["run", path, "--out", str(tmp_path / "a")]) == 0
    assert "PASS" in capsys.readouterr().out
    assert main(["run", path, "--set", "on_us=200", "--out", str(tmp_path / "b")]) == 1
    assert main(["run", path, "--set", "n=99", "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "parameter n = 99 is not allowed (allowed: 1..10)" in err
    assert main(["run", "no_such_scenario"]) == 2
    assert main(["run", path, "--set", "oops"]) == 2
    assert main(["params", path]) == 0
    assert "limit_us" in capsys.readouterr().out



@pytest.mark.parametrize("until", ["-1 s", "0 s", "0 ms"])
def test_zero_or_negative_until_is_refused_before_the_run(until: str, capsys: pytest.CaptureFixture[str]) -> None:
    from cosim.cli import main

    assert main(["run", "pokeys_jog_limit", "--until", until, "--out", "/tmp/cosim-never-written"]) == 2
    assert f"until = '{until}' is not allowed (allowed: a time > 0" in capsys.readouterr().err
