"""Findings of the speed page: the master against its C references, the batch path, the FMI
shell's cost, the command line's start-up, a ``tp`` run's wall time and what a short run costs
against a long one.

One run of each benchmark (``quadcosim bench --json``: :func:`quadcosim.benchmarks.master.measure`;
``python -m quadcosim.benchmarks.startup``: :func:`quadcosim.benchmarks.startup.measure`, for ``list``, ``--help``
and ``run tp``), a few minutes on a loaded machine. Absolute times (µs per step, updates per
second) of one thread move about twofold with the machine's load: their tolerance is their
value; wall times on the shared cores (start-up, the batch path on every core) up to fivefold:
four times their value. The ratios of two loops timed back to back in one process move less: their
tolerance is the spread seen between runs at different loads. Timings are never re-checked in
tests: ``quick`` returns none.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from findings import finding

BENCH = "quadcosim bench --json"
STARTUP = "python -m quadcosim.benchmarks.startup"
TP_OUT = "/tmp/quadcosim-tp"
TP_RUNS = 3
TP = f"python -m quadcosim.benchmarks.startup --repeats {TP_RUNS} -- run tp --out {TP_OUT} --overwrite"
RUN_COST = "python -m quadcosim.benchmarks.run_cost --parts"
RUN_COST_IN_PROCESS = "python -m quadcosim.benchmarks.run_cost --in-process"
# The ratio of a 2 s run's CPU to a 320 s run's moved from 0.43 to 0.51 between pairs of one run.
RUN_COST_TOLERANCE = 0.1
MILLION = 1e6
THOUSAND = 1e3
# Medians of the loop ratios moved by up to about 0.15 between runs at load averages 1 to 20.
RATIO_TOLERANCE = 0.2
# CPU time of one thread: a loaded machine may double it (tolerance: the value itself).
CPU_SWING = 1.0
# Wall time on shared cores: start-up 0.5 s idle against 2.3 s loaded, the batch path on both
# cores 10.4 against 2.5 million updates/s; a re-run may take five times as long.
WALL_SWING = 4.0


def _timing(name: str, value: float, unit: str, command: str, digits: int, swing: float = CPU_SWING) -> dict:
    """A finding of an absolute time or rate: tolerance ``swing`` times its value."""
    return finding(f"speed.{name}", value, unit, command, swing * abs(value), digits)


def _ratio(name: str, value: float, command: str = BENCH, tolerance: float = RATIO_TOLERANCE) -> dict:
    return finding(f"speed.bench.{name}", value, "1", command, tolerance, 2)


def _identical(bench: dict):
    """Raise when a trajectory of a C reference parted from the orchestrator's: the page says equal."""
    parted = [key for key in ("open_loop_identical", "closed_loop_identical", "batch_identical_to_c",
                              "fmu_steps_identical") if not bench[key]]
    if parted:
        raise RuntimeError(f"{BENCH}: {', '.join(parted)} false; the speed page says equal to the last bit")


def bench_findings(bench: dict) -> list[dict]:
    """The findings of one ``quadcosim bench --json`` object (:func:`quadcosim.benchmarks.master.measure`).

    Parameters
    ----------
    bench : dict
        Its figures.

    Returns
    -------
    list of dict
    """
    _identical(bench)
    found = [_ratio(key, bench[key]) for key in ("open_loop_over_c", "closed_loop_over_c", "fmu_step_over_equations")]
    found += [_ratio("batch_over_c", bench["batch_over_c"]),
              _ratio("batch_over_c_euler", bench["batch_over_c_euler"]),
              _timing("bench.closed_loop_us_per_step", bench["closed_loop_us_per_step"], "us", BENCH, 1),
              _timing("bench.closed_loop_c_us_per_step", bench["closed_loop_c_us_per_step"], "us", BENCH, 1),
              _timing("bench.rtf_closed_loop", bench["rtf_closed_loop"], "1", BENCH, 0),
              _timing("bench.rtf_closed_loop_c", bench["rtf_closed_loop_c"], "1", BENCH, 0),
              _timing("bench.fmu_steps_us", bench["fmu_steps_us"], "us", BENCH, 2),
              _timing("bench.equations_steps_us", bench["equations_steps_us"], "us", BENCH, 2)]
    for key, swing in (("batch_updates_per_s", CPU_SWING), ("batch_c_updates_per_s", CPU_SWING),
                       ("parallel_batch_updates_per_s", WALL_SWING)):
        found.append(_timing(f"bench.{key}_million", bench[key] / MILLION, "1e6 updates/s", BENCH, 1, swing))
    if bench.get("ahrs_samples_per_s"):  # ahrs is timed in wall time
        found += [_timing("bench.ahrs_samples_per_s_thousand", bench["ahrs_samples_per_s"] / THOUSAND, "1e3 samples/s",
                          BENCH, 0, WALL_SWING),
                  _timing("bench.batch_over_ahrs", bench["batch_over_ahrs"], "1", BENCH, 0, WALL_SWING)]
    return found


def startup_findings(startup: dict, tp: dict) -> list[dict]:
    """The start-up findings: median wall time of ``quadcosim list`` and ``--help``
    (:func:`quadcosim.benchmarks.startup.measure`), and of ``quadcosim run tp``.

    Parameters
    ----------
    startup : dict
        Figures of ``list`` and ``--help``.
    tp : dict
        Figures of ``run tp``.
    """
    return [_timing("startup.list_s", startup["list"]["median_s"], "s", STARTUP, 2, WALL_SWING),
            _timing("startup.help_s", startup["--help"]["median_s"], "s", STARTUP, 2, WALL_SWING),
            _timing("startup.tp_wall_s", next(iter(tp.values()))["median_s"], "s", TP, 1, WALL_SWING)]


def run_cost_findings(fresh: dict, in_process: dict) -> list[dict]:
    """What a short run costs against a long one (:func:`quadcosim.benchmarks.run_cost.measure`): the
    median ratio of fresh commands and of runs in one process, what the estimators and the
    controller with numba, and matplotlib, cost a fresh interpreter to load, and the fresh ratio
    with that loading taken off both runs.

    Parameters
    ----------
    fresh : dict
        Figures of fresh commands, with ``parts_cpu_s`` (``--parts``).
    in_process : dict
        Figures of runs in one process (``--in-process``).
    """
    parts = fresh["parts_cpu_s"]
    return [finding("speed.run_cost.ratio", fresh["median_ratio"], "1", RUN_COST, RUN_COST_TOLERANCE, 3),
            *(finding(f"speed.run_cost.ratio_without_{ablation}", ratio, "1", RUN_COST, RUN_COST_TOLERANCE, 3)
              for ablation, ratio in fresh["ratio_without"].items()),
            _timing("run_cost.numba_s", parts["numba"], "s", RUN_COST, 2),
            _timing("run_cost.matplotlib_s", parts["matplotlib"], "s", RUN_COST, 2),
            finding("speed.run_cost.in_process_ratio", in_process["median_ratio"], "1", RUN_COST_IN_PROCESS,
                    RUN_COST_TOLERANCE, 3)]


def compute(quick: bool = False) -> list[dict]:
    """Every figure of the speed page, from one run of each benchmark. ``quick``: none (timings
    are not re-checked)."""
    if quick:
        return []
    from quadcosim.benchmarks import master, run_cost, startup

    bench = master.measure()
    with tempfile.TemporaryDirectory() as folder:
        tp = startup.measure([["run", "tp", "--out", str(Path(folder) / "tp"), "--overwrite"]], TP_RUNS)
    fresh = run_cost.measure() | {"parts_cpu_s": run_cost.parts()}
    fresh |= run_cost.without_loading(fresh)
    return (bench_findings(bench) + startup_findings(startup.measure(), tp)
            + run_cost_findings(fresh, run_cost.measure(in_process=True)))
