"""The infrared EKF's consistency detector: small offsets the filter would absorb into b and a
are declared on the right sensor, a turn that exposes an error of a in the cloud is not, and the
streaming block runs the same arithmetic as the batch path."""

import numpy as np
import pytest

from calibration.infrared import EKFSettings, Estimator
from scenarios.ir_calibration import episodes, fault_report, simulate_flight
from scenarios.ir_detection import one_fault


@pytest.mark.parametrize(("sensor", "size", "within", "ended_within"),
                         [("gps", 0.1, 0.6, 2.0), ("gps", 0.2, 0.3, 1.0), ("ir", 100.0, 2.0, 2.5)])
def test_small_offsets_are_declared_on_their_sensor_and_ended(sensor, size, within, ended_within):
    """Seed 1: GPS +0.1 declared after 0.40 s, +0.2 after 0.10 s, IR +100 after 1.65 s (the
    filter's own CUSUMs declared none of them); ended 1.45, 0.35 and 2.30 s after their end."""
    row = one_fault(sensor, size)
    print(f"\n{sensor} +{size:g}: {row}")
    assert row["attributed"] == sensor
    assert 0.0 <= row["declared_after_s"] <= within
    assert 0.0 < row["ended_after_s"] <= ended_within
    assert row["false_alarms"] == 0


def test_a_turn_exposing_an_error_of_a_in_the_cloud_is_no_fault():
    """Seed 84, fault-free: entering the cloud the filter's a is 43 counts per rad/s off, and the
    turn reversal at 183 s exposes it in the consistency residual, whose CUSUM passes its
    threshold; the attribution explains it by the calibration's error and declares nothing."""
    flight = simulate_flight(8000, seed=84)
    estimate = Estimator("kalman").run(flight["ir"], flight["gps_turn_rate"], flight["gps_valid"] > 0.5)
    statistic = np.maximum(estimate["held_up"], estimate["held_down"])
    _, declared = fault_report([], {"ir": estimate["ir_fault"], "gps": estimate["gps_fault"]}, flight["time"])
    peak = float(flight["time"][statistic.argmax()])
    print(f"\nseed 84: consistency statistic {statistic.max():.1f} at {peak:.1f} s "
          f"(threshold {EKFSettings().held_h:g}), {declared} faults declared")
    assert statistic.max() > 2 * EKFSettings().held_h and 180.0 < peak < 190.0
    assert declared == 0


def test_streaming_runs_the_batch_arithmetic_through_a_small_gps_fault():
    """The block's sample-by-sample path declares and ends the GPS +0.1 rad/s fault at the same
    samples as the batch path, with the same state."""
    flight = simulate_flight(8000, seed=1, faults="gps", gps_fault=0.1)
    use = flight["gps_valid"] > 0.5
    window = slice(5400, 6200)  # 270 to 310 s: the fault's onset at 280 s
    estimator = Estimator("kalman")
    batch = estimator.run(flight["ir"], flight["gps_turn_rate"], use)
    estimator.reset()
    streamed = np.array([estimator.update(flight["ir"][k], flight["gps_turn_rate"][k], use[k])[estimator._index]
                         for k in range(window.stop)])
    for j, name in enumerate(estimator.names):
        assert np.array_equal(streamed[window, j], batch[name][window], equal_nan=True), name
    assert episodes(batch["gps_fault"][window], flight["time"][window])[0][0] == pytest.approx(280.4)


def test_consistency_settings_are_checked():
    with pytest.raises(ValueError, match="held_lag"):
        EKFSettings(held_lag=64)
    with pytest.raises(ValueError, match="significance"):
        EKFSettings(significance=0.0)
