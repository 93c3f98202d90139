"""The lab's ``linear`` filter (lab report, section II): its gains and its compiled step.

Per axis, ``dtheta_i = omega_m,i - k_i (theta_i - theta_i,meas)`` with
``theta1,meas = -a_m,y / g``, ``theta2,meas = a_m,x / g`` and the yaw of the magnetometer after
removing the estimated roll and pitch, ``theta3,meas = atan2(-m_level,y, m_level,x)`` (the lab's
``-m_y / m_I,1`` for small angles). Gains ``k1, k2, k3`` (1/s). Explicit Euler. No bias estimate,
no disturbance-aware corrections. NED only (gravity along +z).
"""

from __future__ import annotations

import math

from numba import njit
from quadcosim.estimators.kinds import Gain, Kind
from quadcosim.estimators.layout import ACC, GRAVITY, GYRO, K1, K2, K3, MAG, THETA, Q
from quadcosim.estimators.quaternions import quaternion_from_euler, wrap

#: Its branch of the compiled update (:func:`quadcosim.estimators.core.update`).
CODE = 0
GAIN = 0.05  # 1/s, the lab report's gain of each axis

KIND = Kind("linear", "linear", lab=True, rank=0, code=CODE, ned_only=True, gains={
    "k1": Gain(GAIN, "1/s", "roll gain"),
    "k2": Gain(GAIN, "1/s", "pitch gain"),
    "k3": Gain(GAIN, "1/s", "yaw gain"),
})


@njit(cache=True, error_model="numpy")
def step(x, u, gains, config, dt):
    """One step of the linear filter: the Euler angles of the state ``x`` advanced over ``dt`` (s) by the
    sample ``u`` with the gain vector ``gains`` and the configuration ``config`` (its gravity), and
    its quaternion (the layouts of :mod:`quadcosim.estimators.layout`)."""
    g = math.sqrt(config[GRAVITY] ** 2 + config[GRAVITY + 1] ** 2 + config[GRAVITY + 2] ** 2)
    acc, gyro, mag = u[ACC:ACC + 3], u[GYRO:GYRO + 3], u[MAG:MAG + 3]
    theta = x[THETA:THETA + 3]
    # roll and pitch from the accelerometer (small angles), yaw from the tilt-compensated field
    measured1 = -acc[1] / g
    measured2 = acc[0] / g
    c1, s1 = math.cos(theta[0]), math.sin(theta[0])
    c2, s2 = math.cos(theta[1]), math.sin(theta[1])
    level_x = c2 * mag[0] + s2 * s1 * mag[1] + s2 * c1 * mag[2]
    level_y = c1 * mag[1] - s1 * mag[2]
    measured3 = math.atan2(-level_y, level_x)
    theta[0] += dt * (gyro[0] - gains[K1] * (theta[0] - measured1))
    theta[1] += dt * (gyro[1] - gains[K2] * (theta[1] - measured2))
    theta[2] = wrap(theta[2] + dt * (gyro[2] - gains[K3] * wrap(theta[2] - measured3)))
    quaternion_from_euler(theta, x[Q:Q + 4])
