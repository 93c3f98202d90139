"""Small helpers shared by the tests."""

import numpy as np
from quadcosim.orchestrator.fmu import FMUInstance


def run_fmu(model, parameters, inputs, steps, h=1e-3, outputs=()):
    """Step ``model`` ``steps`` times with constant ``inputs``; outputs after each step."""
    fmu = FMUInstance(model, parameters)
    names = list(inputs)
    if names:
        fmu.set(names, [inputs[n] for n in names])
    values = np.empty((steps + 1, len(outputs)))
    values[0] = fmu.get(outputs)
    for k in range(steps):
        fmu.step(k * h, h)
        if names:
            fmu.set(names, [inputs[n] for n in names])
        values[k + 1] = fmu.get(outputs)
    fmu.close()
    return {name: values[:, j] for j, name in enumerate(outputs)}


def rotation(q):
    """R(q) = I + 2 q0 S(qv) + 2 S(qv)^2 (body to NED)."""
    q0, qv = q[0], np.asarray(q[1:])
    s = np.array([[0, -qv[2], qv[1]], [qv[2], 0, -qv[0]], [-qv[1], qv[0], 0]])
    return np.eye(3) + 2 * q0 * s + 2 * s @ s


def exit_worker_on_large_gain(result, options):
    """Sweep extra metric for tests: the worker process dies (as on a crash) when k > 1000, two
    seconds after its member began to be scored, so that the member run before it on the same
    one-thread worker has reported and handed back its result by then (a worker that dies holds
    them lost, and they are run again: a race on a loaded machine)."""
    import os
    import time

    if options["k"] > 1000:
        time.sleep(2.0)
        os._exit(3)
    return {}


def documentation() -> str:
    """The README and the documentation's pages (``docs/**/*.md``, the built site and generated
    pages left out), one after the other: the text whose examples the tests run as written."""
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    pages = [root / "README.md"] + sorted(p for p in (root / "docs").rglob("*.md")
                                          if not {"_build", "_generated"} & set(p.parts))
    return "\n".join(page.read_text() for page in pages)
