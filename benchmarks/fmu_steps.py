"""What the FMI shell costs on top of the models' equations (``fmu_step_over_equations``).

The three plant FMUs of the closed loop (MotorMagnetics, Quadrotor, IMU with noise and bias on)
are stepped from C, once through their ``fmi2DoStep`` and once through their equations called
directly (``model_do_step`` then ``model_outputs``, ``benchmarks/c/equations/equations_step.c``,
compiled from the FMU's own staged sources with the same flags), on instances with the same
parameters, the same held inputs and the same steps. The figure is the median, over the
repeats, of the ratio of CPU times, FMI over equations; the two paths must end in the same
outputs, bit for bit (``fmu_steps_identical``).
"""

from __future__ import annotations

import ctypes
import statistics
import time
from pathlib import Path

import numpy as np
from quadcosim.benchmarks import SOURCES, libraries_dir, reference_library
from quadcosim.fmus import compiler_command, make_folder

MODELS = ("MotorMagnetics", "Quadrotor", "IMU")
PARAMETERS = {"IMU": {"noise_enabled": True, "bias_enabled": True}}  # as in the closed-loop benchmark
COMMAND = 0.5  # the four ESC commands held over the run (near hover)
DT = 1e-3  # macro step (s), the closed loop's


def equations_library(model: str) -> ctypes.CDLL:
    """The library of ``model``'s equations with :func:`equations_step` exported, compiled from
    the staged sources of the built FMU when missing or older than them.

    Parameters
    ----------
    model : str
        ``"MotorMagnetics"``, ``"Quadrotor"`` or ``"IMU"``.

    Returns
    -------
    ctypes.CDLL
        The loaded library.
    """
    import os
    import subprocess
    import tempfile

    from quadcosim.fmus import default_fmu_dir
    from quadcosim.fmus.build import CFLAGS

    staged = Path(default_fmu_dir()) / model / "sources"
    harness = SOURCES / "equations" / "equations_step.c"
    sources = [staged / "shell.c", staged / "model.c", harness]
    if not staged.is_dir():
        raise RuntimeError(f"no staged sources for {model} in {staged}; run `quadcosim build` first")
    library = libraries_dir() / f"libequations_{model}.so"
    newest = max(path.stat().st_mtime for path in [*sources, *staged.glob("*.h")])
    if not library.is_file() or library.stat().st_mtime < newest:
        make_folder(library.parent, "the benchmarks' C references")
        handle, partial = tempfile.mkstemp(prefix=f".equations_{model}-", suffix=".so", dir=library.parent)
        os.close(handle)
        command = [*compiler_command(), *CFLAGS, "-shared", "-I", str(staged), "-o", partial,
                   *map(str, sources), "-lm"]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode:
            os.unlink(partial)
            raise RuntimeError(f"{' '.join(command)}\n{done.stderr}")
        os.replace(partial, library)
    return ctypes.CDLL(str(library))


def _instances():
    """The three FMUs with the benchmark's parameters and inputs (outputs wired once, held)."""
    from quadcosim.orchestrator.fmu import FMUInstance

    fmus = {name: FMUInstance(name, PARAMETERS.get(name), name=name) for name in MODELS}
    motors, body, imu = fmus.values()
    motors.set([f"c{n}" for n in range(1, 5)], [COMMAND] * 4)
    rotors = [f"omega_r{n}" for n in range(1, 5)]
    rates = rotors + [f"domega_r{n}" for n in range(1, 5)]
    body.set(rates, motors.get(rates))
    motion = ["q0", "q1", "q2", "q3", "omega_x", "omega_y", "omega_z", "f_x", "f_y", "f_z"]
    imu.set(motion, body.get(motion))
    imu.set(rotors, motors.get(rotors))
    imu.set(["b_d_x", "b_d_y", "b_d_z"], motors.get(["b_d_x", "b_d_y", "b_d_z"]))
    return fmus


def _run(functions, fmus, steps: int) -> float:
    """CPU seconds of ``steps`` macro steps of ``fmus``, each stepped by its function."""
    step_all = reference_library("steps").step_all
    step_all.restype = ctypes.c_int
    pointers = (ctypes.c_void_p * len(fmus))(*[ctypes.cast(f, ctypes.c_void_p).value for f in functions])
    components = (ctypes.c_void_p * len(fmus))(*[fmu.component for fmu in fmus.values()])
    started = time.thread_time()
    status = step_all(pointers, components, len(fmus), ctypes.c_long(steps), ctypes.c_double(DT))
    seconds = time.thread_time() - started
    if status:
        raise RuntimeError(f"a step failed with status {status}")
    return seconds


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """The step figures of ``seconds`` simulated, ``repeats`` times.

    Parameters
    ----------
    seconds : float
        Simulated time per measurement (s).
    repeats : int
        Measurements of each path, back to back.

    Returns
    -------
    dict
        ``fmu_step_over_equations`` (median ratio of CPU times, three ``fmi2DoStep`` calls over
        the same three models' equations), ``fmu_step_over_equations_spread`` (lowest,
        highest), ``fmu_steps_us`` and ``equations_steps_us`` (the three steps, µs, lowest over
        the repeats), ``fmu_steps_identical`` (both paths end in the same outputs, bit for bit).
    """
    steps = int(round(seconds / DT))
    direct = [equations_library(model).equations_step for model in MODELS]
    ratios, fmi_us, equation_us, identical = [], [], [], True
    for _ in range(repeats):
        through_fmi, direct_fmus = _instances(), _instances()
        try:
            fmi = _run([fmu.raw_do_step for fmu in through_fmi.values()], through_fmi, steps)
            equations = _run(direct, direct_fmus, steps)
            for name in MODELS:
                outputs = through_fmi[name].outputs
                identical &= bool(np.array_equal(through_fmi[name].get(outputs), direct_fmus[name].get(outputs)))
        finally:
            for fmu in [*through_fmi.values(), *direct_fmus.values()]:
                fmu.close()
        ratios.append(fmi / equations)
        fmi_us.append(fmi / steps * 1e6)
        equation_us.append(equations / steps * 1e6)
    return {"fmu_step_over_equations": statistics.median(ratios),
            "fmu_step_over_equations_spread": [min(ratios), max(ratios)],
            "fmu_steps_us": min(fmi_us), "equations_steps_us": min(equation_us), "fmu_steps_identical": identical}
