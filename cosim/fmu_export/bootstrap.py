"""First instantiation of a portable exported FMU: its wheels installed into a per-user cache, offline.

This file is copied into every portable FMU as ``resources/cosim/bootstrap.py``; the FMU's C entry
point runs it (``runpy.run_path``) in the Python it found and calls :func:`prepare` before it
imports cosim. It uses the standard library only: cosim and its dependencies are what it installs.

What :func:`prepare` does:

1. checks that every wheel in ``resources/cosim/wheels`` fits this Python and this computer (the
   CPython minor version of a compiled wheel, its processor and, for a ``manylinux`` wheel, the
   C library's version), and says which does not;
2. unpacks the wheels, unless it did so before, into ``<cache>/cosim/fmu/<digest>/site``: the
   cache is ``$COSIM_FMU_CACHE``, else ``$XDG_CACHE_HOME``, else ``~/.cache``; the digest is the
   FMU's (a SHA-256 of its machine and wheels, written at export), so two FMUs never share a folder
   and one FMU is unpacked once. Unpacking goes to a staging folder renamed into place when
   complete, so an interrupted or concurrent first instantiation never leaves half a folder;
3. puts that folder on ``sys.path``: first, in an interpreter the FMU started itself (a C
   importer); last, in an importer's own Python (fmpy), whose packages then take precedence.

Nothing is downloaded: a wheel that is missing or does not fit is an error naming it.
"""

from __future__ import annotations

import os
import platform
import re
import shutil
import sys
import zipfile
from pathlib import Path

#: The marker of a complete installation.
COMPLETE = "COMPLETE"


def cache_root() -> Path:
    """Where installations go: ``$COSIM_FMU_CACHE``, else ``$XDG_CACHE_HOME/cosim/fmu``, else ``~/.cache/cosim/fmu``."""
    own = os.environ.get("COSIM_FMU_CACHE")
    if own:
        return Path(own)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "cosim" / "fmu"


def prepare(resources: str, digest: str, own_interpreter: int) -> str:
    """Install the FMU's wheels once and put them on ``sys.path``; returns the folder they are in.

    Raises
    ------
    RuntimeError
        With a message saying what is missing or does not fit (the C entry point logs it).
    """
    wheels_dir = Path(resources) / "cosim" / "wheels"
    wheels = sorted(wheels_dir.glob("*.whl"))
    if not wheels:
        raise RuntimeError(f"the FMU carries no wheels: {wheels_dir} holds none (its resources are incomplete; "
                           "export the machine again with cosim export-fmu)")
    if not re.fullmatch(r"[0-9a-f]{16,64}", digest):
        raise RuntimeError(f"the FMU's digest {digest!r} is not a hexadecimal SHA-256 (export the machine again)")
    misfits = [reason for wheel in wheels if (reason := misfit(wheel.name))]
    if misfits:
        raise RuntimeError("the FMU's Python packages do not fit this computer: " + "; ".join(misfits))
    root = cache_root()
    folder = root / digest
    site = folder / "site"
    if not (folder / COMPLETE).is_file():
        _install(wheels, root, folder)
    path = str(site)
    if path not in sys.path:
        if own_interpreter:
            sys.path.insert(0, path)
        else:
            sys.path.append(path)
    return path


def misfit(name: str) -> str:
    """Why the wheel ``name`` does not fit this Python and computer ("" if it fits)."""
    parts = name[:-4].split("-")
    if len(parts) < 5:
        return f"{name} is not a wheel's name"
    python_tags, abi_tags, platform_tags = (parts[-3].split("."), parts[-2].split("."), parts[-1].split("."))
    version = f"{sys.version_info.major}{sys.version_info.minor}"
    compiled = [tag for tag in python_tags if tag.startswith("cp")]
    if compiled and f"cp{version}" not in compiled and "abi3" not in abi_tags:
        wanted = ", ".join(f"CPython {tag[2]}.{tag[3:]}" for tag in compiled)
        return f"{name} is for {wanted}, this is Python {sys.version.split()[0]}"
    if "any" in platform_tags:
        return ""
    machine = platform.machine()
    fitting = [tag for tag in platform_tags if tag.endswith("_" + machine) and tag.startswith(("manylinux", "linux"))]
    if not fitting or not sys.platform.startswith("linux"):
        return f"{name} is for {', '.join(platform_tags)}, this computer is {sys.platform} {machine}"
    libc = _glibc()
    needed = [_manylinux(tag) for tag in fitting]
    if libc is not None and all(need is not None and need > libc for need in needed):
        have = ".".join(map(str, libc))
        least = ".".join(map(str, min(n for n in needed if n is not None)))
        return f"{name} needs the GNU C library {least} or newer, this computer has {have}"
    return ""


def _manylinux(tag: str) -> tuple[int, int] | None:
    match = re.match(r"manylinux_(\d+)_(\d+)_", tag)
    if match:
        return int(match.group(1)), int(match.group(2))
    return {"manylinux1": (2, 5), "manylinux2010": (2, 12), "manylinux2014": (2, 17)}.get(tag.rsplit("_", 2)[0])


def _glibc() -> tuple[int, int] | None:
    try:
        text = os.confstr("CS_GNU_LIBC_VERSION") or ""
    except (ValueError, OSError, AttributeError):
        return None
    match = re.search(r"(\d+)\.(\d+)", text)
    return (int(match.group(1)), int(match.group(2))) if match else None


def _install(wheels: list[Path], root: Path, folder: Path) -> None:
    """Unpack every wheel into a staging folder, then rename it to ``folder`` (another process may win)."""
    try:
        root.mkdir(parents=True, exist_ok=True)
        staging = root / f".{folder.name}.partial-{os.getpid()}"
        shutil.rmtree(staging, ignore_errors=True)
        site = staging / "site"
        site.mkdir(parents=True)
        for wheel in wheels:
            with zipfile.ZipFile(wheel) as archive:
                for item in archive.infolist():
                    target = site / item.filename
                    if not target.resolve().is_relative_to(site.resolve()):
                        raise RuntimeError(f"{wheel.name} holds a file outside its folder: {item.filename}")
                    archive.extract(item, site)
                    mode = (item.external_attr >> 16) & 0o777
                    if mode:
                        os.chmod(target, mode)
        (staging / COMPLETE).write_text("\n".join(wheel.name for wheel in wheels) + "\n")
        try:
            os.replace(staging, folder)
        except OSError:  # installed meanwhile by another instance: keep theirs
            shutil.rmtree(staging, ignore_errors=True)
            if not (folder / COMPLETE).is_file():
                raise
    except OSError as exc:
        raise RuntimeError(f"cannot install the FMU's Python packages into {folder}: {exc} (set COSIM_FMU_CACHE to a "
                           "folder you can write)") from exc
