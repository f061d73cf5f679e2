"""Build the plant FMUs from ``fmu_src/`` with fmpy's build support.

For each plant (a folder of ``fmu_src/`` with a ``model.toml``) and each FMI version this stages an
FMU folder (model description, ``sources/`` with every file needed to rebuild, documentation),
compiles the platform binary with :func:`fmpy.build.build_platform_binary` (CMake; all warnings on
and turned into errors), checks that the binary exports the plain FMI function names, and zips it
to ``<models>/fmi2/<Model>.fmu`` or ``<models>/fmi3/<Model>.fmu``. The FMI headers come from the
installed fmpy package. :func:`ensure_fmu` rebuilds an FMU that is missing or older than its sources.

Where things are:

* plant sources (``SOURCE_DIR``): ``fmu_src/`` of a source checkout; in an installed wheel,
  ``cosim/_data/fmu_src/`` inside the package;
* built FMUs (``MODELS_DIR``): ``models/`` of a source checkout; for an installed cosim, a per-user
  cache found with ``platformdirs`` (for example ``~/.cache/cosim/<version>/models`` on Linux),

so an installed cosim never writes into its (possibly read-only) package folder. The environment
variables ``COSIM_FMU_SRC`` and ``COSIM_MODELS`` override either place.

Run ``python -m cosim.fmubuild`` (or ``cosim build-fmus``) to build what is missing or stale.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from cosim import __version__, validate
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.fmudesc import ModelSpec

PACKAGE_DIR = Path(__file__).resolve().parent
#: The source checkout cosim runs from (it has ``pyproject.toml`` and ``fmu_src/``), or None when installed.
CHECKOUT: Path | None = (PACKAGE_DIR.parent if (PACKAGE_DIR.parent / "pyproject.toml").is_file()
                         and (PACKAGE_DIR.parent / "fmu_src").is_dir() else None)
#: Data folders the wheel carries inside the package (see ``[tool.hatch.build.targets.wheel.sources]``).
BUNDLED_DIR = PACKAGE_DIR / "_data"


def data_dir(in_checkout: str, in_wheel: str) -> Path:
    """A data folder shipped with cosim: ``in_checkout`` of the source checkout, else ``_data/in_wheel``."""
    return CHECKOUT / in_checkout if CHECKOUT is not None else BUNDLED_DIR / in_wheel


def _cache_dir() -> Path:
    """Per-user cache for FMUs built by an installed cosim (one folder per cosim version)."""
    from platformdirs import user_cache_path

    return user_cache_path("cosim", appauthor=False, version=__version__) / "models"


#: Where the plant sources are (override with ``COSIM_FMU_SRC``).
SOURCE_DIR = Path(os.environ.get("COSIM_FMU_SRC") or data_dir("fmu_src", "fmu_src"))
#: Where built FMUs go: ``models/`` of the checkout, else the per-user cache (override with ``COSIM_MODELS``).
MODELS_DIR = Path(os.environ.get("COSIM_MODELS") or (CHECKOUT / "models" if CHECKOUT is not None else _cache_dir()))
FMI_VERSIONS = (2, 3)
_EXPORTS = {2: ("fmi2Instantiate", "fmi2DoStep", "fmi2GetReal", "fmi2SetBoolean", "fmi2FreeInstance"),
            3: ("fmi3InstantiateCoSimulation", "fmi3DoStep", "fmi3GetFloat64", "fmi3SetBoolean",
                "fmi3UpdateDiscreteStates", "fmi3FreeInstance")}


class BuildError(RuntimeError):
    """A plant FMU could not be built; the message carries the compiler's output."""


def list_models() -> list[str]:
    """Names of the plants in ``fmu_src/`` (folders with a ``model.toml``)."""
    if not SOURCE_DIR.is_dir():
        return []
    return sorted(p.parent.name for p in SOURCE_DIR.glob("*/model.toml"))


def fmu_path(model: str, fmi_version: int = 3) -> Path:
    """Where the built FMU of ``model`` for ``fmi_version`` lives."""
    _check_version(fmi_version)
    return MODELS_DIR / f"fmi{fmi_version}" / f"{model}.fmu"


def _check_version(fmi_version: int) -> None:
    validate.choice(fmi_version, "fmi_version", FMI_VERSIONS, allowed="2 or 3")


def _model_dir(model: str) -> Path:
    folder = SOURCE_DIR / model
    if not (folder / "model.toml").is_file():
        import difflib

        known = list_models()
        close = difflib.get_close_matches(model, known, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ConfigurationError(f"no plant model named {model!r} in {SOURCE_DIR} "
                                 f"(known: {', '.join(known) or 'none'}){hint}")
    return folder


def _inputs(model: str) -> list[Path]:
    """Every file the FMU of ``model`` is made from (its age decides whether to rebuild)."""
    folder = _model_dir(model)
    files = [p for p in folder.iterdir() if p.is_file()]
    files += [p for p in (SOURCE_DIR / "common").iterdir() if p.is_file()]
    files += [Path(__file__), PACKAGE_DIR / "fmudesc.py"]  # (fmudesc is imported where an FMU is built)
    return files


def is_stale(model: str, fmi_version: int = 3) -> bool:
    """True if the FMU is missing or older than any of its sources."""
    target = fmu_path(model, fmi_version)
    if not target.exists():
        return True
    built = target.stat().st_mtime
    return any(p.stat().st_mtime > built for p in _inputs(model))


@contextlib.contextmanager
def _lock() -> Iterator[None]:
    """One build at a time across processes (test runs, scenario runs, a sweep's workers), on any OS."""
    from filelock import FileLock

    MODELS_DIR.mkdir(parents=True, exist_ok=True)
    with FileLock(MODELS_DIR / ".build.lock"):
        yield


def ensure_fmu(model: str, fmi_version: int = 3) -> Path:
    """The FMU of ``model``, built first if it is missing or older than its sources.

    A build (the first use after installing, or after a source changed) says so on stderr, since it
    takes a few seconds.
    """
    _check_version(fmi_version)
    if is_stale(model, fmi_version):
        with _lock():
            if is_stale(model, fmi_version):
                print(f"cosim: building {model} (FMI {fmi_version}.0) into {fmu_path(model, fmi_version)}",
                      file=sys.stderr, flush=True)
                build_fmu(model, fmi_version)
    return fmu_path(model, fmi_version)


def platform_folder(fmi_version: int) -> str:
    """The ``binaries/`` sub-folder for this machine, as fmpy names it (``linux64``, ``x86_64-linux``, ...)."""
    import fmpy

    return str(fmpy.platform_tuple if fmi_version == 3 else fmpy.platform)


def stage(model: str, fmi_version: int, folder: Path) -> ModelSpec:
    """Write the unzipped FMU of ``model`` (without binary) into ``folder``."""
    from cosim import fmudesc

    spec = fmudesc.load_spec(_model_dir(model))
    sources = folder / "sources"
    sources.mkdir(parents=True)
    (folder / "documentation").mkdir()
    for name in (*spec.sources, "model.h", "model.toml"):
        shutil.copy2(spec.folder / name, sources / name)
    for name in (*fmudesc.COMMON_SOURCES, *spec.shared, f"fmi{fmi_version}_cs.c"):
        shutil.copy2(SOURCE_DIR / "common" / name, sources / name)
    (sources / "model_vars.h").write_text(fmudesc.model_vars_h(spec))
    (sources / "model_vars.c").write_text(fmudesc.model_vars_c(spec))
    if fmi_version == 2:
        (folder / "modelDescription.xml").write_text(fmudesc.model_description_fmi2(spec))
    else:
        (folder / "modelDescription.xml").write_text(fmudesc.model_description_fmi3(spec))
        (sources / "buildDescription.xml").write_text(fmudesc.build_description_fmi3(spec))
    for name in ("readme.md", "reference.csv"):
        if (spec.folder / name).exists():
            shutil.copy2(spec.folder / name, folder / "documentation" / name)
    return spec


def compile_binary(unzipdir: Path, *, build_dir: Path | None = None) -> Path:
    """Compile ``unzipdir/sources`` into ``unzipdir/binaries`` with fmpy's CMake project.

    Warnings are errors. Returns the shared library. Raises :class:`BuildError` with the
    compiler output on failure.
    """
    from fmpy import read_model_description, sharedLibraryExtension
    from fmpy.build import build_platform_binary

    md = read_model_description(str(unzipdir))
    fmi_version = 3 if md.fmiVersion.startswith("3") else 2
    identifier = md.coSimulation.modelIdentifier
    options = {
        "CMAKE_C_FLAGS:STRING": "-Werror -fvisibility=hidden",
        "CMAKE_C_STANDARD_LIBRARIES:STRING": "-lm",
    }
    with tempfile.TemporaryDirectory(prefix="cosim-build-") as tmp:
        work = Path(build_dir or tmp)
        work.mkdir(parents=True, exist_ok=True)
        log = work / "build.log"
        with open(log, "w") as out, _redirect(out):
            try:
                build_platform_binary(str(unzipdir), str(work), all_warnings=True, cmake_options=options)
            except (subprocess.CalledProcessError, OSError) as exc:
                out.flush()
                raise BuildError(f"building {identifier} (FMI {fmi_version}.0) failed: {exc}\n"
                                 f"{_tail(log.read_text())}") from exc
    library = unzipdir / "binaries" / platform_folder(fmi_version) / f"{identifier}{sharedLibraryExtension}"
    if not library.exists():
        raise BuildError(f"the build of {identifier} produced no {library}")
    check_exports(library, fmi_version)
    return library


@contextlib.contextmanager
def _redirect(out: object) -> Iterator[None]:
    """Send the compiler's output (written by subprocesses to fds 1 and 2) to ``out``."""
    fileno = out.fileno()  # type: ignore[attr-defined]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    try:
        os.dup2(fileno, 1)
        os.dup2(fileno, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        os.close(saved[0])
        os.close(saved[1])


def _tail(text: str, lines: int = 40) -> str:
    return "\n".join(text.splitlines()[-lines:])


def check_exports(library: Path, fmi_version: int) -> None:
    """Raise :class:`BuildError` unless ``library`` exports the plain (unprefixed) FMI names."""
    lib = ctypes.CDLL(str(library))
    missing = [name for name in _EXPORTS[fmi_version] if not hasattr(lib, name)]
    if missing:
        raise BuildError(f"{library.name} does not export {', '.join(missing)} (function prefix set by mistake?)")


def build_fmu(model: str, fmi_version: int = 3) -> Path:
    """Build ``models/fmi<version>/<model>.fmu`` from ``fmu_src/<model>``; returns its path."""
    _check_version(fmi_version)
    target = fmu_path(model, fmi_version)
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=f"cosim-{model}-fmi{fmi_version}-") as tmp:
        unzipdir = Path(tmp) / "fmu"
        stage(model, fmi_version, unzipdir)
        compile_binary(unzipdir, build_dir=Path(tmp) / "build")
        partial = target.with_suffix(".fmu.part")
        _zip(unzipdir, partial)
        os.replace(partial, target)
    return target


def _zip(folder: Path, target: Path) -> None:
    """Zip ``folder`` deterministically (sorted names, fixed timestamps)."""
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            info = zipfile.ZipInfo(path.relative_to(folder).as_posix(), date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, path.read_bytes())


@dataclass(frozen=True)
class BuildOutcome:
    """What :func:`build_all` did for one FMU."""

    model: str
    fmi_version: int
    path: Path
    built: bool
    seconds: float

    def line(self) -> str:
        """One line for the terminal: ``built ... (4.1 s)`` or ``up to date ...``."""
        what = f"{self.model} FMI {self.fmi_version}.0"
        return (f"built       {what:<18} {self.path}  ({self.seconds:.1f} s)" if self.built
                else f"up to date  {what:<18} {self.path}")


def build_all(*, force: bool = False, models: list[str] | None = None,
              say: Callable[[str], None] | None = None) -> list[BuildOutcome]:
    """Build every plant (or ``models``) for FMI 2.0 and 3.0: what is missing or stale, or all if ``force``.

    ``say`` gets one line per FMU as it is done. Raises :class:`~cosim.errors.ConfigurationError`
    when there are no plant sources at all (a broken install) or a model name is unknown.
    """
    names = models or list_models()
    if not names:
        raise ConfigurationError(f"no plant sources in {SOURCE_DIR} (folders with a model.toml): "
                                 "the installation is incomplete, or COSIM_FMU_SRC points to the wrong place")
    for model in names:
        _model_dir(model)
    outcomes = []
    for model in names:
        for version in FMI_VERSIONS:
            started = time.perf_counter()
            with _lock():
                built = force or is_stale(model, version)
                path = build_fmu(model, version) if built else fmu_path(model, version)
            outcome = BuildOutcome(model, version, path, built, time.perf_counter() - started)
            if say is not None:
                say(outcome.line())
            outcomes.append(outcome)
    return outcomes


def summary(outcomes: list[BuildOutcome]) -> str:
    """``N built, M up to date in MODELS_DIR (sources: SOURCE_DIR)``."""
    built = sum(o.built for o in outcomes)
    return f"{built} built, {len(outcomes) - built} up to date in {MODELS_DIR} (sources: {SOURCE_DIR})"


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m cosim.fmubuild",
        description=f"Build the plant FMUs (FMI 2.0 and 3.0) from {SOURCE_DIR} into {MODELS_DIR}/fmi2 and fmi3. "
                    "Only FMUs that are missing or older than their sources are rebuilt.")
    parser.add_argument("models", nargs="*", metavar="MODEL", help=f"plants to build (default: all of "
                        f"{', '.join(list_models()) or SOURCE_DIR})")
    parser.add_argument("--force", action="store_true", help="rebuild even if up to date")
    parser.add_argument("--quiet", action="store_true", help="print only what was built")
    args = parser.parse_args(argv)

    def say(line: str) -> None:
        if not (args.quiet and line.startswith("up to date")):
            print(line, flush=True)

    try:
        outcomes = build_all(force=args.force, models=args.models or None, say=say)
    except (ConfigurationError, BuildError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(summary(outcomes))
    return 0


if __name__ == "__main__":
    sys.exit(main())
