"""quadcosim: Modelica/FMU co-simulation of a quadrotor for attitude estimation and magnetometer
calibration.

The one import name of the package. Its Python API is here::

    from quadcosim import System, FMUBlock, Table, run

- :class:`System`, :class:`FMUBlock`, :class:`Table`, :class:`Constant`, :class:`Block`,
  :class:`Result`, :class:`Fault`: the co-simulation master (:mod:`quadcosim.orchestrator`);
- :func:`run`, :func:`names`: the named scenarios (:mod:`quadcosim.scenarios`);
- :func:`estimate`, :func:`recording`, :func:`score`, :func:`gain_grid`: the estimators on
  recorded arrays (:mod:`quadcosim.estimators`); :class:`AttitudeEstimator`, the contract of a
  user's estimator; :class:`Controller`, the lab's controller;
- ``assert_attitude_error`` and the other checks of a run, for pytest
  (:mod:`quadcosim.scenarios.testing`, whose fixtures need no import);
- :class:`QuadcosimError` and its branches :class:`UsageError` and :class:`RunError`
  (:mod:`quadcosim.infra.errors`).

The subpackages, by floor from the ground up: ``infra``, ``fmus``, ``orchestrator``,
``flightlogs``, ``estimators``, ``calibration``, ``flight``, ``scenarios``, ``studies``,
``benchmarks``; the command line is :mod:`quadcosim.main`. A name is imported on first use, so
``import quadcosim`` loads none of them.
"""

import importlib

_EXPORTS = {
    **dict.fromkeys(("AlgebraicLoopError", "Block", "Constant", "FMUBlock", "FMUError", "Fault", "Result",
                     "RunInterrupted", "SimulationError", "System", "Table"), "quadcosim.orchestrator"),
    **dict.fromkeys(("run", "names"), "quadcosim.scenarios"),
    **dict.fromkeys(("estimate", "gain_grid", "recording", "score"), "quadcosim.estimators"),
    "AttitudeEstimator": "quadcosim.estimators.contract",
    "Controller": "quadcosim.flight",
    **dict.fromkeys(("assert_attitude_error", "assert_bias_converges", "assert_bounds", "assert_runs_close",
                     "assert_step", "assert_tracking"), "quadcosim.scenarios.testing"),
    **dict.fromkeys(("QuadcosimError", "UsageError", "RunError"), "quadcosim.infra.errors"),
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'quadcosim' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
