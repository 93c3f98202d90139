"""Named sweeps: a fixed set of labelled cases of one scenario, and what is made of their table.

A module that declares ``SWEEP = NamedSweep(...)`` and is listed in :data:`MODULES` can be run
by name: ``quadcosim sweep lab-matrix``.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path

from quadcosim.orchestrator.fmu import nearest

MODULES = ("lab_matrix",)


@dataclass
class NamedSweep:
    """A sweep by name.

    Parameters
    ----------
    name : str
        Command-line name.
    scenario : str
        The scenario every case runs.
    cases : callable
        ``() -> {label: options}``.
    description : str
        One line for ``quadcosim list``.
    summarise : callable, optional
        ``(records, out_dir) -> None``: reports written from the finished members' records
        (their ``metrics.json``, in member order; a record's ``status`` is ``ok`` or
        ``diverged``, and a diverged member's numbers must be marked as a crash).
    extra_metrics : str, optional
        ``"module:function"`` computing more metrics from ``(result, options)`` on the worker.
    keep_results : bool
        Keep every member's results and figures (a small sweep whose cases are looked at).
    """

    name: str
    scenario: str
    cases: object
    description: str = ""
    summarise: object = None
    extra_metrics: str | None = None
    keep_results: bool = False

    def plan(self, settings=()):
        """The sweep's plan, with ``settings`` (``["duration=5", ...]``) applied to every case."""
        from quadcosim.studies.sweep.grid import plan_of_cases, split_assignment

        fixed = dict(split_assignment(s, "--set") for s in settings)
        cases = {label: options | fixed for label, options in self.cases().items()}
        return plan_of_cases(self.scenario, cases, name=self.name)


def registry() -> dict[str, NamedSweep]:
    """Every named sweep, by name."""
    sweeps = {}
    for module in MODULES:
        try:
            found = getattr(importlib.import_module(f"quadcosim.studies.{module}"), "SWEEP", None)
        except ModuleNotFoundError as error:
            if error.name != f"quadcosim.studies.{module}":
                raise
            continue
        if found is not None:
            sweeps[found.name] = found
    return sweeps


def get(name: str) -> NamedSweep:
    """The named sweep ``name``; an error listing the known ones otherwise."""
    sweeps = registry()
    if name not in sweeps:
        raise KeyError(f"unknown named sweep {name!r}.{nearest(name, sweeps)} Named sweeps: {', '.join(sweeps)}.")
    return sweeps[name]


def extra_metrics(plan) -> str | None:
    """The extra-metrics function of the plan's named sweep, if any."""
    return registry()[plan.name].extra_metrics if plan.name else None


def keep_results(plan) -> bool:
    """Whether the plan's named sweep keeps its members' results and figures."""
    return registry()[plan.name].keep_results if plan.name else False


def records(plan, out) -> list[dict]:
    """The records (``metrics.json``) of the members of ``plan`` in the sweep folder ``out``, in
    member order."""
    import json

    from quadcosim.studies.sweep.engine import member_folder

    return [json.loads((member_folder(Path(out), m.index) / "metrics.json").read_text()) for m in plan.members]


def summarise(plan, out, summary) -> Path | None:
    """Run a named sweep's summary on the members of ``plan`` in ``out``, once every member has
    an outcome, ``ok`` or ``diverged`` (according to the ``summary`` of the run: the summary
    marks the diverged ones); return the ``summary.md`` it wrote in ``out`` (None when it wrote
    none)."""
    if not plan.name or summary.failed or summary.missing:
        return None
    named = registry()[plan.name]
    if named.summarise is None:
        return None
    named.summarise(records(plan, out), Path(out))
    written = Path(out) / "summary.md"
    return written if written.is_file() else None
