"""The ``cosim`` command line.

Exit status: 0 when every check passed, 1 when a check failed or a run broke, 2 for usage or
configuration errors (a parameter out of range, an unknown scenario, a broken script).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from cosim.errors import ConfigurationError, CosimError, ScenarioError

EXIT_PASS, EXIT_FAIL, EXIT_USAGE = 0, 1, 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cosim",
        description="Co-simulation workbench for motion-controller timing: run scenarios, check timing, "
                    "build and validate the plant FMUs.",
        epilog="Exit status: 0 all checks passed, 1 a check failed or a run broke, 2 usage/configuration error.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    run = sub.add_parser("run", help="run one scenario and check its timing",
                         description="Run a bundled scenario (by name) or your own script (a .py path), "
                                     "print the check table and write result.json, trace.vcd and tables.")
    run.add_argument("scenario", help="bundled scenario name (see `cosim list`) or path to a .py script")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                     help="set a declared parameter (repeatable; see `cosim params SCENARIO`)")
    run.add_argument("--out", type=Path, default=None,
                     help="results folder (default: results/<scenario>)")
    run.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same trace")
    run.add_argument("--until", default=None, help="end time with unit, e.g. '20 ms' (default: the scenario's)")
    run.add_argument("--format", choices=("parquet", "csv"), default="parquet",
                     help="format of the trace tables (default parquet)")
    run.add_argument("--no-vcd", action="store_true", help="do not write trace.vcd")

    sub.add_parser("list", help="list the bundled scenarios")
    params = sub.add_parser("params", help="show a scenario's parameters (name, default, unit, range, help)")
    params.add_argument("scenario")

    build = sub.add_parser("build-fmus", help="build the plant FMUs (FMI 2.0 and 3.0) into models/")
    build.add_argument("models", nargs="*", help="model names (default: all)")
    build.add_argument("--force", action="store_true", help="rebuild even if up to date")
    sub.add_parser("check-fmus", help="validate the built FMUs with fmpy's validator")

    sweep = sub.add_parser(
        "sweep", help="run a scenario over a parameter grid and/or seeded random samples, on Dask",
        description="Run SCENARIO for every combination of --grid values, times --samples random draws of the "
                    "--random parameters. Run i is seeded from (--seed, i) only, so the table is the same with "
                    "any number of workers. Writes OUT/sweep.parquet (one row per run: parameters, verdict, "
                    "error, every check figure).",
        epilog="example: cosim sweep laser_pwm --grid pwm_period=200,1000 --random pwm_on=0:1000 --samples 50")
    sweep.add_argument("scenario")
    sweep.add_argument("--grid", action="append", default=[], metavar="NAME=V1,V2,...",
                       help="values of one parameter (repeatable; all combinations are run)")
    sweep.add_argument("--random", action="append", default=[], metavar="NAME[=LOW:HIGH]",
                       help="parameter drawn uniformly per sample (default range: the declared one)")
    sweep.add_argument("--samples", type=int, default=1, help="random draws per grid point (default 1)")
    sweep.add_argument("--seed", type=int, default=0, help="sweep seed (default 0)")
    sweep.add_argument("--workers", type=int, default=2,
                       help="local Dask worker processes (default 2; 0 runs in this process)")
    sweep.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler, e.g. tcp://host:8786")
    sweep.add_argument("--out", type=Path, default=None, help="results folder (default results/sweep-<scenario>)")

    from cosim.pokeys_device.cli import add_parser as add_pokeys_device_parser

    add_pokeys_device_parser(sub)

    main = sub.add_parser("main", help="the main job: build, run every bundled scenario, summary and report")
    main.add_argument("--out", type=Path, default=Path("results"), help="results folder (default results/)")
    return parser


def _parse_sets(pairs: Sequence[str]) -> dict[str, str]:
    values = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name.strip():
            raise ConfigurationError(f"--set {pair!r}: write NAME=VALUE, e.g. --set pwm_on=500")
        values[name.strip()] = value.strip()
    return values


def cmd_run(args: argparse.Namespace) -> int:
    from cosim.runner import run_scenario
    from cosim.scenario import load

    scenario = load(args.scenario)
    out = args.out or Path("results") / scenario.name
    formats = (() if args.no_vcd else ("vcd",)) + (args.format,)
    result = run_scenario(scenario, overrides=_parse_sets(args.overrides), seed=args.seed, until=args.until,
                          out=out, formats=formats, progress=True)
    print(result.table())
    print(f"results in {out}/ (result.json, {'trace.vcd, ' if not args.no_vcd else ''}{args.format} tables)")
    if result.error_kind == "configuration":
        return EXIT_USAGE
    return EXIT_PASS if result.verdict == "PASS" else EXIT_FAIL


def cmd_list(args: argparse.Namespace) -> int:
    from cosim.scenario import bundled, load

    names = bundled()
    width = max((len(n) for n in names), default=0)
    for name in names:
        print(f"{name:<{width}}  {load(name).description}")
    return EXIT_PASS


def cmd_params(args: argparse.Namespace) -> int:
    from cosim.scenario import load

    scenario = load(args.scenario)
    print(f"{scenario.name}: {scenario.description}\n(default end time {scenario.until})")
    rows = [(p.name, repr(p.default), p.unit, p.allowed(), p.help) for p in scenario.parameters]
    head = ("name", "default", "unit", "allowed", "help")
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(4)]
    for row in [head, *rows]:
        print("  ".join(f"{c:<{w}}" for c, w in zip(row[:4], widths, strict=True)) + "  " + row[4])
    return EXIT_PASS


def cmd_build(args: argparse.Namespace) -> int:
    from cosim import fmubuild

    models = args.models or fmubuild.list_models()
    for model in models:
        for version in (2, 3):
            path = fmubuild.build_fmu(model, version) if args.force else fmubuild.ensure_fmu(model, version)
            print(f"{path}")
    return EXIT_PASS


def cmd_check(args: argparse.Namespace) -> int:
    from fmpy.validation import validate_fmu

    from cosim import fmubuild

    bad = 0
    for model in fmubuild.list_models():
        for version in (2, 3):
            path = fmubuild.ensure_fmu(model, version)
            problems = validate_fmu(str(path))
            print(f"{'OK  ' if not problems else 'FAIL'}  {path}")
            for problem in problems:
                print(f"      {problem}")
            bad += bool(problems)
    return EXIT_FAIL if bad else EXIT_PASS


def cmd_sweep(args: argparse.Namespace) -> int:
    from cosim import sweep
    from cosim.scenario import load

    scenario = load(args.scenario)
    runs = sweep.plan(args.scenario, grid=sweep.parse_grid(args.grid), random=sweep.parse_random(args.random),
                      samples=args.samples, seed=args.seed)
    out = args.out or Path("results") / f"sweep-{scenario.name}"
    table = sweep.sweep(args.scenario, runs, workers=args.workers, scheduler=args.scheduler, out=out)
    verdicts = table["verdict"].value_counts().to_dict()
    print(f"{len(table)} runs in {table.attrs['wall_time_s']:.1f} s: "
          + ", ".join(f"{n} {v}" for v, n in sorted(verdicts.items())))
    print(f"table: {out / 'sweep.parquet'}")
    return EXIT_PASS if verdicts.get("ERROR", 0) == 0 else EXIT_FAIL


def cmd_pokeys_device(args: argparse.Namespace) -> int:
    from cosim.pokeys_device.cli import cmd_pokeys_device as run

    return run(args)


def cmd_main(args: argparse.Namespace) -> int:
    from cosim.mainjob import main_job

    return main_job(args.out)


COMMANDS = {"run": cmd_run, "list": cmd_list, "params": cmd_params, "build-fmus": cmd_build,
            "check-fmus": cmd_check, "sweep": cmd_sweep,
            "pokeys-device": cmd_pokeys_device, "main": cmd_main}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``cosim`` command."""
    args = _parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except (ConfigurationError, ScenarioError) as exc:
        print(f"cosim {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except CosimError as exc:
        print(f"cosim {args.command}: failed: {exc}", file=sys.stderr)
        return EXIT_FAIL


if __name__ == "__main__":
    sys.exit(main())
