"""The per-user FMU cache: an FMU is unzipped and its model description read once, never stale.

    run 1:  Stepper.fmu --sha256--> <cache>/<hash>/  (unzipped whole, renamed into place) + description
    run 2:  Stepper.fmu --sha256--> <cache>/<hash>/  found: no unzip, no XML parse
    edit :  Stepper.fmu (other bytes) --> <cache>/<other hash>/   (the old folder is never read for it)
"""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path

import pytest

from cosim import fmucache
from cosim.fmu import Fmu, _read_description
from cosim.fmubuild import ensure_fmu

pytestmark = pytest.mark.fmu


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("COSIM_FMU_CACHE", str(tmp_path / "fmus"))
    _read_description.cache_clear()
    return tmp_path / "fmus"


def _laser(tmp_path: Path) -> Path:
    copy = tmp_path / "Laser.fmu"
    shutil.copy(ensure_fmu("Laser", 3), copy)
    return copy


def test_an_fmu_is_unzipped_once_and_its_folder_outlives_the_instances(cache: Path, tmp_path: Path) -> None:
    path = _laser(tmp_path)
    with Fmu(path, instance_name="a") as first, Fmu(path, instance_name="b") as second:
        assert first._unzipdir == second._unzipdir
        folder = Path(first._unzipdir)
        assert folder.parent == cache and folder.name == fmucache.digest(path)[:40]
        assert (folder / "modelDescription.xml").is_file() and (folder / ".complete").is_file()
    assert folder.is_dir()  # kept for the next run
    assert [p.name for p in cache.iterdir() if p.is_dir()] == [folder.name]  # no staging folder left


def test_a_changed_fmu_gets_its_own_folder_never_the_old_one(cache: Path, tmp_path: Path) -> None:
    path = _laser(tmp_path)
    old, _ = fmucache.unzipped(path)
    with zipfile.ZipFile(path, "a") as archive:  # other bytes, same name
        archive.writestr("documentation/note.txt", "changed")
    new, owned = fmucache.unzipped(path)
    assert not owned and new != old and (new / "documentation" / "note.txt").read_text() == "changed"
    assert not (old / "documentation" / "note.txt").exists()


def test_the_model_description_is_read_from_the_fmu_once(cache: Path, tmp_path: Path) -> None:
    path = _laser(tmp_path)
    reads: list[int] = []

    def read() -> str:
        reads.append(1)
        return "the description"

    assert fmucache.description(path, True, read) == "the description"
    assert fmucache.description(path, True, read) == "the description"
    assert fmucache.description(path, False, read) == "the description"  # without validation: kept apart
    assert len(reads) == 2


def test_a_kept_description_that_cannot_be_read_is_read_from_the_fmu_again(cache: Path, tmp_path: Path) -> None:
    path = _laser(tmp_path)
    fmucache.description(path, True, lambda: "first")
    for kept in cache.glob("*.pickle"):
        kept.write_bytes(b"cut sh")
    assert fmucache.description(path, True, lambda: "again") == "again"


def test_an_fmu_loaded_only_once_per_process_gets_a_private_copy_removed_at_close(cache: Path,
                                                                                    tmp_path: Path) -> None:
    path = _laser(tmp_path)
    folder, owned = fmucache.unzipped(path, shared=False)
    assert owned and folder.parent != cache and (folder / "modelDescription.xml").is_file()
    shutil.rmtree(folder)


def test_a_cache_that_cannot_be_written_costs_only_the_unzip(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("COSIM_FMU_CACHE", str(blocked / "fmus"))
    path = _laser(tmp_path)
    with Fmu(path, instance_name="a") as fmu:
        folder = Path(fmu._unzipdir)
        assert fmu._owns_unzipdir and folder.is_dir()
    assert not folder.exists()  # a private copy is removed at close
