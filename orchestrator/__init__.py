"""The co-simulation orchestrator: blocks, connections, a fixed-step master, results."""

import importlib

# Imported on first use, so that a command that needs one name (the command line's signal
# handling, a scenario's option table) does not load fmpy and the master.
_EXPORTS = {
    "Block": "blocks", "Constant": "blocks", "FMUBlock": "blocks", "Table": "blocks",
    "AlgebraicLoopError": "errors", "RunInterrupted": "errors", "SimulationError": "errors",
    "Fault": "faults", "FMUError": "fmu", "FMUInstance": "fmu", "Result": "result", "System": "system",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'quadcosim.orchestrator' has no attribute {name!r}")
    return getattr(importlib.import_module(f"quadcosim.orchestrator.{_EXPORTS[name]}"), name)
