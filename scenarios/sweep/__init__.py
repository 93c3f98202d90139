"""Sweeps: one scenario run over grids of its options and seeds, on Dask distributed.

    from scenarios import sweep
    plan = sweep.plan("tp", grids=["k=0.01:10:log12", "estimator=linear,explicit"], seeds="8")
    summary = sweep.run(plan, "results/sweep", workers=2)
    columns = sweep.read_table("results/sweep")
    sweep.plot(columns, "rms_error_deg[0]", "k", by="estimator", out="results/sweep/k.png")

- :mod:`scenarios.sweep.grid`: the members (``--grid``, ``--set``, ``--seeds``);
- :mod:`scenarios.sweep.engine`: running them on a local or remote Dask cluster, the member
  folders, the table, ``--resume``, retries;
- :mod:`scenarios.sweep.table`: ``sweep.csv`` and ``sweep.parquet``;
- :mod:`scenarios.sweep.figure`: a metric against an option, grouped by another.
"""

from scenarios.sweep.engine import Summary, SweepError, run, run_member
from scenarios.sweep.grid import Member, Plan, plan, plan_of_cases
from scenarios.sweep.table import read as read_table

__all__ = ["Member", "Plan", "Summary", "SweepError", "plan", "plan_of_cases", "read_table", "run", "run_member"]
