"""The recommended filter for real recordings: the explicit filter's time constants, bias learnt in
motion, rest by deviation, magnetic rejection and its recovery, on synthetic recordings whose
answers are known in closed form."""

import math

import numpy as np
import pytest
from quadcosim.estimators import DEFAULT_GAINS, estimate
from quadcosim.estimators.explicit import DEFAULT_TIME_CONSTANTS, explicit_gains, time_constants
from quadcosim.estimators.filters import RECOMMENDED, RECORDED

G = 9.81
FIELD = 4.7e-5  # T
RATE = 100.0  # Hz


def _field(dip_deg):
    dip = math.radians(dip_deg)
    return np.array([FIELD * math.cos(dip), 0.0, FIELD * math.sin(dip)])


def _yaw(q):
    return np.arctan2(2 * (q[..., 1] * q[..., 2] + q[..., 0] * q[..., 3]), 1 - 2 * (q[..., 2] ** 2 + q[..., 3] ** 2))


def _still(seconds, dip_deg=65.0, gyro=(0.0, 0.0, 0.0), field=None):
    """A level sensor heading north, at rest: gyro (rad/s), specific force and field (T), NED."""
    n = int(seconds * RATE)
    m = _field(dip_deg) if field is None else np.asarray(field)
    return {"gyro": np.tile(gyro, (n, 1)), "acc": np.tile((0.0, 0.0, -G), (n, 1)), "mag": np.tile(m, (n, 1)),
            "dt": 1.0 / RATE, "earth_field": _field(dip_deg)}


def _turning(seconds, rate, field_inertial, dip_deg=65.0):
    """A level sensor turning about the vertical at ``rate`` (rad/s), in the inertial field ``field_inertial``."""
    n = int(seconds * RATE)
    yaw = rate * np.arange(n) / RATE
    c, s = np.cos(yaw), np.sin(yaw)
    fx, fy, fz = field_inertial
    mag = np.column_stack([c * fx + s * fy, -s * fx + c * fy, np.full(n, fz)])  # R^T m, R about z
    return {"gyro": np.tile((0.0, 0.0, rate), (n, 1)), "acc": np.tile((0.0, 0.0, -G), (n, 1)), "mag": mag,
            "dt": 1.0 / RATE, "earth_field": _field(dip_deg)}


def test_time_constants_and_gains_are_one_conversion():
    gains = explicit_gains(2.0, 20.0, 200.0)
    assert gains == {"k1": 1.0, "k2": 0.1, "kP": 0.5, "kI": 1.0 / 400.0}
    assert time_constants(gains) == pytest.approx({"tau_inclination": 2.0, "tau_heading": 20.0, "tau_bias": 200.0},
                                                  rel=1e-15)
    assert DEFAULT_GAINS["explicit"] == explicit_gains(**DEFAULT_TIME_CONSTANTS)
    assert explicit_gains(1.0, 1.0, math.inf)["kI"] == 0.0
    with pytest.raises(ValueError, match="positive"):
        explicit_gains(0.0, 1.0, 1.0)


def test_estimate_runs_vqf_by_default_and_the_recommended_filter_takes_time_constants():
    data = _still(2.0)
    default = estimate(**data, outputs=("q",))["q"]
    named = estimate(RECORDED, **data, outputs=("q",))["q"]
    assert RECORDED == "vqf" and np.array_equal(default, named)
    explicit = estimate(RECOMMENDED, **data, outputs=("q",))["q"]
    assert RECOMMENDED == "explicit" and np.array_equal(
        explicit, estimate(RECOMMENDED, **data, gains=DEFAULT_GAINS["explicit"], outputs=("q",))["q"])
    by_time = estimate(RECOMMENDED, **data, gains={"tau_heading": 5.0}, outputs=("q",),
                       q0=(math.cos(0.1), 0, 0, math.sin(0.1)))
    by_gain = estimate(RECOMMENDED, **data, gains=explicit_gains(DEFAULT_TIME_CONSTANTS["tau_inclination"], 5.0,
                                                    DEFAULT_TIME_CONSTANTS["tau_bias"]),
                       outputs=("q",), q0=(math.cos(0.1), 0, 0, math.sin(0.1)))
    assert np.array_equal(by_time["q"], by_gain["q"])
    with pytest.raises(ValueError, match="explicit filter's gains"):
        estimate("passive", **data, gains={"tau_heading": 5.0}, ry="triad")


@pytest.mark.parametrize("dip_deg", [30.0, 65.0, 80.0])
def test_a_heading_error_decays_with_tau_heading_whatever_the_dip(dip_deg):
    # heading error psi: dpsi/dt = -sin(psi) / tau, so tan(psi/2) = tan(psi0/2) exp(-t / tau)
    tau, psi0 = 4.0, math.radians(30.0)
    data = _still(8.0, dip_deg)
    q0 = (math.cos(psi0 / 2), 0.0, 0.0, math.sin(psi0 / 2))
    q = estimate(RECOMMENDED, **data, gains={"tau_inclination": 1.0, "tau_heading": tau, "tau_bias": 1e12}, q0=q0,
                 corrections={"heading_level": True}, outputs=("q",))["q"][0]
    t = np.arange(1, len(q) + 1) / RATE
    predicted = 2 * np.arctan(math.tan(psi0 / 2) * np.exp(-t / tau))
    worst = np.max(np.abs(_yaw(q) - predicted))
    print(f"dip {dip_deg:g} deg: heading within {math.degrees(worst):.2e} deg of exp(-t/tau)")
    assert worst < math.radians(0.025)  # the discrete step's error: 0.013 deg measured at 100 Hz


def test_an_inclination_error_decays_with_tau_inclination():
    tau, roll0 = 1.5, math.radians(20.0)
    q0 = (math.cos(roll0 / 2), math.sin(roll0 / 2), 0.0, 0.0)
    q = estimate(RECOMMENDED, **_still(6.0), gains={"tau_inclination": tau, "tau_heading": 1e6, "tau_bias": 1e12},
                 q0=q0, corrections={"heading_level": True}, outputs=("q",))["q"][0]
    roll = np.arctan2(2 * (q[:, 2] * q[:, 3] + q[:, 0] * q[:, 1]), 1 - 2 * (q[:, 1] ** 2 + q[:, 2] ** 2))
    t = np.arange(1, len(q) + 1) / RATE
    worst = np.max(np.abs(roll - 2 * np.arctan(math.tan(roll0 / 2) * np.exp(-t / tau))))
    print(f"roll within {math.degrees(worst):.2e} deg of exp(-t/tau)")
    assert worst < math.radians(0.04)  # the discrete step's error: 0.024 deg measured at 100 Hz


@pytest.mark.parametrize("bias", [(0.01, -0.008, 0.0), (0.0, 0.0, 0.006)], ids=["tilt axes", "vertical axis"])
def test_a_gyro_bias_is_learnt_in_motion_with_tau_bias(bias):
    # with tau = tau_inclination = tau_heading, every axis's bias error y obeys
    # y'' + y'/tau + y/(tau tau_b) = 0, y(0) = -b, y'(0) = 0; rest detection off (not at rest by design).
    # The tilt and the vertical axes apart: a tilt error turns the horizontal plane the heading is taken in
    tau, tau_b, bias = 1.0, 15.0, np.array(bias)
    data = _still(45.0, gyro=bias)
    b = estimate(RECOMMENDED, **data, gains={"tau_inclination": tau, "tau_heading": tau, "tau_bias": tau_b},
                 corrections={"heading_level": True}, outputs=("b",))["b"][0]
    s1, s2 = np.roots([1.0, 1.0 / tau, 1.0 / (tau * tau_b)])
    t = np.arange(1, len(b) + 1) / RATE
    left = (s1 * np.exp(s2 * t) - s2 * np.exp(s1 * t)) / (s1 - s2)  # the share of the bias not yet learnt
    axes = bias != 0
    measured = 1.0 - b[:, axes] / bias[axes]
    worst = np.max(np.abs(measured - left[:, None]))
    print(f"bias learnt as predicted within {worst:.2e} of the bias (left at the end {left[-1]:.3f})")
    assert left[-1] < 0.1 and worst < 1.5e-3  # 8.8e-4 measured on the tilt axes, 1.2e-4 on the vertical


def test_rest_is_judged_by_the_deviation_not_the_mean():
    # a vibrating sensor: zero-mean 5 Hz rotation of 5 deg/s; its low-pass (0.5 s) is small
    data = _still(6.0)
    t = np.arange(len(data["gyro"])) / RATE
    data["gyro"] = np.column_stack([np.radians(5.0) * np.sin(2 * np.pi * 5.0 * t), np.zeros_like(t), np.zeros_like(t)])
    flags = {}
    for deviation in (0.0, 1.0):
        weights = estimate(RECOMMENDED, **data,
                           corrections={"rest_gyro": True, "rest_deviation": deviation, "bias_clip": True},
                           outputs=("weights",))["weights"][0]
        flags[deviation] = weights[:, 2]
    still = estimate(RECOMMENDED, **_still(6.0, gyro=(0.01, 0.0, 0.0)), outputs=("weights",),
                     corrections={"rest_gyro": True, "rest_deviation": True, "bias_clip": True})["weights"][0][:, 2]
    print(f"vibrating: at rest {flags[0.0].mean():.2f} of the time by the low-pass, {flags[1.0].mean():.2f} by the "
          f"deviation; still with a 0.57 deg/s bias: {still.mean():.2f}")
    assert flags[0.0][-1] == 1.0 and not flags[1.0].any()
    assert still[int(1.6 * RATE):].all() and not still[:int(1.4 * RATE)].any()  # after rest_time = 1.5 s


@pytest.mark.parametrize("turning", [False, True])
def test_a_new_field_is_adopted_only_once_it_has_held_while_turning(turning):
    # an inertial field 40 % stronger than the reference: rejected; adopted after mag_reference_time (2 s)
    # spent turning faster than mag_new_min_gyro (20 deg/s), never while still
    strong = 1.4 * _field(65.0)
    rate = math.radians(40.0) if turning else 0.0
    data = _turning(8.0, rate, strong)
    weight = estimate(RECOMMENDED, **data, corrections={"mag_norm_tolerance": True, "mag_dip_tolerance": True,
                                           "mag_reference_time": True, "mag_new_min_gyro": True},
                      outputs=("weights",))["weights"][0][:, 1]
    t = np.arange(len(weight)) / RATE
    adopted = t[np.argmax(weight > 0.5)] if (weight > 0.5).any() else math.inf
    print(f"turning {turning}: the new field adopted at {adopted:.2f} s")
    if turning:  # the low-passed gyro starts at the first sample's 40 deg/s: 2 s of candidacy from the start
        assert 1.98 < adopted < 2.05 and weight[t > 3.0].min() > 0.99
    else:
        assert adopted == math.inf and weight.max() == 0.0


@pytest.mark.parametrize(("dip_deg", "scale", "expected_s"), [(65.0, True, 5.0), (65.0, 0.0, 7.0), (45.0, True, 7.0)],
                         ids=["norm moved", "norm moved, rule off", "dip moved too"])
def test_a_field_whose_norm_alone_moved_is_adopted_after_mag_scale_time(dip_deg, scale, expected_s):
    # a field 40 % stronger than the reference, rejected: with the reference's dip (a magnetometer rescaled) it is
    # adopted after mag_scale_time (5 s), with another dip (or the rule off) after mag_new_time (7 s here)
    data = _still(10.0, field=1.4 * _field(dip_deg))
    weight = estimate(RECOMMENDED, **data, corrections={"mag_norm_tolerance": True, "mag_dip_tolerance": True,
                                                        "mag_reference_time": True, "mag_new_time": 7.0,
                                                        "mag_scale_time": scale},
                      outputs=("weights",))["weights"][0][:, 1]
    t = np.arange(1, len(weight) + 1) / RATE
    adopted = t[np.argmax(weight > 0.5)]
    print(f"dip {dip_deg} deg, rule {scale}: adopted at {adopted:.2f} s, weight {weight[0]:.2f} then {weight[-1]:.3f}")
    # after adoption the field is the reference: 1.000, and 0.970 with the other dip (its correction tilts the estimate)
    assert weight[0] == 0.0 and expected_s - 0.05 < adopted < expected_s + 0.05 and weight[-1] > 0.95


def test_a_rejection_longer_than_mag_rejection_time_corrects_at_half_weight():
    data = _still(8.0, field=1.4 * _field(65.0))
    weight = estimate(RECOMMENDED, **data, gains={"mag_rejection_time": 5.0},
                      corrections={"mag_norm_tolerance": True, "mag_dip_tolerance": True, "mag_reference_time": True,
                                   "mag_new_min_gyro": True, "mag_rejection_time": True},
                      outputs=("weights",))["weights"][0][:, 1]
    t = np.arange(1, len(weight) + 1) / RATE
    print(f"weight {weight[t < 4.9].max():.2f} before 5 s, {weight[t > 5.1].min():.2f} after")
    assert weight[t < 4.95].max() == 0.0 and np.all(weight[t > 5.05] == 0.5)


class _Bowl:
    """A stand-in for quadcosim.benchmarks.tuning.Scorer: two 'datasets' whose ratio to VQF is a bowl in the log
    of each parameter, minimal at known values (a: 4 and 16 s, b: 8 s)."""

    recordings = {"one": None, "two": None}

    def ratios(self, kind, gains):
        a, b = np.log2(gains["tau_inclination"]), np.log2(gains["tau_heading"])
        self.last = {n: {"total_rmse_deg": np.ones_like(a)} for n in self.recordings}
        return {"one": 1 + (a - 2) ** 2 + (b - 3) ** 2, "two": 1 + 0.5 * (a - 4) ** 2 + (b - 3) ** 2}


def test_the_compass_search_stops_inside_its_grid_at_the_least_worst_ratio():
    from quadcosim.benchmarks import tuning

    chosen = tuning.search(_Bowl(), "explicit", {"tau_inclination": 1.0, "tau_heading": 64.0},
                           log=lambda text: None)
    # the worst of the two bowls is least where they cross between a = 2 and a = 4: at a = 3 (8 s) on the grid
    assert {k: chosen["values"][k] for k in ("tau_inclination", "tau_heading")} == {"tau_inclination": 8.0,
                                                                                  "tau_heading": 8.0}
    last = chosen["history"][-(2 * len(chosen["values"]) + 1):]
    assert last[0]["values"] == chosen["values"] and all(h["score"] >= chosen["score"] for h in last)
