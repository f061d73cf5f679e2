"""Input tables: an FMU's inputs over time from a CSV file (``run-fmu --input``, ``[plant.x] input``).

A table is a CSV file whose first column is the time in seconds (header ``time``) and whose other
columns are named by FMU inputs (or tunable parameters), exactly as the model description spells
them::

    time,Float64_continuous_input,Int32_input,Boolean_input
    0,0,0,false
    0.5,1,0,false
    0.5,1,3,true
    1,0,3,true

Its values are what fmpy's ``simulate_fmu(input=...)`` and the Reference FMUs' ``fmusim
--input-file`` make of the same table:

* a **continuous** input (a real variable of variability ``continuous``) is interpolated linearly
  between rows; two rows with the same time make a jump there (the later row holds from that
  instant on);
* a **discrete** one (integers, Booleans, enumerations, strings, and reals declared ``discrete``) is
  held: from each row's time on, the last row at or before that instant;
* before the first row the first row's values hold, after the last row the last row's.

The master holds an input constant over each step of the FMU (the FMU sees the value of the
step's start, as every FMI importer gives it). So that a continuous input follows the table, its
value is set again wherever the plant arrives (after every step, whatever asked for it), and the
plant is stepped to every row's instant: an output read at any instant sees the table's value
there. Times are exact: each row's time is a whole number of ticks of the run's resolution,
parsed from its text (``0.1`` is 100,000,000 ns), or the table is refused naming its file and line.
"""

from __future__ import annotations

import bisect
import csv
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any, Protocol

from cosim.errors import ConfigurationError
from cosim.fmuvars import Variable
from cosim.timebase import Priority, TimeBase

#: Same-instant priority of a table's changes: before anything else at that instant reads the plant.
TABLE_PRIORITY = Priority.PLANT_EVENT


@dataclass(frozen=True)
class InputTable:
    """A checked input table.

    Attributes
    ----------
    path : Path
        The CSV file.
    times : tuple of int
        Each row's instant [ticks], non-decreasing.
    values : dict of str to tuple
        Each column's values, checked against its variable (one per row).
    continuous : tuple of str
        The columns interpolated linearly; the others are held.
    """

    path: Path
    times: tuple[int, ...]
    values: dict[str, tuple[Any, ...]]
    continuous: tuple[str, ...]

    @property
    def columns(self) -> list[str]:
        """The variables the table drives, in its column order."""
        return list(self.values)

    def at(self, t: int) -> dict[str, Any]:
        """Every column's value from tick ``t`` on (at a jump: the value after it)."""
        i = bisect.bisect_right(self.times, t)  # rows at or before t: [0, i)
        return {name: (self._interpolated(column, i, t) if name in self.continuous else column[max(i - 1, 0)])
                for name, column in self.values.items()}

    def _interpolated(self, column: tuple[Any, ...], i: int, t: int) -> float:
        """Linear between row i - 1 (at or before t) and row i (after t); held outside the table."""
        if i == 0:
            return float(column[0])
        if i == len(self.times):
            return float(column[-1])
        t0, t1 = self.times[i - 1], self.times[i]
        v0, v1 = float(column[i - 1]), float(column[i])
        return v0 + (v1 - v0) * ((t - t0) / (t1 - t0))

    def change_times(self, after: int) -> list[int]:
        """The instants after tick ``after`` where the plant must be stepped: every row's time (a kink,
        a jump or a held value changing there)."""
        return sorted({t for t in self.times if t > after})


def is_continuous(var: Variable) -> bool:
    """Interpolated (a real of variability continuous) rather than held, as fmpy and fmusim decide."""
    return var.kind.is_float and var.variability not in ("discrete", "tunable", "fixed", "constant")


def read_input_table(path: str | Path, variables: Mapping[str, Variable], *, timebase: TimeBase,
                     where: str = "") -> InputTable:
    """Read and check an input table against an FMU's variables.

    Parameters
    ----------
    path : path
        The CSV file (comma-separated; a header row, then one row per instant).
    variables : mapping name -> Variable
        The FMU's variables (:class:`cosim.fmu.Fmu.variables`, or from its model description).
    timebase : TimeBase
        The run's resolution: every time must be a whole number of its ticks.
    where : str
        Where the table was named (``--input``, ``machine.toml: plant.x.input``), for messages.

    Raises
    ------
    ConfigurationError
        A missing or unreadable file, a header whose first column is not ``time``, a column that
        names no input of the FMU (with the closest names), an array, a time that is not a number
        of seconds, not a whole tick or earlier than the row before, a value its variable refuses:
        each naming the file and its line.
    """
    path = Path(path)
    named = f"{where}: " if where else ""
    if not path.is_file():
        missing = "is not a file" if path.exists() else "does not exist"
        raise ConfigurationError(f"{named}input table {path} {missing}")
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = [(n, row) for n, row in enumerate(csv.reader(handle), start=1)
                    if row and any(cell.strip() for cell in row)]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ConfigurationError(f"{named}cannot read input table {path}: {exc}") from None
    if not rows:
        raise ConfigurationError(f"{path}: the input table is empty (write a header: time,<input>,...)")
    line, header = rows[0]
    header = [cell.strip() for cell in header]
    if header[0].lower() != "time" or len(header) < 2:
        raise ConfigurationError(f"{path}:{line}: the header must be time,<input>,<input>,... (got {','.join(header)})")
    columns = header[1:]
    for name in columns:
        _check_column(path, line, name, variables, columns)
    times: list[int] = []
    cells: dict[str, list[Any]] = {name: [] for name in columns}
    for line, row in rows[1:]:
        if len(row) != len(header):
            raise ConfigurationError(f"{path}:{line}: {len(row)} cells where the header has {len(header)}")
        t = _ticks(path, line, row[0].strip(), timebase)
        if times and t < times[-1]:
            raise ConfigurationError(f"{path}:{line}: time {row[0].strip()} s is earlier than the row before "
                                     f"({timebase.seconds(times[-1])!r} s): times must not decrease")
        times.append(t)
        for name, text in zip(columns, row[1:], strict=True):
            cells[name].append(variables[name].parse(text.strip(), where=f"{path}:{line}"))
    if not times:
        raise ConfigurationError(f"{path}: the input table has a header but no rows")
    continuous = tuple(name for name in columns if is_continuous(variables[name]))
    return InputTable(path, tuple(times), {name: tuple(values) for name, values in cells.items()}, continuous)


def _check_column(path: Path, line: int, name: str, variables: Mapping[str, Variable], columns: list[str]) -> None:
    if columns.count(name) > 1:
        raise ConfigurationError(f"{path}:{line}: column {name!r} appears twice")
    var = variables.get(name)
    if var is None:
        import difflib

        inputs = [n for n, v in variables.items() if _drivable(v)]
        close = difflib.get_close_matches(name, inputs, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else f" (inputs: {', '.join(inputs) or 'none'})"
        raise ConfigurationError(f"{path}:{line}: column {name!r} is not a variable of the FMU{hint}")
    if not _drivable(var):
        raise ConfigurationError(f"{path}:{line}: column {name!r} is an {var.causality} ({var.variability}): a table "
                                 "drives inputs and tunable parameters")
    if var.shape:
        raise ConfigurationError(f"{path}:{line}: column {name!r} is an array {var.dimensions}: a table drives "
                                 "scalar inputs")
    if var.kind.name == "Binary":
        raise ConfigurationError(f"{path}:{line}: column {name!r} is a Binary input: a table drives numbers, "
                                 "Booleans, enumerations and strings")


def _drivable(var: Variable) -> bool:
    return var.causality == "input" or (var.causality == "parameter" and var.variability == "tunable")


def _ticks(path: Path, line: int, text: str, timebase: TimeBase) -> int:
    try:
        seconds = Decimal(text)
    except InvalidOperation:
        raise ConfigurationError(f"{path}:{line}: time {text!r} is not a number of seconds") from None
    if not seconds.is_finite() or seconds < 0:
        raise ConfigurationError(f"{path}:{line}: time {text!r} is not allowed (allowed: a number of seconds >= 0)")
    try:
        return timebase.ticks(f"{text} s", name="time")
    except ConfigurationError as exc:
        raise ConfigurationError(f"{path}:{line}: {exc}") from None


class _Driven(Protocol):
    """What :func:`drive_from_table` needs of a plant (:class:`cosim.master.Plant`)."""

    name: str
    fmu: Any
    sim: Any

    def set(self, values: Mapping[str, Any]) -> None: ...

    def after_step(self, hook: Callable[[int], None]) -> None: ...


def drive_from_table(plant: _Driven, table: InputTable) -> None:
    """Let ``table`` drive the plant's inputs from now on (its values at now are set at once).

    At every row's instant after now the plant is advanced and the table's values there are set
    (priority :data:`TABLE_PRIORITY`: before anything else at that instant); after every step of
    the plant its continuous inputs are set to the table's value at the instant it reached.
    """
    sim = plant.sim
    plant.set(table.at(sim.now))
    if table.continuous:
        plant.after_step(_continuous_writer(plant, table))
    times = table.change_times(sim.now)
    if not times:
        return

    def run() -> Any:
        for t in times:
            yield sim.at(t, TABLE_PRIORITY)
            plant.set(table.at(t))

    sim.process(run())


def _continuous_writer(plant: _Driven, table: InputTable) -> Callable[[int], None]:
    names = list(table.continuous)
    variables = [plant.fmu.variable(name) for name in names]
    if all(v.kind.name == "Float64" for v in variables):
        write: Callable[[Sequence[float]], None] = plant.fmu.writer(names)
    else:
        def write(values: Sequence[float]) -> None:
            for name, value in zip(names, values, strict=True):
                plant.fmu.set(name, value)
    times = table.times
    columns = [tuple(float(x) for x in table.values[name]) for name in names]
    last = len(times) - 1

    def set_at(t: int) -> None:
        i = bisect.bisect_right(times, t)
        if i == 0:
            write([column[0] for column in columns])
        elif i > last:
            write([column[-1] for column in columns])
        else:
            t0, t1 = times[i - 1], times[i]
            share = (t - t0) / (t1 - t0)
            write([column[i - 1] + (column[i] - column[i - 1]) * share for column in columns])

    return set_at
