"""FMUs unzipped once and their model descriptions read once, across runs: the per-user FMU cache.

Loading an FMU used to mean unzipping it into a fresh temporary folder, parsing and validating its
``modelDescription.xml`` (20-30 ms for a bundled plant) and deleting the folder when the
simulation closed. Every run paid that for every plant. Here both are kept in the per-user cache
(``platformdirs``, for example ``~/.cache/cosim/<version>/fmus`` on Linux; ``COSIM_FMU_CACHE``
overrides the folder), under the SHA-256 of the FMU file's bytes: a changed FMU is a new folder,
never a stale one, whatever its name or time stamp.

* :func:`unzipped` gives the folder an instance loads its binary from. A folder is made whole
  (unzipped into a temporary folder beside it, then renamed), so runs that start at the same time
  never see half of one; it is never removed while in use. An FMU that may be instantiated only
  once per process (``canBeInstantiatedOnlyOncePerProcess``) gets a private temporary copy per
  instance, as does every FMU when the cache cannot be written.
* :func:`description` keeps the model description as fmpy read it (pickled next to the unzipped
  files, by fmpy version and validation), so a later run skips the XML parse and the schema check.
  A file that cannot be read back is read from the FMU again and replaced.

Folders not used for :data:`KEEP_DAYS` days are removed when a new one is added; the whole cache
may be deleted at any time (between runs).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import shutil
import tempfile
import time
import zipfile
from pathlib import Path
from typing import Any

#: Folders of the cache not used for this many days are removed when a new one is made.
KEEP_DAYS = 30
_COMPLETE = ".complete"  # written last into a folder: it holds the whole FMU
_DIGESTS: dict[tuple[str, int, int], str] = {}  # (path, mtime_ns, size) -> SHA-256, per process


def cache_folder() -> Path:
    """Where unzipped FMUs are kept: ``COSIM_FMU_CACHE``, else ``fmus`` in cosim's per-user cache."""
    override = os.environ.get("COSIM_FMU_CACHE")
    if override:
        return Path(override)
    from platformdirs import user_cache_path

    from cosim import __version__

    return user_cache_path("cosim", appauthor=False, version=__version__) / "fmus"


def digest(path: Path) -> str:
    """SHA-256 of the file's bytes (hashed once per process and version of the file)."""
    stat = path.stat()
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    known = _DIGESTS.get(key)
    if known is None:
        with path.open("rb") as stream:
            known = _DIGESTS[key] = hashlib.file_digest(stream, "sha256").hexdigest()
    return known


def _entry(path: Path) -> Path:
    return cache_folder() / digest(path)[:40]


def unzipped(path: Path, *, shared: bool = True) -> tuple[Path, bool]:
    """A folder holding the FMU file ``path`` unzipped, and whether the caller owns it (must remove it).

    With ``shared`` (the FMU may be instantiated several times in a process) the folder is the
    cache's, made once; otherwise, or when the cache cannot be written, a private temporary folder.
    """
    if shared:
        try:
            folder = _entry(path)
            if not (folder / _COMPLETE).is_file():
                _fill(path, folder)
            with contextlib.suppress(OSError):
                os.utime(folder)  # in use: kept by the pruning
            return folder, False
        except OSError:
            pass  # no cache: unzip privately
    private = Path(tempfile.mkdtemp(prefix="cosim-fmu-"))
    _unzip(path, private)
    return private, True


def _unzip(path: Path, folder: Path) -> None:
    with zipfile.ZipFile(path) as archive:
        archive.extractall(folder)


def _fill(path: Path, folder: Path) -> None:
    """Unzip ``path`` into a temporary folder beside ``folder`` and rename it there (whole, or not at all)."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    _prune(folder.parent)
    staging = Path(tempfile.mkdtemp(prefix=folder.name + ".", suffix=".tmp", dir=folder.parent))
    try:
        _unzip(path, staging)
        (staging / _COMPLETE).write_text(str(path) + "\n")
        try:
            os.rename(staging, folder)
        except OSError:
            if not (folder / _COMPLETE).is_file():  # not another run's complete folder: replace what is there
                shutil.rmtree(folder, ignore_errors=True)
                os.rename(staging, folder)
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def _prune(parent: Path) -> None:
    """Remove folders, kept descriptions and left-over staging folders not used for :data:`KEEP_DAYS` days."""
    limit = time.time() - KEEP_DAYS * 86400
    with contextlib.suppress(OSError):
        for entry in parent.iterdir():
            with contextlib.suppress(OSError):
                if entry.stat().st_mtime < limit:
                    if entry.is_dir():
                        shutil.rmtree(entry, ignore_errors=True)
                    else:
                        entry.unlink()


def description(path: Path, validate: bool, read: Any) -> Any:
    """The model description of the FMU file ``path``: kept in the cache, else ``read()`` (and kept)."""
    from fmpy import __version__ as fmpy_version

    try:
        kept = _entry(path).with_name(f"{digest(path)[:40]}.description-{fmpy_version}-{int(validate)}.pickle")
    except OSError:
        return read()
    try:
        with kept.open("rb") as stream:
            model = pickle.load(stream)
        with contextlib.suppress(OSError):
            os.utime(kept)  # in use: kept by the pruning
        return model
    except Exception:  # missing, cut short, from another fmpy: read the FMU again
        pass
    model = read()
    with contextlib.suppress(OSError, pickle.PicklingError, TypeError, AttributeError):
        kept.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(dir=kept.parent, prefix=kept.name, suffix=".tmp")
        try:
            with os.fdopen(handle, "wb") as stream:
                pickle.dump(model, stream, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(name, kept)
        finally:
            with contextlib.suppress(OSError):
                os.unlink(name)
    return model
