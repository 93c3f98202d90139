"""InfraredSensor FMU: coordinated-turn kinematics, the drifting IR reading, the late GPS turn
rate, noise statistics, bad input, and its Modelica twin."""

import math

import numpy as np
import pytest
from quadcosim.fmus.build import table
from quadcosim.fmus.InfraredSensor.variables import GPS_HEADING_NOISE, IR_NOISE
from quadcosim.orchestrator.fmu import FMUError, FMUInstance

OUTPUTS = ["r", "psi", "a", "b", "ir", "gps_turn_rate", "gps_valid"]
RATE = 20.0


def fly(phi, parameters=None, h=1 / RATE):
    """Step the FMU once per sample with the bank angles ``phi``; outputs at each sample."""
    fmu = FMUInstance("InfraredSensor", parameters or {})
    values = np.empty((len(phi), len(OUTPUTS)))
    for k, bank in enumerate(phi):
        fmu.set(["phi"], [bank])
        values[k] = fmu.get(OUTPUTS)
        fmu.step(k * h, h)
    fmu.close()
    return {name: values[:, j] for j, name in enumerate(OUTPUTS)}


def test_coordinated_turn_and_exact_reading_without_noise_or_drift():
    phi = np.radians(np.r_[np.zeros(40), np.full(100, 25.0), np.full(100, -10.0)])
    out = fly(phi, {"noise_enabled": False, "drift_enabled": False, "ir_gain": -400.0, "ir_offset": 990.0})
    r = 9.81 * np.tan(phi) / 12.0
    assert np.allclose(out["r"], r, rtol=1e-15, atol=0)
    assert np.allclose(out["ir"], -400.0 * r + 990.0, rtol=1e-14)
    # heading: the turn rate integrated, a full 25-degree turn is 0.456 rad/s
    assert out["psi"][-1] == pytest.approx(np.sum(r[:-1]) / RATE, rel=1e-12)
    # GPS: mean turn rate over the window [k - 40, k - 20), valid once 40 samples exist
    k = np.arange(40, len(phi))
    expected = np.array([r[j - 40:j - 20].mean() for j in k])
    assert np.all(out["gps_valid"][:40] == 0) and np.all(out["gps_valid"][40:] == 1)
    assert np.allclose(out["gps_turn_rate"][40:], expected, rtol=0, atol=1e-13)
    # a step of the turn rate shows in the GPS one second late and spread over one second
    onset = 40
    late = out["gps_turn_rate"]
    assert np.all(late[onset:onset + 21] == pytest.approx(0.0, abs=1e-14))
    assert late[onset + 40] == pytest.approx(r[onset + 1], rel=1e-12)


def test_drift_follows_time_of_day_temperature_and_cloud():
    tab = {v.name: v.start for v in table("InfraredSensor").of("parameter")}
    out = fly(np.zeros(8000), {"noise_enabled": False})
    t = np.arange(8000) / RATE
    wave = np.sin(2 * np.pi * t / tab["temperature_period"])
    into = t - tab["cloud_start"]
    ramp, full = tab["cloud_ramp"], tab["cloud_duration"]
    cloud = np.where((into <= 0) | (into >= 2 * ramp + full), 0.0,
                     np.where(into < ramp, np.sin(0.5 * np.pi * into / ramp) ** 2,
                              np.where(into <= ramp + full, 1.0,
                                       np.cos(0.5 * np.pi * (into - ramp - full) / ramp) ** 2)))
    a = tab["ir_gain"] * (1 + tab["gain_day_rate"] * t + tab["gain_temperature"] * wave
                          + tab["gain_cloud"] * cloud)
    b = tab["ir_offset"] + tab["offset_day_rate"] * t + tab["offset_temperature"] * wave \
        + tab["offset_cloud"] * cloud
    assert np.allclose(out["a"], a, rtol=1e-12) and np.allclose(out["b"], b, rtol=1e-12)
    assert np.allclose(out["ir"], b, rtol=1e-12)  # straight flight: IR = b


def test_noise_statistics_and_seed():
    phi = np.full(8000, 0.2)
    clean = fly(phi, {"noise_enabled": False})
    noisy = fly(phi, {"seed": 7})
    again = fly(phi, {"seed": 7})
    other = fly(phi, {"seed": 8})
    ir_noise = noisy["ir"] - clean["ir"]
    gps_noise = (noisy["gps_turn_rate"] - clean["gps_turn_rate"])[40:]
    print(f"\nIR noise std {ir_noise.std():.3f} (set {IR_NOISE}), GPS turn-rate noise std {gps_noise.std():.5f} "
          f"(sqrt(2) x {GPS_HEADING_NOISE} = {math.sqrt(2) * GPS_HEADING_NOISE:.5f})")
    # 8000 samples: the standard deviation is known to 1/sqrt(2 n) = 0.8 %
    assert ir_noise.std() == pytest.approx(IR_NOISE, rel=0.03)
    assert abs(ir_noise.mean()) < 3 * IR_NOISE / math.sqrt(8000)
    assert gps_noise.std() == pytest.approx(math.sqrt(2) * GPS_HEADING_NOISE, rel=0.03)
    # the course noise is shared by the differences 20 samples apart: correlation -1/2
    lag = np.corrcoef(gps_noise[20:], gps_noise[:-20])[0, 1]
    assert lag == pytest.approx(-0.5, abs=0.04)
    assert np.array_equal(noisy["ir"], again["ir"]) and not np.array_equal(noisy["ir"], other["ir"])


def test_noise_does_not_depend_on_the_communication_step():
    phi = np.full(400, 0.1)
    coarse = fly(phi, {"seed": 3})
    fmu = FMUInstance("InfraredSensor", {"seed": 3})
    fine = []
    for k in range(400 * 5):
        fmu.set(["phi"], [0.1])
        if k % 5 == 0:
            fine.append(fmu.get(["ir", "gps_turn_rate"]))
        fmu.step(k * 0.01, 0.01)
    fine = np.array(fine)
    assert np.allclose(fine[:, 0], coarse["ir"], rtol=1e-14)
    assert np.allclose(fine[:, 1], coarse["gps_turn_rate"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("parameter, value, words", [
    ("airspeed", 0.0, "airspeed = 0 m/s must be positive"),
    ("airspeed", -12.0, "airspeed = -12 m/s must be positive"),
    ("sample_rate", 0.0, "sample_rate = 0 Hz must be positive"),
    ("gps_delay", 0.33, "whole numbers of sample periods"),
    ("ir_noise", -1.0, "must be non-negative"),
])
def test_bad_parameter_is_an_error_with_a_message(parameter, value, words):
    with pytest.raises(FMUError) as error:
        FMUInstance("InfraredSensor", {parameter: value})
    assert words in str(error.value)


@pytest.mark.parametrize("bank", [math.pi / 2, -math.pi / 2, 2.0])
def test_bank_at_or_beyond_90_degrees_is_an_error(bank):
    fmu = FMUInstance("InfraredSensor", {})
    fmu.step(0.0, 0.05)
    fmu.set(["phi"], [bank])
    with pytest.raises(FMUError) as error:
        fmu.step(0.05, 0.05)
    assert "at or beyond +-pi/2" in str(error.value) and "bank profile" in str(error.value)
    fmu.close()


def test_twin_agrees_with_the_fmu():
    pytest.importorskip("modelica")
    from quadcosim.fmus.twins import simulate_fmu, simulate_twin

    inputs = {"phi": "0.1 + 0.5*sin(1.3*time)"}
    params = {"noise_enabled": False, "cloud_start": 0.4, "cloud_ramp": 0.5, "cloud_duration": 0.6,
              "temperature_period": 1.7, "offset_day_rate": 10.0, "gain_day_rate": 0.014}
    stop, step, every = 3.0, 1e-3, 50
    outputs = OUTPUTS
    times, fmu = simulate_fmu("InfraredSensor", inputs, params, stop, step, outputs)
    grid = times[::every]
    twin = simulate_twin("InfraredSensor", inputs, params, stop, grid)
    worst = {}
    for name in outputs:
        reference = fmu[name][::every]
        scale = max(np.abs(reference).max(), 1e-300)
        worst[name] = np.abs(twin[name] - reference).max() / scale
    name = max(worst, key=worst.get)
    print(f"\nInfraredSensor twin against FMU over {stop:g} s: largest difference {worst[name]:.2g} of the peak "
          f"({name})")
    assert fmu["gps_valid"][-1] == 1.0 and np.ptp(fmu["gps_turn_rate"]) > 0.1
    bad = {k: float(v) for k, v in worst.items() if not v <= 1e-6}
    assert not bad, bad
