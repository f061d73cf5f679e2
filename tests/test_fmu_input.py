"""Input tables: an FMU's inputs over time from a CSV file (run-fmu --input, [plant.x] input).

The FeedthroughTest FMU copies each input to its output at once, so what run-fmu records at a grid
point is the input the table gave there. The table below, on a 0.25 s grid::

    time [s]                    0     0.25   0.5|0.5   0.75   1.0   1.25   1.5 ... 2.0
    continuous (interpolated)   0     0.5    1 | 2     1      0     -1     -1       -1
    discrete   (held)           0     0      1 | 2     2      2     3      3         3
    Int32                       0     0      1 | 2     2      2     3      3         3
    Boolean                     0     0      0 | 1     1      1     0      0         0

(two rows at 0.5 s: a jump, the later row holds from that instant on; after the last row, at
1.25 s, its values hold). The expected values are the table's own numbers, interpolated by hand.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from cosim.cli import main
from cosim.export import read_trace
from cosim.fmu import Fmu
from cosim.fmubuild import ensure_fmu
from cosim.fmuinput import read_input_table
from cosim.timebase import TimeBase

pytestmark = pytest.mark.fmu

TABLE = """time,Float64_continuous_input,Float64_discrete_input,Int32_input,Boolean_input
0,0,0,0,false
0.5,1,1,1,false
0.5,2,2,2,true
1.25,-1,3,3,false
"""
#: The outputs at 0, 0.25, ... 2.0 s (the table at each grid point, worked out by hand).
EXPECTED = {
    "Float64_continuous_output": [0, 0.5, 2, 1, 0, -1, -1, -1, -1],
    "Float64_discrete_output": [0, 0, 2, 2, 2, 3, 3, 3, 3],
    "Int32_output": [0, 0, 2, 2, 2, 3, 3, 3, 3],
    "Boolean_output": [0, 0, 1, 1, 1, 0, 0, 0, 0],
}
GRID_NS = [k * 250_000_000 for k in range(9)]


def write(folder: Path, text: str, name: str = "inputs.csv") -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("fmi_version", [2, 3])
def test_the_outputs_equal_the_interpolated_table_at_every_grid_point(fmi_version: int, tmp_path: Path) -> None:
    table = write(tmp_path, TABLE)
    out = tmp_path / "out"
    code = main(["run-fmu", str(ensure_fmu("FeedthroughTest", fmi_version)), "--input", str(table),
                 "--step", "0.25 s", "--until", "2 s", "--out", str(out)])
    assert code == 0
    trace = read_trace(out)
    for output, values in EXPECTED.items():
        t, recorded = trace.edges(f"feedthroughtest.{output.lower()}")
        assert t.tolist() == GRID_NS, output
        assert recorded.tolist() == pytest.approx(values, abs=1e-15), output
    with (out / "outputs.csv").open() as handle:  # the FMU's own names, case and all
        rows = list(csv.reader(handle))
    assert rows[0] == ["time", *EXPECTED]
    assert [float(row[0]) for row in rows[1:]] == [k * 0.25 for k in range(9)]
    assert [float(row[1]) for row in rows[1:]] == pytest.approx(EXPECTED["Float64_continuous_output"], abs=1e-15)


def test_between_grid_points_the_fmu_holds_the_value_at_the_start_of_each_step(tmp_path: Path) -> None:
    """A ramp from 0 at 0 s to 1 at 1 s, read on a 0.1 s grid: 0.1 k at each point, as the table says."""
    table = write(tmp_path, "time,Float64_continuous_input\n0,0\n1,1\n")
    out = tmp_path / "out"
    assert main(["run-fmu", str(ensure_fmu("FeedthroughTest", 3)), "--input", str(table), "--step", "0.1 s",
                 "--until", "1 s", "--out", str(out)]) == 0
    t, values = read_trace(out).edges("feedthroughtest.float64_continuous_output")
    assert t.tolist() == [k * 100_000_000 for k in range(11)]
    assert values.tolist() == pytest.approx([k / 10 for k in range(11)], abs=1e-15)


def test_a_table_times_are_exact_ticks_and_its_values_are_checked_by_type(tmp_path: Path) -> None:
    variables = Fmu(ensure_fmu("FeedthroughTest", 3)).variables
    table = read_input_table(write(tmp_path, TABLE), variables, timebase=TimeBase())
    assert table.times == (0, 500_000_000, 500_000_000, 1_250_000_000)
    assert table.continuous == ("Float64_continuous_input",)
    assert table.values["Boolean_input"] == (False, False, True, False)
    assert table.at(499_999_999)["Int32_input"] == 0 and table.at(500_000_000)["Int32_input"] == 2


@pytest.mark.parametrize(("text", "message"), [
    ("t,Int32_input\n0,1\n", "inputs.csv:1: the header must be time,<input>,<input>,..."),
    ("time,Int32_inptu\n0,1\n", "inputs.csv:1: column 'Int32_inptu' is not a variable of the FMU; did you mean "
                                "Int32_input?"),
    ("time,Int32_output\n0,1\n", "inputs.csv:1: column 'Int32_output' is an output (discrete): a table drives "
                                 "inputs and tunable parameters"),
    ("time,Int32_input\n0,1\n0.0000000001,2\n", "inputs.csv:3: time = 0.0000000001 s is not a whole number of "
                                                "ticks of the resolution 1 ns (0.1 ticks)"),
    ("time,Int32_input\n0.5,1\n0.25,2\n", "inputs.csv:3: time 0.25 s is earlier than the row before (0.5 s)"),
    ("time,Int32_input\n0,2147483648\n", "inputs.csv:2: Int32_input = 2147483648 is not allowed (allowed: "
                                         "-2147483648..2147483647)"),
    ("time,Boolean_input\n0,maybe\n", "inputs.csv:2: Boolean_input = 'maybe' is not allowed (allowed: true or "
                                      "false)"),
    ("time,Int32_input\n0,1,2\n", "inputs.csv:2: 3 cells where the header has 2"),
    ("time,Int32_input\nsoon,1\n", "inputs.csv:2: time 'soon' is not a number of seconds"),
    # nan and inf used to reach the FMU, which refused them as the run started: ERROR, exit 1
    ("time,Float64_continuous_input\n0,0\n1,nan\n", "inputs.csv:3: Float64_continuous_input = 'nan' is not "
                                                     "allowed (allowed: any finite number)"),
    ("time,Float64_discrete_input\n0,-inf\n", "inputs.csv:2: Float64_discrete_input = '-inf' is not allowed"),
])
def test_a_bad_table_is_refused_with_its_file_line_column_and_what_is_allowed(
        tmp_path: Path, text: str, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    table = write(tmp_path, text)
    assert main(["run-fmu", str(ensure_fmu("FeedthroughTest", 3)), "--input", str(table),
                 "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err, err


def test_a_missing_table_and_an_input_given_twice_are_refused(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    fmu = str(ensure_fmu("FeedthroughTest", 3))
    assert main(["run-fmu", fmu, "--input", str(tmp_path / "none.csv"), "--out", str(tmp_path / "out")]) == 2
    assert f"--input: input table {tmp_path / 'none.csv'} does not exist" in capsys.readouterr().err
    assert main(["run-fmu", fmu, "--input", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert f"--input: input table {tmp_path} is not a file" in capsys.readouterr().err  # not "does not exist"
    assert main(["run-fmu", fmu, "--set", "Float64_continuous_input=nan", "--out", str(tmp_path / "out")]) == 2
    assert "Float64_continuous_input = 'nan' is not allowed (allowed: any finite number)" in capsys.readouterr().err
    table = write(tmp_path, "time,Int32_input\n0,1\n")
    assert main(["run-fmu", fmu, "--input", str(table), "--set", "Int32_input=2", "--out", str(tmp_path / "out")]) == 2
    assert "--set and --input both give Int32_input" in capsys.readouterr().err


def test_a_machine_plant_takes_the_same_table(tmp_path: Path) -> None:
    """[plant.feed] input = "inputs.csv": the plant's inputs follow the table in a machine file too."""
    write(tmp_path, TABLE)
    fmu = ensure_fmu("FeedthroughTest", 3)
    machine = tmp_path / "feed.toml"
    machine.write_text(f"""[machine]
description = "a scripted controller and a feedthrough plant driven by a table"
until = "2 s"

[controller]
family = "pokeys"

[plant.feed]
fmu = "{fmu}"
input = "inputs.csv"
record = {{ variables = ["Float64_continuous_output", "Int32_output"], period = "250 ms" }}
""")
    out = tmp_path / "out"
    main(["run", str(machine), "--out", str(out), "--allow-unchecked"])
    trace = read_trace(out)
    t, values = trace.edges("feed.float64_continuous_output")
    on_grid = np.isin(t, GRID_NS[:-1])  # the run ends before its end instant's events
    assert t[on_grid].tolist() == GRID_NS[:-1]
    assert values[on_grid].tolist() == pytest.approx(EXPECTED["Float64_continuous_output"][:-1], abs=1e-15)
    t, values = trace.edges("feed.int32_output")
    assert values[np.isin(t, GRID_NS[:-1])].tolist() == EXPECTED["Int32_output"][:-1]
