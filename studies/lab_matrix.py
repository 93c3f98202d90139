"""The lab's matrix in one go: every ``tp`` case of the report, and the checks against analysis.

    quadcosim sweep lab-matrix --out results/lab-matrix      (or python -m quadcosim.studies.lab_matrix)

A named sweep: its members run on Dask like any sweep (``--workers``, ``--scheduler``,
``--resume``); each case leaves its own folder (figures, metrics.json, results) under
``members/`` with ``sweep.csv`` beside, and ``summary.md`` gathers the numbers:
- estimation RMS error (roll, pitch, yaw) and tracking RMS for each case;
- the explicit filter without bias estimate: simulated steady error against the linearised
  prediction (quadcosim.estimators.analysis.explicit_bias_steady_error);
- the passive filter: bias-convergence time against the linearised prediction for
  kP = kI in {0.1, 1, 10, 100}, with R_reel and with TRIAD;
- the published filters beside the lab's: VQF (``vqf``) and Madgwick (``ahrs``) with the
  linear, explicit and passive (TRIAD) filters at the lab's gains, estimate-fed, noise and
  gyro bias, on both flight profiles; quaternion-error RMSE (total, inclination, heading)
  and the estimation and tracking RMS;
- the lab's findings as checks, each with its measured figures: the linear filter accurate in
  quasi-stationary flight (a non-zero error below 1 degree on every axis) and degraded in
  non-stationary flight; the explicit filter below 2 degrees RMS in both; the bias cases as
  the analyses predict where they do (the explicit filter's roll and yaw; its pitch is named as
  missed).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from quadcosim.estimators import analysis, kinds, score
from quadcosim.fmus.IMU.variables import LAB_GYRO_BIAS

from quadcosim.infra.files import write_json, write_text

CASES = {
    "linear-quasi-gt": {"estimator": "linear"},
    "linear-quasi-gt-noise": {"estimator": "linear", "noise": True},
    "linear-quasi-estimate-noise": {"estimator": "linear", "noise": True, "feedback": "estimate"},
    "linear-nonstationary-gt": {"estimator": "linear", "flight": "nonstationary"},
    "linear-nonstationary-gt-noise": {"estimator": "linear", "flight": "nonstationary", "noise": True},
    "linear-nonstationary-estimate-noise": {"estimator": "linear", "flight": "nonstationary", "noise": True,
                                            "feedback": "estimate"},
    "explicit-0.002-quasi-gt": {"estimator": "explicit", "k1": 0.002, "k2": 0.002},
    "explicit-0.002-nonstationary-gt": {"estimator": "explicit", "k1": 0.002, "k2": 0.002, "flight": "nonstationary"},
    "explicit-0.002-quasi-estimate": {"estimator": "explicit", "k1": 0.002, "k2": 0.002, "feedback": "estimate"},
    "explicit-0.2-nonstationary-estimate": {"estimator": "explicit", "flight": "nonstationary",
                                            "feedback": "estimate"},
    "explicit-nonstationary-estimate-noise": {"estimator": "explicit", "flight": "nonstationary",
                                              "feedback": "estimate", "noise": True},
    "explicit-nonstationary-estimate-noise-bias": {"estimator": "explicit", "flight": "nonstationary",
                                                   "feedback": "estimate", "noise": True, "bias": True},
    **{f"passive-reel-{g:g}-quasi-estimate-noise-bias": {"estimator": "passive", "kP": g, "kI": g, "bias": True,
                                                          "noise": True, "feedback": "estimate"}
       for g in (0.1, 1.0, 10.0, 100.0)},
    "passive-triad-quasi-estimate-noise-bias": {"estimator": "passive", "ry": "triad", "bias": True, "noise": True,
                                                "feedback": "estimate"},
    "passive-triad-hover-estimate-noise-bias": {"estimator": "passive", "ry": "triad", "bias": True, "noise": True,
                                                "feedback": "estimate", "flight": "hover"},
}
# the published filters beside the lab's, in the same closed loop (estimate-fed, noise, gyro bias)
COMPARED = kinds.compared()
COMPARISON = {f"compare-{kind}-{flight}": {"estimator": kind, "flight": flight, "feedback": "estimate", "noise": True,
                                           "bias": True, **options}
              for flight in ("quasi", "nonstationary") for kind, options in COMPARED.items()}
EXPLICIT_GAINS = (0.2, 1.0, 2.0)
EXPLICIT_WITHOUT_BIAS = ("explicit-0.002-quasi-gt", "explicit-0.002-nonstationary-gt", "explicit-0.002-quasi-estimate",
                         "explicit-0.2-nonstationary-estimate", "explicit-nonstationary-estimate-noise")
LINEAR_ACCURATE_DEG = 1.0  # deg, every axis, quasi-stationary flight
EXPLICIT_ACCURATE_DEG = 2.0  # deg, every axis, both flights
PREDICTION_TOLERANCE = {"explicit": 0.1, "passive": 0.2}  # relative, as in tests/test_lab_cases.py
PASSIVE_GAINS = (0.1, 1.0, 10.0, 100.0)
# the explicit filter's pitch steady error under the lab's bias, hover, 60 s: -0.53 against -0.29 deg
# predicted at k1 = k2 = 1, -0.21 against -0.14 at 2 (roll and yaw within 1 %): a gap the analysis leaves
PITCH_MISSED = 0.3


def cases() -> dict[str, dict]:
    """Every member: the matrix's cases, then the runs the checks against analysis rest on."""
    members = dict(CASES) | COMPARISON
    for k in EXPLICIT_GAINS:  # the explicit filter's steady error without bias estimate
        members[f"explicit-steady-k{k:g}-hover-bias"] = {"estimator": "explicit", "flight": "hover", "bias": True,
                                                        "k1": k, "k2": k, "kI": 0.0, "duration": 60.0}
    for ry in ("reel", "triad"):  # the passive filter's bias-convergence time
        for g in PASSIVE_GAINS:
            members[f"passive-{ry}-{g:g}-hover-bias-convergence"] = {
                "estimator": "passive", "flight": "hover", "bias": True, "kP": g, "kI": g, "ry": ry,
                "duration": max(10.0, 1.5 * _passive_prediction(g))}
    return members


def _passive_prediction(gain: float) -> float:
    return analysis.passive_bias_convergence_time(gain, gain, max(np.abs(LAB_GYRO_BIAS)), 1e-3)


def late_mean_error(result, options) -> dict:
    """Mean estimation error over the last quarter of the run (deg; roll, pitch, yaw): the
    steady error of a filter that does not estimate the gyro bias (after 45 s of 60), and the
    quaternion-error RMSE after the settling time (deg; total, inclination, heading), from a
    member's ``result`` and its tp ``options``."""
    late = result.time > 0.75 * options["duration"]
    error = np.column_stack([result[f"Quaternion_estim.theta_est{i}"] - result[f"Quadrotor.theta{i}"]
                             for i in (1, 2, 3)])[late].mean(axis=0)
    settle = min(options["settle"], 0.5 * options["duration"])
    quaternion = score(result["Quaternion_estim.q_est"], result["Quadrotor.q"], result.time >= settle)
    return {"late_mean_error_deg": np.degrees(error).tolist(),
            "quaternion_rmse_deg": [quaternion[f"{k}_rmse_deg"] for k in ("total", "inclination", "heading")]}


def summary_of(records: list[dict]) -> dict:
    """The matrix's numbers and checks, from its members' records (metrics.json)."""
    by_label = {r["label"]: r["metrics"] for r in records}
    status = {r["label"]: r.get("status", "ok") for r in records}
    summary = {
        "diverged": {r["label"]: r.get("error") for r in records if status[r["label"]] == "diverged"},
        "cases": {name: {k: by_label[name][k] for k in ("rms_error_deg", "tracking_rms_deg", "bias_error_final")}
                  | {"status": status[name]} for name in CASES},
        "explicit_steady_bias_error_deg": [
            {"k1=k2": k, "simulated": by_label[f"explicit-steady-k{k:g}-hover-bias"]["late_mean_error_deg"],
             "predicted": np.degrees(analysis.explicit_bias_steady_error(k, k, 1.0, LAB_GYRO_BIAS)).tolist()}
            for k in EXPLICIT_GAINS],
        "comparison": {name: {k: by_label[name][k] for k in ("quaternion_rmse_deg", "rms_error_deg",
                                                               "tracking_rms_deg")} | {"status": status[name]}
                       for name in COMPARISON},
        "passive_bias_convergence_s": [
            {"ry": ry, "kP=kI": g,
             "simulated": by_label[f"passive-{ry}-{g:g}-hover-bias-convergence"]["bias_convergence_s"],
             "predicted": _passive_prediction(g)}
            for ry in ("reel", "triad") for g in PASSIVE_GAINS],
    }
    summary["checks"] = checks(summary)
    return summary


def summarise(records: list[dict], out: Path) -> dict:
    """Write ``summary.json`` and ``summary.md`` in ``out``; return the summary of the members'
    ``records`` (their metrics.json)."""
    summary = summary_of(records)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "summary.json", summary)
    write_text(out / "summary.md", markdown(summary))
    return summary


def checks(summary: dict) -> list[dict]:
    """The lab's findings as pass/fail checks with the figures they rest on (deg, s), from the
    matrix's ``summary`` (:func:`summary_of`)."""
    rms = {name: np.array(m["rms_error_deg"]) for name, m in summary["cases"].items()}
    quasi, fast = rms["linear-quasi-gt"], rms["linear-nonstationary-gt"]
    explicit = np.array([rms[name] for name in EXPLICIT_WITHOUT_BIAS])
    steady = [r for r in summary["explicit_steady_bias_error_deg"] if r["k1=k2"] >= 1.0]
    explicit_gap = max(abs(r["simulated"][axis] / r["predicted"][axis] - 1) for r in steady for axis in (0, 2))
    pitch_gap = min(abs(r["simulated"][1] / r["predicted"][1] - 1) for r in steady)
    passive_gap = max(np.inf if r["simulated"] is None else abs(r["simulated"] / r["predicted"] - 1)
                      for r in summary["passive_bias_convergence_s"])
    rested_on = [name for name in summary.get("diverged", {}) if not name.startswith("compare-")]
    return [
        {"check": "the members the checks rest on: none diverged (count)",
         "measured": [float(len(rested_on))], "ok": not rested_on},
        {"check": f"linear, quasi-stationary, GT: 0 < RMS < {LINEAR_ACCURATE_DEG:g} deg on every axis",
         "measured": quasi.tolist(), "ok": bool(np.all(quasi > 0) and np.all(quasi < LINEAR_ACCURATE_DEG))},
        {"check": "linear, non-stationary, GT: RMS above the quasi-stationary one on every axis (ratio)",
         "measured": (fast / quasi).tolist(), "ok": bool(np.all(fast > quasi))},
        {"check": f"explicit, without gyro bias, both flights: RMS < {EXPLICIT_ACCURATE_DEG:g} deg (largest)",
         "measured": [float(explicit.max())], "ok": bool(explicit.max() < EXPLICIT_ACCURATE_DEG)},
        {"check": "explicit without bias estimate, k1 = k2 >= 1: roll and yaw steady error as predicted "
                  f"(largest relative gap < {PREDICTION_TOLERANCE['explicit']:g})",
         "measured": [float(explicit_gap)], "ok": bool(explicit_gap < PREDICTION_TOLERANCE["explicit"])},
        {"check": "explicit without bias estimate, k1 = k2 >= 1: pitch steady error NOT as the linearised analysis "
                  f"predicts (smallest relative gap > {PITCH_MISSED:g})",
         "measured": [float(pitch_gap)], "ok": bool(pitch_gap > PITCH_MISSED)},
        {"check": "passive, R_reel and TRIAD, hover: bias-convergence time as predicted "
                  f"(largest relative gap < {PREDICTION_TOLERANCE['passive']:g})",
         "measured": [float(passive_gap)], "ok": bool(passive_gap < PREDICTION_TOLERANCE["passive"])},
    ]


def markdown(summary: dict) -> str:
    """The matrix's tables in Markdown: estimation and tracking RMS per case (deg), the explicit
    filter's steady bias error against its prediction (deg), the passive filter's bias
    convergence time against its prediction (s), and the checks.

    Parameters
    ----------
    summary : dict
        As :func:`summary_of` returns (with ``checks`` when present).

    Returns
    -------
    str
        The tables, separated by blank lines.
    """
    def deg(values):
        return " / ".join(f"{v:.3f}" for v in values)

    def crashed(m, values):  # a diverged member's numbers describe a crash: marked, never a result
        return f"DIVERGED (a crash: {deg(values)})" if m.get("status") == "diverged" else deg(values)

    lines = ["| case | estimation RMS (deg, roll/pitch/yaw) | tracking RMS (deg) |", "|---|---|---|"]
    for name, m in summary["cases"].items():
        lines.append(f"| {name} | {crashed(m, m['rms_error_deg'])} | {crashed(m, m['tracking_rms_deg'])} |")
    lines += ["", "| flight | estimator (estimate-fed, noise, bias) | quaternion RMSE total / inclination / heading "
              "(deg) | estimation RMS (deg, roll/pitch/yaw) | tracking RMS (deg) |", "|---|---|---|---|---|"]
    for name, m in summary["comparison"].items():
        options = COMPARISON[name]
        lines.append(f"| {options['flight']} | {options['estimator']} | {crashed(m, m['quaternion_rmse_deg'])} | "
                     f"{crashed(m, m['rms_error_deg'])} | {crashed(m, m['tracking_rms_deg'])} |")
    lines += ["", "| explicit, no bias estimate, k1 = k2 | simulated steady error (deg) | predicted (deg) |",
              "|---|---|---|"]
    for row in summary["explicit_steady_bias_error_deg"]:
        lines.append(f"| {row['k1=k2']:g} | {deg(row['simulated'])} | {deg(row['predicted'])} |")
    lines += ["", "| passive, R_y | kP = kI | bias within 1e-3 rad/s after (s), simulated | predicted |",
              "|---|---|---|---|"]
    for row in summary["passive_bias_convergence_s"]:
        simulated = "not reached" if row["simulated"] is None else f"{row['simulated']:.2f}"
        lines.append(f"| {row['ry']} | {row['kP=kI']:g} | {simulated} | {row['predicted']:.2f} |")
    if summary.get("diverged"):
        lines += ["", "Diverged members (their flight crossed the scenario's bounds; their numbers are not results):",
                  ""] + [f"- {name}: {why}" for name, why in summary["diverged"].items()]
    if "checks" in summary:
        lines += ["", "| check | measured | holds |", "|---|---|---|"]
        for row in summary["checks"]:
            lines.append(f"| {row['check']} | {deg(row['measured'])} | {'yes' if row['ok'] else 'NO'} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """Command line ``python -m quadcosim.studies.lab_matrix``: run the matrix as the named sweep
    ``lab-matrix`` and print its summary.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``): ``--out``, ``--workers``, ``--scheduler``,
        ``--resume``; the others are passed on to ``quadcosim sweep``.

    Returns
    -------
    int
        The sweep's exit status (0: every member completed).
    """
    from quadcosim.studies.sweep import command

    parser = argparse.ArgumentParser(prog="python -m quadcosim.studies.lab_matrix", description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="output folder (default results/lab-matrix, or results/lab-matrix-N when that "
                                      "holds an earlier matrix)")
    parser.add_argument("--workers", help="local Dask worker processes (default: the CPUs)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--resume", action="store_true", help="continue the matrix in --out")
    args, rest = parser.parse_known_args(argv)
    args.out = args.out or str(command.default_out(Path("results/lab-matrix"), args.resume, parser.prog))
    forwarded = ["lab-matrix", "--out", args.out, *rest]
    forwarded += ["--workers", args.workers] if args.workers else []
    forwarded += ["--scheduler", args.scheduler] if args.scheduler else []
    forwarded += ["--resume"] if args.resume else []
    return command.main(forwarded)  # prints the summary.md it writes


def _sweep():
    from quadcosim.studies.sweep.named import NamedSweep

    return NamedSweep("lab-matrix", "tp", cases, "every tp case of the lab report, and the checks against analysis",
                      summarise=summarise, extra_metrics="quadcosim.studies.lab_matrix:late_mean_error",
                      keep_results=True)


SWEEP = _sweep()


if __name__ == "__main__":  # the same as quadcosim study lab-matrix
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study lab-matrix").run, main)
