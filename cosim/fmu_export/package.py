"""Writing an exported machine FMU: model description, resources, the C entry point, the zip.

An exported FMU holds::

    modelDescription.xml                FMI 3.0 (or 2.0) co-simulation; time is value reference 0
    binaries/<platform>/<id>.so         the C entry point (fmu_src/export/), the same for every machine
    resources/cosim/machine.json        the machine document, its variables, the instantiation token
    resources/cosim/machine/...         the programs, a PMAC's setup files (and the plants' own FMUs) the
                                        document names
    resources/cosim/runtime.txt         the Python runtime it needs: libpython, PYTHONHOME, site folders
    documentation/index.html            what it is, and what it needs to run

The binary is compiled once per FMI version into the FMU cache (``models/export/`` of a checkout)
with fmpy's CMake project and the FMI headers of the installed fmpy, warnings as errors, and
rebuilt when its sources change. The FMU is written deterministically: the same machine file and
environment give the same bytes.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import uuid
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

from cosim import __version__, validate
from cosim.errors import ConfigurationError
from cosim.fmu_export.machine import ExportedMachine
from cosim.fmu_export.runtime import RESOURCES
from cosim.fmu_export.spec import Port, read_spec

SOURCES = ("machine.h", "machine.c")
WRAPPERS = {2: "fmi2_machine.c", 3: "fmi3_machine.c"}
BINARY = "cosim_machine"
#: A fixed namespace for the instantiation tokens (uuid5 of the FMU's content).
TOKEN_NAMESPACE = uuid.UUID("0b5e6c1e-2c47-4f3e-9a55-6d0c5e3a1f23")
#: The machine file's keys that name files, copied into the FMU (relative to the machine file).
FILE_KEYS = ("program[].file", "controller.setup", "plant.NAME.fmu", "plant.NAME.input")


@dataclass(frozen=True)
class Exported:
    """What :func:`export_fmu` wrote.

    Attributes
    ----------
    path : Path
        The FMU.
    outputs, inputs : tuple of Port
        Its variables (value references 1, 2, ... in this order, outputs first).
    step_s, stop_s : float
        Default communication step and stop time [s].
    wheels : tuple of str
        The wheels a portable FMU carries (file names); empty for a linked one.
    """

    path: Path
    outputs: tuple[Port, ...]
    inputs: tuple[Port, ...]
    step_s: float
    stop_s: float
    wheels: tuple[str, ...] = ()


def export_fmu(machine: str | Path, out: str | Path, *, fmi_version: int = 3,
               overrides: Mapping[str, Any] | None = None, portable: bool = True) -> Exported:
    """Export a machine file as a co-simulation FMU.

    Parameters
    ----------
    machine : path
        The machine file (``.toml``) with an ``[export]`` table.
    out : path
        The ``.fmu`` to write.
    fmi_version : {3, 2}
        FMI 3.0 (early return and event mode at event-bearing outputs) or FMI 2.0.
    overrides : mapping, optional
        ``--set`` values, as for ``cosim run``.
    portable : bool
        Carry cosim and the distributions the machine imports as wheels, installed on first
        instantiation into a per-user cache (:mod:`cosim.fmu_export.bootstrap`): the FMU runs on
        any computer of this platform with a CPython of this minor version (default). False: record
        this environment's site folders instead (a small FMU that runs only where they exist).

    Raises
    ------
    ConfigurationError
        A bad machine file or ``[export]`` table (nothing is written).
    """
    from cosim.machine import load_machine

    fmi_version = validate.choice(fmi_version, "fmi_version", (2, 3), allowed="2 or 3")
    out = Path(out)
    if out.suffix != ".fmu":
        raise ConfigurationError.out_of_range("-o", str(out), "a file name ending .fmu")
    loaded = load_machine(machine)
    values = loaded.resolve(overrides)
    spec = read_spec(values, file=loaded.path)
    built = ExportedMachine(values, file=loaded.path, base=loaded.path.parent)
    try:
        resolution = built.sim.timebase.resolution_s
        step_s, stop_s = float(built.step * resolution), float(built.until * resolution)
        outputs, inputs = tuple(built.outputs), tuple(built.inputs)
    finally:
        built.close()
    document, files = _relocated(values, base=loaded.path.parent, plants=spec.plants)
    variables = [_variable(p, "output") for p in outputs] + [_variable(p, "input") for p in inputs]
    identifier = _identifier(loaded.name)
    token = "{" + str(uuid.uuid5(TOKEN_NAMESPACE, json.dumps([document, variables, __version__], sort_keys=True))) + "}"
    description = {"file": loaded.path.name, "token": token, "cosim_version": __version__,
                   "variables": variables, "document": document}
    text = str(values.get("machine", {}).get("description", "")) or f"the machine {loaded.name}"
    md = (model_description_fmi3 if fmi_version == 3 else model_description_fmi2)(
        name=loaded.name, identifier=identifier, token=token, description=f"{text} (cosim export-fmu)",
        outputs=outputs, inputs=inputs, step_s=step_s, stop_s=stop_s)
    library = binary(fmi_version)
    with tempfile.TemporaryDirectory(prefix="cosim-export-") as tmp:
        root = Path(tmp) / "fmu"
        own = root / "resources" / RESOURCES
        (own / "machine").mkdir(parents=True)
        (root / "modelDescription.xml").write_text(md)
        (own / "machine.json").write_text(json.dumps(description, indent=1, sort_keys=True))
        for target, source in files.items():
            (own / "machine" / target).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, own / "machine" / target)
        wheels: tuple[str, ...] = ()
        digest = ""
        if portable:
            wheels, digest = _carry(root / "resources", own, fmi_version=fmi_version, step_s=step_s)
        (own / "runtime.txt").write_text(runtime_text(digest=digest))
        platform = _platform_folder(fmi_version)
        (root / "binaries" / platform).mkdir(parents=True)
        shutil.copy2(library, root / "binaries" / platform / f"{identifier}.so")
        (root / "documentation").mkdir()
        (root / "documentation" / "index.html").write_text(_documentation(loaded.name, text, outputs, inputs))
        out.parent.mkdir(parents=True, exist_ok=True)
        _zip(root, out)
    return Exported(path=out, outputs=outputs, inputs=inputs, step_s=step_s, stop_s=stop_s, wheels=wheels)


def _carry(resources: Path, own: Path, *, fmi_version: int, step_s: float) -> tuple[tuple[str, ...], str]:
    """Put the wheels the machine needs and the bootstrap into ``own``; their names and the FMU's digest."""
    import hashlib

    from cosim.fmu_export import bootstrap
    from cosim.fmu_export.wheels import imported_distributions, wheels_for
    from cosim.fmubuild import MODELS_DIR

    names = imported_distributions(resources, fmi_version=fmi_version, step_s=step_s)
    folder = own / "wheels"
    folder.mkdir()
    digest = hashlib.sha256((own / "machine.json").read_bytes())
    for wheel in wheels_for(names, MODELS_DIR / "export" / "wheels"):
        shutil.copyfile(wheel, folder / wheel.name)
        digest.update(wheel.name.encode() + hashlib.sha256(wheel.read_bytes()).digest())
    shutil.copyfile(bootstrap.__file__, own / "bootstrap.py")
    digest.update((own / "bootstrap.py").read_bytes())
    return tuple(sorted(p.name for p in folder.iterdir())), digest.hexdigest()


# -- the machine document inside the FMU ------------------------------------------------------------
def _relocated(values: dict[str, Any], *, base: Path, plants: str) -> tuple[dict[str, Any], dict[str, Path]]:
    """The document with its file names pointing into the FMU, and the files to copy there."""
    document = json.loads(json.dumps(values))
    files: dict[str, Path] = {}
    for i, program in enumerate(document.get("program", [])):
        if isinstance(program, dict) and isinstance(program.get("file"), str):
            source = (base / program["file"]).resolve()
            target = f"programs/{i}_{source.name}"
            files[target] = source
            program["file"] = target
    controller = document.get("controller")
    setup = controller.get("setup") if isinstance(controller, dict) else None  # a PMAC's files read at power-up
    if isinstance(setup, str | list):
        names = [setup] if isinstance(setup, str) else setup
        for i, name in enumerate(names):
            if isinstance(name, str):
                source = (base / name).resolve()
                names[i] = f"setup/{i}_{source.name}"
                files[names[i]] = source
        controller["setup"] = names
    if plants == "inside":
        for name, plant in document.get("plant", {}).items():
            if not isinstance(plant, dict):
                continue
            if isinstance(plant.get("model"), str):  # a bundled plant: its built FMU and preset go in as they are
                from cosim.fmubuild import ensure_fmu

                plant["fmu"] = str(ensure_fmu(plant.pop("model"), int(plant.get("fmi", 3))))
                if isinstance(plant.get("preset"), str):
                    from cosim.presets import load_preset

                    plant["parameters"] = {**load_preset(plant.pop("preset")), **plant.get("parameters", {})}
            if isinstance(plant.get("fmu"), str):
                target = f"fmus/{name}.fmu"
                files[target] = (base / plant["fmu"]).resolve()
                plant["fmu"] = target
            if isinstance(plant.get("input"), str):
                target = f"inputs/{name}_{Path(plant['input']).name}"
                files[target] = (base / plant["input"]).resolve()
                plant["input"] = target
    return document, files


def _variable(port: Port, causality: str) -> dict[str, Any]:
    return {"name": port.name, "type": port.fmi_type, "causality": causality, "source": port.source}


def _identifier(name: str) -> str:
    identifier = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return identifier if re.match(r"^[A-Za-z_]", identifier) else f"machine_{identifier}"


# -- the runtime it needs ---------------------------------------------------------------------------
def libpython() -> str:
    """The shared libpython of this interpreter ("" if it was built without one)."""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        return ""
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    for name in (sysconfig.get_config_var("INSTSONAME"), sysconfig.get_config_var("LDLIBRARY")):
        if name and (Path(libdir) / name).is_file():
            return str(Path(libdir) / name)
    return ""


def site_folders() -> list[str]:
    """The folders that make cosim and its dependencies importable: this environment's site folders,
    and the folder holding the cosim package (a source checkout)."""
    import site

    import cosim

    folders = [*site.getsitepackages(), str(Path(cosim.__file__).resolve().parent.parent)]
    return list(dict.fromkeys(f for f in folders if Path(f).is_dir()))


def runtime_text(*, digest: str = "") -> str:
    """``resources/cosim/runtime.txt``: read by the C entry point (key=value lines).

    A portable FMU (``digest`` given) carries its packages (``wheels=``, ``bootstrap=``) and names
    no folder of this environment; the Python it was exported with (``libpython``, ``home``) is the
    first place its entry point looks, then ``python3.X`` on the PATH and the system's libraries.
    A linked one names this environment's site folders (``path=``).
    """
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    lines = ["# The Python runtime this FMU needs (written by cosim export-fmu; read by its C entry point).",
             f"python_version={version}",
             f"python={getattr(sys, '_base_executable', sys.executable)}",
             f"libpython={libpython()}",
             f"home={sys.base_prefix}"]
    if digest:
        lines += ["wheels=wheels", "bootstrap=bootstrap.py", f"digest={digest}"]
    else:
        lines += [f"path={folder}" for folder in site_folders()]
    lines += ["module=cosim.fmu_export.runtime", f"cosim_version={__version__}"]
    return "\n".join(lines) + "\n"


# -- model descriptions -----------------------------------------------------------------------------
def _log_categories() -> str:
    return """  <LogCategories>
    <Category name="logEvents" description="Events: early returns at event-bearing outputs"/>
    <Category name="logStatusWarning" description="Warnings"/>
    <Category name="logStatusError" description="Errors"/>
  </LogCategories>"""


def _description(port: Port) -> str:
    unit = f" [{port.unit}]" if port.unit else ""
    what = {"pulse": "signed pulse count of", "plant": "plant variable"}.get(port.kind, "")
    text = f"{what} {port.source}{unit}".strip() + (f": {port.description}" if port.description else "")
    return quoteattr(text + (" (event-bearing)" if port.event else ""))


def _start(port: Port) -> str:
    if port.fmi_type == "Boolean":
        return "true" if port.start else "false"
    return str(int(port.start)) if port.fmi_type == "Int32" else repr(float(port.start))


def model_description_fmi3(*, name: str, identifier: str, token: str, description: str, outputs: tuple[Port, ...],
                           inputs: tuple[Port, ...], step_s: float, stop_s: float) -> str:
    """FMI 3.0 ``modelDescription.xml`` of an exported machine (early return and event mode)."""
    rows = ['    <Float64 name="time" valueReference="0" causality="independent" variability="continuous" '
            'description="Simulation time"/>']
    for vr, port in enumerate(outputs, start=1):
        variability = "continuous" if port.kind == "plant" and port.fmi_type == "Float64" else "discrete"
        rows.append(f'    <{port.fmi_type} name="{port.name}" valueReference="{vr}" causality="output" '
                    f'variability="{variability}" description={_description(port)}/>')
    for vr, port in enumerate(inputs, start=1 + len(outputs)):
        rows.append(f'    <{port.fmi_type} name="{port.name}" valueReference="{vr}" causality="input" '
                    f'variability="discrete" start="{_start(port)}" description={_description(port)}/>')
    structure = [f'    <Output valueReference="{vr}"/>' for vr in range(1, 1 + len(outputs))]
    structure += [f'    <InitialUnknown valueReference="{vr}"/>' for vr in range(1, 1 + len(outputs))]
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(name)} instantiationToken="{token}"
  description={quoteattr(description)} generationTool="cosim export-fmu {__version__}" version="{__version__}"
  variableNamingConvention="structured">
  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true"
    hasEventMode="true" mightReturnEarlyFromDoStep="true" canReturnEarlyAfterIntermediateUpdate="false"
    providesIntermediateUpdate="false" canGetAndSetFMUState="false" canSerializeFMUState="false"/>
{_log_categories()}
  <DefaultExperiment startTime="0" stopTime="{stop_s!r}" stepSize="{step_s!r}"/>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>
  <ModelStructure>
{chr(10).join(structure)}
  </ModelStructure>
</fmiModelDescription>
"""


def model_description_fmi2(*, name: str, identifier: str, token: str, description: str, outputs: tuple[Port, ...],
                           inputs: tuple[Port, ...], step_s: float, stop_s: float) -> str:
    """FMI 2.0 ``modelDescription.xml`` of an exported machine."""
    types = {"Float64": "Real", "Int32": "Integer", "Boolean": "Boolean"}
    rows = ['    <ScalarVariable name="time" valueReference="0" causality="independent" variability="continuous" '
            'description="Simulation time">\n      <Real/>\n    </ScalarVariable>']
    for vr, port in enumerate(outputs, start=1):
        variability = "continuous" if port.kind == "plant" and port.fmi_type == "Float64" else "discrete"
        rows.append(f'    <ScalarVariable name="{port.name}" valueReference="{vr}" causality="output" '
                    f'variability="{variability}" description={_description(port)}>\n'
                    f'      <{types[port.fmi_type]}/>\n    </ScalarVariable>')
    for vr, port in enumerate(inputs, start=1 + len(outputs)):
        rows.append(f'    <ScalarVariable name="{port.name}" valueReference="{vr}" causality="input" '
                    f'variability="discrete" description={_description(port)}>\n'
                    f'      <{types[port.fmi_type]} start="{_start(port)}"/>\n    </ScalarVariable>')
    unknowns = "\n".join(f'      <Unknown index="{vr + 1}"/>' for vr in range(1, 1 + len(outputs)))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(name)} guid="{token}"
  description={quoteattr(description)} generationTool="cosim export-fmu {__version__}" version="{__version__}"
  variableNamingConvention="structured" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true"/>
{_log_categories()}
  <DefaultExperiment startTime="0" stopTime="{stop_s!r}" stepSize="{step_s!r}"/>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{unknowns}
    </Outputs>
    <InitialUnknowns>
{unknowns}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def _documentation(name: str, text: str, outputs: tuple[Port, ...], inputs: tuple[Port, ...]) -> str:
    rows = "".join(f"<tr><td>{escape(p.name)}</td><td>{kind}</td><td>{p.fmi_type}</td><td>{escape(p.source)}</td>"
                   f"<td>{'yes' if p.event else ''}</td></tr>"
                   for kind, ports in (("output", outputs), ("input", inputs)) for p in ports)
    return (f"<html><body><h1>{escape(name)}</h1><p>{escape(text)}: a machine exported by cosim "
            f"{__version__} (cosim export-fmu).</p><p>It runs cosim in Python: it needs a CPython of the minor version "
            "named in resources/cosim/runtime.txt (a shared libpython for a C importer). A portable FMU carries "
            "cosim and its packages in resources/cosim/wheels and installs them on first use into a per-user cache "
            "(COSIM_FMU_CACHE, else ~/.cache/cosim/fmu); a linked one needs the environment runtime.txt names. It "
            "says in its log what is missing.</p>"
            "<table><tr><th>variable</th><th>causality</th><th>type</th><th>source</th><th>event</th></tr>"
            f"{rows}</table></body></html>\n")


def _zip(folder: Path, target: Path) -> None:
    """Zip ``folder`` deterministically (sorted names, fixed timestamps); written beside, then moved."""
    partial = target.with_name(target.name + ".part")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            info = zipfile.ZipInfo(path.relative_to(folder).as_posix(), date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_STORED if path.suffix == ".whl" else zipfile.ZIP_DEFLATED  # zipped already
            info.external_attr = (0o755 if path.suffix == ".so" else 0o644) << 16
            zf.writestr(info, path.read_bytes())
    os.replace(partial, target)


# -- the binary -------------------------------------------------------------------------------------
def _platform_folder(fmi_version: int) -> str:
    from cosim.fmubuild import platform_folder

    return platform_folder(fmi_version)


def source_dir() -> Path:
    """The C sources of the entry point (``fmu_src/export/``)."""
    from cosim.fmubuild import SOURCE_DIR

    return SOURCE_DIR / "export"


def binary(fmi_version: int) -> Path:
    """The compiled entry point for ``fmi_version``, built first if it is missing or older than its sources."""
    from filelock import FileLock

    from cosim.fmubuild import MODELS_DIR

    target = MODELS_DIR / "export" / f"fmi{fmi_version}" / f"{BINARY}.so"
    sources = [source_dir() / name for name in (*SOURCES, WRAPPERS[fmi_version])]
    missing = [s for s in sources if not s.is_file()]
    if missing:
        raise ConfigurationError(f"the C sources of the FMU entry point are missing: {', '.join(map(str, missing))} "
                                 "(the installation is incomplete)")
    target.parent.mkdir(parents=True, exist_ok=True)
    with FileLock(target.parent / ".build.lock"):
        if not target.is_file() or any(s.stat().st_mtime > target.stat().st_mtime for s in [*sources, Path(__file__)]):
            print(f"cosim: building the FMU entry point (FMI {fmi_version}.0) into {target}", file=sys.stderr,
                  flush=True)
            _compile(fmi_version, sources, target)
    return target


def _compile(fmi_version: int, sources: list[Path], target: Path) -> None:
    from cosim.fmubuild import BuildError, check_exports

    token = "{00000000-0000-0000-0000-000000000000}"
    with tempfile.TemporaryDirectory(prefix="cosim-export-build-") as tmp:
        unzipdir = Path(tmp) / "fmu"
        (unzipdir / "sources").mkdir(parents=True)
        for source in sources:
            shutil.copy2(source, unzipdir / "sources" / source.name)
        c_files = [s.name for s in sources if s.suffix == ".c"]
        if fmi_version == 3:
            (unzipdir / "modelDescription.xml").write_text(
                f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiModelDescription fmiVersion="3.0" modelName="{BINARY}" '
                f'instantiationToken="{token}">\n  <CoSimulation modelIdentifier="{BINARY}"/>\n  <ModelVariables>\n'
                '    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>\n'
                "  </ModelVariables>\n  <ModelStructure/>\n</fmiModelDescription>\n")
            files = "\n".join(f'      <SourceFile name="{name}"/>' for name in c_files)
            (unzipdir / "sources" / "buildDescription.xml").write_text(
                f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiBuildDescription fmiVersion="3.0">\n'
                f'  <BuildConfiguration modelIdentifier="{BINARY}">\n    <SourceFileSet language="C99">\n{files}\n'
                "    </SourceFileSet>\n  </BuildConfiguration>\n</fmiBuildDescription>\n")
        else:
            files = "\n".join(f'      <File name="{name}"/>' for name in c_files)
            (unzipdir / "modelDescription.xml").write_text(
                f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiModelDescription fmiVersion="2.0" modelName="{BINARY}" '
                f'guid="{token}">\n  <CoSimulation modelIdentifier="{BINARY}">\n    <SourceFiles>\n{files}\n'
                "    </SourceFiles>\n  </CoSimulation>\n  <ModelVariables>\n"
                '    <ScalarVariable name="time" valueReference="0" causality="independent" variability="continuous">'
                "<Real/></ScalarVariable>\n  </ModelVariables>\n  <ModelStructure/>\n</fmiModelDescription>\n")
        options = {"CMAKE_C_FLAGS:STRING": "-Werror -fvisibility=hidden",
                   "CMAKE_C_STANDARD_LIBRARIES:STRING": "-ldl -lpthread"}
        script = ("import json, sys; from fmpy.build import build_platform_binary; build_platform_binary("
                  "sys.argv[1], sys.argv[2], all_warnings=True, cmake_options=json.loads(sys.argv[3]))")
        (Path(tmp) / "build").mkdir()
        command = [sys.executable, "-c", script, str(unzipdir), str(Path(tmp) / "build"), json.dumps(options)]
        done = subprocess.run(command, capture_output=True, text=True)
        library = unzipdir / "binaries" / _platform_folder(fmi_version) / f"{BINARY}.so"
        if done.returncode != 0 or not library.is_file():
            tail = "\n".join((done.stdout + done.stderr).splitlines()[-40:])
            raise BuildError(f"building the FMU entry point (FMI {fmi_version}.0) failed:\n{tail}")
        check_exports(library, fmi_version)
        partial = target.with_name(target.name + ".part")
        shutil.copy2(library, partial)
        os.replace(partial, target)


