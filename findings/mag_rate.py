"""Finding of the magnetometer's rate ablation: the estimators at 1 kHz and at the held 100 Hz sample.

``python -m quadcosim.studies.mag_rate --noise off`` runs the lab's estimators and flights twice, the
magnetometer at 1 kHz and at its own 100 Hz held, and prints the largest difference of their RMS
errors (:mod:`quadcosim.studies.mag_rate`). Eight ``20`` s ``tp`` runs: no quick subset.
"""

from __future__ import annotations

from findings import finding

COMMAND = "python -m quadcosim.studies.mag_rate --noise off"
TOLERANCE_DEG = 5e-5  # deg: deterministic without noise, printed to 4 decimals


def compute(quick: bool = False) -> list[dict]:
    """The largest difference (deg RMS) without noise; nothing with ``quick``."""
    if quick:
        return []
    import numpy as np
    from quadcosim.studies.mag_rate import DURATION_S, differences

    largest = max(float(np.abs(held - fast).max()) for *_, fast, held in differences(DURATION_S, False))
    return [finding("mag_rate.largest_difference_noiseless_deg", largest, "deg", COMMAND, TOLERANCE_DEG, 4)]
