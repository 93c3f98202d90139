"""quadcosim: Modelica/FMU co-simulation of a quadrotor for attitude estimation and magnetometer
calibration.

The one import name of the package. Its Python API is here::

    from quadcosim import System, FMUBlock, Table, run

- :class:`System`, :class:`FMUBlock`, :class:`Table`, :class:`Constant`, :class:`Block`,
  :class:`Result`, :class:`Fault`: the co-simulation master (:mod:`quadcosim.orchestrator`);
- :func:`run`, :func:`names`: the named scenarios (:mod:`quadcosim.scenarios`);
- :func:`estimate`, :func:`recording`, :func:`score`: the estimators on recorded arrays
  (:mod:`quadcosim.estimators`);
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
    **dict.fromkeys(("estimate", "recording", "score"), "quadcosim.estimators"),
    **dict.fromkeys(("QuadcosimError", "UsageError", "RunError"), "quadcosim.infra.errors"),
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'quadcosim' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
