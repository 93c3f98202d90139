"""Benchmark figures of the estimators' batch path, for ``quadcosim bench`` (``quadcosim.benchmarks.master``).

- the batch path of the explicit filter (``quadcosim.estimators.estimate``, 256 gain sets in one call,
  attitude kept) against its C reference (``benchmarks/c/batch_explicit.c``, the same update
  operation for operation, compiled by ``quadcosim build``), both single-threaded, for the
  exponential map and the Euler step: ``batch_updates_per_s``, ``batch_c_updates_per_s``,
  ``batch_over_c`` (numba time / C time, exponential map), ``batch_over_c_euler``, and
  ``batch_identical_to_c`` (the two give the same attitude to the last bit, checked in the run);
- ``parallel_batch_updates_per_s``: the batch path on every core (``parallel_threads``);
- ``ahrs_samples_per_s``: samples per second of the ``ahrs`` package's Mahony filter
  (``updateIMU``) on the same data, measured in the same run, for the ratio.
"""

from __future__ import annotations

import time

import numpy as np


def _data(samples: int):
    rng = np.random.default_rng(0)
    acc = np.array([0.0, 0.0, -9.81]) + 0.1 * rng.standard_normal((samples, 3))
    gyro = 0.01 * rng.standard_normal((samples, 3))
    mag = np.array([2e-5, 0.0, 4.3e-5]) + 1e-7 * rng.standard_normal((samples, 3))
    return acc, gyro, mag


# slot numbers the C reference uses, in the order of its batch_explicit_slots()
_C_SLOTS = ("ACC", "GYRO", "MAG", "INPUT_SIZE", "GRAVITY", "FIELD", "DISCRETE", "K1", "K2", "KP", "KI", "HEADING_ONLY",
            "ACC_TOL", "MAG_NORM_TOL", "MAG_DIP_TOL", "REST_GYRO", "REST_ACC", "REST_MIN_TIME", "REST_GAIN",
            "GAIN_SIZE", "EULER")


# corrections benchmarks/c/batch_explicit.c does not transcribe: off in its case
_NOT_IN_C = ("acc_lowpass", "mag_lowpass", "mag_reference_time", "bias_clip", "heading_level", "rest_deviation",
             "mag_new_min_gyro", "mag_rejection_time", "correct_at_sample", "mag_new_time", "mag_first_time",
             "heading_angle", "mag_scale_time")


def _batch_case(gain_sets: int, samples: int, discretisation: str) -> dict:
    """The arrays of one batch run: the explicit filter's defaults with the corrections the C reference
    transcribes on (the low-passes and the magnetic reference tracking off), kI = 0.1 (1/s^2) and k1
    from 0.01 to 10 over the gain sets."""
    from quadcosim.estimators import layout
    from quadcosim.estimators.corrections import CORRECTIONS
    from quadcosim.estimators.filters import check_measurements, config_vector, gain_table

    acc, gyro, mag = _data(samples)
    config = config_vector(discretisation)
    inputs = check_measurements(gyro, acc, mag, float(np.linalg.norm(config[layout.GRAVITY:layout.GRAVITY + 3])), True)
    inputs = np.ascontiguousarray(np.column_stack([inputs, np.zeros((samples, 9))]))
    gains = {"k1": np.geomspace(0.01, 10, gain_sets), "kI": 0.1}
    corrections = {name: (0.0 if name in _NOT_IN_C else True) for name in CORRECTIONS}
    return {"acc": acc, "gyro": gyro, "mag": mag, "inputs": inputs, "gains": gains, "corrections": corrections,
            "config": config, "table": np.ascontiguousarray(gain_table("explicit", gains, corrections)),
            "discretisation": discretisation}


def _numba_batch(case: dict) -> np.ndarray:
    """The attitude (G, N, 4) of the batch path, through the public ``estimate``."""
    from quadcosim.estimators import estimate

    return estimate("explicit", acc=case["acc"], gyro=case["gyro"], mag=case["mag"], dt=1e-3, gains=case["gains"],
                    corrections=case["corrections"], discretisation=case["discretisation"], outputs=("q",))["q"]


def _c_batch(case: dict) -> np.ndarray:
    """The attitude (G, N, 4) of the C reference, after checking its slot numbers against
    :mod:`quadcosim.estimators.layout`'s layouts."""
    import ctypes

    from quadcosim.benchmarks import reference_library
    from quadcosim.estimators import layout

    library = reference_library("batch_explicit")
    slots = np.zeros(len(_C_SLOTS), dtype=np.int64)
    library.batch_explicit_slots(slots.ctypes.data_as(ctypes.c_void_p))
    expected = [getattr(layout, name) for name in _C_SLOTS]
    if slots.tolist() != expected:
        raise RuntimeError(f"benchmarks/c/batch_explicit.c numbers its slots {slots.tolist()}, "
                           "quadcosim.estimators.layout "
                           f"{expected} ({', '.join(_C_SLOTS)}): update the C reference")
    table, inputs = case["table"], case["inputs"]
    q = np.empty((len(table), len(inputs), 4))
    pointer = ctypes.c_void_p
    library.batch_explicit(ctypes.c_long(len(table)), ctypes.c_long(len(inputs)), pointer(inputs.ctypes.data),
                           pointer(table.ctypes.data), pointer(case["config"].ctypes.data), ctypes.c_double(1e-3),
                           pointer(np.array([1.0, 0.0, 0.0, 0.0]).ctypes.data), pointer(np.zeros(3).ctypes.data),
                           pointer(q.ctypes.data))
    return q


def _best_time(run, case: dict, repeats: int, clock=time.process_time) -> tuple[float, np.ndarray]:
    """Best time (s, of ``clock``: the process's CPU time by default) of ``repeats`` calls of
    ``run(case)``, and its result."""
    best = np.inf
    for _ in range(repeats):
        started = clock()
        result = run(case)
        best = min(best, clock() - started)
    return best, result


def batch_figures(gain_sets: int = 256, samples: int = 4000, repeats: int = 3) -> dict:
    """The batch path against its C reference, single-threaded, and on every core.

    Single-threaded figures are of the process's CPU time (the C reference and numba's one
    thread both run on the calling thread), so that other jobs on the machine change them
    little; the parallel figure is of wall time.

    Parameters
    ----------
    gain_sets : int
        Filters evaluated in one call (G).
    samples : int
        Samples per filter (N), at 1 kHz.
    repeats : int
        Timed calls of each, the best kept.

    Returns
    -------
    dict
        ``batch_updates_per_s`` (numba, one thread), ``batch_c_updates_per_s`` (C, one thread),
        ``batch_over_c`` (numba time / C time, exponential map), ``batch_over_c_euler``,
        ``batch_identical_to_c`` (same attitude to the last bit, both discretisations),
        ``batch_max_difference_to_c`` (largest absolute difference of a quaternion component),
        ``parallel_batch_updates_per_s`` and ``parallel_threads``; updates are filter steps
        (samples x gain sets) per second.
    """
    import numba

    threads = numba.get_num_threads()
    updates = gain_sets * samples
    figures, difference = {}, 0.0
    for discretisation, suffix in (("exp", ""), ("euler", "_euler")):
        case = _batch_case(gain_sets, samples, discretisation)
        _numba_batch(_batch_case(2, 10, discretisation))  # compiled (or loaded from the cache) before timing
        numba.set_num_threads(1)
        try:
            numba_time, q_numba = _best_time(_numba_batch, case, repeats)
        finally:
            numba.set_num_threads(threads)
        c_time, q_c = _best_time(_c_batch, case, repeats)
        difference = max(difference, float(np.max(np.abs(q_numba - q_c))))
        figures[f"batch_over_c{suffix}"] = numba_time / c_time
        if not suffix:
            figures["batch_updates_per_s"] = updates / numba_time
            figures["batch_c_updates_per_s"] = updates / c_time
            wall = _best_time(_numba_batch, case, repeats, time.perf_counter)[0]
            figures["parallel_batch_updates_per_s"] = updates / wall
            figures["parallel_threads"] = threads
    figures["batch_identical_to_c"] = difference == 0.0
    figures["batch_max_difference_to_c"] = difference
    return figures


def ahrs_samples_per_s(samples: int = 4000) -> float:
    """Samples per second of the ``ahrs`` package's Mahony ``updateIMU`` on ``samples`` samples."""
    from ahrs.filters import Mahony

    acc, gyro, _ = _data(samples)
    mahony = Mahony(k_P=1.0, k_I=0.1, frequency=1000.0)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    started = time.perf_counter()
    for n in range(samples):
        q = mahony.updateIMU(q, gyr=gyro[n], acc=-acc[n], dt=1e-3)
    return samples / (time.perf_counter() - started)


def measure(seconds: float = 5.0, repeats: int = 3) -> dict:
    """The estimator figures as a dict (:func:`batch_figures` and the ``ahrs`` comparison).

    Parameters
    ----------
    seconds : float
        Unused (the batch runs are 4 s of samples at 1 kHz); kept for ``quadcosim.benchmarks.master``'s call.
    repeats : int
        Timed calls of each, the best kept.

    Returns
    -------
    dict
        The figures by name.
    """
    figures = batch_figures(repeats=repeats)
    try:
        figures["ahrs_samples_per_s"] = ahrs_samples_per_s()
        figures["batch_over_ahrs"] = figures["batch_updates_per_s"] / figures["ahrs_samples_per_s"]
    except ImportError:
        figures["ahrs_samples_per_s"] = None
    return figures


def main(argv=None) -> int:
    """Print the batch path's figures (``python -m quadcosim.benchmarks.estimators``); returns 0.
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse
    import json

    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.estimators",
                                     description="the batch path against C")
    parser.add_argument("--gain-sets", type=int, default=256, help="filters per call")
    parser.add_argument("--samples", type=int, default=4000, help="samples per filter")
    parser.add_argument("--repeats", type=int, default=3, help="timed calls, best kept")
    args = parser.parse_args(argv)
    print(json.dumps(batch_figures(args.gain_sets, args.samples, args.repeats)))
    return 0


if __name__ == "__main__":  # the same as quadcosim bench estimators
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench estimators").run, main)
