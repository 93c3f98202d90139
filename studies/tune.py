"""``quadcosim tune``: the options of a scenario that minimise one of its metrics, on Dask.

    quadcosim tune tp --minimize "rms_error_deg[0]" --over k=0.005:20:log \\
        --set duration=10 noise=on --seeds 4 --budget 40 --workers 2 --out results/tune-k

Each evaluation runs the scenario once per seed (``--seeds N``: seeds 1 to N, the same seeds at
every point, so that two points differ by their options alone) on the cluster a sweep uses
(:func:`quadcosim.studies.sweep.engine.cluster`), and its value is the metric's mean over the seeds. The
optimiser is scipy.optimize's, on coordinates scaled to [0, 1] (logarithmic for ``:log``):

- first a scan: a batch of points spread over the box (evenly for one option, a Sobol sequence
  for several), evaluated at once so that every worker is busy;
- then a refinement from the best point of the scan: Brent's bounded method
  (:func:`scipy.optimize.minimize_scalar`) between its neighbours for one option, Nelder-Mead with
  bounds (:func:`scipy.optimize.minimize`) for several, until the budget of evaluations is spent.

An evaluation where any member diverged, failed or has no value of the metric (a step that never
rose to 90 %) has no value: the optimiser sees a penalty (:data:`PENALTY`), and it is never the
best. ``tune.json`` (the best point, its value, the
evaluations, the whole history) is rewritten after every batch; ``--resume`` replays the
optimiser, deterministic, through the evaluations already recorded, and runs only the new ones.
``convergence.png`` draws each evaluation and the best so far.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from quadcosim.infra.errors import RunError, UsageError, refusals

#: What the optimiser sees for an evaluation without a value (a member diverged or failed).
PENALTY = 1e9
#: Share of the budget spent on the first scan (and its most points).
SCAN_SHARE, SCAN_MOST = 0.25, 16
_OVER = re.compile(r"^\s*([^=\s]+)\s*=\s*([^:]+):([^:]+)(?::(log|lin))?\s*$")
_METRIC = re.compile(r"^[A-Za-z_][\w.]*(\[\d+\])?$")


class TuneError(UsageError, ValueError):
    """A tune refused or stopped: the message names the problem and the fix."""


@dataclass
class Dimension:
    """One option tuned: its name and bounds (in its unit), searched on a log scale or not."""

    name: str
    low: float
    high: float
    log: bool = False

    def value(self, u: float) -> float:
        """The option's value at the scaled coordinate ``u`` in [0, 1] (12 significant digits)."""
        u = min(max(float(u), 0.0), 1.0)
        if self.log:
            x = math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low)))
        else:
            x = self.low + u * (self.high - self.low)
        return float(f"{x:.12g}")


def parse_over(text: str) -> Dimension:
    """``--over NAME=LOW:HIGH[:log]`` as a :class:`Dimension`; a clear error otherwise."""
    match = _OVER.match(text)
    if match is None:
        raise TuneError(f"--over {text!r}: write NAME=LOW:HIGH or NAME=LOW:HIGH:log (k=0.005:20:log)")
    name, low, high, scale = match.groups()
    try:
        low, high = float(low), float(high)
    except ValueError:
        raise TuneError(f"--over {text!r}: the bounds must be numbers") from None
    if not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise TuneError(f"--over {text!r}: give finite bounds LOW < HIGH")
    if scale == "log" and low <= 0:
        raise TuneError(f"--over {text!r}: a log scale needs LOW > 0")
    return Dimension(name, low, high, scale == "log")


@dataclass
class TunePlan:
    """What a tune runs: the scenario, the metric, the options tuned, the options fixed (typed), the
    seeds and the budget of evaluations."""

    scenario: str
    metric: str
    over: list[Dimension]
    base: dict
    seeds: list[int]
    budget: int
    description: dict = field(default_factory=dict)

    def members(self, point: dict) -> list[dict]:
        """The options of each member of one evaluation at ``point`` (option name to value)."""
        from quadcosim.studies.sweep.grid import _typed

        from quadcosim import scenarios

        scenario = scenarios.get(self.scenario)
        typed = {name: _typed(scenario, name, [value])[0] for name, value in point.items()}
        if not self.seeds:
            return [self.base | typed]
        return [self.base | typed | {"seed": seed} for seed in self.seeds]

    def to_json(self) -> dict:
        """The plan as ``tune.json`` keeps it (what ``--resume`` compares)."""
        return {"scenario": self.scenario, "minimize": self.metric, "seeds": self.seeds,
                "over": [vars(d) for d in self.over], "set": self.description.get("set", []),
                "base": json.loads(json.dumps(self.base, default=float))}


def plan(scenario_name: str, metric: str, over, settings=(), seeds: int | None = None, budget: int = 40) -> TunePlan:
    """Check and type a tune's arguments (the ``--`` options of ``quadcosim tune``).

    Raises
    ------
    TuneError, ValueError, KeyError
        A bad metric, bound, option, seed count or budget (the message names it).
    """
    from quadcosim.studies.sweep.grid import _typed, split_assignment

    from quadcosim import scenarios

    scenario = scenarios.get(scenario_name)
    if not _METRIC.match(metric):
        raise TuneError(f"--minimize {metric!r}: give a metric column, as sweep-plot names it (rms_error_deg[0])")
    dimensions = [parse_over(text) for text in over]
    if not dimensions:
        raise TuneError("--over: give at least one option to tune, NAME=LOW:HIGH[:log]")
    names = [d.name for d in dimensions]
    if len(set(names)) != len(names):
        raise TuneError(f"--over: {', '.join(sorted({n for n in names if names.count(n) > 1}))} given twice")
    if budget < 2:
        raise TuneError(f"--budget {budget}: give at least 2 evaluations")
    fixed = dict(split_assignment(s, "--set") for s in settings)
    for d in dimensions:
        if d.name in fixed:
            raise TuneError(f"option {d.name} is both tuned (--over) and fixed (--set); keep one")
        _typed(scenario, d.name, [d.low, d.high])  # refuses an unknown name or a value out of range
    seed_list = []
    if seeds is not None:
        if "seed" not in scenario.options:
            raise TuneError(f"scenario {scenario_name} has no seed option; --seeds does not apply to it")
        if seeds < 1 or "seed" in fixed:
            raise TuneError(f"--seeds {seeds}: give a count N >= 1 (seeds 1 to N), and no seed in --set")
        seed_list = list(range(1, seeds + 1))
    base = scenario.parse(fixed)
    return TunePlan(scenario_name, metric, dimensions, base, seed_list, budget,
                    {"set": list(settings), "over": list(over)})


def loop_margins(tune_plan: TunePlan, best: dict | None) -> dict | None:
    """python-control's phase margins of the attitude loops at the tuned gains, when a tune of
    ``tp`` moved ``Controller.kp``, ``kd``, ``kp_yaw`` or ``kd_yaw``: the loop broken at the plant's
    input, ``L(s) = (kd s + kp) / s^2`` (the law ``tau = J (-kp e - kd omega)`` on the rigid body
    ``J``), for roll and pitch and for yaw; None otherwise."""
    names = {d.name for d in tune_plan.over}
    if tune_plan.scenario != "tp" or best is None or not names & {f"Controller.{g}" for g in
                                                                   ("kp", "kd", "kp_yaw", "kd_yaw")}:
        return None
    import control
    from quadcosim.flight.controller import GAINS

    def gain(name):
        key = f"Controller.{name}"
        return float(best.get(key, tune_plan.base.get(key, GAINS[name][0])))

    margins = {}
    for axis, (kp, kd) in (("roll_pitch", ("kp", "kd")), ("yaw", ("kp_yaw", "kd_yaw"))):
        _, phase_margin, _, crossover = control.margin(control.tf([gain(kd), gain(kp)], [1.0, 0.0, 0.0]))
        margins |= {f"{axis}_phase_margin_deg": float(phase_margin), f"{axis}_crossover_rad_s": float(crossover)}
    return {"what": "phase margins of the attitude loops at the tuned gains, L(s) = (kd s + kp) / s^2 "
                    "(python-control's margin)"} | margins


def prediction(tune_plan: TunePlan) -> dict | None:
    """python-control's predicted optimum where one applies, else None: the linear filter's gain
    ``k`` against the IMU's white noise (:func:`quadcosim.estimators.analysis.linear_optimal_gain`), for
    ``tp`` with ``estimator=linear``, ``noise=on`` and roll or pitch error tuned over ``k`` alone.
    The prediction counts the sensor noise only: a flight's accelerations, which the
    accelerometer reads as tilt, move the simulated optimum towards smaller gains."""
    o = tune_plan.base
    if (tune_plan.scenario != "tp" or [d.name for d in tune_plan.over] != ["k"] or o.get("estimator") != "linear"
            or not o.get("noise") or tune_plan.metric not in ("rms_error_deg[0]", "rms_error_deg[1]")):
        return None
    from quadcosim.estimators import analysis

    sigma_gyro, sigma_angle = analysis.imu_noise_per_sample(o["imu_rate"])
    dt = 1.0 / o["imu_rate"]
    k = analysis.linear_optimal_gain(dt, sigma_gyro, sigma_angle)
    rms = math.degrees(math.sqrt(float(analysis.linear_error_variance(k, dt, sigma_gyro, sigma_angle)[0])))
    return {"what": "linear filter's gain against the IMU's white noise (python-control, "
                    "quadcosim.estimators.analysis.linear_optimal_gain)", "k": k, "rms_error_deg": rms}


class _BudgetSpent(Exception):
    """The budget of evaluations is spent: the optimiser stops where it is."""


class _Tuner:
    """The evaluations of one tune: run on the cluster in batches, cached by point, recorded."""

    def __init__(self, tune_plan: TunePlan, client, out: Path, history: list, progress: bool):
        self.plan, self.client, self.out, self.progress = tune_plan, client, out, progress
        self.history = []
        self.cache = {self._key(entry["options"]): entry for entry in history}  # --resume: already run
        self.members_run = 0

    def _key(self, point: dict) -> str:
        return json.dumps({d.name: float(f"{point[d.name]:.12g}") for d in self.plan.over}, sort_keys=True)

    def points(self, us) -> list[dict]:
        return [{d.name: d.value(u) for d, u in zip(self.plan.over, np.atleast_1d(u), strict=True)} for u in us]

    def evaluate(self, us, phase: str) -> list[float]:
        """What the optimiser sees at the scaled points ``us``: each point's mean metric over the
        seeds, or :data:`PENALTY`. New points run at once, every member of the batch together."""
        from quadcosim.studies.sweep.engine import run_member

        points = self.points(us)
        room = self.plan.budget - len(self.history)
        if room <= 0:
            raise _BudgetSpent
        points = points[:room]
        fresh = [p for p in dict.fromkeys(self._key(p) for p in points) if p not in self.cache]
        by_key = {self._key(p): p for p in points}
        futures = {key: [self.client.submit(run_member, self.plan.scenario, options, pure=False)
                         for options in self.plan.members(by_key[key])] for key in fresh}
        for key, submitted in futures.items():
            records = self.client.gather(submitted)
            self.members_run += len(records)
            self.cache[key] = self._entry(by_key[key], records)
        values = []
        for point in points:
            entry = dict(self.cache[self._key(point)]) | {"evaluation": len(self.history) + 1, "phase": phase}
            self.history.append(entry)
            values.append(PENALTY if entry["value"] is None else entry["value"])
            if self.progress:
                shown = "no value" if entry["value"] is None else f"{entry['value']:.6g}"
                print(f"tune: evaluation {entry['evaluation']}/{self.plan.budget} ({phase}) "
                      f"{_text(point)}: {self.plan.metric} = {shown} ({entry['status']})", file=sys.stderr)
        self.save()
        if len(values) < len(np.atleast_2d(us)) or len(self.history) >= self.plan.budget:
            raise _BudgetSpent
        return values

    def _entry(self, point: dict, records: list) -> dict:
        from quadcosim.studies.sweep.table import flatten

        members = []
        for seed, record in zip(self.plan.seeds or [None], records, strict=True):
            flat = flatten(record.get("metrics") or {})
            if record["status"] == "ok" and self.plan.metric not in flat:
                from quadcosim.orchestrator.fmu import nearest

                raise TuneError(f"--minimize {self.plan.metric}: the scenario has no such metric."
                                f"{nearest(self.plan.metric, flat)}")
            value = flat.get(self.plan.metric)
            status = "no value" if record["status"] == "ok" and value is None else record["status"]
            members.append({"seed": seed, "status": status, "value": value,
                            "error": next(iter((record.get("error") or "").splitlines()), None)})
        statuses = {m["status"] for m in members}
        status = next((s for s in ("diverged", "failed", "no value") if s in statuses), "ok")
        value = float(np.mean([m["value"] for m in members])) if status == "ok" else None
        return {"options": point, "value": value, "status": status, "members": members}

    def best(self) -> dict | None:
        kept = [e for e in self.history if e["value"] is not None]
        return min(kept, key=lambda e: e["value"]) if kept else None

    def save(self, finished: bool = False, extra: dict | None = None):
        from quadcosim.infra.files import write_json

        best = self.best()
        data = self.plan.to_json() | {
            "budget": self.plan.budget, "optimiser": OPTIMISER, "finished": finished,
            "best": best["options"] if best else None, "value": best["value"] if best else None,
            "evaluations": len(self.history), "members_run_now": self.members_run,
            "diverged_or_failed": sum(e["value"] is None for e in self.history),
            "history": self.history} | (extra or {})
        write_json(self.out / "tune.json", json.loads(json.dumps(data, default=float)))
        return data


OPTIMISER = ("a scan (evenly spread for one option, Sobol for several) evaluated at once, then from its best "
             "point scipy.optimize's bounded Brent (one option) or bounded Nelder-Mead (several), on coordinates "
             "scaled to [0, 1]")


def _text(point: dict) -> str:
    return " ".join(f"{k}={v:.6g}" for k, v in point.items())


def optimise(tuner: _Tuner) -> None:
    """The scan, then the refinement (see the module documentation), until the budget is spent or
    the refinement converges."""
    from scipy.optimize import minimize, minimize_scalar

    dims, budget = len(tuner.plan.over), tuner.plan.budget
    count = int(min(SCAN_MOST, max(dims + 2, round(SCAN_SHARE * budget))))
    if dims == 1:
        scan = (np.arange(count) + 0.5) / count
        values = tuner.evaluate(scan[:, None], "scan")
        best = int(np.argmin(values))
        low, high = max(scan[best] - 1.0 / count, 0.0), min(scan[best] + 1.0 / count, 1.0)
        minimize_scalar(lambda u: tuner.evaluate([[u]], "Brent")[0], bounds=(low, high), method="bounded",
                        options={"xatol": 1e-3 / count, "maxiter": budget})
        return
    from scipy.stats import qmc

    count = 2 ** int(math.log2(count))  # a Sobol sequence is balanced at powers of 2
    scan = qmc.Sobol(dims, scramble=False).random(count)
    values = tuner.evaluate(scan, "scan")
    start = scan[int(np.argmin(values))]
    simplex = np.vstack([start] + [np.clip(start + 0.15 * np.eye(dims)[i] * (1 if start[i] < 0.5 else -1), 0, 1)
                                   for i in range(dims)])
    minimize(lambda u: tuner.evaluate([u], "Nelder-Mead")[0], start, method="Nelder-Mead",
             bounds=[(0.0, 1.0)] * dims,
             options={"initial_simplex": simplex, "maxfev": budget, "xatol": 1e-3, "fatol": 0.0})


def run(tune_plan: TunePlan, out, workers: int | None = None, scheduler: str | None = None, resume: bool = False,
        progress: bool = True, connect_timeout: float = 10.0) -> dict:
    """Tune: see the module documentation. Returns what ``tune.json`` holds.

    Parameters
    ----------
    tune_plan : TunePlan
        From :func:`plan`.
    out : path
        The tune's folder (``tune.json``, ``convergence.png``); held while the tune runs.
    workers, scheduler, connect_timeout
        The cluster, as for a sweep (:func:`quadcosim.studies.sweep.engine.cluster`).
    resume : bool
        Continue the tune in ``out`` (the same plan): the evaluations recorded are not run again.
    progress : bool
        A line per evaluation on standard error.

    Raises
    ------
    TuneError
        The folder holds another tune, or no tune to resume; the metric is not the scenario's.
    """
    from quadcosim.studies.sweep import checks, folder
    from quadcosim.studies.sweep.engine import Preload, cluster
    from quadcosim.studies.sweep.grid import Member, Plan

    folder.check_scheduler(scheduler)
    out = folder.check_out(Path(out))
    history = _stored_history(tune_plan, out, resume)
    first = tune_plan.members({d.name: d.low for d in tune_plan.over})[0]
    last = tune_plan.members({d.name: d.high for d in tune_plan.over})[0]
    checks.check(Plan(tune_plan.scenario, [Member(0, first, "the lower bounds"), Member(1, last, "the upper bounds")]))
    with folder.held(out, command=" ".join(["quadcosim", *sys.argv[1:]])):
        with cluster(workers, scheduler, connect_timeout) as client:
            client.register_plugin(Preload(tune_plan.scenario))
            tuner = _Tuner(tune_plan, client, out, history, progress)
            started = time.perf_counter()
            try:
                optimise(tuner)
            except _BudgetSpent:
                pass
            except KeyboardInterrupt:
                tuner.save()
                raise
        data = tuner.save(finished=True, extra={"seconds": time.perf_counter() - started,
                                                "prediction": prediction(tune_plan),
                                                "loop_margins": loop_margins(tune_plan, tuner.best() and
                                                                             tuner.best()["options"])})
        figure(data, out / "convergence.png")
    return data


def _stored_history(tune_plan: TunePlan, out: Path, resume: bool) -> list:
    path = out / "tune.json"
    if not path.exists():
        if resume:
            raise TuneError(f"--resume: {out} holds no tune (no tune.json); run it without --resume to start it")
        return []
    if not resume:
        raise TuneError(f"{out} already holds a tune (tune.json): continue it with --resume, or choose another --out")
    try:
        stored = json.loads(path.read_text())
    except (OSError, ValueError) as error:
        raise TuneError(f"{path} is unreadable ({error}); choose another --out") from None
    now = tune_plan.to_json()
    changed = [key for key in now if stored.get(key) != now[key]]
    if changed:
        raise TuneError(f"{out} holds a tune with other {', '.join(changed)}; resume with the same arguments "
                        "(--budget may grow), or choose another --out")
    return stored.get("history", [])


def figure(data: dict, path: Path) -> Path:
    """``convergence.png``: each evaluation's value and the best so far against the evaluation
    number (a diverged or failed one a red cross on the top edge, no value); for one option, the
    values against it, the best and python-control's prediction where there is one."""
    import matplotlib.pyplot as plt
    from matplotlib.transforms import blended_transform_factory
    from quadcosim.studies.sweep.figure import metric_unit

    from quadcosim.infra.files import save_figure

    history, metric = data["history"], data["minimize"]
    unit = metric_unit(metric)
    label = f"{metric} ({unit})" if unit else metric
    one = len(data["over"]) == 1
    fig, axes = plt.subplots(1, 2 if one else 1, figsize=(12 if one else 7, 4.5), squeeze=False)
    ax = axes[0][0]
    n = np.array([e["evaluation"] for e in history])
    values = np.array([np.nan if e["value"] is None else e["value"] for e in history])
    ax.plot(n, values, "o", ms=4, color="C0", label="evaluation (mean over the seeds)")
    ax.plot(n, np.fmin.accumulate(np.where(np.isnan(values), np.inf, values)), "-", color="C1", label="best so far",
            drawstyle="steps-post")
    crashed = n[np.isnan(values)]
    if len(crashed):
        ax.plot(crashed, [1.0] * len(crashed), "x", color="red", ms=8, mew=2, clip_on=False,
                transform=blended_transform_factory(ax.transData, ax.transAxes),
                label=f"diverged or failed ({len(crashed)}): no value")
    ax.set_xlabel("evaluation")
    ax.set_ylabel(label)
    ax.set_yscale("log" if np.nanmin(values, initial=np.inf) > 0 else "linear")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    best = data["best"] or {}
    seeds = f" x {len(data['seeds'])} seeds" if data["seeds"] else ""
    ax.set_title(f"{data['scenario']}: {metric}, {len(history)} evaluations{seeds}\n"
                 + (f"best {data['value']:.4g} at {_text(best)}" if best else "no evaluation has a value"), fontsize=9)
    if one:
        name = data["over"][0]["name"]
        ax2 = axes[0][1]
        x = np.array([e["options"][name] for e in history])
        ax2.plot(x[~np.isnan(values)], values[~np.isnan(values)], "o", ms=4, color="C0", label="evaluations")
        if best:
            ax2.plot([best[name]], [data["value"]], "*", ms=14, color="C1", label=f"tuned {name} = {best[name]:.4g}")
        predicted = data.get("prediction")
        if predicted and name in predicted:
            ax2.axvline(predicted[name], color="C2", ls="--",
                        label=f"python-control's optimum {name} = {predicted[name]:.4g} (noise only)")
        if data["over"][0]["log"]:
            ax2.set_xscale("log")
        ax2.set_yscale(ax.get_yscale())
        from quadcosim.studies.sweep.units import of_options

        unit_x = of_options(data["scenario"], [name]).get(name)
        ax2.set_xlabel(f"{name} ({unit_x})" if unit_x else name)
        ax2.set_ylabel(label)
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=8)
    fig.tight_layout()
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
    return path


def add_arguments(p: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of ``quadcosim tune`` on the parser ``p``; returns it."""
    p.add_argument("scenario", help="a scenario (quadcosim list)")
    p.add_argument("--minimize", required=True, metavar="METRIC", help="a metric column, e.g. 'rms_error_deg[0]'")
    p.add_argument("--over", action="append", default=[], required=True, metavar="NAME=LOW:HIGH[:log]",
                   help="an option (or Block.parameter) to tune within its bounds; :log searches in log")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="NAME=VALUE", help="fixed options")
    p.add_argument("--seeds", type=int, metavar="N", help="each evaluation: the mean over seeds 1 to N")
    p.add_argument("--budget", type=int, default=40, metavar="N", help="evaluations at most (default 40)")
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: the CPUs)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="use a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to reach the --scheduler (default 10)")
    p.add_argument("--out", help="tune folder (default results/tune-SCENARIO, or -N when that holds a tune)")
    p.add_argument("--resume", action="store_true", help="continue the tune in --out")
    p.add_argument("--quiet", action="store_true", help="no line per evaluation")
    return p


def command(args) -> int:
    """Run ``quadcosim tune`` from parsed ``args``; print the best point.

    Returns
    -------
    int
        0: a best point found; 1: no evaluation had a value; 2: refused (bad arguments, a folder
        held or holding another tune, an unreachable scheduler); 128 + the signal if interrupted.
    """
    from quadcosim.studies.sweep.command import default_out

    label = f"quadcosim tune {args.scenario}"
    with refusals(failures=()):  # TuneError is a ValueError: exit 2
        if args.workers is not None and args.workers < 1:
            raise TuneError(f"--workers {args.workers}: give at least 1")
        if args.workers and args.scheduler:
            raise TuneError("--workers and --scheduler: the scheduler's own workers run the tune; give one")
        tune_plan = plan(args.scenario, args.minimize, args.over, args.set, args.seeds, args.budget)
        out = Path(args.out) if args.out else default_out(Path("results") / f"tune-{args.scenario}", args.resume,
                                                          label, marker="tune.json")
        data = run(tune_plan, out, args.workers, args.scheduler, args.resume, not args.quiet, args.connect_timeout)
    if data["best"] is None:
        raise RunError(f"no evaluation of {data['evaluations']} has a value (every one diverged or failed); see "
                       f"{out / 'tune.json'}")
    print(f"tune {args.scenario}: {args.minimize} = {data['value']:.6g} at {_text(data['best'])} "
          f"({data['evaluations']} evaluations, {data['diverged_or_failed']} without a value)")
    if data.get("prediction"):
        p = data["prediction"]
        print(f"  python-control predicts k = {p['k']:.4g} 1/s ({p['what']})")
    if data.get("loop_margins"):
        m = data["loop_margins"]
        print(f"  phase margin at the tuned gains: roll and pitch {m['roll_pitch_phase_margin_deg']:.1f} deg at "
              f"{m['roll_pitch_crossover_rad_s']:.3g} rad/s, yaw {m['yaw_phase_margin_deg']:.1f} deg at "
              f"{m['yaw_crossover_rad_s']:.3g} rad/s (python-control)")
    print(f"tune.json and convergence.png in {out}/")
    return 0
