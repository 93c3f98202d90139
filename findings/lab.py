"""Findings of the lab's matrix: the estimators in the closed loop, their ablations, the analyses' predictions.

Each is a ``quadcosim run tp`` (its metrics.json records the number) or ``python -m
quadcosim.scenarios.ablation`` (it prints it). The quick subset: the default ``tp`` run (a few seconds).
"""

from __future__ import annotations

import numpy as np

from findings import command, finding

RUN = "quadcosim run tp"
ABLATION = "python -m quadcosim.scenarios.ablation"
AXES = ("roll", "pitch", "yaw")
PASSIVE_GAINS = (0.1, 1.0, 10.0, 100.0)


def _command(settings: dict) -> str:
    return command(RUN, settings)


def _tp(settings: dict) -> dict:
    from quadcosim import scenarios

    return scenarios.run("tp", settings)[1]


def _triple(name: str, values, unit: str, command: str, digits: int) -> list[dict]:
    tolerance = 0.5 * 10.0 ** -digits
    return [finding(f"{name}.{axis}", v, unit, command, tolerance, digits)
            for axis, v in zip(AXES, values, strict=True)]


def rms(name: str, settings: dict, digits: int, key: str = "rms_error_deg") -> tuple[list[dict], dict]:
    """The errors (deg, roll, pitch, yaw) of one ``tp`` run as findings ``name.roll`` ..., and its metrics.

    Parameters
    ----------
    name : str
        Prefix of the findings' names.
    settings : dict
        The run's ``tp`` options.
    digits : int
        Decimals printed.
    key : str
        The metric (``rms_error_deg``).
    """
    m = _tp(settings)
    return _triple(name, m[key], "deg", _command(settings), digits), m


def defaults() -> list[dict]:
    """The default run (the quick subset): its errors and the span of the cruise's attitude."""
    found, m = rms("lab.linear_quasi_gt", {}, 3)
    return found + _triple("lab.cruise_span_deg", m["attitude_span_deg"], "deg", RUN, 1)


def linear() -> list[dict]:
    """The linear filter in non-stationary flight, and the ablations that say where its error comes from."""
    from quadcosim.scenarios.ablation import linear_ablation

    found, m = rms("lab.linear_nonstationary_gt", {"flight": "nonstationary"}, 2)
    quasi = _tp({})["rms_error_deg"]
    ratios = [fast / slow for fast, slow in zip(m["rms_error_deg"], quasi, strict=True)]
    found += [finding("lab.nonstationary_over_quasi_min", min(ratios), "1", "quadcosim sweep lab-matrix", 0.5, 0),
              finding("lab.nonstationary_over_quasi_max", max(ratios), "1", "quadcosim sweep lab-matrix", 0.5, 0)]
    rows = linear_ablation({"flight": "nonstationary"})
    command = f"{ABLATION} --set flight=nonstationary"
    found += _triple("lab.ablation.ideal_accelerometer", rows["ideal accelerometer"], "deg", command, 2)
    found += _triple("lab.ablation.true_euler_rates", rows["true Euler rates"], "deg", command, 2)
    found += _triple("lab.ablation.both", rows["both"], "deg", command, 3)
    for flight, digits in (("quasi", 3), ("nonstationary", 2)):
        rows = linear_ablation({"flight": flight, "rotor_drag": False})
        found += _triple(f"lab.ablation.{flight}_without_drag", rows["recorded"], "deg",
                         f"{ABLATION} --set flight={flight} --set rotor_drag=off", digits)
    return found


def explicit() -> list[dict]:
    """The explicit filter: estimate-fed in non-stationary flight; with a gyro bias and no bias
    estimate, simulated against predicted."""
    found, _ = rms("lab.explicit_nonstationary_estimate",
                   {"estimator": "explicit", "flight": "nonstationary", "feedback": "estimate"}, 2)
    settings = {"estimator": "explicit", "flight": "hover", "bias": True, "k1": 1.0, "k2": 1.0, "kI": 0.0,
                "duration": 60.0}
    m = _tp(settings)
    found += _triple("lab.explicit_bias.simulated", m["steady_error_deg"], "deg", _command(settings), 2)
    found += _triple("lab.explicit_bias.predicted", m["steady_error_predicted_deg"], "deg", _command(settings), 2)
    return found


def passive() -> list[dict]:
    """The passive filter's bias-convergence time at kP = kI, with R_reel and with TRIAD, against
    the prediction: each run long enough to show it (1.5 times the prediction, 10 s at least)."""
    from quadcosim.estimators import analysis
    from quadcosim.fmus.IMU.variables import LAB_GYRO_BIAS
    from quadcosim.scenarios.tp import BIAS_TOLERANCE

    found = []
    for gain in PASSIVE_GAINS:
        predicted = analysis.passive_bias_convergence_time(gain, gain, max(abs(b) for b in LAB_GYRO_BIAS),
                                                           BIAS_TOLERANCE)
        for ry in ("reel", "triad"):
            settings = {"estimator": "passive", "flight": "hover", "bias": True, "kP": gain, "kI": gain,
                        "ry": ry, "duration": float(round(max(10.0, 1.5 * predicted)))}
            m = _tp(settings)
            label = f"lab.passive_convergence.{ry}.k{gain:g}".replace("k0.1", "k0_1")
            digits = 1 if predicted >= 10 else 2
            found += [finding(f"{label}.simulated_s", m["bias_convergence_s"], "s", _command(settings),
                              0.5 * 10.0 ** -digits, digits),
                      finding(f"{label}.predicted_s", m["bias_convergence_predicted_s"], "s", _command(settings),
                              0.5 * 10.0 ** -digits, digits)]
    return found


def triad() -> list[dict]:
    """The passive filter on TRIAD: the bias estimate in non-stationary flight (ablation), and
    estimate-fed in the cruise."""
    from quadcosim.scenarios.ablation import triad_ablation

    rows = triad_ablation({"flight": "nonstationary"})
    command = f"{ABLATION} --triad --set flight=nonstationary"
    found = [finding(f"lab.triad_bias.recorded.{a}", v, "rad/s", command, 5e-4, 3)
             for a, v in zip("xyz", rows["recorded"], strict=True)]
    found += [finding(f"lab.triad_bias.times_true.{a}", abs(v / b), "1", command, 0.05, 1)
              for a, v, b in zip("xyz", rows["recorded"], rows["true bias"], strict=True)]
    found += [finding(f"lab.triad_bias.ideal_accelerometer.{a}", v, "rad/s", command, 5e-5, 4)
              for a, v in zip("xyz", rows["ideal accelerometer"], strict=True)]
    base = {"estimator": "passive", "ry": "triad", "bias": True, "noise": True, "feedback": "estimate"}
    for name, extra in (("runaway", {}), ("gravity", {"accelerometer": "gravity"}), ("hover", {"flight": "hover"})):
        found += rms(f"lab.triad_estimate.{name}", base | extra, 1 if name == "runaway" else 2)[0]
    return found


def madgwick() -> list[dict]:
    """Madgwick's filter flown estimate-fed (the README's own estimator, as the ahrs package's)."""
    return rms("lab.madgwick", {"estimator": "madgwick", "feedback": "estimate", "noise": True, "duration": 10.0},
               2)[0]


SEEDS = range(1, 7)  # case 2: the noise's spread over these seeds
CASE6 = {"estimator": "explicit", "noise": True, "bias": True, "feedback": "estimate"}
CASE6_STEADY_S = 960.0  # s of hover: the last quarter's mean moves by under 0.1 deg from 480 s on


def noise_seeds() -> list[dict]:
    """Case 2: the linear filter's roll error without noise, and with noise over seeds 1 to 6."""
    settings = {"estimator": "linear", "noise": True}
    command_line = "quadcosim sweep tp --grid noise=off,on --seeds 6 --set estimator=linear"
    roll = [_tp(settings | {"seed": seed})["rms_error_deg"][0] for seed in SEEDS]
    return [finding("lab.noise_seeds.off_roll", _tp({"estimator": "linear"})["rms_error_deg"][0], "deg",
                    command_line, 5e-4, 3),
            finding("lab.noise_seeds.on_roll_min", min(roll), "deg", command_line, 5e-4, 3),
            finding("lab.noise_seeds.on_roll_max", max(roll), "deg", command_line, 5e-4, 3),
            finding("lab.noise_seeds.on_roll_mean", float(np.mean(roll)), "deg", command_line, 5e-4, 3),
            finding("lab.noise_seeds.on_roll_seed1", roll[0], "deg", command_line, 5e-4, 3)]


def bias_steady() -> list[dict]:
    """Case 6: the explicit filter's steady error under a gyro bias without bias estimate, in the
    case's 20 s non-stationary flight (still growing) and in a hover long enough to be steady,
    against the linearised prediction; how much the hover's error moved over its last half."""
    from quadcosim import scenarios

    short = CASE6 | {"flight": "nonstationary"}
    m = _tp(short)
    found = _triple("lab.bias_steady.nonstationary_20s", m["steady_error_deg"], "deg", _command(short), 1)
    found += _triple("lab.bias_steady.predicted", m["steady_error_predicted_deg"], "deg", _command(short), 1)
    long = CASE6 | {"flight": "hover", "duration": CASE6_STEADY_S, "bench_supply": True}
    result, m = scenarios.run("tp", long)
    found += _triple("lab.bias_steady.hover", m["steady_error_deg"], "deg", _command(long), 1)
    error = np.column_stack([result[f"Quaternion_estim.theta_est{i}"] - result[f"Quadrotor.theta{i}"]
                             for i in (1, 2, 3)])
    half, quarter = 0.5 * CASE6_STEADY_S, 0.25 * CASE6_STEADY_S
    earlier = error[(result.time > half) & (result.time <= half + quarter)].mean(axis=0)
    later = error[result.time > half + quarter].mean(axis=0)
    moved = float(np.degrees(np.max(np.abs(later - earlier))))
    return found + [finding("lab.bias_steady.hover_moved", moved, "deg", _command(long), 0.05, 1)]


def compute(quick: bool = False) -> list[dict]:
    """Every lab finding; ``quick``: the default run's and the cases of the lab page checked by
    measurement (noise over seeds, the bias's steady error: about half a minute)."""
    if quick:
        return defaults() + noise_seeds() + bias_steady()
    return defaults() + noise_seeds() + bias_steady() + linear() + explicit() + passive() + triad() + madgwick()
