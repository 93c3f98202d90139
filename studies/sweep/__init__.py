"""Sweeps: one scenario run over grids of its options and seeds, on Dask distributed.

    from quadcosim.studies import sweep
    plan = sweep.plan("tp", grids=["k=0.01:10:log12", "estimator=linear,explicit"], seeds="8")
    summary = sweep.run(plan, "results/sweep", workers=2)
    columns = sweep.read_table("results/sweep")
    sweep.plot(columns, "rms_error_deg[0]", "k", by="estimator", out="results/sweep/k.png")

- :mod:`quadcosim.studies.sweep.grid`: the members (``--grid``, ``--set``, ``--seeds``);
- :mod:`quadcosim.studies.sweep.engine`: running them on a local or remote Dask cluster, the member
  folders, the table, ``--resume``, retries;
- :mod:`quadcosim.studies.sweep.table`: ``sweep.csv`` and ``sweep.parquet``;
- :mod:`quadcosim.studies.sweep.figure`: a metric against an option, grouped by another;
- :mod:`quadcosim.studies.sweep.named`: sweeps by name (``lab-matrix``);
- :mod:`quadcosim.studies.sweep.command`: ``quadcosim sweep`` and ``quadcosim sweep-plot``.

A script that runs a local cluster needs ``if __name__ == "__main__":`` around its sweep:
the worker processes are started by ``multiprocessing``'s spawn, which imports the script.
"""

import importlib

# Imported on first use: the command line builds its parser without loading Dask.
_EXPORTS = {
    "Summary": "engine", "SweepError": "engine", "run": "engine", "run_member": "engine",
    "Member": "grid", "Plan": "grid", "plan": "grid", "plan_of_cases": "grid",
    "plot": "figure", "read_table": "table",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'quadcosim.studies.sweep' has no attribute {name!r}")
    module = importlib.import_module(f"quadcosim.studies.sweep.{_EXPORTS[name]}")
    return getattr(module, "read" if name == "read_table" else name)
