"""``gain-study``: the linear filter's gain swept, python-control predictions against simulated errors.

1. GT mode: the closed loop hovers, fed by the ground truth, with IMU noise on; the sensor
   stream is recorded once and the linear filter is run on it by the batch path for every
   gain of a log grid at once. Its roll and pitch error variances are set against the
   variance python-control predicts from the IMU's noise densities
   (estimators/analysis.py), and the two optimal gains are compared.
2. Estimate-fed mode: one closed-loop run per gain, the controller fed by the estimate, run
   as a sweep on Dask (a local cluster, or the scheduler given by ``scheduler``); their roll
   and pitch error variances go on the same figure, and a run that fails is named with its
   gain and error, its point left out, the others kept.
   With the AR(1) standard error of a run that long. ``closed_accelerometer=gravity`` feeds
   the IMU gravity alone (``R^T (0, 0, -g)``, its own noise kept) in these runs: the ablation
   that shows why, at large gains, they leave the prediction (see the README).

The statistical uncertainty of each simulated variance is measured by batch means: the
stream is cut into 20 blocks, each far longer than the filter's time constant 1/k, and the
standard error of the mean of the block variances is reported, relative to the variance.
The AR(1) formula sqrt(2 / (k T)) per axis gives the same order and fixes the duration
needed: T >= 800 / k_min seconds for 5 % on one axis, half that for roll and pitch pooled.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.divergence import Bounds
from quadcosim.scenarios.figures import fault_text, faults_of, title_lines
from quadcosim.scenarios.plant import save_figure
from quadcosim.scenarios.tp import BLOCKS as TP_BLOCKS

from quadcosim.infra.progress import active, status

OPTIONS = {
    "k_min": Option(0.05, "smallest gain (1/s)", minimum=1e-4),
    "k_max": Option(5.0, "largest gain (1/s)", minimum=1e-4),
    "count": Option(16, "gains on the log grid", minimum=3),
    "duration": Option(10200.0, "length of the recorded GT stream (s)", minimum=1.0),
    "burn_in": Option(200.0, "stream time discarded at the start of every filter (s)", minimum=0.0),
    "imu_rate": Option(100.0, "IMU and estimator rate (Hz); also the macro step rate", minimum=1.0),
    "seed": Option(1, "IMU noise seed"),
    "closed_loop": Option(True, "also run the estimate-fed closed loop for each gain, as a Dask sweep"),
    "closed_duration": Option(120.0, "length of each estimate-fed run (s)", minimum=1.0),
    "closed_flight": Option("hover", "flight of the estimate-fed runs", choices=("hover", "quasi")),
    "workers": Option(0, "Dask worker processes for the estimate-fed runs (0: one per CPU)", minimum=0),
    "scheduler": Option("", "address of a running Dask scheduler for them (empty: a local cluster)"),
    "closed_accelerometer": Option("measured", "estimate-fed runs: the true specific force, or gravity alone "
                                   "(the ablation that shows where they leave the prediction)",
                                   choices=("measured", "gravity")),
    "closed_drag": Option(True, "estimate-fed runs: rotor drag on"),
}
BLOCKS = 20  # batch means: the stream after burn-in is cut into this many blocks


def grid(o: dict) -> np.ndarray:
    """The log-spaced gains of the study.

    Parameters
    ----------
    o : dict
        Parsed options; ``k_min``, ``k_max`` (1/s) and ``count`` are used.

    Returns
    -------
    numpy.ndarray
        ``count`` gains (1/s) from ``k_min`` to ``k_max``, geometrically spaced.

    Raises
    ------
    ValueError
        ``k_max`` does not exceed ``k_min``.
    """
    if not o["k_max"] > o["k_min"]:
        raise ValueError(f"k_max = {o['k_max']} must exceed k_min = {o['k_min']}")
    return np.geomspace(o["k_min"], o["k_max"], o["count"])


def validate(o: dict) -> None:
    """Refuse options that would give meaningless variances, before anything runs."""
    grid(o)
    if not o["burn_in"] < o["duration"]:
        raise ValueError(f"burn_in = {o['burn_in']:g} s must be shorter than duration = {o['duration']:g} s: "
                         "no stream would be left to measure the error on")
    block = (o["duration"] - o["burn_in"]) / BLOCKS
    if block < 1.0 / o["k_min"]:
        raise ValueError(f"duration - burn_in = {o['duration'] - o['burn_in']:g} s is too short for k_min = "
                         f"{o['k_min']:g} 1/s: each of the {BLOCKS} batch-means blocks must outlast the slowest "
                         f"filter's time constant 1/k_min; give duration >= {o['burn_in'] + BLOCKS / o['k_min']:g} s")
    if o["k_max"] / o["imu_rate"] >= 1.0:
        raise ValueError(f"k_max = {o['k_max']:g} 1/s at imu_rate = {o['imu_rate']:g} Hz: k dt = "
                         f"{o['k_max'] / o['imu_rate']:.3g} must stay below 1 for the discrete filter to be the "
                         "one analysed; lower k_max or raise imu_rate")


def build(o: dict):
    """The ground-truth-fed hover whose sensor stream the study filters (tp's system, linear filter,
    IMU noise on, macro step ``1 / imu_rate``, bench supply).

    Parameters
    ----------
    o : dict
        Parsed options of the study; checked first by :func:`validate`.

    Returns
    -------
    quadcosim.orchestrator.System
        The system to run for ``duration`` seconds.
    """
    from quadcosim import scenarios

    validate(o)
    tp = scenarios.get("tp")
    return tp.build(tp.parse({"estimator": "linear", "flight": "hover", "feedback": "gt", "noise": True,
                              "duration": o["duration"], "dt": 1.0 / o["imu_rate"], "imu_rate": o["imu_rate"],
                              "seed": o["seed"], "settle": 0.0, "bench_supply": True}))


RECORD = ["IMU.acc", "IMU.gyro", "IMU.magneto", "Quadrotor.theta1", "Quadrotor.theta2", "Quadrotor.theta3"]


def simulated_variances(result, gains, o) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch error variances (rad^2, pooled) and their relative standard errors, of the
    linear filter run by the batch path at each of ``gains`` (1/s) on the stream of ``result``
    (the recorded hover), after ``o["burn_in"]``."""
    from quadcosim.estimators import estimate

    dt = 1.0 / o["imu_rate"]
    truth = np.column_stack([result["Quadrotor.theta1"], result["Quadrotor.theta2"]])
    start = int(round(o["burn_in"] / dt))
    variances, errors = [], []
    for chunk in np.array_split(gains, max(1, len(gains) // 2)):
        status(f"gain-study: linear filter over the recorded stream, k = {', '.join(f'{k:.3g}' for k in chunk)} 1/s")
        out = estimate("linear", acc=result["IMU.acc"], gyro=result["IMU.gyro"], mag=result["IMU.magneto"], dt=dt,
                       gains={"k1": chunk, "k2": chunk, "k3": chunk}, outputs=("theta",))
        for g in range(len(chunk)):
            error = out["theta"][g, start:, :2] - truth[start:]
            blocks = np.array_split(error, BLOCKS)
            block_vars = np.array([(b**2).mean() for b in blocks])
            variances.append(block_vars.mean())
            errors.append(block_vars.std(ddof=1) / np.sqrt(len(blocks)) / block_vars.mean())
    return np.array(variances), np.array(errors)


def closed_loop_relative_standard_error(gains, o) -> np.ndarray:
    """Relative standard error of an estimate-fed run's pooled roll/pitch variance: the AR(1)
    formula sqrt(2 / (k T)) per axis over the ``T`` seconds after settling, over two axes, for
    each of ``gains`` (1/s) and the options ``o``."""
    kept = o["closed_duration"] - min(20.0, o["closed_duration"] / 4)
    return np.sqrt(2.0 / (np.asarray(gains) * kept)) / np.sqrt(2.0)


def closed_loop_options(k: float, o: dict) -> dict:
    """The ``tp`` options of the estimate-fed closed-loop run at gain ``k`` (1/s)."""
    return {"estimator": "linear", "k": k, "flight": o["closed_flight"], "feedback": "estimate", "noise": True,
            "duration": o["closed_duration"], "settle": min(20.0, o["closed_duration"] / 4), "seed": o["seed"],
            "accelerometer": o["closed_accelerometer"], "rotor_drag": o["closed_drag"]}


def closed_loop_variances(gains, o, out=None) -> tuple[np.ndarray, list, list]:
    """Roll/pitch error variance (rad^2, NaN for a failed run) and tracking RMS of one
    estimate-fed closed-loop run per gain of ``gains`` (1/s), run as a sweep (into
    ``out``/closed-loop if given); and the failures, as (gain, error)."""
    import shutil

    from quadcosim.studies.sweep import engine, grid, named

    plan = grid.plan_of_cases("tp", {f"k={k:.6g}": closed_loop_options(float(k), o) for k in gains})
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(out) / "closed-loop" if out is not None else Path(scratch)
        # the sweep's own progress (a bar on a terminal, lines to a pipe) when the command line reports
        settings = {"workers": o["workers"] or None, "scheduler": o["scheduler"] or None,
                    "progress": None if active() else False}
        status(f"gain-study: {len(gains)} estimate-fed closed loops of {o['closed_duration']:g} s on Dask "
               "(starting the cluster)")
        try:  # the same runs left by an interrupted study are kept
            summary = engine.run(plan, folder, resume=(folder / "sweep.json").exists(), **settings)
        except engine.SweepError:  # another study's runs: this one replaces them, as it replaces its figures
            shutil.rmtree(folder)
            summary = engine.run(plan, folder, **settings)
        if summary.interrupted:
            raise KeyboardInterrupt
        records = named.records(plan, folder)
    variances, tracking, failures = [], [], []
    for k, record in zip(gains, records, strict=True):
        if record["status"] == "ok":
            rms = np.radians(record["metrics"]["rms_error_deg"][:2])
            variances.append(float((rms**2).mean()))
            tracking.append(record["metrics"]["tracking_rms_deg"])
        else:
            variances.append(np.nan)
            tracking.append(None)
            failures.append((float(k), record["error"]))
    return np.array(variances), tracking, failures


def optimum_of(gains, values) -> float:
    """Minimum of a sampled curve ``values`` against ``gains``: parabola through the three points
    around the smallest sample (in log gain, log value)."""
    i = int(np.clip(np.argmin(values), 1, len(values) - 2))
    x, y = np.log(gains[i - 1:i + 2]), np.log(values[i - 1:i + 2])
    a, b, _ = np.polyfit(x, y, 2)
    return float(np.exp(-b / (2 * a))) if a > 0 else float(gains[np.argmin(values)])


#: Units of the report's metrics whose names carry none (``metrics.json``'s ``units``).
METRIC_UNITS = {"gains": "1/s", "predicted_optimal_gain": "1/s", "simulated_optimal_gain": "1/s",
                "relative_difference": "1", "max_abs_relative_difference": "1", "optimum_ratio": "1",
                "simulated_relative_standard_error": "1", "max_relative_standard_error": "1",
                "closed_loop_over_predicted": "1", "closed_loop_relative_difference": "1",
                "closed_loop_relative_standard_error": "1"}


def report(result, o, out) -> dict:
    """Error variance against gain: python-control's prediction, the batch path on the recorded
    stream, and (option ``closed_loop``) one estimate-fed run per gain on Dask.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The recorded hover (IMU signals and true Euler angles).
    o : dict
        Parsed options of the study.
    out : pathlib.Path or None
        Folder of the figure ``gain_study.png`` and of the closed-loop members; None writes no file.

    Returns
    -------
    dict
        Metrics: gains (1/s), predicted and simulated roll/pitch error variances (rad^2), their
        relative differences and standard errors, both optimal gains (1/s), the closed-loop
        variances, failures and tracking RMS (deg), and the figures written.
    """
    import matplotlib.pyplot as plt
    from quadcosim.estimators import analysis  # python-control: imported by the report only
    gains = grid(o)
    dt = 1.0 / o["imu_rate"]
    sigma_gyro, sigma_angle = analysis.imu_noise_per_sample(o["imu_rate"])
    predicted = analysis.linear_error_variance(gains, dt, sigma_gyro, sigma_angle)
    simulated, relative_se = simulated_variances(result, gains, o)
    k_predicted, k_simulated = analysis.linear_optimal_gain(dt, sigma_gyro, sigma_angle), optimum_of(gains, simulated)
    closed, tracking, failures = closed_loop_variances(gains, o, out) if o["closed_loop"] else (None, None, [])

    fig, ax = plt.subplots(figsize=(8, 5))
    fine = np.geomspace(gains[0], gains[-1], 200)
    ax.loglog(fine, np.degrees(np.sqrt(analysis.linear_error_variance(fine, dt, sigma_gyro, sigma_angle))),
              label="python-control prediction")
    ax.errorbar(gains, np.degrees(np.sqrt(simulated)), yerr=np.degrees(np.sqrt(simulated)) * relative_se / 2,
                fmt="o", label="simulated, GT mode (batch path)")
    if closed is not None:
        closed_se = closed_loop_relative_standard_error(gains, o)
        label = "simulated, estimate-fed closed loop" + (", gravity-only accelerometer"
                                                         if o["closed_accelerometer"] == "gravity" else "")
        ax.errorbar(gains, np.degrees(np.sqrt(closed)), yerr=np.degrees(np.sqrt(closed)) * closed_se / 2, fmt="s",
                    mfc="none", label=label)
    ax.axvline(0.05, color="grey", ls=":", label="lab gain 0.05")
    ax.axvline(k_predicted, color="C0", ls="--", lw=0.8, label=f"predicted optimum {k_predicted:.2f}")
    ax.axvline(k_simulated, color="C1", ls="--", lw=0.8, label=f"simulated optimum {k_simulated:.2f}")
    _label(ax, result, o)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    figure = save_figure(fig, out, "gain_study.png")
    ratio = simulated / predicted - 1.0
    return in_percent({
        "gains": gains.tolist(),
        "predicted_variance_rad2": predicted.tolist(),
        "simulated_variance_rad2": simulated.tolist(),
        "relative_difference": ratio.tolist(),
        "max_abs_relative_difference": float(np.abs(ratio).max()),
        "simulated_relative_standard_error": relative_se.tolist(),
        "max_relative_standard_error": float(relative_se.max()),
        "predicted_optimal_gain": k_predicted,
        "simulated_optimal_gain": k_simulated,
        "optimum_ratio": max(k_predicted, k_simulated) / min(k_predicted, k_simulated),
        "bandwidth_at_lab_gain_rad_s": analysis.linear_bandwidth(0.05),
        "closed_loop_variance_rad2": None if closed is None else closed.tolist(),
        "closed_loop_failures": [{"k": k, "error": error} for k, error in failures],
        "closed_loop_over_predicted": None if closed is None else (closed / predicted).tolist(),
        "closed_loop_relative_difference": None if closed is None else (closed / predicted - 1.0).tolist(),
        "closed_loop_relative_standard_error": None if closed is None
        else closed_loop_relative_standard_error(gains, o).tolist(),
        "closed_loop_tracking_rms_deg": tracking,
        "figures": [figure] if figure else [],
    })


#: The relative metrics also given in percent (``NAME_pct``), as the README quotes them.
IN_PERCENT = ("max_abs_relative_difference", "max_relative_standard_error", "closed_loop_relative_difference",
              "closed_loop_relative_standard_error")
PERCENT = 100.0


def in_percent(metrics: dict) -> dict:
    """``metrics`` with each of :data:`IN_PERCENT` also in percent, as ``NAME_pct`` (None stays None).

    Parameters
    ----------
    metrics : dict
        The report's metrics (relative figures as fractions, unit 1).
    """
    def percent(value):
        if value is None:
            return None
        return [PERCENT * v for v in value] if isinstance(value, list) else PERCENT * value

    return metrics | {f"{name}_pct": percent(metrics[name]) for name in IN_PERCENT}


def _label(ax, result, o: dict) -> None:
    """Axis labels in plain numbers (not powers of ten: the error axis spans less than a
    decade) and the title naming the stream, the estimate-fed runs and the faults."""
    from matplotlib.ticker import FormatStrFormatter

    ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
    ax.yaxis.set_minor_formatter(FormatStrFormatter("%g"))
    ax.set_xlabel("gain k (1/s)")
    ax.set_ylabel("roll/pitch error, standard deviation (deg)")
    closed_text = (f"estimate-fed runs: {o['closed_duration']:g} s each, {o['closed_flight']}, rotor drag "
                   f"{'on' if o['closed_drag'] else 'off'}" + (", gravity-only accelerometer"
                                                                 if o["closed_accelerometer"] == "gravity" else "")
                   if o["closed_loop"] else "no estimate-fed runs")
    ax.set_title(title_lines(f"gain-study: linear filter's roll/pitch error against its gain k, {o['count']} gains",
                             f"GT stream {o['duration']:g} s at {o['imu_rate']:g} Hz (first {o['burn_in']:g} s left "
                             f"out), IMU noise on; {closed_text}", fault_text(faults_of(result)), width=90), fontsize=9)


def duration(o: dict) -> float:
    """Simulated length (s) of the recorded stream: the option ``duration``.

    Parameters
    ----------
    o : dict
        Parsed options.

    Returns
    -------
    float
        Duration (s).
    """
    return o["duration"]


def resolve(o: dict) -> dict:
    """The options as used: ``workers = 0`` replaced by the worker count a local cluster starts
    (one per CPU), or None when a running scheduler's workers run the closed loops."""
    import os

    return o | {"workers": None if o["scheduler"] else (o["workers"] or os.cpu_count() or 1)}


# the recorded stream is a hover fed by the ground truth: level within 1e-14 deg over 10 s. A tilt of
# 30 deg held 0.2 s is no hover (it has no setpoint step; Controller.kp=5000 rolls it over after 1.5 s);
# the stream records no velocity nor setpoint, so the tilt from level is the bound
DIVERGENCE = Bounds(tilt_error_deg=None, altitude_error_m=None, speed_m_s=None, held_s=0.2, tilt_deg=30.0)
SCENARIO = Scenario("gain-study", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report,
                    duration=duration, extra={"record": RECORD, "units": METRIC_UNITS, "divergence": DIVERGENCE,
                                              "blocks": TP_BLOCKS},
                    resolve=resolve)
