"""The mathematics of the attitude estimators, written once.

Every function here is compiled by numba and used by both the streaming
``Quaternion_estim`` block (one call per sample) and the batch path (a compiled loop over
samples and gain sets), so the two paths run the same arithmetic.

Conventions: ``q = (q0, q1, q2, q3)`` scalar first and Hamilton, ``R(q)`` body to inertial.
The inertial frame is set by two reference vectors in the configuration: the acceleration
of gravity ``g_I`` (m/s^2; NED: ``(0, 0, 9.81)``) and the Earth field ``m_I`` (T, or any unit
shared with the magnetometer). At rest the accelerometer reads the specific force
``R^T (-g_I)``. Measurements in the body frame: ``acc`` (m/s^2), ``gyro`` (rad/s), ``mag``.

Every layout (inputs, state, outputs, gains, configuration) is declared once below as
``(name, size)`` pairs; the compiled code reads slots by the constants derived from those
names, never by bare positions.

Discretisation of the nonlinear filters, chosen by the configuration's ``discretisation``:
- ``EXP`` (0, default): ``q <- q (x) exp(0.5 Omega dt)``, exact for a rate constant over the
  sample, then normalised against round-off;
- ``EULER`` (1): ``q <- q + dt 0.5 q (x) (0, Omega)``, then normalised (Mahony's and the
  ``ahrs`` package's form).
In both the bias is updated first and the new bias is used in ``Omega``.

Speed: ``update`` and the helpers of its explicit and passive steps are compiled inline
(numba's ``inline="always"``) and work on scalars and tuples, not array views, so that the
batch path's inner loop is straight code that allocates nothing. ``benchmarks/c/batch_explicit.c``
is a C transcription of the explicit step; ``quadcosim bench`` checks that both give the
same estimates to the last bit and prints their speed ratio.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange


def _offsets(layout):
    """{name: (start, stop)} of consecutive slots declared as (name, size) pairs."""
    slots, start = {}, 0
    for name, size in layout:
        slots[name] = (start, start + size)
        start += size
    return slots, start


LINEAR, EXPLICIT, PASSIVE = 0, 1, 2
OBSERVER_CODES = {"linear": LINEAR, "explicit": EXPLICIT, "passive": PASSIVE}
EXP, EULER = 0, 1
REEL, TRIAD = 0, 1

INPUT_LAYOUT = (("acc", 3), ("gyro", 3), ("mag", 3), ("R_reel", 9))
INPUT_SLOTS, INPUT_SIZE = _offsets(INPUT_LAYOUT)
ACC, GYRO, MAG, R_Y = (INPUT_SLOTS[n][0] for n in ("acc", "gyro", "mag", "R_reel"))

CONFIG_LAYOUT = (("gravity", 3), ("earth_field", 3), ("discretisation", 1), ("ry", 1))
CONFIG_SLOTS, CONFIG_SIZE = _offsets(CONFIG_LAYOUT)
GRAVITY, FIELD, DISCRETE, RY = (CONFIG_SLOTS[n][0] for n in ("gravity", "earth_field", "discretisation", "ry"))

# "pending" is 1 until the first sample has set the attitude from TRIAD (initial="triad");
# "started" is 0 until the first sample has set the low-pass filters (rest detector, specific force);
# "acc_filter", "mag_filter": the two delay vectors of the low-passes of specific force and field,
# body coordinates; "field_reference" and "field_candidate": (norm, dip) of the accepted field
# and of the candidate one, "candidate_time" how long the candidate has held (s); "rejection_time" how
# long the magnetometer has been rejected, less twice the time it has been accepted since (s)
STATE_LAYOUT = (("q", 4), ("b", 3), ("theta", 3), ("gyro_lowpass", 3), ("acc_lowpass", 3), ("rest_time", 1),
                ("pending", 1), ("started", 1), ("acc_filter", 6), ("mag_filter", 6), ("field_reference", 2),
                ("field_candidate", 2), ("candidate_time", 1), ("rejection_time", 1))
STATE_SLOTS, STATE_SIZE = _offsets(STATE_LAYOUT)
Q, B, THETA, GYRO_LP, ACC_LP, REST_TIME, PENDING, STARTED, ACC_FILTER, MAG_FILTER = (STATE_SLOTS[n][0] for n in (
    "q", "b", "theta", "gyro_lowpass", "acc_lowpass", "rest_time", "pending", "started", "acc_filter", "mag_filter"))
FIELD_REF, FIELD_CANDIDATE, CANDIDATE_TIME, REJECTION_TIME = (STATE_SLOTS[n][0] for n in (
    "field_reference", "field_candidate", "candidate_time", "rejection_time"))

# weights: accelerometer weight, magnetometer weight (0..1), at rest (0 or 1)
OUTPUT_LAYOUT = (("q", 4), ("theta", 3), ("b", 3), ("omega", 3), ("weights", 3))
OUTPUT_SLOTS, OUTPUT_SIZE = _offsets(OUTPUT_LAYOUT)
OUT_Q, OUT_THETA, OUT_B, OUT_OMEGA, OUT_WEIGHTS = (OUTPUT_SLOTS[n][0] for n in ("q", "theta", "b", "omega", "weights"))

# Gains and correction settings, one vector per gain set; see quadcosim.estimators.filters for meanings.
GAIN_NAMES = ("k1", "k2", "k3", "kP", "kI", "heading_only", "acc_tolerance", "mag_norm_tolerance",
              "mag_dip_tolerance", "rest_gyro", "rest_acc", "rest_time", "rest_gain",
              "acc_lowpass", "mag_lowpass", "mag_reference_time", "bias_clip", "heading_level", "rest_deviation",
              "mag_new_min_gyro", "mag_rejection_time", "correct_at_sample")
GAIN_SLOTS = {name: i for i, name in enumerate(GAIN_NAMES)}
GAIN_SIZE = len(GAIN_NAMES)
K1, K2, K3, KP, KI = (GAIN_SLOTS[n] for n in ("k1", "k2", "k3", "kP", "kI"))
HEADING_ONLY, ACC_TOL, MAG_NORM_TOL, MAG_DIP_TOL = (GAIN_SLOTS[n] for n in (
    "heading_only", "acc_tolerance", "mag_norm_tolerance", "mag_dip_tolerance"))
REST_GYRO, REST_ACC, REST_MIN_TIME, REST_GAIN = (GAIN_SLOTS[n] for n in ("rest_gyro", "rest_acc", "rest_time",
                                                                          "rest_gain"))
ACC_LOWPASS, MAG_LOWPASS, MAG_REF_TIME, BIAS_CLIP = (GAIN_SLOTS[n] for n in ("acc_lowpass", "mag_lowpass",
                                                                             "mag_reference_time", "bias_clip"))
HEADING_LEVEL, REST_DEVIATION, MAG_NEW_MIN_GYRO, MAG_REJECTION_TIME, CORRECT_AT_SAMPLE = (GAIN_SLOTS[n] for n in (
    "heading_level", "rest_deviation", "mag_new_min_gyro", "mag_rejection_time", "correct_at_sample"))

REST_LOWPASS_TAU = 0.5  # s, time constant of the low-pass filters of the rest detector
REJECTION_SLOWDOWN = 0.5  # magnetometer weight once rejected for longer than mag_rejection_time (VQF's factor 2)
REJECTION_RECOVERY = 2.0  # the rejection time runs back this many times faster while the field is accepted (VQF's)
SMALL_ANGLE = 1e-12  # rad: a smaller rotation in one step is integrated to first order (sin x = x)
WORK_LAYOUT = (("R", 9), ("omega", 3), ("R_y", 9), ("v_up", 3), ("v_field", 3), ("scratch", 3), ("acc", 3),
               ("mag", 3))
WORK_SLOTS, WORK_SIZE = _offsets(WORK_LAYOUT)
W_R, W_OMEGA, W_RY, W_UP, W_FIELD, W_SCRATCH, W_ACC, W_MAG = (WORK_SLOTS[n][0] for n in (
    "R", "omega", "R_y", "v_up", "v_field", "scratch", "acc", "mag"))
# error sums of the in-loop reduction, per gain set
ERROR_LAYOUT = (("total2", 1), ("inclination2", 1), ("heading2", 1), ("heading_sin", 1), ("heading_cos", 1),
                ("count", 1))
ERROR_SLOTS, ERROR_SIZE = _offsets(ERROR_LAYOUT)
E_TOTAL, E_INCL, E_HEAD, E_SIN, E_COS, E_COUNT = range(ERROR_SIZE)


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
def _ramp(deviation, tolerance):
    """Weight 1 at no deviation, falling linearly to 0 at ``tolerance``; 1 when tolerance is 0 (off)."""
    if tolerance <= 0.0:
        return 1.0
    return max(0.0, 1.0 - abs(deviation) / tolerance)


@njit(cache=True, error_model="numpy")
def _linear(x, u, gains, config, dt):
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


@njit(cache=True, error_model="numpy", inline="always")
def _rest(x, acc, gyro, gains, g, dt, first):
    """Rest detector on low-passed gyro and accelerometer; True once at rest for ``rest_time``."""
    alpha = dt / (REST_LOWPASS_TAU + dt)
    if first:
        for i in range(3):
            x[GYRO_LP + i], x[ACC_LP + i] = gyro[i], acc[i]
    for i in range(3):
        x[GYRO_LP + i] += alpha * (gyro[i] - x[GYRO_LP + i])
        x[ACC_LP + i] += alpha * (acc[i] - x[ACC_LP + i])
    if gains[REST_GYRO] <= 0.0:
        return False
    if gains[REST_DEVIATION] > 0.0:
        # deviation test (VQF's): each signal stays near its own low-pass, and the low-passed gyro is
        # a bias (within bias_clip), not a slow rotation
        still = (_norm(gyro[0] - x[GYRO_LP], gyro[1] - x[GYRO_LP + 1], gyro[2] - x[GYRO_LP + 2]) < gains[REST_GYRO]
                 and _norm(acc[0] - x[ACC_LP], acc[1] - x[ACC_LP + 1], acc[2] - x[ACC_LP + 2]) < gains[REST_ACC]
                 and (gains[BIAS_CLIP] <= 0.0 or max(abs(x[GYRO_LP]), abs(x[GYRO_LP + 1]), abs(x[GYRO_LP + 2]))
                      <= gains[BIAS_CLIP]))
    else:
        still = (_norm(x[GYRO_LP], x[GYRO_LP + 1], x[GYRO_LP + 2]) < gains[REST_GYRO]
                 and abs(_norm(x[ACC_LP], x[ACC_LP + 1], x[ACC_LP + 2]) - g) < gains[REST_ACC])
    x[REST_TIME] = x[REST_TIME] + dt if still else 0.0
    return x[REST_TIME] >= gains[REST_MIN_TIME]


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
def _rotate_back(v, wx, wy, wz, dt):
    """v <- exp(-S(omega dt)) v: a vector fixed in the inertial frame, seen from the body after it
    turned by ``omega dt`` (Rodrigues)."""
    angle = math.sqrt(wx * wx + wy * wy + wz * wz) * dt
    if angle < SMALL_ANGLE:
        return
    ux, uy, uz = wx * dt / angle, wy * dt / angle, wz * dt / angle
    c, s = math.cos(angle), -math.sin(angle)
    along = (1.0 - c) * (ux * v[0] + uy * v[1] + uz * v[2])
    v0, v1, v2 = v[0], v[1], v[2]
    v[0] = c * v0 + s * (uy * v2 - uz * v1) + along * ux
    v[1] = c * v1 + s * (uz * v0 - ux * v2) + along * uy
    v[2] = c * v2 + s * (ux * v1 - uy * v0) + along * uz


@njit(cache=True, error_model="numpy", inline="always")
def _lowpass_in_gyro_frame(z, v, wx, wy, wz, tau, dt, first):
    """The body-frame measurement ``v`` low-passed in the frame that turns with the corrected gyro (3-tuple).

    A second-order Butterworth low-pass of cut-off ``sqrt(2) / (2 pi tau)`` (the choice of
    VQF, Laidig and Seel, "VQF: highly accurate IMU orientation estimation with bias estimation
    and magnetic disturbance rejection", 2023) whose two delay vectors ``z`` (6) are kept in
    body coordinates and turned with the body by ``omega = gyro - b`` each sample: the filter
    runs in an almost inertial frame, where linear accelerations average out and gravity does not.
    """
    z1, z2 = z[0:3], z[3:6]
    c = math.tan(math.pi * math.sqrt(2.0) / (2.0 * math.pi * tau) * dt)
    d = c * c + math.sqrt(2.0) * c + 1.0
    b0 = c * c / d
    a1, a2 = 2.0 * (c * c - 1.0) / d, (1.0 - math.sqrt(2.0) * c + c * c) / d
    if first:  # steady state of a constant input
        for i in range(3):
            z1[i], z2[i] = (1.0 - b0) * v[i], (b0 - a2) * v[i]
    else:
        _rotate_back(z1, wx, wy, wz, dt)
        _rotate_back(z2, wx, wy, wz, dt)
    out0 = b0 * v[0] + z1[0]
    out1 = b0 * v[1] + z1[1]
    out2 = b0 * v[2] + z1[2]
    for i, out in ((0, out0), (1, out1), (2, out2)):  # transposed direct form II, b1 = 2 b0, b2 = b0
        z1[i] = 2.0 * b0 * v[i] - a1 * out + z2[i]
        z2[i] = b0 * v[i] - a2 * out
    return out0, out1, out2


@njit(cache=True, error_model="numpy", inline="always")
def _field_weight(norm, dip, reference_norm, reference_dip, gains):
    """Magnetometer weight (0..1): ramps on the relative norm and on the dip against the reference."""
    return _ramp(norm / reference_norm - 1.0, gains[MAG_NORM_TOL]) * _ramp(dip - reference_dip, gains[MAG_DIP_TOL])


@njit(cache=True, error_model="numpy", inline="always")
def _track_field(x, norm, dip, gains, dt, first, field, field_dip):
    """Magnetic reference tracking, after VQF (Laidig and Seel, 2023): the reference (norm, dip)
    follows the field slowly while the field agrees with it (weight over 0.5); a candidate
    field that has held its own norm and dip (within the tolerances) for ``mag_reference_time``
    while the reference is rejected becomes the reference. A short disturbance stays rejected,
    a lasting new field (an uncompensated motor field, a room's iron) is accepted instead of
    being rejected for ever. With ``mag_new_min_gyro`` (rad/s) the candidate's time runs only while the
    low-passed gyro norm reaches it (VQF's test)."""
    if first:
        x[FIELD_REF], x[FIELD_REF + 1] = field, field_dip
        x[FIELD_CANDIDATE], x[FIELD_CANDIDATE + 1], x[CANDIDATE_TIME] = norm, dip, 0.0
    span = gains[MAG_REF_TIME]
    k = min(1.0, dt / span)
    accepted = _field_weight(norm, dip, x[FIELD_REF], x[FIELD_REF + 1], gains) > 0.5
    if accepted:
        x[FIELD_REF] += k * (norm - x[FIELD_REF])
        x[FIELD_REF + 1] += k * (dip - x[FIELD_REF + 1])
    if _field_weight(norm, dip, x[FIELD_CANDIDATE], x[FIELD_CANDIDATE + 1], gains) > 0.0:
        x[FIELD_CANDIDATE] += k * (norm - x[FIELD_CANDIDATE])
        x[FIELD_CANDIDATE + 1] += k * (dip - x[FIELD_CANDIDATE + 1])
        # with mag_new_min_gyro, only time spent turning counts: a field that keeps its norm and dip
        # while the body turns is fixed in the inertial frame, one carried by the body is not
        if gains[MAG_NEW_MIN_GYRO] <= 0.0 or (_norm(x[GYRO_LP], x[GYRO_LP + 1], x[GYRO_LP + 2])
                                              >= gains[MAG_NEW_MIN_GYRO]):
            x[CANDIDATE_TIME] += dt
    else:
        x[FIELD_CANDIDATE], x[FIELD_CANDIDATE + 1], x[CANDIDATE_TIME] = norm, dip, 0.0
    if not accepted and x[CANDIDATE_TIME] >= span:
        x[FIELD_REF], x[FIELD_REF + 1] = x[FIELD_CANDIDATE], x[FIELD_CANDIDATE + 1]


@njit(cache=True, error_model="numpy", inline="always")
def _rejection(x, mag_weight, longest, dt):
    """The magnetometer weight after a bounded rejection (after VQF): a field rejected (weight under 0.5)
    for longer than ``longest`` (s) corrects the heading again at :data:`REJECTION_SLOWDOWN` of its weight,
    so that a lasting disturbance bounds the gyro's heading drift; the time spent rejected runs back
    :data:`REJECTION_RECOVERY` times faster while the field is accepted."""
    if mag_weight < 0.5:
        if x[REJECTION_TIME] <= longest:
            x[REJECTION_TIME] += dt
            return mag_weight
        return REJECTION_SLOWDOWN
    x[REJECTION_TIME] = max(0.0, x[REJECTION_TIME] - REJECTION_RECOVERY * dt)
    return mag_weight


@njit(cache=True, error_model="numpy", inline="always")
def _asin(s):
    return math.asin(min(1.0, max(-1.0, s)))


@njit(cache=True, error_model="numpy", inline="always")
def _weights(acc, mag, gains, v_up, v_field, g, field, x, dt, first):
    """Accelerometer and magnetometer weights (0..1) of the disturbance-aware corrections."""
    na, nm = _norm3(acc), _norm3(mag)
    # a null measurement (free fall, a dropped sensor) carries no direction: weight 0
    acc_weight = _ramp(na - g, gains[ACC_TOL]) if na > 0.0 else 0.0
    if nm == 0.0:
        return acc_weight, 0.0
    # dip: angle of the field below the horizontal plane, measured against the estimate's vertical
    sin_dip = -(mag[0] * v_up[0] + mag[1] * v_up[1] + mag[2] * v_up[2]) / nm
    if gains[MAG_REF_TIME] > 0.0:
        field_dip = _asin(-(v_field[0] * v_up[0] + v_field[1] * v_up[1] + v_field[2] * v_up[2]))
        _track_field(x, nm, _asin(sin_dip), gains, dt, first, field, field_dip)
        mag_weight = _field_weight(nm, _asin(sin_dip), x[FIELD_REF], x[FIELD_REF + 1], gains)
    else:
        mag_weight = _ramp(nm / field - 1.0, gains[MAG_NORM_TOL])
        if gains[MAG_DIP_TOL] > 0.0:
            sin_ref = -(v_field[0] * v_up[0] + v_field[1] * v_up[1] + v_field[2] * v_up[2])
            mag_weight *= _ramp(_asin(sin_dip) - _asin(sin_ref), gains[MAG_DIP_TOL])
    if gains[MAG_REJECTION_TIME] > 0.0:
        mag_weight = _rejection(x, mag_weight, gains[MAG_REJECTION_TIME], dt)
    return acc_weight, mag_weight


@njit(cache=True, error_model="numpy", inline="always")
def _explicit_correction(acc, mag, gains, acc_weight, mag_weight, v_up, v_field):
    """sum k_i v_i x vhat_i, weighted, as a 3-tuple; the magnetometer's part kept vertical when heading only."""
    w0, w1, w2 = 0.0, 0.0, 0.0
    if acc_weight > 0.0:
        c = _cross(acc, _norm3(acc), v_up, gains[K1] * acc_weight)
        w0, w1, w2 = w0 + c[0], w1 + c[1], w2 + c[2]
    if mag_weight > 0.0 and gains[HEADING_LEVEL] > 0.0:
        # the sine of the heading error between the horizontal parts of the measured and the predicted
        # field, about the vertical: k2 kP is the heading's rate whatever the dip
        m_up = mag[0] * v_up[0] + mag[1] * v_up[1] + mag[2] * v_up[2]
        f_up = v_field[0] * v_up[0] + v_field[1] * v_up[1] + v_field[2] * v_up[2]
        h = (mag[0] - m_up * v_up[0], mag[1] - m_up * v_up[1], mag[2] - m_up * v_up[2])
        f = (v_field[0] - f_up * v_up[0], v_field[1] - f_up * v_up[1], v_field[2] - f_up * v_up[2])
        norms = _norm(h[0], h[1], h[2]) * _norm(f[0], f[1], f[2])
        if norms > 0.0:
            c = _cross(h, norms, f, gains[K2] * mag_weight)
            w0, w1, w2 = w0 + c[0], w1 + c[1], w2 + c[2]
    elif mag_weight > 0.0:
        c = _cross(mag, _norm3(mag), v_field, gains[K2] * mag_weight)
        if gains[HEADING_ONLY] > 0.0:
            # the magnetometer's correction kept along the vertical: it turns the heading only
            c = _parts((0.0 + c[0], 0.0 + c[1], 0.0 + c[2]), v_up, 0.0, 1.0)
        w0, w1, w2 = w0 + c[0], w1 + c[1], w2 + c[2]
    return w0, w1, w2


@njit(cache=True, error_model="numpy")
def _passive_correction(acc, mag, u, config, gains, acc_weight, mag_weight, r, work, w):
    """w = vex(Pa(R^T R_y)), R_y from R_reel or TRIAD, split into tilt (weight k1) and heading (k2)."""
    v_up = work[W_UP:W_UP + 3]
    ry = work[W_RY:W_RY + 9].reshape((3, 3))
    if config[RY] == TRIAD:
        if not triad(acc, mag, config, ry):
            # no field (a missing magnetometer): the field the estimate predicts, so that R_y
            # carries the accelerometer's tilt and the estimate's own heading
            v_field = work[W_FIELD:W_FIELD + 3]
            _body(r, config[FIELD], config[FIELD + 1], config[FIELD + 2], v_field)
            if not triad(acc, v_field, config, ry):
                return
    else:
        for i in range(3):
            for j in range(3):
                ry[i, j] = u[R_Y + 3 * i + j]
        acc_weight, mag_weight = 1.0, 1.0  # R_reel carries no sensor disturbance
    # only the antisymmetric part of R^T R_y is needed
    for i, j, k in ((2, 1, 0), (0, 2, 1), (1, 0, 2)):
        upper, lower = 0.0, 0.0
        for m in range(3):
            upper += r[m, i] * ry[m, j]
            lower += r[m, j] * ry[m, i]
        w[k] = 0.5 * (upper - lower)
    if gains[HEADING_ONLY] > 0.0:
        # tilt from R_y's vertical alone (the accelerometer for TRIAD), heading from the rest
        along = w[0] * v_up[0] + w[1] * v_up[1] + w[2] * v_up[2]
        v_meas = work[W_SCRATCH:W_SCRATCH + 3]
        _body(ry, -config[GRAVITY], -config[GRAVITY + 1], -config[GRAVITY + 2], v_meas)
        w[:] = 0.0
        _add_cross(v_meas, 1.0, v_up, gains[K1] * acc_weight, w)
        for i in range(3):
            w[i] += gains[K2] * mag_weight * along * v_up[i]
    elif gains[K1] * acc_weight != 1.0 or gains[K2] * mag_weight != 1.0:
        _split(w, v_up, gains[K1] * acc_weight, gains[K2] * mag_weight)


@njit(cache=True, error_model="numpy")
def _passive(acc, mag, u, config, gains, acc_weight, mag_weight, r, v_up, work):
    """The passive filter's correction (3-tuple), through the arrays of ``work``."""
    rm, w = work[W_R:W_R + 9].reshape((3, 3)), work[W_OMEGA:W_OMEGA + 3]
    for i in range(9):
        rm[i // 3, i % 3] = r[i]
    for i in range(3):
        work[W_UP + i], work[W_ACC + i], work[W_MAG + i] = v_up[i], acc[i], mag[i]
    w[:] = 0.0
    _passive_correction(work[W_ACC:W_ACC + 3], work[W_MAG:W_MAG + 3], u, config, gains, acc_weight, mag_weight, rm,
                        work, w)
    return w[0], w[1], w[2]


@njit(cache=True, error_model="numpy", inline="always")
def _complementary(kind, x, u, gains, config, dt, work, y):
    """The explicit or passive filter's step; writes the weights and the rest flag into ``y``.

    Scalars and tuples throughout (no array views): this is the batch path's inner step."""
    acc = (u[ACC], u[ACC + 1], u[ACC + 2])
    gyro = (u[GYRO], u[GYRO + 1], u[GYRO + 2])
    mag = (u[MAG], u[MAG + 1], u[MAG + 2])
    first = x[STARTED] == 0.0
    x[STARTED] = 1.0
    wx, wy, wz = gyro[0] - x[B], gyro[1] - x[B + 1], gyro[2] - x[B + 2]
    filtered, field = acc, mag
    if gains[ACC_LOWPASS] > 0.0:
        filtered = _lowpass_in_gyro_frame(x[ACC_FILTER:ACC_FILTER + 6], acc, wx, wy, wz, gains[ACC_LOWPASS], dt, first)
    if gains[MAG_LOWPASS] > 0.0:
        field = _lowpass_in_gyro_frame(x[MAG_FILTER:MAG_FILTER + 6], mag, wx, wy, wz, gains[MAG_LOWPASS], dt, first)
    r = _rotation(x[Q], x[Q + 1], x[Q + 2], x[Q + 3])
    gx, gy, gz = config[GRAVITY], config[GRAVITY + 1], config[GRAVITY + 2]
    mx, my, mz = config[FIELD], config[FIELD + 1], config[FIELD + 2]
    g = math.sqrt(gx * gx + gy * gy + gz * gz)
    v_up = _direction(r, -gx, -gy, -gz)  # estimated direction of the specific force at rest ("up")
    v_field = _direction(r, mx, my, mz)
    if gains[CORRECT_AT_SAMPLE] > 0.0:
        # corrections and weights against this sample's attitude, the previous one advanced by the gyro:
        # against the previous one, a turn of omega dt reads as an error (1.4 deg at 1.2 rad/s, 50 Hz)
        p = _advance(x[Q], x[Q + 1], x[Q + 2], x[Q + 3], wx, wy, wz, dt, int(config[DISCRETE]))
        r = _rotation(p[0], p[1], p[2], p[3])
        v_up = _direction(r, -gx, -gy, -gz)
        v_field = _direction(r, mx, my, mz)
    acc_weight, mag_weight = _weights(filtered, field, gains, v_up, v_field, g, math.sqrt(mx * mx + my * my + mz * mz),
                                      x, dt, first)
    if kind == EXPLICIT:
        w = _explicit_correction(filtered, field, gains, acc_weight, mag_weight, v_up, v_field)
    else:
        w = _passive(filtered, field, u, config, gains, acc_weight, mag_weight, r, v_up, work)
        if config[RY] != TRIAD:
            acc_weight, mag_weight = 1.0, 1.0
    at_rest = _rest(x, acc, gyro, gains, g, dt, first)
    for i in range(3):
        x[B + i] -= dt * gains[KI] * w[i]
        if at_rest:
            x[B + i] += dt * gains[REST_GAIN] * (gyro[i] - x[B + i])
        if gains[BIAS_CLIP] > 0.0:  # a slow rotation taken for rest, or a disturbance, leaves a bounded bias
            x[B + i] = min(gains[BIAS_CLIP], max(-gains[BIAS_CLIP], x[B + i]))
    kp = gains[KP]
    q = _advance(x[Q], x[Q + 1], x[Q + 2], x[Q + 3], gyro[0] - x[B] + kp * w[0], gyro[1] - x[B + 1] + kp * w[1],
                 gyro[2] - x[B + 2] + kp * w[2], dt, int(config[DISCRETE]))
    theta = _euler(q[0], q[1], q[2], q[3])
    for i in range(4):
        x[Q + i] = q[i]
    for i in range(3):
        x[THETA + i] = theta[i]
    y[OUT_WEIGHTS], y[OUT_WEIGHTS + 1], y[OUT_WEIGHTS + 2] = acc_weight, mag_weight, 1.0 if at_rest else 0.0


@njit(cache=True, error_model="numpy", inline="always")
def update(kind, x, u, gains, config, dt, y, work):
    """One estimator step with the sample ``u``; writes the outputs ``y``.

    ``kind`` is LINEAR, EXPLICIT or PASSIVE; ``x`` the state, ``u`` the sample, ``gains`` the
    gain vector and ``config`` the configuration, each in the layout declared above; ``work``
    is a scratch array of WORK_SIZE floats owned by the caller, so that nothing is allocated.
    ``dt`` (s) is the time since the previous sample.
    """
    if x[PENDING] > 0.0:
        x[PENDING] = 0.0
        # without a field (no magnetometer) the heading is the Earth field's: TRIAD on the configured field
        field = u[MAG:MAG + 3] if _norm3(u[MAG:MAG + 3]) > 0.0 else config[FIELD:FIELD + 3]
        if triad(u[ACC:ACC + 3], field, config, work[W_RY:W_RY + 9].reshape((3, 3))):
            quaternion_from_rotation(work[W_RY:W_RY + 9].reshape((3, 3)), x[Q:Q + 4])
            euler_from_quaternion(x[Q:Q + 4], x[THETA:THETA + 3])
    if kind == LINEAR:
        _linear(x, u, gains, config, dt)
        y[OUT_WEIGHTS], y[OUT_WEIGHTS + 1], y[OUT_WEIGHTS + 2] = 1.0, 1.0, 0.0
    else:
        _complementary(kind, x, u, gains, config, dt, work, y)
    for i in range(4):
        y[OUT_Q + i] = x[Q + i]
    for i in range(3):
        y[OUT_THETA + i] = x[THETA + i]
        y[OUT_B + i] = x[B + i]
        y[OUT_OMEGA + i] = u[GYRO + i] - x[B + i]


@njit(cache=True, error_model="numpy")
def initial_state(q0, b0, from_triad, x):
    """State at the start, written into ``x`` (STATE_LAYOUT): attitude ``q0`` (body to inertial,
    scalar first), or, with ``from_triad``, the TRIAD attitude of the first sample; gyro bias
    ``b0`` (rad/s, body axes)."""
    x[:] = 0.0
    for i in range(4):
        x[Q + i] = q0[i]
    for i in range(3):
        x[B + i] = b0[i]
    x[PENDING] = 1.0 if from_triad else 0.0
    euler_from_quaternion(x[Q:Q + 4], x[THETA:THETA + 3])


@njit(cache=True, error_model="numpy")
def error_angles(q, reference, gravity, heading_offset):
    """Total, inclination and signed heading errors (rad) of ``q`` against ``reference``.

    The error is the rotation ``q (x) reference^-1`` in the inertial frame, first turned by
    ``-heading_offset`` about the vertical (``gravity``'s direction) when the two frames differ
    by a constant heading. Heading is its part about the vertical, inclination the rest
    (the decomposition of the BROAD benchmark, Laidig et al. 2021).
    """
    p0, p1, p2, p3 = reference[0], -reference[1], -reference[2], -reference[3]
    e0 = q[0] * p0 - q[1] * p1 - q[2] * p2 - q[3] * p3
    e1 = q[0] * p1 + q[1] * p0 + q[2] * p3 - q[3] * p2
    e2 = q[0] * p2 - q[1] * p3 + q[2] * p0 + q[3] * p1
    e3 = q[0] * p3 + q[1] * p2 - q[2] * p1 + q[3] * p0
    ng = math.sqrt(gravity[0] ** 2 + gravity[1] ** 2 + gravity[2] ** 2)
    ux, uy, uz = gravity[0] / ng, gravity[1] / ng, gravity[2] / ng
    if heading_offset != 0.0:
        c, s = math.cos(0.5 * heading_offset), -math.sin(0.5 * heading_offset)
        a1, a2, a3 = s * ux, s * uy, s * uz
        e0, e1, e2, e3 = (c * e0 - a1 * e1 - a2 * e2 - a3 * e3, c * e1 + a1 * e0 + a2 * e3 - a3 * e2,
                          c * e2 - a1 * e3 + a2 * e0 + a3 * e1, c * e3 + a1 * e2 - a2 * e1 + a3 * e0)
    if e0 < 0.0:
        e0, e1, e2, e3 = -e0, -e1, -e2, -e3
    vector = math.sqrt(e1 * e1 + e2 * e2 + e3 * e3)
    vertical = e1 * ux + e2 * uy + e3 * uz
    total = 2.0 * math.atan2(vector, e0)
    inclination = 2.0 * math.atan2(math.sqrt(max(0.0, vector * vector - vertical * vertical)),
                                   math.sqrt(e0 * e0 + vertical * vertical))
    heading = 2.0 * math.atan2(vertical, e0)
    return total, inclination, heading


@njit(cache=True, error_model="numpy")
def accumulate_error(q, reference, gravity, heading_offset, sums):
    """Add one sample's squared errors (and heading circular sums) to ``sums`` (ERROR_LAYOUT): the
    estimate ``q`` against ``reference`` (both body to inertial, scalar first), the vertical
    along ``gravity`` (inertial frame), after turning by ``heading_offset`` (rad) about it (see
    :func:`error_angles`)."""
    total, inclination, heading = error_angles(q, reference, gravity, heading_offset)
    sums[E_TOTAL] += total * total
    sums[E_INCL] += inclination * inclination
    sums[E_HEAD] += heading * heading
    sums[E_SIN] += math.sin(heading)
    sums[E_COS] += math.cos(heading)
    sums[E_COUNT] += 1.0


@njit(cache=True, parallel=True, error_model="numpy")
def run_batch(kind, inputs, gains, config, dt, q0, b0, from_triad, columns, outputs, reference, scored,
              heading_offsets, sums):
    """Run ``len(gains)`` filters over the samples ``inputs`` (N, INPUT_SIZE), gain sets in parallel.

    ``gains`` (G, GAIN_SIZE). The outputs listed by ``columns`` (indices into OUTPUT_LAYOUT) are
    written into ``outputs`` (G, N, len(columns)), unless ``outputs`` has no sample axis
    (shape (G, 0, 0)). With a ``reference`` (N, 4), the errors of the samples where
    ``scored`` is true, after removing ``heading_offsets`` (G,), are summed into ``sums``
    (G, ERROR_SIZE): a gain study then keeps no time series at all.
    ``kind`` is LINEAR, EXPLICIT or PASSIVE, ``config`` the configuration vector, ``dt`` (s) the
    sample period; every filter starts from ``q0``/``b0`` (or TRIAD, ``from_triad``) as in
    :func:`initial_state`.
    """
    keep = outputs.shape[1] > 0
    score = reference.shape[0] > 0
    for g in prange(gains.shape[0]):
        x = np.empty(STATE_SIZE)
        work = np.empty(WORK_SIZE)
        y = np.empty(OUTPUT_SIZE)
        initial_state(q0, b0, from_triad, x)
        for n in range(inputs.shape[0]):
            update(kind, x, inputs[n], gains[g], config, dt, y, work)
            if keep:
                for c in range(columns.shape[0]):
                    outputs[g, n, c] = y[columns[c]]
            if score and scored[n]:
                accumulate_error(y[OUT_Q:OUT_Q + 4], reference[n], config[GRAVITY:GRAVITY + 3], heading_offsets[g],
                                 sums[g])


@njit(cache=True, parallel=True, error_model="numpy")
def score_series(q, reference, scored, gravity, heading_offsets, sums):
    """The reduction of :func:`run_batch` on stored estimates ``q`` (G, N, 4): errors against
    ``reference`` (N, 4) over the ``scored`` samples, the vertical along ``gravity``, after the
    ``heading_offsets`` (G,) (rad), summed into ``sums`` (G, ERROR_SIZE)."""
    for g in prange(q.shape[0]):
        for n in range(q.shape[1]):
            if scored[n]:
                accumulate_error(q[g, n], reference[n], gravity, heading_offsets[g], sums[g])
