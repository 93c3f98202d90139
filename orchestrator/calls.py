"""The call runner: a small C library that runs a prepared list of FMI calls in one go.

A co-simulation step then costs one crossing from Python into C per group of FMU calls
instead of one per call. The runner's source is ``orchestrator/c/calls.c``; it is compiled
with the system C compiler into the runner folder, a setting: ``$QUADCOSIM_RUNNER_DIR`` or
``orchestrator/`` under :func:`quadcosim.fmus.build_root`. :func:`runner_path` compiles it on first use when it
is missing or older than its source; ``quadcosim build`` compiles it with the FMUs.
"""

from __future__ import annotations

import ctypes
import os
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from quadcosim.infra.errors import RunError

SOURCE = Path(__file__).resolve().parent / "c" / "calls.c"
LIBRARY_NAME = "libquadcosim_calls.so"
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-Wall", "-Wextra", "-Werror", "-shared")


class RunnerBuildError(RunError, RuntimeError):
    """The C compiler refused the call runner, or no C compiler was found."""


def runner_dir() -> Path:
    """Folder of the compiled call runner.

    Returns
    -------
    pathlib.Path
        ``$QUADCOSIM_RUNNER_DIR`` if set, else ``orchestrator/`` under :func:`quadcosim.fmus.build_root`
        (``build/`` in a source checkout, a per-user cache for an installed package).
    """
    from quadcosim.fmus import build_root

    env = os.environ.get("QUADCOSIM_RUNNER_DIR")
    return Path(env) if env else build_root() / "orchestrator"


def build_runner(out_dir: str | Path | None = None, compiler: str | None = None) -> Path:
    """Compile ``orchestrator/c/calls.c`` into a shared library, warnings as errors.

    Parameters
    ----------
    out_dir : str or pathlib.Path, optional
        Destination folder; :func:`runner_dir` by default.
    compiler : str, optional
        C compiler command; ``$CC`` or ``cc`` by default.

    Returns
    -------
    pathlib.Path
        Path of the library.
    """
    out = Path(out_dir) if out_dir is not None else runner_dir()
    return compile_shared(SOURCE, out / LIBRARY_NAME, compiler)


def compile_shared(source: Path, library: Path, compiler: str | None = None) -> Path:
    """Compile one C file into a shared library with :data:`CFLAGS` (warnings as errors, no
    floating-point contraction, no machine-specific instructions).

    Parameters
    ----------
    source : pathlib.Path
        The C file.
    library : pathlib.Path
        The library to write. It is written under a temporary name and renamed, so that
        processes starting together never load a half-written file.
    compiler : str, optional
        C compiler command; ``$CC`` or ``cc`` by default.

    Returns
    -------
    pathlib.Path
        ``library``.

    Raises
    ------
    RunnerBuildError
        No compiler, or it refused the source (its messages included).
    """
    from quadcosim.fmus import compiler_command, make_folder

    compiler = compiler_command(compiler)
    make_folder(library.parent, "the compiled runner")
    handle, partial = tempfile.mkstemp(prefix=f".{library.stem}-", suffix=".so", dir=library.parent)
    os.close(handle)
    command = [*compiler, *CFLAGS, "-o", partial, str(source), "-lm"]
    try:
        done = subprocess.run(command, capture_output=True, text=True)
    except FileNotFoundError:
        os.unlink(partial)
        raise RunnerBuildError(f"no C compiler {compiler[0]!r}: install one (e.g. gcc) or set $CC") from None
    if done.returncode != 0:
        os.unlink(partial)
        raise RunnerBuildError(f"{source.name}: {' '.join(command)}\n{done.stderr}")
    os.replace(partial, library)
    return library


def runner_path() -> Path:
    """Path of the compiled call runner, compiling it first if it is missing or stale.

    Returns
    -------
    pathlib.Path
        Path of ``libquadcosim_calls.so`` in :func:`runner_dir`.
    """
    library = runner_dir() / LIBRARY_NAME
    if not library.is_file() or library.stat().st_mtime < SOURCE.stat().st_mtime:
        build_runner()
    return library


_library = None


def runner_library() -> ctypes.CDLL:
    """The compiled runner, loaded once per process, its functions' types declared.

    Returns
    -------
    ctypes.CDLL
        ``run_calls(calls, count, t, failed)`` (a list of FMI calls) and
        ``run_chunk(program, end)`` (the chunk runner of :mod:`quadcosim.orchestrator.chunks`).
    """
    global _library
    if _library is None:
        library = ctypes.CDLL(str(runner_path()))
        library.run_calls.restype = ctypes.c_int
        library.run_chunk.restype = ctypes.c_int
        library.run_chunk.argtypes = [ctypes.c_void_p, ctypes.c_long]
        _library = library
    return _library


def run_calls():
    """The runner's ``run_calls(calls, count, t, failed)`` function, loaded once per process."""
    return runner_library().run_calls


class _CCall(ctypes.Structure):
    """One FMI call, laid out as ``Call`` in ``orchestrator/c/calls.c``."""

    _fields_ = [("kind", ctypes.c_int), ("function", ctypes.c_void_p), ("component", ctypes.c_void_p),
                ("vr", ctypes.c_void_p), ("n", ctypes.c_size_t), ("values", ctypes.c_void_p),
                ("h", ctypes.c_double)]


@dataclass(frozen=True)
class SetInputs:
    """One call that sets FMU inputs from their sources' bus slots (``fmi2SetReal`` straight
    from the bus for an FMI 2.0 FMU's Real inputs in consecutive slots: no copy).

    Parameters
    ----------
    block : quadcosim.orchestrator.FMUBlock
        The block, with a live instance.
    entry : quadcosim.orchestrator.fmi_types.CEntry
        The C call (:meth:`quadcosim.orchestrator.fmu.FMUInstance.setter`).
    """

    block: object  # an FMUBlock with a live instance
    entry: object
    kind = 0

    @property
    def function(self) -> str:
        """The FMI function it failed in, for messages (of a typed call, the one of the group)."""
        failed = getattr(self.entry.keep, "failed_function", None)
        return failed() if failed is not None else self.entry.label


@dataclass(frozen=True)
class GetOutputs:
    """One call that writes FMU outputs into their bus slots (as :class:`SetInputs`).

    Parameters
    ----------
    block : quadcosim.orchestrator.FMUBlock
        The block, with a live instance.
    entry : quadcosim.orchestrator.fmi_types.CEntry
        The C call (:meth:`quadcosim.orchestrator.fmu.FMUInstance.getter`).
    """

    block: object
    entry: object
    kind = 1

    @property
    def function(self) -> str:
        """The FMI function it failed in, for messages (of a typed call, the one of the group)."""
        failed = getattr(self.entry.keep, "failed_function", None)
        return failed() if failed is not None else self.entry.label


@dataclass(frozen=True)
class DoStep:
    """One communication step from the present time (:meth:`quadcosim.orchestrator.fmu.FMUInstance.stepper`).

    Parameters
    ----------
    block : quadcosim.orchestrator.FMUBlock
        The block, with a live instance.
    entry : quadcosim.orchestrator.fmi_types.CEntry
        The C call.
    h : float
        Communication step (s).
    """

    block: object
    entry: object
    h: float
    kind = 2

    @property
    def function(self) -> str:
        """The FMI function it failed in, for messages (of an isolated FMU, an input set kept
        for the step may be the one)."""
        failed = getattr(self.entry.keep, "failed_function", None)
        return failed() if failed is not None else self.entry.label


FMICall = SetInputs | GetOutputs | DoStep


def _pack(call: FMICall, bus: np.ndarray) -> _CCall:
    entry = call.entry
    h = call.h if isinstance(call, DoStep) else 0.0
    return _CCall(call.kind, entry.function, entry.component, entry.vr or None, entry.n, entry.values or None, h)


def batch(calls: list[FMICall], taps: list, bus: np.ndarray):
    """One phase of the loop: faults applied, then FMI calls run by one call into C.

    Parameters
    ----------
    calls : list of SetInputs, GetOutputs or DoStep
        In the order they run.
    taps : list of quadcosim.orchestrator.faults.FaultTap
        Faults to apply first.
    bus : ndarray
        The bus the calls read and write (float64; its address is resolved now).

    Returns
    -------
    callable
        ``phase(t)`` with ``t`` the present time (s); it raises
        :class:`quadcosim.orchestrator.fmu.FMUError`, naming the block, the FMI function, the time and
        the FMU's log, when a call returns Error or Fatal.
    """
    from quadcosim.orchestrator.faults import apply_faults
    from quadcosim.orchestrator.fmu_errors import FMUError

    run = run_calls()
    array = (_CCall * len(calls))(*[_pack(c, bus) for c in calls])
    count, failed, now = ctypes.c_int(len(calls)), ctypes.c_int(-1), ctypes.c_double(0.0)
    failed_ref = ctypes.byref(failed)

    def phase(t, calls=calls):  # ``calls`` keeps alive the arrays the C calls point into
        if taps:
            apply_faults(taps, bus, t)
        now.value = t
        status = run(array, count, now, failed_ref)
        if not 0 <= status <= 1:  # -1, or any number that is no FMI status, is a failure
            call = calls[failed.value]
            raise FMUError(call.block.name, call.function, status, t, list(call.block.instance.log))
    return phase
