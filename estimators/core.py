"""The mathematics of the attitude estimators, written once.

Every function here is compiled by numba and used by both the streaming
``Quaternion_estim`` block (one call per sample) and the batch path (a compiled loop over
samples and gain sets), so the two paths run the same arithmetic.

Conventions: NED/FRD, ``q = (q0, q1, q2, q3)`` scalar first and Hamilton, ``R(q)`` body to
NED. Measurements in the body frame: ``acc`` (m/s^2, specific force), ``gyro`` (rad/s),
``mag`` (T). The input vector ``u`` of an update is ``acc[3], gyro[3], mag[3]`` followed,
for the passive filter fed by the true rotation, by ``R_reel`` row-major ``[9]``.

State ``x``: ``q[0:4]``, gyro bias estimate ``b[4:7]`` (rad/s), Euler angles ``theta[7:10]``
(rad; the linear filter's own state). Output ``y``: ``q_est[4]``, ``theta_est[3]`` (Z-Y-X),
``b_est[3]`` (rad/s), ``omega_est[3] = gyro - b_est`` (rad/s).

Discretisation of the nonlinear filters, chosen by ``config[DISCRETE]``:
- ``EXP`` (0, default): ``q <- q (x) exp(0.5 Omega dt)``, exact for a rate constant over the
  sample, then normalised against round-off;
- ``EULER`` (1): ``q <- q + dt 0.5 q (x) (0, Omega)``, then normalised (Mahony's and the
  ``ahrs`` package's form).
In both the bias is updated first and the new bias is used in ``Omega``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

LINEAR, EXPLICIT, PASSIVE = 0, 1, 2
KINDS = {"linear": LINEAR, "explicit": EXPLICIT, "passive": PASSIVE}
EXP, EULER = 0, 1
REEL, TRIAD = 0, 1
# config vector: gravity (m/s^2), Earth field m_I (T, NED, 3), discretisation, R_y source
G, M_I, DISCRETE, RY = 0, 1, 4, 5
CONFIG_SIZE = 6
STATE_SIZE = 10
OUTPUT_SIZE = 13
WORK_SIZE = 21


@njit(cache=True, error_model="numpy")
def quaternion_multiply(p, q, out):
    """out = p (x) q (Hamilton)."""
    a0, a1, a2, a3 = p[0], p[1], p[2], p[3]
    b0, b1, b2, b3 = q[0], q[1], q[2], q[3]
    out[0] = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    out[1] = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
    out[2] = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
    out[3] = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0


@njit(cache=True, error_model="numpy")
def rotation(q, r):
    """r = R(q) = I + 2 q0 S(qv) + 2 S(qv)^2, row-major 3x3."""
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    r[0, 0] = 1.0 - 2.0 * (q2 * q2 + q3 * q3)
    r[0, 1] = 2.0 * (q1 * q2 - q0 * q3)
    r[0, 2] = 2.0 * (q1 * q3 + q0 * q2)
    r[1, 0] = 2.0 * (q1 * q2 + q0 * q3)
    r[1, 1] = 1.0 - 2.0 * (q1 * q1 + q3 * q3)
    r[1, 2] = 2.0 * (q2 * q3 - q0 * q1)
    r[2, 0] = 2.0 * (q1 * q3 - q0 * q2)
    r[2, 1] = 2.0 * (q2 * q3 + q0 * q1)
    r[2, 2] = 1.0 - 2.0 * (q1 * q1 + q2 * q2)


@njit(cache=True, error_model="numpy")
def euler_from_quaternion(q, theta):
    """Z-Y-X Euler angles (roll, pitch, yaw) of q, rad."""
    q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
    theta[0] = math.atan2(2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2))
    s = 2.0 * (q0 * q2 - q1 * q3)
    theta[1] = math.asin(min(1.0, max(-1.0, s)))
    theta[2] = math.atan2(2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q2 * q2 + q3 * q3))


@njit(cache=True, error_model="numpy")
def euler_to_quaternion(roll, pitch, yaw):
    """Quaternion (q0, q1, q2, q3) of Z-Y-X Euler angles (rad)."""
    c1, s1 = math.cos(0.5 * roll), math.sin(0.5 * roll)
    c2, s2 = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    c3, s3 = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (c3 * c2 * c1 + s3 * s2 * s1, c3 * c2 * s1 - s3 * s2 * c1,
            c3 * s2 * c1 + s3 * c2 * s1, s3 * c2 * c1 - c3 * s2 * s1)


@njit(cache=True, error_model="numpy")
def quaternion_from_euler(theta, q):
    q[0], q[1], q[2], q[3] = euler_to_quaternion(theta[0], theta[1], theta[2])


@njit(cache=True, error_model="numpy")
def wrap(angle):
    """Angle wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True, error_model="numpy")
def _normalise(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for i in range(4):
        q[i] /= n


@njit(cache=True, error_model="numpy")
def _integrate(q, wx, wy, wz, dt, discretisation):
    """Advance q by the body rate (wx, wy, wz) over dt."""
    if discretisation == EULER:
        d0 = 0.5 * (-q[1] * wx - q[2] * wy - q[3] * wz)
        d1 = 0.5 * (q[0] * wx + q[2] * wz - q[3] * wy)
        d2 = 0.5 * (q[0] * wy + q[3] * wx - q[1] * wz)
        d3 = 0.5 * (q[0] * wz + q[1] * wy - q[2] * wx)
        q[0] += dt * d0
        q[1] += dt * d1
        q[2] += dt * d2
        q[3] += dt * d3
    else:
        angle = math.sqrt(wx * wx + wy * wy + wz * wz) * dt
        if angle > 1e-12:
            s = math.sin(0.5 * angle) / (angle / dt)
            c = math.cos(0.5 * angle)
        else:
            s, c = 0.5 * dt, 1.0
        e1, e2, e3 = s * wx, s * wy, s * wz
        q0, q1, q2, q3 = q[0], q[1], q[2], q[3]
        q[0] = q0 * c - q1 * e1 - q2 * e2 - q3 * e3
        q[1] = q0 * e1 + q1 * c + q2 * e3 - q3 * e2
        q[2] = q0 * e2 - q1 * e3 + q2 * c + q3 * e1
        q[3] = q0 * e3 + q1 * e2 - q2 * e1 + q3 * c
    _normalise(q)


@njit(cache=True, error_model="numpy")
def _cross_with_reference(r, v, vx, vy, vz, norm_v, gain, w):
    """w += gain (v/|v|) x (R^T ref/|ref|), the correction of one reference direction."""
    bx = r[0, 0] * vx + r[1, 0] * vy + r[2, 0] * vz
    by = r[0, 1] * vx + r[1, 1] * vy + r[2, 1] * vz
    bz = r[0, 2] * vx + r[1, 2] * vy + r[2, 2] * vz
    scale = gain / (norm_v * math.sqrt(bx * bx + by * by + bz * bz))
    w[0] += scale * (v[1] * bz - v[2] * by)
    w[1] += scale * (v[2] * bx - v[0] * bz)
    w[2] += scale * (v[0] * by - v[1] * bx)


@njit(cache=True, error_model="numpy")
def triad(acc, mag, config, r):
    """Rotation body -> NED from the accelerometer (primary: gravity) and the magnetometer.

    Inertial triad (down, down x m_I, down x (down x m_I)) matched with the body triad built
    the same way from d = -acc/|acc| and the measured field. False, and ``r`` unset, when
    the two measurements give no frame (null or parallel).
    """
    na = math.sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2])
    if na == 0.0:
        return False
    d0, d1, d2 = -acc[0] / na, -acc[1] / na, -acc[2] / na
    # body: s2 = d x mag / |.|, s3 = d x s2
    s20, s21, s22 = d1 * mag[2] - d2 * mag[1], d2 * mag[0] - d0 * mag[2], d0 * mag[1] - d1 * mag[0]
    n = math.sqrt(s20 * s20 + s21 * s21 + s22 * s22)
    if n == 0.0:
        return False
    s20, s21, s22 = s20 / n, s21 / n, s22 / n
    s30, s31, s32 = d1 * s22 - d2 * s21, d2 * s20 - d0 * s22, d0 * s21 - d1 * s20
    # inertial: t1 = e3, t2 = e3 x m_I / |.| = (-m_y, m_x, 0)/|.|, t3 = e3 x t2 = (-t2_y, t2_x, 0)
    mx, my = config[M_I], config[M_I + 1]
    n = math.sqrt(mx * mx + my * my)
    t20, t21 = -my / n, mx / n
    t30, t31 = -t21, t20
    r[0, 0] = t20 * s20 + t30 * s30
    r[0, 1] = t20 * s21 + t30 * s31
    r[0, 2] = t20 * s22 + t30 * s32
    r[1, 0] = t21 * s20 + t31 * s30
    r[1, 1] = t21 * s21 + t31 * s31
    r[1, 2] = t21 * s22 + t31 * s32
    r[2, 0] = d0
    r[2, 1] = d1
    r[2, 2] = d2
    return True


@njit(cache=True, error_model="numpy")
def update(kind, x, u, gains, config, dt, y, work):
    """One estimator step with the sample ``u``; writes the outputs ``y``.

    ``kind`` is LINEAR, EXPLICIT or PASSIVE; ``gains`` in the order of
    :data:`estimators.filters.DEFAULT_GAINS`; ``work`` is a
    scratch array of WORK_SIZE floats owned by the caller, so that nothing is allocated.
    """
    acc, gyro, mag = u[0:3], u[3:6], u[6:9]
    q, b, theta = x[0:4], x[4:7], x[7:10]
    if kind == LINEAR:
        g = config[G]
        # roll and pitch from the accelerometer (small angles), yaw from the tilt-compensated field
        measured1 = -acc[1] / g
        measured2 = acc[0] / g
        c1, s1 = math.cos(theta[0]), math.sin(theta[0])
        c2, s2 = math.cos(theta[1]), math.sin(theta[1])
        level_x = c2 * mag[0] + s2 * s1 * mag[1] + s2 * c1 * mag[2]
        level_y = c1 * mag[1] - s1 * mag[2]
        measured3 = math.atan2(-level_y, level_x)
        theta[0] += dt * (gyro[0] - gains[0] * (theta[0] - measured1))
        theta[1] += dt * (gyro[1] - gains[1] * (theta[1] - measured2))
        theta[2] = wrap(theta[2] + dt * (gyro[2] - gains[2] * wrap(theta[2] - measured3)))
        quaternion_from_euler(theta, q)
    else:
        r = work[0:9].reshape((3, 3))
        w = work[9:12]
        rotation(q, r)
        w[:] = 0.0
        if kind == EXPLICIT:
            # v1 = acc/|acc| against R^T (0, 0, -1); v2 = mag/|mag| against R^T m_I/|m_I|
            # a null measurement (free fall, a dropped sensor) carries no direction: skipped
            na = math.sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2])
            nm = math.sqrt(mag[0] * mag[0] + mag[1] * mag[1] + mag[2] * mag[2])
            if na > 0.0:
                _cross_with_reference(r, acc, 0.0, 0.0, -1.0, na, gains[0], w)
            if nm > 0.0:
                _cross_with_reference(r, mag, config[M_I], config[M_I + 1], config[M_I + 2], nm, gains[1], w)
            kp, ki = gains[2], gains[3]
        else:
            ry = work[12:21].reshape((3, 3))
            usable = True
            if config[RY] == TRIAD:
                usable = triad(acc, mag, config, ry)
            else:
                for i in range(3):
                    for j in range(3):
                        ry[i, j] = u[9 + 3 * i + j]
            # omega = vex(Pa(R^T R_y)): only the antisymmetric part of R^T R_y is needed
            for i, j, k in ((2, 1, 0), (0, 2, 1), (1, 0, 2)):
                if not usable:
                    break
                upper, lower = 0.0, 0.0
                for m in range(3):
                    upper += r[m, i] * ry[m, j]
                    lower += r[m, j] * ry[m, i]
                w[k] = 0.5 * (upper - lower)
            kp, ki = gains[0], gains[1]
        b[0] -= dt * ki * w[0]
        b[1] -= dt * ki * w[1]
        b[2] -= dt * ki * w[2]
        _integrate(q, gyro[0] - b[0] + kp * w[0], gyro[1] - b[1] + kp * w[1], gyro[2] - b[2] + kp * w[2], dt,
                   int(config[DISCRETE]))
        euler_from_quaternion(q, theta)
    for i in range(4):
        y[i] = q[i]
    for i in range(3):
        y[4 + i] = theta[i]
        y[7 + i] = b[i]
        y[10 + i] = gyro[i] - b[i]


@njit(cache=True, error_model="numpy")
def initial_state(q0, b0, x):
    for i in range(4):
        x[i] = q0[i]
    for i in range(3):
        x[4 + i] = b0[i]
    euler_from_quaternion(x[0:4], x[7:10])


@njit(cache=True, parallel=True, error_model="numpy")
def run_batch(kind, inputs, gains, config, dt, q0, b0, outputs):
    """Run ``len(gains)`` filters over the samples ``inputs`` (N, n_u), gain sets in parallel.

    ``gains`` (G, n_gains); ``outputs`` (G, N, OUTPUT_SIZE) is filled in place.
    """
    for g in prange(gains.shape[0]):
        x = np.empty(STATE_SIZE)
        work = np.empty(WORK_SIZE)
        initial_state(q0, b0, x)
        for n in range(inputs.shape[0]):
            update(kind, x, inputs[n], gains[g], config, dt, outputs[g, n], work)
