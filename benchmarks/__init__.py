"""Benchmark scripts that print figures (``quadcosim bench``); they are not timed tests.

- :mod:`quadcosim.benchmarks.master`: the co-simulation master, open and closed loop, against reference
  loops written in C (``benchmarks/c/loops.c``) that make the same FMI calls;
- :mod:`quadcosim.benchmarks.estimators`: the closed loop's real-time factor and the estimators'
  batch path against the ``ahrs`` package;
- :mod:`quadcosim.benchmarks.infrared`: operations per iteration and time per update of the IR
  calibration estimators against the slides' 300 operations at 20 Hz.

The C references in ``benchmarks/c/`` ship with the package as sources; ``quadcosim build``
(:func:`build_references`), or their first use, compiles them with the system C compiler into
``benchmarks/`` under :func:`quadcosim.fmus.build_root`.
"""

from __future__ import annotations

from pathlib import Path

SOURCES = Path(__file__).resolve().parent / "c"


def libraries_dir() -> Path:
    """Folder of the compiled C references: ``benchmarks/`` under :func:`quadcosim.fmus.build_root`.

    Returns
    -------
    pathlib.Path
        The folder (it may not exist yet).
    """
    from quadcosim.fmus import build_root

    return build_root() / "benchmarks"


def build_references() -> list[Path]:
    """Compile every ``benchmarks/c/*.c`` into ``lib<name>.so`` in :func:`libraries_dir`.

    Returns
    -------
    list of pathlib.Path
        The libraries written.
    """
    from quadcosim.orchestrator.calls import compile_shared

    return [compile_shared(source, libraries_dir() / f"lib{source.stem}.so") for source in sorted(SOURCES.glob("*.c"))]


def reference_library(name: str):
    """The compiled reference ``benchmarks/c/<name>.c``, compiled first if missing or older than
    its source or a shared header.

    Parameters
    ----------
    name : str
        Stem of the C file.

    Returns
    -------
    ctypes.CDLL
        The loaded library.
    """
    import ctypes

    from quadcosim.orchestrator.calls import compile_shared

    source, library = SOURCES / f"{name}.c", libraries_dir() / f"lib{name}.so"
    newest = max(path.stat().st_mtime for path in [source, *SOURCES.glob("*.h")])
    if not library.is_file() or library.stat().st_mtime < newest:
        compile_shared(source, library)
    return ctypes.CDLL(str(library))
