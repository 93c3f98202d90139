"""Findings of ``quadcosim tune`` against the grids it replaces, and the figures of the sweeps guide.

- the linear filter's gain ``k`` against the roll error, noise on, 4 seeds: the tune's best
  against the best of a 49-point log grid over the same range with the same seeds, and
  python-control's predicted optimum (noise only);
- the attitude loop's three gains (``Controller.kp``, ``kd``, ``kp_yaw``) against the integral
  of the absolute error of a step on every axis (summed): the tune's best and its number of
  evaluations against a 6 x 6 x 6 grid over the same box.

Every member is deterministic (its seed is an option), so a re-run gives the same numbers; the
figures ``docs/tuning/tune_k.png`` and ``docs/tuning/tune_step.png`` are drawn from the same runs.
A few minutes on two workers: ``quick`` returns none.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from findings import ROOT, finding

WORKERS = 2
K_ARGS = ["tp", "--minimize", "rms_error_deg[0]", "--over", "k=0.005:20:log", "--set", "duration=10", "noise=on",
          "--seeds", "4", "--budget", "40", "--workers", str(WORKERS)]
K_GRID = ["tp", "--grid", "k=0.005:20:log49", "--seeds", "4", "--set", "duration=10", "noise=on",
          "--workers", str(WORKERS)]
STEP_OVER = ["Controller.kp=30:600:log", "Controller.kd=5:60:log", "Controller.kp_yaw=15:300:log"]
STEP_SET = ["flight=step", "step_axis=all", "duration=3"]
STEP_METRIC = "step_iae_total_deg_times_s"
STEP_ARGS = ["tp", "--minimize", STEP_METRIC, *[a for o in STEP_OVER for a in ("--over", o)],
             "--set", *STEP_SET, "--budget", "40", "--workers", str(WORKERS)]
STEP_GRID_SIDE = 6
STEP_GRID = ["tp", *[a for o in STEP_OVER for a in ("--grid", f"{o}{STEP_GRID_SIDE}")], "--set", *STEP_SET,
             "--workers", str(WORKERS)]
FIGURES = ROOT / "docs" / "tuning"


def _tune(args: list[str], out: Path) -> dict:
    from quadcosim.studies import tune

    parsed = tune.add_arguments(__import__("argparse").ArgumentParser()).parse_args(args)
    tune_plan = tune.plan(parsed.scenario, parsed.minimize, parsed.over, parsed.set, parsed.seeds, parsed.budget)
    return tune.run(tune_plan, out, workers=WORKERS, progress=False)


def _grid(args: list[str], out: Path) -> dict:
    from quadcosim.studies.sweep import command, engine, table

    parsed = command.add_arguments(__import__("argparse").ArgumentParser()).parse_args([*args, "--out", str(out)])
    plan = command.make_plan(parsed)
    summary = engine.run(plan, out, workers=WORKERS, progress=False)
    if summary.failed:
        raise RuntimeError(f"quadcosim sweep {' '.join(args)}: {summary.failed} members failed")
    return table.read(out)


def _pooled(columns: dict, metric: str, names: list[str]) -> dict:
    """The metric's mean over the seeds at each point of the grid (members that diverged: None)."""
    pooled: dict[tuple, list] = {}
    for i, status in enumerate(columns["status"]):
        key = tuple(float(columns[n][i]) for n in names)
        pooled.setdefault(key, []).append(columns[metric][i] if status == "ok" else None)
    return {key: (None if any(v is None for v in values) else float(np.mean(values))) for key, values in pooled.items()}


def _k_figure(tuned: dict, grid: dict, path: Path) -> None:
    import matplotlib.pyplot as plt

    from quadcosim.infra.files import save_figure

    ks = sorted(grid)
    fig, ax = plt.subplots(figsize=(8, 5))
    ax.plot([k[0] for k in ks], [grid[k] for k in ks], "-", color="0.6", lw=1, marker=".",
            label="49-point log grid (mean of seeds 1-4): 196 runs")
    history = [e for e in tuned["history"] if e["value"] is not None]
    order = np.arange(1, len(history) + 1)
    points = ax.scatter([e["options"]["k"] for e in history], [e["value"] for e in history], c=order, cmap="viridis",
                        s=22, zorder=3, label=f"tune: {len(tuned['history'])} evaluations (colour: their order)")
    ax.plot([tuned["best"]["k"]], [tuned["value"]], "*", color="C3", ms=15, zorder=4,
            label=f"tuned k = {tuned['best']['k']:.3g} 1/s")
    predicted = tuned["prediction"]
    ax.axvline(predicted["k"], color="C2", ls="--",
               label=f"python-control's optimum, noise only: {predicted['k']:.3g} 1/s")
    fig.colorbar(points, ax=ax, label="evaluation")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("k (1/s)")
    ax.set_ylabel("roll: rms_error_deg[0] (deg)")
    ax.set_title("tp, linear filter, noise on, 10 s, seeds 1-4: quadcosim tune against a grid", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def _step_figure(tuned: dict, grid: dict, names: list[str], path: Path) -> None:
    """The three-gain tune: each evaluation and the best so far against the grid's best; each gain's
    value along the search."""
    import matplotlib.pyplot as plt

    from quadcosim.infra.files import save_figure

    history = tuned["history"]
    n = np.arange(1, len(history) + 1)
    values = np.array([np.nan if e["value"] is None else e["value"] for e in history])
    kept = [v for v in grid.values() if v is not None]
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    ax.plot(n, values, "o", ms=4, label="evaluation")
    ax.plot(n, np.fmin.accumulate(np.where(np.isnan(values), np.inf, values)), "-", drawstyle="steps-post",
            label=f"tune, best so far: {tuned['value']:.3f} deg s")
    ax.axhline(min(kept), color="C3", ls="--", label=f"best of the {STEP_GRID_SIDE}^3 grid ({len(grid)} runs): "
                                                     f"{min(kept):.3f} deg s")
    ax.set_yscale("log")
    ax.set_xlabel("evaluation")
    ax.set_ylabel(f"{STEP_METRIC} (deg s)")
    ax.set_title(f"tp, {STEP_SET[1]}: 5 deg step on roll, pitch and yaw, 3 s\nquadcosim tune over the attitude gains",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    for k, name in enumerate(names):
        ax2.plot(n, [e["options"][name] for e in history], "o-", ms=3, lw=0.8, color=f"C{k}", label=name)
        ax2.axhline(tuned["best"][name], color=f"C{k}", ls=":", lw=0.8)
    ax2.set_yscale("log")
    ax2.set_xlabel("evaluation")
    ax2.set_ylabel("gain (kp, kp_yaw: 1/s^2; kd: 1/s)")
    ax2.set_title("each gain along the search (dotted: the tuned values)", fontsize=9)
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def k_findings(folder: Path) -> list[dict]:
    """The gain ``k`` tuned against the 49-point grid."""
    tuned = _tune([*K_ARGS, "--out", str(folder / "tune-k")], folder / "tune-k")
    grid = _pooled(_grid(K_GRID, folder / "grid-k"), "rms_error_deg[0]", ["k"])
    kept = {k: v for k, v in grid.items() if v is not None}
    best_k = min(kept, key=kept.get)
    FIGURES.mkdir(parents=True, exist_ok=True)
    _k_figure(tuned, grid, FIGURES / "tune_k.png")
    tune_cmd = "quadcosim tune " + " ".join(a if "[" not in a else f'"{a}"' for a in K_ARGS)
    grid_cmd = "quadcosim sweep " + " ".join(K_GRID)
    return [finding("tune.k.tuned_k", tuned["best"]["k"], "1/s", tune_cmd, 5e-4, 3),
            finding("tune.k.tuned_deg", tuned["value"], "deg", tune_cmd, 5e-5, 4),
            finding("tune.k.evaluations", tuned["evaluations"], "1", tune_cmd, 0.5, 0),
            finding("tune.k.grid_best_k", best_k[0], "1/s", grid_cmd, 5e-4, 3),
            finding("tune.k.grid_best_deg", kept[best_k], "deg", grid_cmd, 5e-5, 4),
            finding("tune.k.tuned_over_grid", tuned["value"] / kept[best_k], "1", tune_cmd, 5e-4, 3),
            finding("tune.k.predicted_k", tuned["prediction"]["k"], "1/s", tune_cmd, 5e-3, 2)]


def step_findings(folder: Path) -> list[dict]:
    """The attitude loop's three gains tuned on the step's summed error integral, against a 6 x 6 x 6 grid."""
    tuned = _tune([*STEP_ARGS, "--out", str(folder / "tune-step")], folder / "tune-step")
    names = [o.split("=")[0] for o in STEP_OVER]
    grid = _pooled(_grid(STEP_GRID, folder / "grid-step"), STEP_METRIC, names)
    kept = {k: v for k, v in grid.items() if v is not None}
    best = min(kept, key=kept.get)
    FIGURES.mkdir(parents=True, exist_ok=True)
    _step_figure(tuned, grid, names, FIGURES / "tune_step.png")
    tune_cmd = "quadcosim tune " + " ".join(STEP_ARGS)
    grid_cmd = "quadcosim sweep " + " ".join(STEP_GRID)
    found = [finding(f"tune.step.tuned_{n.split('.')[1]}", tuned["best"][n], "1/s^2" if "kp" in n else "1/s",
                     tune_cmd, 0.05, 1) for n in names]
    found += [finding(f"tune.step.grid_best_{n.split('.')[1]}", value, "1/s^2" if "kp" in n else "1/s", grid_cmd,
                      0.05, 1) for n, value in zip(names, best, strict=True)]
    return found + [finding("tune.step.tuned_deg_s", tuned["value"], "deg s", tune_cmd, 5e-4, 3),
                    finding("tune.step.evaluations", tuned["evaluations"], "1", tune_cmd, 0.5, 0),
                    finding("tune.step.without_value", tuned["diverged_or_failed"], "1", tune_cmd, 0.5, 0),
                    finding("tune.step.grid_best_deg_s", kept[best], "deg s", grid_cmd, 5e-4, 3),
                    finding("tune.step.grid_members", len(grid), "1", grid_cmd, 0.5, 0),
                    finding("tune.step.grid_diverged", len(grid) - len(kept), "1", grid_cmd, 0.5, 0)]


def compute(quick: bool = False) -> list[dict]:
    """The findings (none in the quick subset: minutes of runs)."""
    if quick:
        return []
    with tempfile.TemporaryDirectory() as folder:
        return k_findings(Path(folder)) + step_findings(Path(folder))
