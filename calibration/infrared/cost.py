"""What the estimators cost per iteration: operations counted on the compiled arithmetic, and time.

:func:`cost` runs each step function's Python source (the source numba compiles) on numbers
that count what is done to them: a flop is one ``+ - * /`` or negation, a comparison one
``< <= > >= == !=`` between numbers, a function one ``sqrt``, ``atan`` or ``abs``. Indexing,
assignments, branches on booleans and the loop are not counted. The slides count 300
operations per iteration, by a convention they do not state.
"""

from __future__ import annotations

import math

import numpy as np
from quadcosim.calibration.infrared.estimator import Estimator, InfraredCalibrationError, _finite
from quadcosim.calibration.infrared.filters import buffer_size
from quadcosim.calibration.infrared.settings import EKFSettings

SLIDES_OPERATIONS = 300  # per iteration, counted by the slides
SLIDES_RATE = 20.0  # Hz
SLIDES_PROCESSOR = 20e6  # Hz, the aircraft's processor in the slides


class _Tally:
    def __init__(self):
        self.flops = self.comparisons = self.functions = 0


_TALLY = _Tally()


class _Counted(float):
    """A float that counts the operations made on it (the cost model of :func:`cost`)."""

    def _arith(self, other, op):
        _TALLY.flops += 1
        return _Counted(op(float(self), float(other)))

    def __add__(self, o):
        return self._arith(o, float.__add__)

    def __radd__(self, o):
        return self._arith(o, lambda x, y: y + x)

    def __sub__(self, o):
        return self._arith(o, float.__sub__)

    def __rsub__(self, o):
        return self._arith(o, lambda x, y: y - x)

    def __mul__(self, o):
        return self._arith(o, float.__mul__)

    def __rmul__(self, o):
        return self._arith(o, lambda x, y: y * x)

    def __truediv__(self, o):
        return self._arith(o, float.__truediv__)

    def __rtruediv__(self, o):
        return self._arith(o, lambda x, y: y / x)

    def __neg__(self):
        _TALLY.flops += 1
        return _Counted(-float(self))

    def __abs__(self):
        _TALLY.functions += 1
        return _Counted(abs(float(self)))

    def _compare(self, other, op):
        _TALLY.comparisons += 1
        return op(float(self), float(other))

    def __lt__(self, o):
        return self._compare(o, float.__lt__)

    def __le__(self, o):
        return self._compare(o, float.__le__)

    def __gt__(self, o):
        return self._compare(o, float.__gt__)

    def __ge__(self, o):
        return self._compare(o, float.__ge__)

    def __eq__(self, o):
        return self._compare(o, float.__eq__)

    def __ne__(self, o):
        return self._compare(o, float.__ne__)

    __hash__ = float.__hash__


_REAL_MATH = math  # the counting run swaps the module's math for _CountedMath


class _CountedMath:
    nan = math.nan

    @staticmethod
    def sqrt(x):
        _TALLY.functions += 1
        return _Counted(_REAL_MATH.sqrt(x))

    @staticmethod
    def atan(x):
        _TALLY.functions += 1
        return _Counted(_REAL_MATH.atan(x))


def _modules():
    from quadcosim.calibration.infrared import attribution, detection, estimator, filters

    return (filters, detection, attribution, estimator)


def _count_operations(estimator, ir, gps, use) -> np.ndarray:
    """Operations of each sample (flops, comparisons, functions), running the step functions'
    Python source on counting numbers: the arithmetic counted is the arithmetic compiled."""
    saved = []
    try:
        for module in _modules():  # every compiled function, in every module that calls it, by its Python source
            for name, value in list(vars(module).items()):
                if hasattr(value, "py_func"):
                    saved.append((module, name, value))
                    setattr(module, name, value.py_func)
            saved.append((module, "math", module.__dict__.get("math", _REAL_MATH)))
            module.math = _CountedMath
        runner = _modules()[-1]  # the estimator, whose _sample steps the rest
        state = [_Counted(v) for v in estimator._initial]
        config = [_Counted(v) for v in estimator.config]
        buffer = [_Counted(0.0) for _ in range(buffer_size(estimator.delay, estimator.window))]
        counts = np.zeros((len(ir), 3), dtype=np.int64)
        for k in range(len(ir)):
            _TALLY.flops = _TALLY.comparisons = _TALLY.functions = 0
            runner._sample(estimator._kind, state, config, buffer, k, _Counted(ir[k]), _Counted(gps[k]), bool(use[k]),
                           estimator.delay, estimator.window, estimator._suspect)
            counts[k] = _TALLY.flops, _TALLY.comparisons, _TALLY.functions
        return counts
    finally:
        for module, name, value in reversed(saved):
            setattr(module, name, value)


def cost(ir, gps, gps_use=None, repeats: int = 3, methods=None) -> dict[str, dict]:
    """Operations per iteration and time per update of each estimator, on a recorded flight.

    Parameters
    ----------
    ir, gps : (n,) arrays
        IR readings (count) and GPS turn rates (rad/s), one per sample.
    gps_use : (n,) bool array, optional
        Samples whose GPS is used (default: all).
    repeats : int
        Timings are the best of this many runs.
    methods : sequence of str, optional
        Which of the variants below to measure (default: all).

    Returns
    -------
    dict
        For ``kalman`` (sequential, gated), ``kalman_ungated``, ``kalman_joint`` (the slides'
        2x2 update), ``regression`` and ``rls``: ``operations_mean`` and ``operations_max`` per
        iteration (flops + comparisons + functions), ``flops_mean``, ``comparisons_mean``,
        ``functions_mean``; ``us_per_update_batch`` (compiled loop over the arrays) and
        ``us_per_update_streaming`` (one :meth:`Estimator.update` call from Python); and
        ``operations_per_s`` at the slides' 20 Hz. ``slides`` holds their figures: 300
        operations per iteration at 20 Hz on a 20 MHz processor.
    """
    import time

    ir = _finite("IR", ir)
    gps = _finite("GPS turn rate", gps)
    use = np.ones(ir.shape, dtype=np.bool_) if gps_use is None else np.asarray(gps_use, dtype=np.bool_)
    variants = {"kalman": ("kalman", EKFSettings()), "kalman_ungated": ("kalman", EKFSettings(gate=0.0)),
                "kalman_joint": ("kalman", EKFSettings(gate=0.0, form="joint")),
                "regression": ("regression", None), "rls": ("rls", None)}
    unknown = set(methods or ()) - set(variants)
    if unknown:
        raise InfraredCalibrationError(f"unknown estimators {sorted(unknown)}; choose among {', '.join(variants)}")
    out = {}
    for label, (method, settings) in variants.items():
        if methods is not None and label not in methods:
            continue
        estimator = Estimator(method, settings)
        counts = _count_operations(estimator, ir, gps, use)
        total = counts.sum(axis=1)
        estimator.run(ir[:100], gps[:100], use[:100])  # compile
        batch = min(_timed(lambda e=estimator: e.run(ir, gps, use), time) for _ in range(repeats)) / len(ir)
        streaming = min(_timed(lambda e=estimator: _stream(e, ir, gps, use), time) for _ in range(repeats)) / len(ir)
        out[label] = {"operations_mean": float(total.mean()), "operations_max": int(total.max()),
                      "flops_mean": float(counts[:, 0].mean()), "comparisons_mean": float(counts[:, 1].mean()),
                      "functions_mean": float(counts[:, 2].mean()),
                      "operations_per_s": float(total.mean() * SLIDES_RATE),
                      "us_per_update_batch": batch * 1e6, "us_per_update_streaming": streaming * 1e6}
    out["slides"] = {"operations_per_iteration": SLIDES_OPERATIONS, "rate_hz": SLIDES_RATE,
                     "processor_hz": SLIDES_PROCESSOR, "operations_per_s": SLIDES_OPERATIONS * SLIDES_RATE}
    return out


def _timed(function, time) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def _stream(estimator: Estimator, ir, gps, use):
    estimator.reset()
    for k in range(len(ir)):
        estimator.update(ir[k], gps[k], use[k])

