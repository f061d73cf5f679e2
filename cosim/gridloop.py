"""The master's sampled grid in C (``gridloop.c``): built once per user with the system's C compiler.

A plant recorded on a grid with nothing else due between samples (``Plant.record``'s rows) is
stepped and read in C, a row of up to a block of samples per call from Python, instead of one
doStep and one getter call per FMI type through ctypes per sample: the same FMI calls with the same
arguments, so the same values (see the C file). :func:`library` compiles ``gridloop.c`` against
fmpy's FMI headers into the per-user FMU cache (named by the SHA-256 of the source, the headers'
folder and the platform: a changed source is a new file, never a stale one) and loads it; where no C
compiler is found, or the cache cannot be written, it returns None and the master keeps its Python
loop (slower, same results). ``COSIM_GRIDLOOP=0`` turns the C loop off (for comparing the two).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from pathlib import Path
from typing import Any

SOURCE = Path(__file__).with_name("gridloop.c")


class Getter(ctypes.Structure):
    """``CosimGetter`` of gridloop.c: one FMI getter call of a sample, reading into a block's rows."""

    _fields_ = [("get", ctypes.c_void_p), ("vrs", ctypes.c_void_p), ("nvr", ctypes.c_size_t),
                ("row0", ctypes.c_void_p), ("stride", ctypes.c_ssize_t)]


_LOADED: list[Any] = []  # [library or None], once per process


def library() -> Any:
    """The loaded grid loop (a ``ctypes.CDLL`` with argument types set), or None where it cannot be built."""
    if not _LOADED:
        _LOADED.append(None if os.environ.get("COSIM_GRIDLOOP", "1") == "0" else _load())
    return _LOADED[0]


def _headers() -> Path:
    import fmpy

    return Path(fmpy.__file__).parent / "c-code"


def _load() -> Any:
    import subprocess

    try:
        path = _build()
        lib = ctypes.CDLL(str(path)) if path is not None else None
    except (OSError, subprocess.SubprocessError):
        return None
    if lib is None:
        return None
    i64, c_int, p = ctypes.c_int64, ctypes.c_int, ctypes.c_void_p
    out_int = ctypes.POINTER(ctypes.c_int)
    common: list[Any] = [p, p, i64, i64, i64, i64, c_int, ctypes.c_double]
    lib.cosim_grid_fmi2.argtypes = [*common, p, c_int, p, c_int, out_int, out_int]
    lib.cosim_grid_fmi2.restype = c_int
    out_bool = ctypes.POINTER(ctypes.c_bool)
    lib.cosim_grid_fmi3.argtypes = [*common, c_int, p, c_int, p, c_int, out_int, out_int, out_bool, out_bool,
                                    out_bool, ctypes.POINTER(ctypes.c_double)]
    lib.cosim_grid_fmi3.restype = c_int
    return lib


def _build() -> Path | None:
    """The compiled library in the per-user cache (compiled there first if missing); None if it could not be
    compiled before (a ``.failed`` file beside it says why: delete it to try again)."""
    import hashlib
    import shutil
    import subprocess
    import sysconfig
    import tempfile

    import fmpy

    from cosim.fmucache import cache_folder

    headers = _headers()
    identity = f"{headers}\n{fmpy.__version__}\n{sysconfig.get_platform()}\n".encode()
    key = hashlib.sha256(identity + SOURCE.read_bytes()).hexdigest()[:24]
    suffix = ".dll" if sys.platform == "win32" else ".dylib" if sys.platform == "darwin" else ".so"
    folder = cache_folder()
    target = folder / f"gridloop-{key}{suffix}"
    if target.is_file():
        with contextlib.suppress(OSError):
            os.utime(target)  # in use: kept by the cache's pruning
        return target
    failed = target.with_suffix(".failed")
    if failed.is_file():
        return None
    compiler = (sysconfig.get_config_var("CC") or "cc").split()[0]
    if shutil.which(compiler) is None:
        compiler = "cc"
    folder.mkdir(parents=True, exist_ok=True)
    handle, staging = tempfile.mkstemp(dir=folder, prefix=target.name, suffix=".tmp")
    os.close(handle)
    try:
        try:
            subprocess.run([compiler, "-O2", "-shared", "-fPIC", f"-I{headers}", str(SOURCE), "-o", staging],
                           check=True, capture_output=True, timeout=120)
        except subprocess.CalledProcessError as exc:
            failed.write_bytes(exc.stderr or b"")  # not again on every run
            raise
        os.replace(staging, target)  # whole, or not at all (runs starting together each build their own)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(staging)
    return target


#: Ticks up to which a grid instant converts to a double exactly (the C loop's condition for equal arguments).
EXACT_TICKS = 2**53


class GridRow:
    """Steps of one FMU over rows of grid instants, each sampled into a :class:`~cosim.fmu.BlockSampler`, in C.

    Made by :meth:`cosim.fmu.Fmu.grid_row`. :meth:`run` makes the regular steps (no event, early
    return, terminate request or failure) and takes their samples; a step that needs more is made
    and left for :meth:`finish`, which completes it as the FMU's Python path does.
    """

    def __init__(self, lib: Any, fmu: Any, block: Any, *, do_step: int, per_second: int,
                 getters: list[tuple[int, Any, int, int, int]]) -> None:
        self.fmu = fmu
        self.block = block
        self.pending = False
        self._read_failed = ctypes.c_int()
        self._status = ctypes.c_int()
        self._event, self._terminate, self._early = ctypes.c_bool(), ctypes.c_bool(), ctypes.c_bool()
        self._last = ctypes.c_double()
        self._t_from = 0
        self._getters = (Getter * len(getters))(*[Getter(get, ctypes.cast(vrs, ctypes.c_void_p), nvr, row0, stride)
                                                    for get, vrs, nvr, row0, stride in getters])
        self._keep = getters  # the value-reference arrays the structures point to
        component = fmu._fmu.component
        times = block.times.ctypes.data
        status, failed = ctypes.byref(self._status), ctypes.byref(self._read_failed)
        table, count, rate = self._getters, len(getters), float(per_second)
        if fmu.fmi_version == 2:
            grid2 = lib.cosim_grid_fmi2

            def call(t_now: int, t0: int, period: int, k: int, n: int, row: int) -> int:
                return int(grid2(do_step, component, t_now, t0, period, k, n, rate, table, count, times, row,
                                 status, failed))
        else:
            grid3, event_mode = lib.cosim_grid_fmi3, int(fmu.event_mode)
            flags = (ctypes.byref(self._event), ctypes.byref(self._terminate), ctypes.byref(self._early),
                     ctypes.byref(self._last))

            def call(t_now: int, t0: int, period: int, k: int, n: int, row: int) -> int:
                return int(grid3(do_step, component, t_now, t0, period, k, n, rate, event_mode, table, count, times,
                                 row, status, failed, *flags))

        self._call = call
        self._per_second = per_second

    def run(self, t0: int, period: int, k: int, n: int) -> int:
        """Step to ``t0 + (k + j) * period`` and sample there, for j = 0 .. n-1; returns the steps done and sampled.

        ``n`` must fit in the block (``block.rows - block.count``) and every instant be below
        :data:`EXACT_TICKS` and after the FMU's time. Fewer than ``n`` means the next step was made
        and needs :meth:`finish` (:attr:`pending`).
        """
        fmu, block = self.fmu, self.block
        if fmu._ended is not None:
            raise fmu._ended
        t_from = fmu.t
        done = self._call(t_from, t0, period, k, n, block.count)
        if done:
            block.count += done
            t_from = fmu.t = t0 + (k + done - 1) * period
        self._t_from = t_from
        self.pending = done < n
        return int(done)

    def finish(self, t: int) -> int:
        """Complete the step to tick ``t`` that :meth:`run` made and left: returns the tick reached (see
        :meth:`cosim.fmu.Fmu.advance_to`); raises as it does."""
        self.pending = False
        fmu = self.fmu
        if self._read_failed.value:  # a regular step whose sample failed: the caller reads again
            fmu.t = t
            return t
        now, per_second = self._t_from, self._per_second
        t_s, h_s = now / per_second, (t - now) / per_second
        status = self._status.value
        if fmu.fmi_version == 2:
            outcome = (status, False, False, False, t_s + h_s)
        else:
            outcome = (status, self._event.value, self._terminate.value, self._early.value, self._last.value)
        return int(fmu._finish(t, t_s, h_s, outcome))

