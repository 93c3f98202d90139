"""The compiled update of the lab's filters, and the batch loop over samples and gain sets.

Every function here is compiled by numba and used by both the streaming ``Quaternion_estim``
block (one call per sample) and the batch path (a compiled loop over samples and gain sets), so
the two paths run the same arithmetic. :func:`update` runs the filter of a code: the linear
filter's own step (:mod:`quadcosim.estimators.linear`), or the complementary filters' step with
the correction of the explicit (:mod:`quadcosim.estimators.explicit`) or the passive filter
(:mod:`quadcosim.estimators.passive`), weighed by the disturbance-aware corrections of
:mod:`quadcosim.estimators.corrections`. numba compiles each with the functions it calls from
those modules; the layouts of its vectors are :mod:`quadcosim.estimators.layout`'s.

Conventions: ``q = (q0, q1, q2, q3)`` scalar first and Hamilton, ``R(q)`` body to inertial.
The inertial frame is set by two reference vectors in the configuration: the acceleration
of gravity ``g_I`` (m/s^2; NED: ``(0, 0, 9.81)``) and the Earth field ``m_I`` (T, or any unit
shared with the magnetometer). At rest the accelerometer reads the specific force
``R^T (-g_I)``. Measurements in the body frame: ``acc`` (m/s^2), ``gyro`` (rad/s), ``mag``.

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
from quadcosim.estimators import corrections, explicit, layout, linear, passive, quaternions
from quadcosim.estimators.corrections import _lowpass_in_gyro_frame, _rest, _weights
from quadcosim.estimators.explicit import correction as explicit_correction
from quadcosim.estimators.layout import (
    ACC,
    ACC_FILTER,
    ACC_LOWPASS,
    BIAS_CLIP,
    CORRECT_AT_SAMPLE,
    DISCRETE,
    E_COS,
    E_COUNT,
    E_HEAD,
    E_INCL,
    E_SIN,
    E_TOTAL,
    FIELD,
    GRAVITY,
    GYRO,
    KI,
    KP,
    MAG,
    MAG_FILTER,
    MAG_LOWPASS,
    OUT_B,
    OUT_OMEGA,
    OUT_Q,
    OUT_THETA,
    OUT_WEIGHTS,
    OUTPUT_SIZE,
    PENDING,
    REST_GAIN,
    RY,
    STARTED,
    STATE_SIZE,
    THETA,
    TRIAD,
    W_RY,
    WORK_SIZE,
    B,
    Q,
)
from quadcosim.estimators.linear import step as linear_step
from quadcosim.estimators.passive import correction as passive_correction
from quadcosim.estimators.quaternions import (
    _advance,
    _direction,
    _euler,
    _norm3,
    _rotation,
    euler_from_quaternion,
    quaternion_from_rotation,
    triad,
)

LINEAR, EXPLICIT, PASSIVE = linear.CODE, explicit.CODE, passive.CODE
#: The filters :func:`update` runs, name -> :class:`quadcosim.estimators.kinds.Kind` (its ``code`` selects its branch).
COMPILED = {member.KIND.name: member.KIND for member in (linear, explicit, passive)}
assert all(kind.code is not None for kind in COMPILED.values())
#: The modules :func:`update` is compiled from (a compiled step holds their fingerprint in its cache key).
SOURCES = (layout, quaternions, corrections, linear, explicit, passive)


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
        w = explicit_correction(filtered, field, gains, acc_weight, mag_weight, v_up, v_field)
    else:
        w = passive_correction(filtered, field, u, config, gains, acc_weight, mag_weight, r, v_up, work)
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
        linear_step(x, u, gains, config, dt)
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
