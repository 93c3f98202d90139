"""The ablations re-run the estimator on the recorded stream: their "recorded" row is the
closed loop's own figure, so that the rows beside it differ by the swapped input alone."""

import numpy as np
from quadcosim.scenarios.ablation import linear_ablation, triad_ablation


def test_linear_ablation_recorded_row_is_the_streaming_row():
    rms = linear_ablation({"flight": "nonstationary", "duration": 4.0})
    assert np.allclose(rms["recorded"], rms["streaming"], rtol=1e-9, atol=1e-12)
    assert not np.allclose(rms["true Euler rates"], rms["recorded"], rtol=0.1)


def test_triad_ablation_recorded_row_is_the_streaming_row():
    """The batch path takes tp's estimator options (corrections off, the lab's gains): the
    recorded accelerometer gives the closed loop's final bias error to round-off."""
    errors = triad_ablation({"flight": "nonstationary", "duration": 4.0})
    assert np.allclose(errors["recorded"], errors["streaming"], rtol=1e-9, atol=1e-12)
    assert not np.allclose(errors["ideal accelerometer"], errors["recorded"], atol=1e-3)
