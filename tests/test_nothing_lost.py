"""Nothing lost, nothing silently wrong: output folders, interrupts, failing figures and checks, sys.exit.

    run 1 (parquet) ──> out/ {result.json, edges.parquet, ...}
    run 2 (csv)     ──> out/ {result.json, edges.csv, ...}      no file of run 1 survives
    Ctrl-C at 5 ms  ──> out/ {result.json: INTERRUPTED, trace up to 5 ms}, exit 130
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from cosim.cli import main
from cosim.export import read_trace
from cosim.kernel import Simulation
from cosim.outdir import MARK
from cosim.runner import run_scenario
from cosim.scenario import load

BLINK = '''"""A gate blinking every 100 us."""
from cosim.scenario import Param, Run
from cosim.signals import Signal
PARAMETERS = (Param("period_us", 100, "us", (1, 1000)),)
UNTIL = "1 ms"

def scenario(run: Run) -> None:
    gate = Signal(run.sim, "blink.gate")
    def blink():
        k = 0
        while True:
            yield run.sim.at(k * run.sim.ticks(run.p.period_us, "us"))
            gate.set(k % 2)
            k += 1
    run.sim.process(blink())
'''


def _script(tmp_path: Path, text: str, name: str = "blink.py") -> Path:
    path = tmp_path / "scripts" / name
    path.parent.mkdir(exist_ok=True)
    path.write_text(text)
    return path


def test_a_second_run_replaces_the_first_completely(tmp_path: Path) -> None:
    script, out = _script(tmp_path, BLINK), tmp_path / "out"
    assert main(["run", str(script), "--out", str(out), "--allow-unchecked"]) == 0
    assert (out / "edges.parquet").is_file() and (out / MARK).is_file()
    assert main(["run", str(script), "--out", str(out), "--format", "csv", "--set", "period_us=200",
                 "--allow-unchecked"]) == 0
    assert not list(out.glob("*.parquet"))  # not a single file of the first run survives
    t, _v = read_trace(out).edges("blink.gate")
    assert t.tolist()[:3] == [0, 200_000, 400_000]  # the second run's edges (every 200 us), from its own tables
    assert json.loads((out / "result.json").read_text())["parameters"]["period_us"] == 200


def test_a_folder_cosim_did_not_write_is_refused_and_left_alone(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    assert main(["run", str(_script(tmp_path, BLINK)), "--out", str(out)]) == 2
    assert "holds files cosim did not write (notes.txt)" in capsys.readouterr().err
    assert [p.name for p in out.iterdir()] == ["notes.txt"]


def test_an_unwritable_out_is_found_before_the_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert main(["run", str(_script(tmp_path, BLINK)), "--out", str(blocker / "sub")]) == 2
    assert f"--out {blocker / 'sub'}: {blocker} is a file, not a folder" in capsys.readouterr().err


@pytest.mark.parametrize(("signum", "name"), [(signal.SIGINT, "SIGINT"), (signal.SIGTERM, "SIGTERM")])
def test_an_interrupted_run_keeps_what_it_simulated(tmp_path: Path, signum: int, name: str) -> None:
    """A signal at 500 us: the run ends there, the trace up to it and the checks on it are written."""
    text = BLINK.replace('UNTIL = "1 ms"', 'UNTIL = "10 ms"') + f'''
    def interrupt():
        yield run.sim.at(run.sim.ticks("500 us"))
        import os
        os.kill(os.getpid(), {int(signum)})
    run.sim.process(interrupt())
    from cosim.checks import ValueAt
    run.check(ValueAt("blink.gate", None, 1, name="the gate is on at the end"))
'''
    out = tmp_path / "out"
    assert main(["run", str(_script(tmp_path, text)), "--out", str(out)]) == 130
    result = json.loads((out / "result.json").read_text())
    assert result["verdict"] == "INTERRUPTED" and result["interrupted"]["signal"] in (name, "SIGINT")
    assert result["interrupted"]["t_ticks"] == 500_000 and result["checks"][0]["checked"] == 1
    t, _v = read_trace(out).edges("blink.gate")
    assert t.tolist()[-1] == 500_000  # edges up to the interrupt, nothing after


def test_a_figure_or_a_check_that_raises_is_an_error_entry_and_the_rest_is_kept(tmp_path: Path) -> None:
    text = BLINK + '''
    from cosim.checks import ValueAt
    class Boom:
        label = "my custom check"
        def evaluate(self, trace):
            raise RuntimeError("custom check blew up")
    run.check(ValueAt("blink.gate", None, 1, name="gate on at the end"))
    run.check(Boom())
    run.check(ValueAt("blink.gat", None, 1, name="misspelt signal"))
    run.figure("good", 2.5, "s")
    run.figure("text", lambda: "not a number")
'''
    script = _script(tmp_path, text)
    result = run_scenario(load(script), out=tmp_path / "out")
    assert result.verdict == "ERROR" and (tmp_path / "out" / "trace.vcd").is_file()
    good, boom, misspelt = result.checks
    assert good["passed"] and good["checked"] == 1
    raised = 1 + text.splitlines().index('            raise RuntimeError("custom check blew up")')
    assert boom["error"] == f"{script}:{raised}: check my custom check: RuntimeError: custom check blew up"
    assert misspelt["error"].startswith(f"{script}:")  # the line that declared it
    assert "no signal named 'blink.gat' in the trace; did you mean blink.gate" in misspelt["error"]
    assert result.figures["good"] == {"value": 2.5, "unit": "s"}
    assert result.figures["text"]["value"] is None
    declared = 1 + text.splitlines().index('    run.figure("text", lambda: "not a number")')
    assert result.figures["text"]["error"] == (f"{script}:{declared}: figure text: TypeError: the value 'not a number' "
                                               "is a str, not a number")
    assert "  figure text = (could not be evaluated: see the error)" in result.table().splitlines()
    assert json.loads((tmp_path / "out" / "result.json").read_text())["checks"][0]["passed"] is True


def test_sys_exit_in_a_scenario_is_an_error_of_the_run_not_of_cosim(tmp_path: Path) -> None:
    text = BLINK + "    raise SystemExit(0)\n"
    out = tmp_path / "out"
    assert main(["run", str(_script(tmp_path, text)), "--out", str(out)]) == 1
    result = json.loads((out / "result.json").read_text())
    assert result["verdict"] == "ERROR" and "the scenario called sys.exit(0)" in result["error"]


@pytest.mark.fmu
def test_long_sampled_runs_report_progress_although_they_run_without_kernel_events() -> None:
    from cosim.master import Plant

    sim = Simulation()
    laser = Plant.load(sim, "Laser", name="laser")
    laser.record(["power"], period=sim.ticks("10 us"))
    seen: list[int] = []
    sim.env.on_progress = seen.append
    sim.run(until=sim.ticks("200 ms"))
    assert len(seen) >= 4 and seen == sorted(seen) and seen[-1] > sim.ticks("150 ms")
    sim.close()


def test_the_staging_folder_is_not_left_behind(tmp_path: Path) -> None:
    assert main(["run", str(_script(tmp_path, BLINK)), "--out", str(tmp_path / "out"), "--allow-unchecked"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "scripts"]
    assert os.listdir(tmp_path / "out").count(MARK) == 1
