"""A dummy estimator for the registry test: the gyro integrated alone, no correction. Registered
by one line, ``gyro-only = dummy_estimator:KIND``, in the entry-point group ``quadcosim.estimators``."""

import numpy as np
from quadcosim.estimators.contract import AttitudeEstimator
from quadcosim.estimators.kinds import Kind


class GyroOnly(AttitudeEstimator):
    """The attitude advanced by the gyro's rotation over each sample; no bias estimate."""

    def update(self, acc, gyro, mag):
        half = 0.5 * gyro * self.dt  # rad
        w, x, y, z = self.q
        dw, dx, dy, dz = 1.0, *half
        q = np.array((w * dw - x * dx - y * dy - z * dz, w * dx + x * dw + y * dz - z * dy,
                      w * dy - x * dz + y * dw + z * dx, w * dz + x * dy - y * dx + z * dw))
        self.q = q / np.linalg.norm(q)


# a block of its own, run in closed loops only (no batch path for recorded arrays), compared with the others
KIND = Kind("gyro-only", "gyro only", batch=False, block="dummy_estimator:GyroOnly")
