"""The attitude arithmetic of the estimators, compiled by numba: quaternions, rotations, Euler
angles, TRIAD, and the small vector helpers of the corrections.

Conventions: ``q = (q0, q1, q2, q3)`` scalar first and Hamilton, ``R(q)`` body to inertial,
row-major. The helpers compiled inline (numba's ``inline="always"``) work on scalars and tuples,
not array views, so that the batch path's inner loop is straight code that allocates nothing.
"""

from __future__ import annotations

import math

from numba import njit
from quadcosim.estimators.layout import EULER, FIELD, GRAVITY, SMALL_ANGLE


@njit(cache=True, error_model="numpy")
def quaternion_multiply(p, q, out):
    """out = p (x) q (Hamilton)."""
    a0, a1, a2, a3 = p[0], p[1], p[2], p[3]
    b0, b1, b2, b3 = q[0], q[1], q[2], q[3]
    out[0] = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    out[1] = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
    out[2] = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
    out[3] = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0


@njit(cache=True, error_model="numpy", inline="always")
def _rotation(q0, q1, q2, q3):
    """R(q) = I + 2 q0 S(qv) + 2 S(qv)^2, row-major, as a 9-tuple."""
    return (1.0 - 2.0 * (q2 * q2 + q3 * q3), 2.0 * (q1 * q2 - q0 * q3), 2.0 * (q1 * q3 + q0 * q2),
            2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q1 * q1 + q3 * q3), 2.0 * (q2 * q3 - q0 * q1),
            2.0 * (q1 * q3 - q0 * q2), 2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2))


@njit(cache=True, error_model="numpy")
def rotation(q, r):
    """r = R(q) = I + 2 q0 S(qv) + 2 S(qv)^2, row-major 3x3."""
    m = _rotation(q[0], q[1], q[2], q[3])
    for i in range(3):
        for j in range(3):
            r[i, j] = m[3 * i + j]


@njit(cache=True, error_model="numpy")
def quaternion_from_rotation(r, q):
    """Unit quaternion (q0 >= 0) of the rotation matrix ``r`` (Shepperd's method)."""
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    if trace >= max(r[0, 0], r[1, 1], r[2, 2]):
        s = 2.0 * math.sqrt(1.0 + trace)
        q[0], q[1], q[2], q[3] = 0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s
    elif r[0, 0] >= r[1, 1] and r[0, 0] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q[0], q[1], q[2], q[3] = (r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s
    elif r[1, 1] >= r[2, 2]:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])
        q[0], q[1], q[2], q[3] = (r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])
        q[0], q[1], q[2], q[3] = (r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s
    if q[0] < 0.0:
        for i in range(4):
            q[i] = -q[i]
    _normalise(q)


@njit(cache=True, error_model="numpy", inline="always")
def _euler(q0, q1, q2, q3):
    """Z-Y-X Euler angles (roll, pitch, yaw) of q, rad."""
    roll = math.atan2(2.0 * (q2 * q3 + q0 * q1), 1.0 - 2.0 * (q1 * q1 + q2 * q2))
    s = 2.0 * (q0 * q2 - q1 * q3)
    pitch = math.asin(min(1.0, max(-1.0, s)))
    return roll, pitch, math.atan2(2.0 * (q1 * q2 + q0 * q3), 1.0 - 2.0 * (q2 * q2 + q3 * q3))


@njit(cache=True, error_model="numpy")
def euler_from_quaternion(q, theta):
    """Z-Y-X Euler angles (roll, pitch, yaw; rad) of the unit quaternion ``q`` (body to inertial,
    scalar first), written into ``theta`` (3,)."""
    theta[0], theta[1], theta[2] = _euler(q[0], q[1], q[2], q[3])


@njit(cache=True, error_model="numpy")
def euler_to_quaternion(roll, pitch, yaw):
    """Quaternion (q0, q1, q2, q3; body to inertial, scalar first) of the Z-Y-X Euler angles
    ``roll``, ``pitch``, ``yaw`` (rad)."""
    c1, s1 = math.cos(0.5 * roll), math.sin(0.5 * roll)
    c2, s2 = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    c3, s3 = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (c3 * c2 * c1 + s3 * s2 * s1, c3 * c2 * s1 - s3 * s2 * c1,
            c3 * s2 * c1 + s3 * c2 * s1, s3 * c2 * c1 - c3 * s2 * s1)


@njit(cache=True, error_model="numpy")
def quaternion_from_euler(theta, q):
    """Write into ``q`` the quaternion of the Z-Y-X Euler angles ``theta`` (rad)."""
    q[0], q[1], q[2], q[3] = euler_to_quaternion(theta[0], theta[1], theta[2])


@njit(cache=True, error_model="numpy")
def wrap(angle):
    """``angle`` (rad) wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True, error_model="numpy")
def _normalise(q):
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for i in range(4):
        q[i] /= n


@njit(cache=True, error_model="numpy", inline="always")
def _norm(v0, v1, v2):
    return math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)


@njit(cache=True, error_model="numpy", inline="always")
def _norm3(v):
    return _norm(v[0], v[1], v[2])


@njit(cache=True, error_model="numpy", inline="always")
def _advance(q0, q1, q2, q3, wx, wy, wz, dt, discretisation):
    """q advanced by the body rate (wx, wy, wz) over dt, then normalised, as a 4-tuple."""
    if discretisation == EULER:
        d0 = 0.5 * (-q1 * wx - q2 * wy - q3 * wz)
        d1 = 0.5 * (q0 * wx + q2 * wz - q3 * wy)
        d2 = 0.5 * (q0 * wy + q3 * wx - q1 * wz)
        d3 = 0.5 * (q0 * wz + q1 * wy - q2 * wx)
        p0, p1, p2, p3 = q0 + dt * d0, q1 + dt * d1, q2 + dt * d2, q3 + dt * d3
    else:
        angle = math.sqrt(wx * wx + wy * wy + wz * wz) * dt
        if angle > SMALL_ANGLE:
            s = math.sin(0.5 * angle) / (angle / dt)
            c = math.cos(0.5 * angle)
        else:
            s, c = 0.5 * dt, 1.0
        e1, e2, e3 = s * wx, s * wy, s * wz
        p0 = q0 * c - q1 * e1 - q2 * e2 - q3 * e3
        p1 = q0 * e1 + q1 * c + q2 * e3 - q3 * e2
        p2 = q0 * e2 - q1 * e3 + q2 * c + q3 * e1
        p3 = q0 * e3 + q1 * e2 - q2 * e1 + q3 * c
    n = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2 + p3 * p3)
    return p0 / n, p1 / n, p2 / n, p3 / n


@njit(cache=True, error_model="numpy")
def _integrate(q, wx, wy, wz, dt, discretisation):
    """Advance q by the body rate (wx, wy, wz) over dt."""
    q[0], q[1], q[2], q[3] = _advance(q[0], q[1], q[2], q[3], wx, wy, wz, dt, discretisation)


@njit(cache=True, error_model="numpy", inline="always")
def _direction(r, vx, vy, vz):
    """R^T (vx, vy, vz) / |.| (``r`` row-major 9-tuple), an inertial direction seen in the body frame."""
    o0 = r[0] * vx + r[3] * vy + r[6] * vz
    o1 = r[1] * vx + r[4] * vy + r[7] * vz
    o2 = r[2] * vx + r[5] * vy + r[8] * vz
    n = _norm(o0, o1, o2)
    return o0 / n, o1 / n, o2 / n


@njit(cache=True, error_model="numpy")
def _body(r, vx, vy, vz, out):
    """out = R^T (vx, vy, vz) / |.|, an inertial direction seen in the body frame."""
    out[0], out[1], out[2] = _direction((r[0, 0], r[0, 1], r[0, 2], r[1, 0], r[1, 1], r[1, 2], r[2, 0], r[2, 1],
                                         r[2, 2]), vx, vy, vz)


@njit(cache=True, error_model="numpy", inline="always")
def _cross(v, norm_v, vhat, gain):
    """gain (v/|v|) x vhat (3-tuples), the correction of one reference direction (vhat unit)."""
    scale = gain / norm_v
    return (scale * (v[1] * vhat[2] - v[2] * vhat[1]), scale * (v[2] * vhat[0] - v[0] * vhat[2]),
            scale * (v[0] * vhat[1] - v[1] * vhat[0]))


@njit(cache=True, error_model="numpy")
def _add_cross(v, norm_v, vhat, gain, w):
    """w += gain (v/|v|) x vhat, the correction of one reference direction (vhat unit)."""
    c = _cross((v[0], v[1], v[2]), norm_v, (vhat[0], vhat[1], vhat[2]), gain)
    for i in range(3):
        w[i] += c[i]


@njit(cache=True, error_model="numpy")
def triad(acc, mag, config, r):
    """Rotation body -> inertial from the accelerometer (primary: gravity) and the magnetometer.

    Inertial triad ``(d_I, d_I x m_I, d_I x (d_I x m_I))`` with ``d_I = g_I/|g_I|``, matched with
    the body triad built the same way from ``d = -acc/|acc|`` and the measured field, so that
    ``R^T d_I = d`` exactly: the magnetometer sets the heading only. False, and ``r`` unset,
    when the measurements or the references give no frame (null or parallel). ``acc`` (m/s^2)
    and ``mag`` (any unit) are body-axis samples, ``config`` the configuration vector (its
    ``gravity`` and ``earth_field`` references, inertial frame); ``r`` (9,) receives R row-major.
    """
    na = _norm3(acc)
    gx, gy, gz = config[GRAVITY], config[GRAVITY + 1], config[GRAVITY + 2]
    ng = math.sqrt(gx * gx + gy * gy + gz * gz)
    if na == 0.0 or ng == 0.0:
        return False
    d0, d1, d2 = -acc[0] / na, -acc[1] / na, -acc[2] / na
    s20, s21, s22 = d1 * mag[2] - d2 * mag[1], d2 * mag[0] - d0 * mag[2], d0 * mag[1] - d1 * mag[0]
    n = math.sqrt(s20 * s20 + s21 * s21 + s22 * s22)
    if n == 0.0:
        return False
    s20, s21, s22 = s20 / n, s21 / n, s22 / n
    s30, s31, s32 = d1 * s22 - d2 * s21, d2 * s20 - d0 * s22, d0 * s21 - d1 * s20
    t10, t11, t12 = gx / ng, gy / ng, gz / ng
    mx, my, mz = config[FIELD], config[FIELD + 1], config[FIELD + 2]
    t20, t21, t22 = t11 * mz - t12 * my, t12 * mx - t10 * mz, t10 * my - t11 * mx
    n = math.sqrt(t20 * t20 + t21 * t21 + t22 * t22)
    if n == 0.0:
        return False
    t20, t21, t22 = t20 / n, t21 / n, t22 / n
    t30, t31, t32 = t11 * t22 - t12 * t21, t12 * t20 - t10 * t22, t10 * t21 - t11 * t20
    # R = t1 d^T + t2 s2^T + t3 s3^T
    r[0, 0] = t10 * d0 + t20 * s20 + t30 * s30
    r[0, 1] = t10 * d1 + t20 * s21 + t30 * s31
    r[0, 2] = t10 * d2 + t20 * s22 + t30 * s32
    r[1, 0] = t11 * d0 + t21 * s20 + t31 * s30
    r[1, 1] = t11 * d1 + t21 * s21 + t31 * s31
    r[1, 2] = t11 * d2 + t21 * s22 + t31 * s32
    r[2, 0] = t12 * d0 + t22 * s20 + t32 * s30
    r[2, 1] = t12 * d1 + t22 * s21 + t32 * s31
    r[2, 2] = t12 * d2 + t22 * s22 + t32 * s32
    return True


@njit(cache=True, error_model="numpy", inline="always")
def _parts(w, vhat, tilt_weight, heading_weight):
    """tilt_weight * (part of w normal to vhat) + heading_weight * (part along vhat), as a 3-tuple."""
    along = w[0] * vhat[0] + w[1] * vhat[1] + w[2] * vhat[2]
    return (tilt_weight * (w[0] - along * vhat[0]) + heading_weight * along * vhat[0],
            tilt_weight * (w[1] - along * vhat[1]) + heading_weight * along * vhat[1],
            tilt_weight * (w[2] - along * vhat[2]) + heading_weight * along * vhat[2])


@njit(cache=True, error_model="numpy")
def _split(w, vhat, tilt_weight, heading_weight):
    """w <- tilt_weight * (part of w normal to vhat) + heading_weight * (part along vhat)."""
    w[0], w[1], w[2] = _parts(w, vhat, tilt_weight, heading_weight)


@njit(cache=True, error_model="numpy", inline="always")
def _asin(s):
    return math.asin(min(1.0, max(-1.0, s)))
