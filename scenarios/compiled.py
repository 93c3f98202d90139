"""The numba-compiled code (estimators, controller, compensator, IR calibration), compiled ahead.

numba compiles a function the first time it is called with new argument types and keeps the
machine code in its on-disk cache (``cache=True``; placed and keyed by its sources by
:mod:`quadcosim.infra.numba_cache`), where later processes load it. Without
this module the first run after installing would sit silent for tens of seconds while that
happens. :func:`compile_all` (run by ``quadcosim build``, so by ``make demo``) calls every
compiled step once, the way the scenarios call them, so that runs load them from the cache;
:func:`announce_compiles` makes any compilation still left say so, in one line, when it starts.
"""

from __future__ import annotations

import sys
import time

import numpy as np

_announced = False
_listener = None

#: A short run of each code path that reaches compiled code (scenario, options).
WARM_UP_RUNS = (
    ("tp", {"duration": 0.05, "estimator": "linear"}),
    ("tp", {"duration": 0.05, "estimator": "explicit", "noise": True, "bias": True}),
    ("tp", {"duration": 0.05, "estimator": "passive", "ry": "triad"}),
    ("tp", {"duration": 0.05, "estimator": "passive"}),
    ("open-loop", {"duration": 0.05}),
)


def _on_compile(event):
    global _announced
    if _announced or not event.is_start:
        return
    _announced = True
    name = getattr(getattr(event.data.get("dispatcher"), "py_func", None), "__qualname__", "a step")
    from quadcosim.infra.progress import say

    say(f"quadcosim: compiling numba code ({name} first), once, into numba's cache; this takes a while "
        "(`quadcosim build` does it ahead)", sys.stderr)


def compiled_any() -> bool:
    """Whether numba compiled anything in this process (rather than loading it all from its cache)."""
    return _announced


def announce_compiles() -> None:
    """Print one line on standard error when numba starts compiling, rather than loading from its
    cache, for the first time in this process."""
    global _listener
    if _listener is not None:
        return
    from numba.core import event

    class Announcer(event.Listener):
        def on_start(self, started):
            _on_compile(started)

        def on_end(self, ended):
            pass

    _listener = Announcer()
    event.register("numba:compile", _listener)


def _batch_paths() -> None:
    """The estimators' batch path, each filter, and its scoring."""
    from quadcosim.estimators import filters

    samples, dt = 20, 0.01
    acc = np.tile([0.0, 0.0, -9.81], (samples, 1))
    gyro = np.zeros((samples, 3))
    mag = np.tile([2.0e-5, 0.0, 4.3e-5], (samples, 1))
    level = np.tile([1.0, 0.0, 0.0, 0.0], (samples, 1))
    identity = np.tile(np.eye(3).ravel(), (samples, 1))
    for kind, extra in (("linear", {}), ("explicit", {}), ("passive", {"R_reel": identity}),
                        ("passive", {"ry": "triad"})):
        run = filters.estimate(kind, gyro=gyro, acc=acc, mag=mag, dt=dt, reference=level, align_heading=True,
                               **extra)
        filters.score(run["q"], level)
        filters.score(run["q"][0], level, align_heading=True)


def compile_all(verbose: bool = True) -> float:
    """Compile (or load from numba's cache) every compiled step the scenarios use.

    Parameters
    ----------
    verbose : bool
        Print a line saying what is being done.

    Returns
    -------
    float
        Seconds it took (s).
    """
    from quadcosim import scenarios

    global _announced
    _announced = False  # compiled_any() then says whether this call compiled anything
    started = time.perf_counter()
    if verbose:
        print("the numba steps (estimators, controller, calibration): loading them from numba's cache, compiling "
              "those it lacks ...", flush=True)
    for name, options in WARM_UP_RUNS:
        scenarios.run(name, options)
    _batch_paths()
    return time.perf_counter() - started
