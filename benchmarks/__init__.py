"""Benchmark scripts that print figures (``quadcosim bench``); they are not timed tests.

- :mod:`benchmarks.master`: the co-simulation master against a hand-written ctypes loop;
- :mod:`benchmarks.estimators`: the closed loop's real-time factor and the estimators'
  batch path against the ``ahrs`` package;
- :mod:`benchmarks.infrared`: operations per iteration and time per update of the IR
  calibration estimators against the slides' 300 operations at 20 Hz.
"""
