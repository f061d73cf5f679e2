"""The ``cosim`` command line.

Exit status, by verdict (see :attr:`cosim.runner.Result.verdict`): 0 for PASS and HAZARD SHOWN, 1 for
FAIL, HAZARD MISSED and ERROR, 2 for usage or configuration errors (a parameter out of range, an unknown
scenario, a broken script, an ``--until`` the scenario refuses), 3 for TERMINATED (a plant FMU ended the
run early; the checks passed up to that instant), 4 for UNCHECKED (nothing was checked; 0 with
``--allow-unchecked``), 130 for INTERRUPTED.

Each sub-command is two small functions, ``_args_<name>(parser)`` (its arguments) and
``cmd_<name>(args) -> exit status``, and one line in :data:`COMMANDS`. Command functions import
what they need when they run, so that ``cosim --help``, ``cosim list`` and shell completion start
in a fraction of a second.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim import __version__
from cosim.errors import ConfigurationError, CosimError, ScenarioError

EXIT_PASS, EXIT_FAIL, EXIT_USAGE, EXIT_TERMINATED, EXIT_UNCHECKED, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
#: Exit status of each verdict (a configuration error is EXIT_USAGE whatever the verdict).
EXIT_STATUS = {"PASS": EXIT_PASS, "HAZARD SHOWN": EXIT_PASS, "FAIL": EXIT_FAIL, "HAZARD MISSED": EXIT_FAIL,
               "ERROR": EXIT_FAIL, "TERMINATED": EXIT_TERMINATED, "UNCHECKED": EXIT_UNCHECKED,
               "INTERRUPTED": EXIT_INTERRUPTED}
EPILOG = ("Exit status: 0 PASS (every check passed) or HAZARD SHOWN (the hazard the scenario demonstrates "
          "happened); 1 FAIL (a check failed), HAZARD MISSED (the declared hazard did not happen) or ERROR (the "
          "run broke); 2 usage/configuration error; 3 TERMINATED (a plant FMU ended the run early; the checks up "
          "to then passed); 4 UNCHECKED (no checks, or they examined nothing; 0 with --allow-unchecked); 130 "
          "INTERRUPTED (Ctrl-C or SIGTERM: what was simulated is written).")
#: How many failing sweep runs are listed with their reason before the rest is only counted.
SHOWN_FAILURES = 5


def _scenario_argument(parser: argparse.ArgumentParser, help_text: str) -> None:
    """The SCENARIO positional; shell completion offers the bundled names and ``.py`` files."""
    from cosim.scenario import bundled

    action = parser.add_argument("scenario", help=help_text)
    names = " ".join(bundled())
    action.complete = {  # type: ignore[attr-defined]  # read by shtab
        "bash": "_cosim_scenarios",
        "zsh": f"({names})",
        "tcsh": f"({names})",
        "preamble": {"bash": (f'_cosim_scenarios() {{\n  compgen -W "{names}" -- "$1"\n'
                              '  compgen -f -X "!*.py" -- "$1"\n  compgen -f -X "!*.toml" -- "$1"\n'
                              '  compgen -d -- "$1"\n}\n')},
    }


def _folder_completion(action: argparse.Action) -> None:
    action.complete = {"bash": "_shtab_compgen_dirs", "zsh": "_files -/", "tcsh": "d"}  # type: ignore[attr-defined]


# -- run ------------------------------------------------------------------------------------------

#: Program files ``cosim run PROGRAM --machine MACHINE.toml`` takes, by suffix: the family that runs them.
PROGRAM_SUFFIXES = {".bas": "Trio BASIC", ".pmc": "PMAC", ".pmac": "PMAC", ".nc": "G-code (PoKeys)",
                    ".ngc": "G-code (PoKeys)", ".gcode": "G-code (PoKeys)"}
PROGRAM_KINDS = ("a Trio BASIC program (.bas), a PMAC program (.pmc, .pmac) or a G-code program (.nc, .ngc, "
                 ".gcode)")


def _args_run(parser: argparse.ArgumentParser) -> None:
    _scenario_argument(parser, "bundled scenario name (see `cosim list`), a scenario script (.py), a machine file "
                               f"(.toml), or {PROGRAM_KINDS} to run on --machine")
    parser.add_argument("--machine", type=Path, default=None, metavar="MACHINE.toml",
                        help="the machine file a program given as SCENARIO runs on (.bas on a Trio, .pmc/.pmac on a "
                             "PMAC, .nc/.ngc/.gcode on a PoKeys machine); it replaces the file's [[program]] list")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="set a declared parameter, or a machine-file key by its dotted path or a unique "
                             "last part (repeatable; see `cosim params SCENARIO`)")
    _folder_completion(parser.add_argument("--out", type=Path, default=None,
                                           help="results folder (default: results/<scenario>)"))
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same trace")
    parser.add_argument("--until", default=None, help="end time with unit, e.g. '20 ms' (default: the scenario's)")
    parser.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                        help="format of the trace tables (default parquet)")
    parser.add_argument("--no-vcd", action="store_true", help="do not write trace.vcd")
    parser.add_argument("--plain-vcd", action="store_true",
                        help="write trace.vcd and trace_digital.vcd as text even for a long run (by default a run "
                             "of more than 20 million changes gets one compressed trace.vcd.gz)")
    _allow_unchecked(parser)


def _allow_unchecked(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--allow-unchecked", action="store_true",
                        help="exit 0, not 4, when the verdict is UNCHECKED (no checks, or they examined nothing)")


def _parse_sets(pairs: Sequence[str]) -> dict[str, str]:
    values = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise ConfigurationError(f"--set {pair!r}: write NAME=VALUE, e.g. --set pwm_on=500")
        values[name.strip()] = value.strip()
    return values


def _load(args: argparse.Namespace) -> object:
    """The scenario or machine to run: a name, a .py script, a .toml machine, or a program on --machine."""
    from cosim.catalog import load

    machine = getattr(args, "machine", None)
    if machine is not None:
        from cosim.machine import load_machine

        return load_machine(machine, program=args.scenario)
    suffix = Path(args.scenario).suffix.lower()
    if suffix in PROGRAM_SUFFIXES:
        raise ConfigurationError(f"{args.scenario} is a {PROGRAM_SUFFIXES[suffix]} program: name the machine it runs "
                                 "on with --machine MACHINE.toml (see docs/machines.md)")
    return load(args.scenario)


def cmd_run(args: argparse.Namespace) -> int:
    from cosim.runner import run_scenario
    from cosim.scenario import ScenarioFile

    scenario = _load(args)
    assert isinstance(scenario, ScenarioFile)
    out = args.out or Path("results") / scenario.name
    formats = (() if args.no_vcd else ("vcd-plain" if args.plain_vcd else "vcd",)) + (args.format,)
    result = run_scenario(scenario, overrides=_parse_sets(args.overrides), seed=args.seed, until=args.until,
                          out=out, formats=formats, progress=True)
    print(result.table())
    print(_results_line(out))
    return _exit_status(result, allow_unchecked=args.allow_unchecked)


def _results_line(out: Path) -> str:
    """Where the run's files are, and which they are (as written, not as expected)."""
    folder = Path(out)
    files = folder.iterdir() if folder.is_dir() else iter(())
    names = sorted(p.name for p in files if p.is_file() and not p.name.startswith("."))
    return f"results in {folder}/ ({', '.join(names) or 'nothing written'})"


def _exit_status(result: Any, *, allow_unchecked: bool = False) -> int:
    """The exit status of a run's verdict (:data:`EXIT_STATUS`)."""
    if result.verdict == "INTERRUPTED":
        return EXIT_INTERRUPTED
    if result.error_kind == "configuration":
        return EXIT_USAGE
    if result.verdict == "UNCHECKED" and allow_unchecked:
        return EXIT_PASS
    return EXIT_STATUS.get(result.verdict, EXIT_FAIL)


def _args_check_machine(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("machine", type=Path, help="the machine file (.toml)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="set a machine-file key first (as for `cosim run`)")


def cmd_check_machine(args: argparse.Namespace) -> int:
    from cosim.machine import load_machine
    from cosim.machine.check import check_machine

    machine = load_machine(args.machine)
    print(check_machine(machine, overrides=_parse_sets(args.overrides)))
    return EXIT_PASS


# -- export-fmu -----------------------------------------------------------------------------------

def _args_export_fmu(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("machine", type=Path, help="the machine file (.toml) with an [export] table")
    parser.add_argument("-o", "--out", type=Path, default=None, metavar="MACHINE.fmu",
                        help="the FMU to write (default: MACHINE's name with .fmu, in the current folder)")
    parser.add_argument("--fmi", type=int, choices=(3, 2), default=3,
                        help="FMI version (default 3: early return and event mode at event-bearing outputs)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="set a machine-file key first (as for `cosim run`)")
    parser.add_argument("--linked", action="store_true",
                        help="do not carry cosim and its packages: the FMU uses this environment (its site folders "
                             "are recorded) and runs only where it exists; small and quick to write")


def cmd_export_fmu(args: argparse.Namespace) -> int:
    from cosim.fmu_export.package import export_fmu, libpython
    from cosim.fmubuild import platform_folder

    out = args.out or Path(f"{args.machine.stem}.fmu")
    _check_output_file(out, "-o")
    exported = export_fmu(args.machine, out, fmi_version=args.fmi, overrides=_parse_sets(args.overrides),
                          portable=not args.linked)
    size_mb = exported.path.stat().st_size / 1e6
    print(f"wrote {exported.path}: FMI {args.fmi}.0 co-simulation, step {exported.step_s:g} s, "
          f"stop {exported.stop_s:g} s, {size_mb:.1f} MB")
    for kind, ports in (("output", exported.outputs), ("input", exported.inputs)):
        for port in ports:
            event = " (event)" if port.event else ""
            print(f"  {kind:<6}  {port.name:<32} {port.fmi_type:<7} {port.source}{event}")
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    if exported.wheels:
        print(f"it carries cosim and {len(exported.wheels) - 1} packages ({', '.join(exported.wheels)}), installed "
              f"on first use into a per-user cache: it runs on any {platform_folder(args.fmi)} computer with CPython "
              f"{version} (a C importer needs its shared libpython; this one's: {libpython() or 'none'}); see "
              "docs/export.md")
    else:
        runtime = libpython() or "none: the FMU runs only inside a Python importer (fmpy)"
        print(f"it runs cosim in Python {version} (libpython: {runtime}) with this environment ({sys.prefix}): "
              "only where it exists (--linked); see docs/export.md")
    return EXIT_PASS


def _check_output_file(path: Path, option: str) -> None:
    """Refuse an output file that cannot be written, before any work: a folder in its way, a parent that is a file."""
    if path.is_dir():
        raise ConfigurationError(f"{option} {path}: is a folder; give the file to write (e.g. {path / 'machine.fmu'})")
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise ConfigurationError(f"{option} {path}: {parent} is a file, not a folder: the FMU cannot be "
                                         "written there")
            break


# -- list, params ---------------------------------------------------------------------------------

def cmd_list(args: argparse.Namespace) -> int:
    from cosim.catalog import description, examples, shown
    from cosim.scenario import bundled

    rows = [(name, description(name)) for name in bundled()]
    rows += [(shown(path), description(path)) for path in examples()]
    width = max((len(n) for n, _ in rows), default=0)
    for name, text in rows:
        print(f"{name:<{width}}  {text}")
    return EXIT_PASS


def _args_params(parser: argparse.ArgumentParser) -> None:
    _scenario_argument(parser, "bundled scenario name, a .py script or a .toml machine file")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="a machine file: set a key first (as for `cosim run`)")


def cmd_params(args: argparse.Namespace) -> int:
    from cosim.catalog import load
    from cosim.machine import MachineFile

    scenario = load(args.scenario)
    print(f"{scenario.name}: {scenario.description}\n(default end time {scenario.until})")
    if isinstance(scenario, MachineFile):
        from cosim.machine.check import machine_keys

        specs = machine_keys(scenario, overrides=_parse_sets(args.overrides))
        rows = [(s.key, _shorter(_toml(s.value) if s.given else f"({_toml(s.value)})" if s.value is not None
                                 else "-"), s.unit, s.allowed) for s in specs]
        print("(every key of the machine file, and in parentheses the defaults of keys it does not give; set any "
              "with --set KEY=VALUE)")
        _table(("key", "value", "unit", "allowed"), rows)
        return EXIT_PASS
    _table(("name", "default", "unit", "allowed", "help"),
           [(p.name, repr(p.default), p.unit, p.allowed(), p.help) for p in scenario.parameters])
    return EXIT_PASS


def _toml(value: object) -> str:
    """A value as it is written in a machine file (``"2 s"``, ``true``, ``[1, 2]``)."""
    import json

    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str | list | dict):
        return json.dumps(value, default=str)
    return str(value)


def _shorter(text: str, width: int = 40) -> str:
    return text if len(text) <= width else text[:width - 3] + "..."


def _table(head: tuple[str, ...], rows: Sequence[tuple[str, ...]]) -> None:
    """Columns padded to their widest cell (the last one is not padded)."""
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head) - 1)]
    for row in [head, *rows]:
        print("  ".join(f"{c:<{w}}" for c, w in zip(row[:-1], widths, strict=True)) + "  " + row[-1])


# -- FMUs -----------------------------------------------------------------------------------------

def _args_build(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("models", nargs="*", help="model names (default: all)")
    parser.add_argument("--force", action="store_true", help="rebuild even if up to date")


def cmd_build(args: argparse.Namespace) -> int:
    from cosim import fmubuild

    try:
        outcomes = fmubuild.build_all(force=args.force, models=args.models or None,
                                      say=lambda line: print(line, flush=True))
    except fmubuild.BuildError as exc:
        print(f"cosim build-fmus: failed: {exc}", file=sys.stderr)
        return EXIT_FAIL
    print(fmubuild.summary(outcomes))
    return EXIT_PASS


def cmd_check(args: argparse.Namespace) -> int:
    from fmpy.validation import validate_fmu

    from cosim import fmubuild

    models = fmubuild.list_models()
    if not models:
        raise ConfigurationError(f"no plant sources in {fmubuild.SOURCE_DIR}: nothing to check "
                                 "(the installation is incomplete, or COSIM_FMU_SRC points to the wrong place)")
    bad = 0
    for model in models:
        for version in fmubuild.FMI_VERSIONS:
            try:
                path = fmubuild.ensure_fmu(model, version)
            except fmubuild.BuildError as exc:
                print(f"cosim check-fmus: failed: {exc}", file=sys.stderr)
                return EXIT_FAIL
            problems = validate_fmu(str(path))
            print(f"{'OK  ' if not problems else 'FAIL'}  {path}", flush=True)
            for problem in problems:
                print(f"      {problem}")
            bad += bool(problems)
    total = len(models) * len(fmubuild.FMI_VERSIONS)
    print(f"{total - bad} of {total} FMUs valid (fmpy's validator) in {fmubuild.MODELS_DIR}")
    return EXIT_FAIL if bad else EXIT_PASS


def _args_fmu_info(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("fmu", type=Path, help="the .fmu file")
    parser.add_argument("--json", action="store_true", help="print everything as JSON")


def cmd_fmu_info(args: argparse.Namespace) -> int:
    from cosim.fmutools import fmu_info, format_info

    info = fmu_info(args.fmu)
    if args.json:
        from cosim.runner import to_json

        print(to_json(info.as_dict()))
    else:
        print(format_info(info), end="")
    return EXIT_PASS


def _args_run_fmu(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("fmu", type=Path, help="the .fmu file (co-simulation, FMI 2.0 or 3.0)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                        help="start value of a parameter or input (repeatable; arrays: 1,2,3; enumerations: "
                             "the item name; binaries: hex)")
    parser.add_argument("--input", type=Path, default=None, metavar="TABLE.csv",
                        help="inputs over time: a CSV table, first column time [s], then one column per input "
                             "named as the FMU names it; continuous real inputs are interpolated linearly, the "
                             "others held from each row (as fmpy and fmusim do)")
    parser.add_argument("--start", default=None,
                        help="start time with unit, e.g. '1 s' (default: the FMU's default experiment, else 0)")
    parser.add_argument("--until", default=None,
                        help="end time with unit, e.g. '2 s' (default: the FMU's default experiment, else start + 1 s)")
    parser.add_argument("--step", default=None,
                        help="output grid with unit, e.g. '1 ms' (default: the default experiment's step size, "
                             "else 1/500 of the run)")
    parser.add_argument("--no-validate", dest="validate", action="store_false",
                        help="run an FMU whose model description fmpy's validator flags (a legacy FMU); the run's "
                             "notes list what the validator found")
    _folder_completion(parser.add_argument("--out", type=Path, default=None,
                                           help="results folder (default results/<fmu name>)"))
    parser.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                        help="format of the trace tables (default parquet)")


def cmd_run_fmu(args: argparse.Namespace) -> int:
    from cosim.fmurun import plant_name, run_fmu

    out = args.out or Path("results") / plant_name(args.fmu)
    result = run_fmu(args.fmu, sets=_parse_sets(args.overrides), until=args.until, step=args.step, start=args.start,
                     input_table=args.input, validate=args.validate, out=out, formats=("vcd", args.format),
                     progress=True)
    for note in result.notes:
        if note.startswith("WARNING"):
            print(f"cosim run-fmu: {note}", file=sys.stderr)
    print(result.table())
    print(_results_line(out) + "; the tables hold every numeric output on the grid (outputs.csv: with the FMU's "
          "own names)")
    return _exit_status(result, allow_unchecked=True)  # an FMU run alone declares no checks: UNCHECKED, exit 0


# -- sweep ----------------------------------------------------------------------------------------

def _args_sweep(parser: argparse.ArgumentParser) -> None:
    _scenario_argument(parser, "bundled scenario name or path to a .py script")
    parser.add_argument("--grid", action="append", default=[], metavar="NAME=V1,V2,...",
                        help="values of one parameter (repeatable; all combinations are run)")
    parser.add_argument("--random", action="append", default=[], metavar="NAME[=LOW:HIGH[:STEP]]",
                        help="parameter drawn per sample (default range: the declared one); integers and "
                             "times (ms, us, ...) are drawn on their grid (whole numbers, whole ns), or on STEP")
    parser.add_argument("--samples", type=int, default=1, help="random draws per grid point (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="sweep seed (default 0)")
    parser.add_argument("--workers", type=int, default=2,
                        help="local Dask worker processes (default 2; 0 runs in this process, no start-up cost)")
    parser.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler, e.g. tcp://host:8786")
    _folder_completion(parser.add_argument("--out", type=Path, default=None,
                                           help="results folder (default results/sweep-<scenario>)"))
    parser.add_argument("--no-report", action="store_true", help="do not write the HTML report sweep.html")


def cmd_sweep(args: argparse.Namespace) -> int:
    from cosim import sweep, sweep_report
    from cosim.catalog import load

    scenario = load(args.scenario)
    runs = sweep.plan(args.scenario, grid=sweep.parse_grid(args.grid), random=sweep.parse_random(args.random),
                      samples=args.samples, seed=args.seed)
    out = args.out or Path("results") / f"sweep-{scenario.name}"
    table = sweep.sweep(args.scenario, runs, workers=args.workers, scheduler=args.scheduler, out=out,
                        report=not args.no_report)
    verdicts = sweep_report.verdict_counts(table)
    startup = f", {table.attrs['startup_s']:.1f} s of it starting Dask" if table.attrs["startup_s"] else ""
    print(f"{len(table)} runs in {table.attrs['wall_time_s']:.1f} s{startup}: "
          + ", ".join(f"{n} {v}" for v, n in verdicts.items()))
    for line in sweep_report.reasons(table, limit=SHOWN_FAILURES):
        print(f"  {line}")
    for key, name in table.attrs["legend"].items():
        print(f"  {key} = {name}")
    files = "sweep.parquet, sweep.json" + ("" if args.no_report else ", sweep.html (report)")
    print(f"results in {out}/ ({files})")
    return EXIT_PASS if verdicts.get("ERROR", 0) == 0 else EXIT_FAIL


# -- others ---------------------------------------------------------------------------------------

def _pokeys_device_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    from cosim.pokeys_device.cli import add_parser

    return add_parser(sub)


def cmd_pokeys_device(args: argparse.Namespace) -> int:
    from cosim.pokeys_device.cli import cmd_pokeys_device as run

    return run(args)


def _args_main(parser: argparse.ArgumentParser) -> None:
    _folder_completion(parser.add_argument("--out", type=Path, default=Path("results"),
                                           help="results folder (default results/)"))


def cmd_main(args: argparse.Namespace) -> int:
    from cosim.mainjob import main_job

    return main_job(args.out)


SHELLS = ("bash", "zsh", "tcsh")


def _args_completion(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("shell", choices=SHELLS, help="the shell to complete for")


def cmd_completion(args: argparse.Namespace) -> int:
    import shtab

    print(shtab.complete(_parser(), shell=args.shell))
    return EXIT_PASS


# -- the table of commands ------------------------------------------------------------------------

@dataclass(frozen=True)
class Command:
    """One sub-command: its name, what it does, how its arguments are declared and how it runs.

    ``arguments`` adds the arguments to the sub-command's parser; a command whose parser is made
    elsewhere gives ``parser`` instead (it gets the sub-parsers object and returns the parser).
    """

    name: str
    run: Callable[[argparse.Namespace], int]
    help: str = ""
    description: str | None = None
    epilog: str | None = None
    arguments: Callable[[argparse.ArgumentParser], None] | None = None
    parser: Callable[[argparse._SubParsersAction], argparse.ArgumentParser] | None = None


COMMANDS: tuple[Command, ...] = (
    Command("run", cmd_run, "run one scenario or machine file and check its timing", arguments=_args_run,
            description="Run a bundled scenario (by name), your own scenario script (.py) or a machine file "
                        f"(.toml), or, with --machine, {PROGRAM_KINDS} on a machine file's machine; print the "
                        "check table and write result.json, console.txt, trace.vcd and tables.",
            epilog="examples: cosim run laser_pwm --set pwm_on=200; cosim run examples/pokeys_mill/mill.toml "
                   "--set controller.axis.x.max_speed_hz=12000; cosim run engrave.bas --machine engraver.toml; "
                   "cosim run pocket.nc --machine router.toml; cosim run shear.pmc --machine shear.toml. "
                   + EPILOG),
    Command("check-machine", cmd_check_machine, "check a machine file: build the machine without running it",
            arguments=_args_check_machine,
            description="Read MACHINE.toml, check every key, load its programs and FMUs and join the couplings, "
                        "without simulating: errors name the file and the key (or the program's line), with the "
                        "allowed values. Exit 0 when the machine can run, 2 when it cannot."),
    Command("export-fmu", cmd_export_fmu, "export a machine file as an FMI 3.0 (or 2.0) co-simulation FMU",
            arguments=_args_export_fmu,
            description="Write MACHINE.toml as a co-simulation FMU whose outputs and inputs are those its [export] "
                        "table names (controller signals, step counts, plant variables; switches and digital "
                        "inputs). The FMU runs the machine in cosim's integer time in Python: it carries cosim and "
                        "the packages the machine imports as wheels, installed on first use into a per-user cache, "
                        "so it runs on any computer of this platform with a CPython of this minor version (--linked: "
                        "it uses this environment instead). Event-bearing outputs (gate edges, direction, limit "
                        "stops) come with FMI 3.0 early return and event mode. See docs/export.md.",
            epilog="example: cosim export-fmu examples/trio_tn20_81/tn20_81.toml -o tn20_81.fmu"),
    Command("list", cmd_list, "list the bundled scenarios and example machines with their descriptions"),
    Command("params", cmd_params, "show a scenario's parameters or a machine file's keys (value, unit, allowed)",
            arguments=_args_params,
            description="A scenario (a bundled name or a .py script): its declared parameters with default, unit, "
                        "allowed range and help. A machine file (.toml): every key it gives and the defaults of the "
                        "keys it does not, with unit and allowed values (the machine is built, not run)."),
    Command("build-fmus", cmd_build, "build the plant FMUs (FMI 2.0 and 3.0); says what it built and where",
            arguments=_args_build,
            description="Build the plant FMUs that are missing or older than their sources (all with --force). "
                        "In a source checkout they go to models/; an installed cosim keeps them in a per-user "
                        "cache. Prints one line per FMU and where they are."),
    Command("check-fmus", cmd_check, "validate the built FMUs with fmpy's validator (builds missing ones first)"),
    Command("fmu-info", cmd_fmu_info, "what is in an FMU: variables, units, ranges, and the couplings it can serve",
            arguments=_args_fmu_info,
            description="Read an FMU file (nothing is run): FMI version, interfaces, every variable (type, "
                        "causality, variability, unit, start, range, dimensions), default experiment, the "
                        "platforms it has binaries for, and for each coupling whether its roles are found "
                        "under the bundled FMUs' names or which ones to map with variables={role: name}."),
    Command("run-fmu", cmd_run_fmu, "simulate one FMU alone (like fmpy's simulate_fmu) into a result folder",
            arguments=_args_run_fmu,
            description="Simulate one co-simulation FMU with the master: start values from --set, inputs over "
                        "time from --input TABLE.csv, every numeric output recorded on a grid (start, start + "
                        "step, ... and the end), and write the usual result folder (result.json, trace.vcd, "
                        "tables) and outputs.csv (the grid with the FMU's own variable names). An FMU that asks "
                        "to end the simulation ends the run there, with a last sample at that instant (verdict "
                        "TERMINATED, exit status 3). It declares no checks: its verdict is UNCHECKED, with exit "
                        "status 0. A file that is not an FMU, or an FMU fmpy's validator flags (without "
                        "--no-validate), exits 2.",
            epilog="examples: cosim run-fmu models/fmi3/Stepper.fmu --set step_rate=2000 --until '50 ms' "
                   "--step '1 ms'; cosim run-fmu Feedthrough.fmu --input inputs.csv --step '10 ms'; cosim run-fmu "
                   "legacy.fmu --no-validate"),
    Command("sweep", cmd_sweep, "run a scenario over a parameter grid and/or seeded random samples, on Dask",
            arguments=_args_sweep,
            description="Run SCENARIO for every combination of --grid values, times --samples random draws of "
                        "the --random parameters. Run i is seeded from (--seed, i) only, so the table is the "
                        "same with any number of workers. Writes OUT/sweep.parquet (one row per run: "
                        "parameters, verdict, error, failed checks, check columns c1.*, c2.*, figures fig.*), "
                        "OUT/sweep.json (the legend of the column names) and OUT/sweep.html (each figure "
                        "against each swept parameter, coloured by verdict). Prints why runs failed.",
            epilog="example: cosim sweep laser_pwm --grid pwm_period=200,1000 --random gate_ms=0.5:3 --samples 20"),
    Command("pokeys-device", cmd_pokeys_device, parser=_pokeys_device_parser),
    Command("main", cmd_main, "the main job: build, run every bundled scenario, summary and report",
            arguments=_args_main),
    Command("completion", cmd_completion, "print a shell completion script (bash, zsh, tcsh)",
            arguments=_args_completion,
            description="Print a completion script for SHELL. Install it, for example, with\n"
                        "  cosim completion bash > ~/.local/share/bash-completion/completions/cosim\n"
                        "  cosim completion zsh > ~/.zfunc/_cosim   (with fpath+=~/.zfunc before compinit)",
            epilog=None),
)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cosim",
        description="Co-simulation workbench for motion-controller timing: run scenarios, check timing, "
                    "sweep parameters, build and validate the plant FMUs.",
        epilog=EPILOG,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        if command.parser is not None:
            command.parser(sub)
            continue
        formatter = argparse.RawDescriptionHelpFormatter if command.name == "completion" else argparse.HelpFormatter
        child = sub.add_parser(command.name, help=command.help, description=command.description or command.help,
                               epilog=command.epilog, formatter_class=formatter)
        if command.arguments is not None:
            command.arguments(child)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``cosim`` command (and of ``python -m cosim``)."""
    args = _parser().parse_args(argv)
    run = {c.name: c.run for c in COMMANDS}[args.command]
    try:
        return run(args)
    except BrokenPipeError:  # `cosim list | head`: the reader has what it wanted
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return EXIT_PASS
    except (ConfigurationError, ScenarioError) as exc:
        print(f"cosim {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except CosimError as exc:
        print(f"cosim {args.command}: failed: {exc}", file=sys.stderr)
        return EXIT_FAIL


if __name__ == "__main__":
    sys.exit(main())
