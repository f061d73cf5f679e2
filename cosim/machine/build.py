"""Building a machine from its file: controller, plants and their couplings, programs, stimuli, checks.

The order is the machine's wiring order, top to bottom, like a scenario script's: the controller
(its family reads ``[controller]``), every ``[plant.NAME]`` (loaded, then coupled to the
controller's ports), the programs and the family's own tables, the ``[[stimulus]]`` schedules,
the job's check and the axes' travel (:mod:`cosim.machine.expect`), the ``[[check]]`` and
``[[figure]]`` tables (every signal they name must be one the machine has), and the warnings said
after the run; finally every key of the file must have been used.
Everything here happens at t = 0, before the run: a bad key, value, file, FMU or variable mapping
stops the machine before anything is simulated.
"""

from __future__ import annotations

import re
from importlib import import_module
from pathlib import Path
from typing import Any

from cosim.controllers.scripted import play
from cosim.errors import ConfigurationError, FmuError
from cosim.machine.checks import check_from_table, figure_from_table
from cosim.machine.document import Table
from cosim.machine.expect import declare_job, declare_travel, declare_warnings, signal_problem
from cosim.machine.families import Family, families
from cosim.master import PlantLike
from cosim.scenario import Run

#: Couplings a plant table may name, with the module and function that join a port to the plant (imported
#: when a plant names the coupling: the servo coupling's python-control is loaded only by a machine that uses it).
COUPLINGS = {"stepper": "cosim.couplings.stepper:couple_stepper", "laser": "cosim.couplings.laser:couple_laser",
             "switches": "cosim.couplings.switches:couple_switches",
             "encoder": "cosim.couplings.encoder:couple_encoder", "servo": "cosim.couplings.servo:couple_servo"}
PLANT_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


def build_machine(run: Run, document: Table, *, base: Path) -> Any:
    """Wire the machine ``document`` describes into ``run``; returns its controller."""
    machine = document.table("machine", required=True)
    for key in ("name", "description", "until", "resolution"):
        machine.raw(key, None)  # read by the loader
    document.raw("export", None)  # the FMU's inputs and outputs: read by `cosim export-fmu` (cosim.fmu_export)
    controller_table = document.table("controller", required=True)
    family_name = controller_table.text("family", choices=sorted(families()))
    family: Family = families()[family_name]
    controller = family.controller(run, controller_table, base=base)
    couplings: list[tuple[str, str, Any]] = []
    plants = {name: _plant(run, family, controller, name, table, couplings, base=base)
              for name, table in document.table("plant").items()}
    family.start(run, controller, document.tables("program"), document, base=base)
    for table in document.tables("stimulus"):
        _stimulus(run, controller, table)
    declare_job(run, controller, document.table("job"))
    declare_travel(run, family_name, controller, document.table("travel"), document)
    trace = run.sim.trace
    for table in document.tables("check"):
        shows = table.text("hazard", None)  # a declared hazard: the check is expected to fail
        check, where = check_from_table(table), f"{table.file}: {table.path}"
        _signals_known(table, check.signals(), trace, plants)
        _kinds_fit(table, check, trace)
        if shows is None:
            run.check(check, where=where)
        else:
            with table.at("hazard"):
                run.hazard(check, shows=shows, where=where)
    for table in document.tables("figure"):
        name, value, unit = figure_from_table(table, plants)
        if table.has("signal"):
            _signals_known(table, {"signal": table.data["signal"]}, trace, plants)
            _figure_kind_fits(table, trace)
        run.figure(name, lambda value=value: value(trace), unit,  # type: ignore[misc]
                   where=f"{table.file}: {table.path}")
    declare_warnings(run, couplings)
    document.finish()
    return controller


def _signals_known(table: Table, names: dict[str, Any], trace: Any, plants: dict[str, PlantLike]) -> None:
    """Refuse a check or figure whose signal the machine does not have (before the run, naming the key)."""
    for key, name in names.items():
        problem = signal_problem(trace, name, plants)
        if problem is not None:
            raise ConfigurationError(f"{table.file}: {table.key(key)}: {problem}")


def _kinds_fit(table: Table, check: Any, trace: Any) -> None:
    """Refuse a check that reads a signal of the wrong kind (a pulse train where a value goes), before the run.

    The check is evaluated on the trace as built (its signals declared, nothing simulated): a check
    reads each signal through readers that refuse the wrong kind (:func:`cosim.checks.base.records`),
    so that refusal comes now instead of after the run. Anything else it finds in an empty trace
    (nothing examined, a signal still to be declared) is for after the run.
    """
    try:
        check.evaluate(trace)
    except ConfigurationError as exc:
        raise ConfigurationError(f"{table.file}: {table.path}: {exc}") from None
    except Exception:  # the run evaluates it again and reports what it finds then
        return


def _figure_kind_fits(table: Table, trace: Any) -> None:
    """Refuse a figure whose ``reduce`` cannot read its signal's kind (``pulses`` of a value, ``max`` of a train)."""
    name, reduce = table.data["signal"], table.data.get("reduce", "last")
    info = trace.info.get(name) if isinstance(name, str) else None
    if info is None:
        return
    if reduce == "pulses" and info.kind != "pulse":
        raise ConfigurationError(f"{table.file}: {table.key('reduce')}: reduce = 'pulses' counts the pulses of a "
                                 f"pulse train; {name} is a {info.kind} signal (use last, max, min or changes)")
    if reduce != "pulses" and info.kind == "pulse":
        raise ConfigurationError(f"{table.file}: {table.key('reduce')}: reduce = {reduce!r} reads a value; {name} "
                                 "is a pulse train (use reduce = \"pulses\": its net signed count)")


def _plant(run: Run, family: Family, controller: Any, name: str, table: Table,
           couplings: list[tuple[str, str, Any]], *, base: Path) -> PlantLike:
    if not PLANT_NAME.match(name):
        raise ConfigurationError(f"{table.file}: {table.path}: a plant name is lower case [a-z0-9_], starting "
                                 f"with a letter (it prefixes the plant's signals); got {name!r}")
    model = table.raw("model", None)
    fmu = table.raw("fmu", None)
    table.describe("model", allowed="Laser, Stepper, Servo, Conveyor (a bundled plant)")
    table.describe("fmu", allowed="the path of a co-simulation FMU, relative to the machine file")
    if (model is None) == (fmu is None):
        raise ConfigurationError(f"{table.file}: {table.path}: give either model (a bundled plant: Laser, Stepper, "
                                 "Servo, Conveyor) or fmu (the path of your own co-simulation FMU)")
    preset = table.text("preset", None)
    fmi = table.integer("fmi", 3, low=2, high=3)
    parameters = table.raw("parameters", {})
    if not isinstance(parameters, dict):
        raise table.error("parameters", parameters, "a table of FMU parameter values")
    with table.at("fmu" if fmu is not None else "model"):
        if fmu is not None:
            if not isinstance(fmu, str):
                raise ConfigurationError.out_of_range("value", fmu, "the path of an .fmu file")
            path = (base / fmu).resolve()
            if not path.is_file():
                raise ConfigurationError(f"FMU file {path} does not exist")
            if path.suffix.lower() != ".fmu":
                raise ConfigurationError(f"{path} is not an FMU: fmu = takes an .fmu file (model = takes a "
                                         f"bundled model's name)")
            source: str | Path = path
        else:
            if not isinstance(model, str):
                raise ConfigurationError.out_of_range("value", model, "a bundled model name")
            source = model
        try:
            plant = run.plant(source, name=name, fmi_version=fmi, preset=preset, parameters=parameters)
        except FmuError as exc:  # the FMU refused a start value: the machine file's, so a configuration error
            raise ConfigurationError(f"{table.file}: {table.key('parameters')}: the FMU refused a start value: "
                                     f"{exc}") from None
    for kind in COUPLINGS:
        if not table.has(kind):
            table.raw(kind, None)
            continue
        spec = table.table(kind)
        port = family.port(controller, kind, spec)
        couplings.append((kind, name, port))
        variables = spec.raw("variables", None)
        if variables is not None and not isinstance(variables, dict):
            raise spec.error("variables", variables, "a table {role = \"variable\"} (a role = \"\" leaves it unwired)")
        mapping = {k: (v or None) for k, v in (variables or {}).items()}
        module, function = COUPLINGS[kind].split(":")
        couple = getattr(import_module(module), function)
        with spec.at():
            if kind == "switches":
                couple(plant, port, variables=mapping)
            else:
                couple(port, plant, variables=mapping)
    inputs = table.text("input", None)  # an input table (cosim.fmuinput): the plant's inputs over time
    if inputs is not None:
        from cosim.fmuinput import drive_from_table, read_input_table

        with table.at("input"):
            drive_from_table(plant, read_input_table(base / inputs, plant.fmu.variables, timebase=run.sim.timebase))
    record = table.table("record")
    if record.data:
        names = record.raw("variables")
        period = record.time("period")
        with record.at("variables"):
            if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
                raise ConfigurationError.out_of_range("value", names, "a list of output names")
            plant.record(names, period=period)
    return plant


def _stimulus(run: Run, controller: Any, table: Table) -> None:
    """``[[stimulus]] signal = "pokeys.x.home"; at = ["0 ms", "5 ms"]; values = [0, 1]``."""
    name = table.text("signal")
    inputs = {s.name: s for s in controller.inputs()}
    if name not in inputs:
        raise table.error("signal", name, ", ".join(sorted(inputs)) or "none (this controller reads no inputs)")
    times = table.raw("at")
    values = table.raw("values")
    with table.at("at"):
        if not isinstance(times, list) or not isinstance(values, list) or len(times) != len(values):
            raise ConfigurationError.out_of_range("at, values", (times, values), "two lists of the same length")
        ticks = [table.ticks(t) for t in times]
        play(run.sim, [(t, {inputs[name]: v}) for t, v in zip(ticks, values, strict=True)])
