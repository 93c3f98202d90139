"""Findings of the lab's matrix: the estimators in the closed loop, their ablations, the analyses' predictions.

Each is a ``quadcosim run tp`` (its metrics.json records the number) or ``python -m
scenarios.ablation`` (it prints it). The quick subset: the default ``tp`` run (a few seconds).
"""

from __future__ import annotations

from findings import command, finding

RUN = "quadcosim run tp"
ABLATION = "python -m scenarios.ablation"
AXES = ("roll", "pitch", "yaw")
PASSIVE_GAINS = (0.1, 1.0, 10.0, 100.0)


def _command(settings: dict) -> str:
    return command(RUN, settings)


def _tp(settings: dict) -> dict:
    import scenarios

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
    from scenarios.ablation import linear_ablation

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
    from estimators import analysis
    from fmus.IMU.variables import LAB_GYRO_BIAS
    from scenarios.tp import BIAS_TOLERANCE

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
    from scenarios.ablation import triad_ablation

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


def compute(quick: bool = False) -> list[dict]:
    """Every lab finding; ``quick``: the default run's."""
    if quick:
        return defaults()
    return defaults() + linear() + explicit() + passive() + triad() + madgwick()
