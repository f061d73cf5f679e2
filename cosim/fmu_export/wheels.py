"""The wheels a portable exported FMU carries: cosim and the distributions its machine imports.

A portable FMU (the default of ``cosim export-fmu``) runs on a computer that has only the FMU and a
stock CPython of the same minor version: it carries, in ``resources/cosim/wheels/``, a wheel of
cosim and one of every distribution the machine's runtime imports, and installs them on first
instantiation into a per-user cache (:mod:`cosim.fmu_export.bootstrap`).

Which distributions: :func:`imported_distributions` builds the machine from the FMU's own
resources in a child interpreter, as the FMU's runtime does (instantiation, initialisation and
its first steps), and maps the modules it imported to their distributions
(``importlib.metadata.packages_distributions``). The wheels are made from what is installed here
(no network, no build): :func:`wheel_of` packs an installed distribution's files as its ``RECORD``
lists them (those inside the site folder: no scripts, no bytecode) with its own ``METADATA`` and
``WHEEL`` and a new ``RECORD``; cosim from a source checkout (an editable install) is packed from
its package folder. Each wheel is made once per distribution version and content, kept in the FMU
cache (``models/export/wheels``), and written deterministically (sorted entries, fixed times).
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import subprocess
import sys
import zipfile
from collections.abc import Iterable
from importlib import metadata
from pathlib import Path

from cosim.errors import ConfigurationError

#: Distributions never carried: the installers, which a runtime does not import.
NOT_CARRIED = frozenset({"pip", "setuptools", "wheel"})
#: The fixed time of every wheel entry (deterministic wheels).
ZIP_TIME = (1980, 1, 1, 0, 0, 0)
#: Files of an installed dist-info folder that are the installer's, not the distribution's.
INSTALLER_FILES = frozenset({"RECORD", "INSTALLER", "REQUESTED", "direct_url.json"})
COSIM = "cosim-workbench"

_PROBE = r"""
import json, sys
from pathlib import Path
before = set(sys.modules)
resources, fmi_version, steps = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
from cosim.fmu_export.runtime import Slave
description = json.loads((resources / "cosim" / "machine.json").read_text())
messages = []
slave = Slave(resources, description["token"], fmi_version=fmi_version, event_mode_used=fmi_version == 3,
              early_return_allowed=fmi_version == 3, log=lambda *m: messages.append(m), logging_on=False)
slave.enter_initialization(0.0, 0, 0.0)
slave.exit_initialization()
step = float(sys.argv[4])
for k in range(steps):
    t = slave.values[0]
    if slave.do_step(t, step) != 0:
        break
    if slave.step[2]:  # an early return: event mode, as an importer would
        slave.update_discrete_states()
slave.free()
from importlib import metadata
owners = metadata.packages_distributions()
new = {name.partition(".")[0] for name in set(sys.modules) - before}
print(json.dumps(sorted({d for name in new for d in owners.get(name, [])})))
"""


def imported_distributions(resources: Path, *, fmi_version: int, step_s: float, steps: int = 50) -> list[str]:
    """The distributions the machine's runtime imports, found by running it in a child interpreter.

    The child builds the machine from ``resources`` (the FMU's resources folder), initialises it and
    takes ``steps`` steps of ``step_s``, as an importer would; it inherits this interpreter's
    environment (``sys.path`` of the child: the same site folders and ``PYTHONPATH``).
    """
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    done = subprocess.run([sys.executable, "-c", _PROBE, str(resources), str(fmi_version), str(steps), repr(step_s)],
                          capture_output=True, text=True, env=env)
    if done.returncode != 0:
        tail = "\n".join((done.stdout + done.stderr).splitlines()[-20:])
        raise ConfigurationError(f"the exported machine does not run from its own resources:\n{tail}")
    found = json.loads(done.stdout.splitlines()[-1])
    return sorted({*found, COSIM} - NOT_CARRIED, key=str.lower)


def distribution(name: str) -> metadata.Distribution:
    """The installed distribution ``name`` (ConfigurationError if it is not installed)."""
    try:
        return metadata.distribution(name)
    except metadata.PackageNotFoundError:
        raise ConfigurationError(f"the distribution {name} is not installed here: it cannot be carried in the "
                                 "FMU") from None


def wheel_of(name: str, cache: Path) -> Path:
    """A wheel of the installed distribution ``name``, made once into ``cache`` and reused."""
    dist = distribution(name)
    files = _files(dist)
    version = dist.version
    stem = _normalize(dist.metadata["Name"] or name)
    content = hashlib.sha256("\n".join(f"{arc}:{source.stat().st_size}:{source.stat().st_mtime_ns}"
                                       for arc, source in files).encode()).hexdigest()[:12]
    target = cache / content / f"{stem}-{version}-{_tag(dist)}.whl"  # one folder per content: never stale
    if target.is_file():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    info = f"{stem}-{version}.dist-info"
    entries = [(arc, source.read_bytes()) for arc, source in files]
    entries.append((f"{info}/METADATA", (dist.read_text("METADATA") or f"Name: {name}\nVersion: {version}\n").encode()))
    entries.append((f"{info}/WHEEL", _wheel_text(dist).encode()))
    _write_wheel(target, entries, info)
    return target


def _files(dist: metadata.Distribution) -> list[tuple[str, Path]]:
    """(name in the wheel, installed file) of a distribution: its RECORD's files in the site folder, or for
    an editable install (a source checkout) its package folders."""
    direct = dist.read_text("direct_url.json")
    if direct and json.loads(direct).get("dir_info", {}).get("editable"):
        return _editable_files(dist)
    root = Path(str(dist.locate_file("")))
    info = f"{_normalize(dist.metadata['Name'])}-{dist.version}.dist-info"
    files = []
    for item in dist.files or []:
        text = str(item).replace("\\", "/")
        if text.startswith("..") or item.suffix == ".pyc" or "__pycache__" in item.parts:
            continue
        if item.parts[0].endswith(".dist-info"):
            if item.name in INSTALLER_FILES or item.name in ("METADATA", "WHEEL"):
                continue
            text = "/".join((info, *item.parts[1:]))  # the wheel's dist-info folder, however it was spelt here
        source = root / item
        if source.is_file():
            files.append((text, source))
    return sorted(files)


def _editable_files(dist: metadata.Distribution) -> list[tuple[str, Path]]:
    """The importable packages of an editable install, found where this interpreter imports them."""
    import importlib.util

    name = dist.metadata["Name"]
    tops = ["cosim"] if _normalize(name) == _normalize(COSIM) else (dist.read_text("top_level.txt") or "").split()
    files = []
    for top in tops:
        spec = importlib.util.find_spec(top)
        if spec is None or spec.origin is None:
            continue
        origin = Path(spec.origin)
        if origin.name != "__init__.py":
            files.append((origin.name, origin))
            continue
        folder = origin.parent
        for path in folder.rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
                files.append((f"{top}/{path.relative_to(folder).as_posix()}", path))
    if not files:
        raise ConfigurationError(f"cannot find the packages of the editable install {dist.metadata['Name']}")
    return sorted(files)


def _tag(dist: metadata.Distribution) -> str:
    """The wheel's compatibility tag (``py3-none-any``, ``cp311-cp311-manylinux_2_17_x86_64``...)."""
    tags = [line.split(":", 1)[1].strip() for line in (dist.read_text("WHEEL") or "").splitlines()
            if line.startswith("Tag:")]
    if not tags:
        return "py3-none-any"
    parts = [sorted({tag.split("-")[i] for tag in tags}) for i in range(3)]
    return "-".join(".".join(part) for part in parts)


def _wheel_text(dist: metadata.Distribution) -> str:
    installed = dist.read_text("WHEEL")
    direct = dist.read_text("direct_url.json")
    if installed and not (direct and json.loads(direct).get("dir_info", {}).get("editable")):
        return installed
    return "Wheel-Version: 1.0\nGenerator: cosim export-fmu\nRoot-Is-Purelib: true\nTag: py3-none-any\n"


def _normalize(name: str) -> str:
    return re.sub(r"[-_.]+", "_", name).lower()


def _write_wheel(target: Path, entries: list[tuple[str, bytes]], info: str) -> None:
    """Write a wheel deterministically (sorted entries, fixed times, a RECORD with every file's hash)."""
    record = []
    for name, data in entries:
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{name},sha256={digest},{len(data)}")
    record.append(f"{info}/RECORD,,")
    entries = [*entries, (f"{info}/RECORD", ("\n".join(sorted(record)) + "\n").encode())]
    partial = target.with_name(f"{target.name}.{os.getpid()}.part")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as wheel:
        for name, data in sorted(entries):
            item = zipfile.ZipInfo(name, date_time=ZIP_TIME)
            item.compress_type = zipfile.ZIP_DEFLATED
            item.external_attr = (0o755 if name.endswith(".so") or ".so." in name else 0o644) << 16
            wheel.writestr(item, data)
    os.replace(partial, target)


def wheels_for(names: Iterable[str], cache: Path) -> list[Path]:
    """The wheels of ``names`` (see :func:`wheel_of`), sorted by file name."""
    return sorted((wheel_of(name, cache) for name in names), key=lambda path: path.name)
