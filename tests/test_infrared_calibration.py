"""In-flight IR calibration: the Kalman filter against the slides' regression and the RLS,
the slides' faults followed without gating and declared with it, batch equals streaming, and
refusals of bad data."""

import numpy as np
import pytest

import scenarios
from calibration.infrared import CalibrationError, EKFSettings, Estimator


@pytest.fixture(scope="module")
def both_faults():
    return scenarios.run("ir-calibration", {"faults": "both"})


def test_kalman_turn_rate_error_is_a_third_of_the_regression_on_drifting_data():
    result, metrics = scenarios.run("ir-calibration", {})
    stats = metrics["turn_rate_error_deg_s"]
    print("\n8000 drifting samples, turn-rate error std (deg/s): "
          + ", ".join(f"{m} {s['std']:.2f}" for m, s in stats.items()))
    assert stats["kalman"]["std"] <= stats["regression"]["std"] / 3
    assert stats["kalman"]["std"] < stats["rls"]["std"]
    assert metrics["false_alarms"] == 0
    # batch path on the recorded arrays: the same arithmetic as the streaming block
    batch = Estimator("kalman").run(result["Faults.ir"], result["Faults.gps_turn_rate"],
                                    result["InfraredSensor.gps_valid"] > 0.5)
    assert np.array_equal(batch["a"], result["Kalman.a"]) and np.array_equal(batch["b"], result["Kalman.b"])


def test_without_gating_b_absorbs_the_ir_fault():
    result, metrics = scenarios.run("ir-calibration", {"faults": "ir", "gating": False})
    t = result.time
    during = (t > 150) & (t < 200)
    shift = result["Kalman.b"][during].mean() - result["InfraredSensor.b"][during].mean()
    print(f"\nungated filter, IR +1200: b shifted by {shift:.0f} counts")
    assert shift == pytest.approx(1200, rel=0.06)
    assert metrics["faults"][0]["declared_s"] is None


def test_gated_filter_declares_and_attributes_both_faults(both_faults):
    result, metrics = both_faults
    for fault in metrics["faults"]:
        delay = fault["declared_s"] - fault["onset_s"]
        print(f"\n{fault['sensor']} fault at {fault['onset_s']:g} s declared after {delay:.2f} s, "
              f"cleared {fault['cleared_s'] - fault['end_s']:.2f} s after its end")
        # the IR reaches the filter paired with the GPS window, 1 s late: declared 1.5 s after onset
        assert 0 < delay <= (1.6 if fault["sensor"] == "ir" else 0.6)
        assert fault["cleared_s"] is not None
    assert metrics["false_alarms"] == 0


def test_non_finite_input_and_bad_covariance_are_refused():
    with pytest.raises(CalibrationError, match="non-finite value .* at sample 3"):
        Estimator("kalman").run([900.0, 901, 902, np.nan], [0.0, 0, 0, 0])
    with pytest.raises(CalibrationError, match="finite readings only"):
        Estimator("rls").update(np.inf, 0.1)
    with pytest.raises(ValueError, match="not positive definite"):
        Estimator("kalman", covariance=np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(ValueError, match="must be positive"):
        EKFSettings(sd_ir=0.0)
