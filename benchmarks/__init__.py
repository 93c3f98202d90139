"""Benchmark scripts that print figures (``quadcosim bench``); they are not timed tests.

- :mod:`benchmarks.master`: the co-simulation master against a hand-written ctypes loop;
- :mod:`benchmarks.estimators`: the closed loop's real-time factor and the estimators'
  batch path against the ``ahrs`` package.
"""
