"""Output folders owned by one run: nothing of an earlier run is ever read as part of a new one.

A run writes into a staging folder beside its output folder (``.NAME.partial-PID``) and, when it
is done (whatever its verdict: the trace up to an error or an interrupt is part of its results),
the staging folder replaces the output folder as a whole: a file the earlier run wrote and this
one did not (``values.csv`` after a Parquet run) cannot survive next to the new files.

cosim marks the folders it writes with a file ``.cosim``; it refuses an output folder that holds
files but no mark (a folder it did not write: it never deletes a user's files), and it checks
that it can write beside the folder before the run starts, not after.

Examples
--------
>>> import tempfile
>>> root = Path(tempfile.mkdtemp())
>>> out = OutputFolder(root / "run")
>>> _ = (out.staging / "result.json").write_text("{}")
>>> sorted(p.name for p in out.commit().iterdir())
['.cosim', 'result.json']
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from cosim.errors import ConfigurationError

MARK = ".cosim"
"""The file cosim writes into every output folder it owns (its content never changes: runs stay bit-identical)."""
MARK_TEXT = "This folder was written by cosim; a new run into it replaces it as a whole.\n"


def owned(folder: Path) -> bool:
    """Is ``folder`` absent, empty, or one that cosim wrote (it may be replaced)."""
    if not folder.exists():
        return True
    if not folder.is_dir():
        return False
    return (folder / MARK).is_file() or not any(folder.iterdir())


class OutputFolder:
    """The output folder of one run, staged beside its final place.

    Parameters
    ----------
    folder : path
        Where the results end up (``--out``).

    Raises
    ------
    ConfigurationError
        If ``folder`` is a file, holds files cosim did not write, or cannot be written.
    """

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        if self.folder.exists() and not self.folder.is_dir():
            raise ConfigurationError(f"--out {self.folder} is a file, not a folder")
        blocker = next((p for p in self.folder.parents if p.exists() and not p.is_dir()), None)
        if blocker is not None:
            raise ConfigurationError(f"--out {self.folder}: {blocker} is a file, not a folder")
        if not owned(self.folder):
            names = sorted(p.name for p in self.folder.iterdir())
            shown = ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "")
            raise ConfigurationError(f"--out {self.folder} holds files cosim did not write ({shown}); it never "
                                     "replaces them: choose a new or empty folder")
        parent = self.folder.parent
        self.staging = parent / f".{self.folder.name}.partial-{os.getpid()}"
        try:
            parent.mkdir(parents=True, exist_ok=True)
            if self.staging.exists():
                shutil.rmtree(self.staging)
            self.staging.mkdir()
            (self.staging / MARK).write_text(MARK_TEXT)
        except OSError as exc:
            raise ConfigurationError(f"--out {self.folder}: cannot write there ({exc.strerror or exc}); choose a "
                                     "folder you can write to") from None

    def commit(self) -> Path:
        """Put the staged results in place of the folder (and of an earlier run's results); returns the folder."""
        old = None
        if self.folder.exists():
            old = self.folder.parent / f".{self.folder.name}.replaced-{os.getpid()}"
            if old.exists():
                shutil.rmtree(old)
            self.folder.rename(old)
        self.staging.rename(self.folder)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.folder
