"""Alignment of an optical reference attitude to the IMU it scores, when the two were not aligned.

A motion-capture system gives the attitude of a marker body in the capture volume's frame. Two
constant rotations then stand between it and what an estimator gives (the IMU's attitude in an
Earth frame):

- on the body side, the IMU's axes against the marker body's: estimated from the angular
  rates, the gyro's against the reference's own (differentiated), by the rotation that best
  maps one onto the other (Wahba's problem, :func:`body_rotation`);
- on the inertial side, the capture frame against the Earth's: its vertical is found from the
  accelerometer, whose specific force averages to "up" over a recording
  (:func:`vertical_rotation`), and the remaining constant heading offset is removed when
  scoring (``align_heading`` of :func:`quadcosim.estimators.estimate`).

Both are fitted on the recording being scored, once and the same for every filter, from the
raw sensors and the reference (never from an estimate), so that no filter is favoured. A
reference already in an Earth frame and the IMU's axes (BROAD) needs none of this.

Quaternions are scalar first, body to inertial (Hamilton).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

MOVING_RATE = 0.5  # rad/s: samples turning faster than this weigh in the body alignment
UP = np.array([0.0, 0.0, 1.0])  # ENU's up


def _rotation(q) -> Rotation:
    q = np.asarray(q, dtype=float)
    return Rotation.from_quat(q[..., [1, 2, 3, 0]])


def _quaternion(r: Rotation) -> np.ndarray:
    q = r.as_quat()[..., [3, 0, 1, 2]]
    return q * np.where(q[..., :1] < 0, -1.0, 1.0)


def resample(time_ref, quat_ref, time) -> np.ndarray:
    """The reference ``quat_ref`` (M, 4) at times ``time_ref`` (s, increasing) interpolated (slerp) at
    ``time`` (N,, s); NaN rows where the reference is missing (NaN) or ``time`` is outside its span."""
    time_ref = np.asarray(time_ref, dtype=float)
    quat_ref = np.asarray(quat_ref, dtype=float)
    valid = np.isfinite(quat_ref).all(axis=1) & (np.linalg.norm(np.nan_to_num(quat_ref), axis=1) > 0)
    out = np.full((len(time), 4), np.nan)
    inside = (time >= time_ref[valid][0]) & (time <= time_ref[valid][-1])
    out[inside] = _quaternion(Slerp(time_ref[valid], _rotation(quat_ref[valid]))(np.asarray(time)[inside]))
    # a gap of the reference (an occluded marker) is not bridged by the interpolation
    gap = np.interp(np.asarray(time)[inside], time_ref, (~valid).astype(float)) > 0
    out[np.flatnonzero(inside)[gap]] = np.nan
    return out


def body_rates(quat, dt: float) -> np.ndarray:
    """Angular rate (N, 3, rad/s, body axes) of the attitude series ``quat`` (N, 4) sampled every
    ``dt`` (s), by central differences; NaN where a neighbour is missing."""
    r = _rotation(np.nan_to_num(quat, nan=0.0) + np.where(np.isfinite(quat).all(axis=1, keepdims=True), 0.0,
                                                                   [1.0, 0.0, 0.0, 0.0]))
    rates = np.full((len(quat), 3), np.nan)
    step = (r[:-2].inv() * r[2:]).as_rotvec() / (2.0 * dt)
    rates[1:-1] = step
    known = np.isfinite(quat).all(axis=1)
    rates[~(np.r_[False, known[:-2] & known[2:], False])] = np.nan
    return rates


def body_rotation(gyro, quat, dt: float) -> np.ndarray:
    """Quaternion ``q_b`` of the IMU's axes in the reference body's: ``quat (x) q_b`` is the IMU's
    attitude. Fitted so that ``R(q_b) gyro`` matches the reference's own body rate (least squares
    over the samples turning faster than :data:`MOVING_RATE`). ``gyro`` (N, 3, rad/s), ``quat``
    (N, 4), ``dt`` (s)."""
    rates = body_rates(quat, dt)
    use = np.isfinite(rates).all(axis=1) & (np.linalg.norm(gyro, axis=1) > MOVING_RATE)
    if use.sum() < 3:
        raise ValueError("too little rotation in the recording to align the IMU's axes with the reference's")
    rotation, _ = Rotation.align_vectors(rates[use], np.asarray(gyro)[use])
    return _quaternion(rotation)


def rate_mismatch(gyro, quat, dt: float) -> float:
    """How far the reference ``quat`` (N, 4, the IMU's attitude) turns otherwise than the gyro
    (N, 3, rad/s) says, sampled every ``dt`` (s): the median of ``|omega_ref - gyro|`` over the
    median of ``|gyro|``, over the samples turning faster than :data:`MOVING_RATE` (0 for a
    perfect match; 1 for no relation)."""
    rates = body_rates(quat, dt)
    use = np.isfinite(rates).all(axis=1) & (np.linalg.norm(gyro, axis=1) > MOVING_RATE)
    if use.sum() < 3:
        return float("inf")
    return float(np.median(np.linalg.norm(rates[use] - gyro[use], axis=1)) /
                 np.median(np.linalg.norm(gyro[use], axis=1)))


def vertical_rotation(acc, quat) -> np.ndarray:
    """Quaternion ``q_e`` turning the reference's inertial frame so that its vertical is ENU's up
    (+z), the smallest such turn: ``q_e (x) quat`` is then in an Earth frame up to a heading.
    The up direction is the mean of the specific force ``acc`` (N, 3, body axes) seen in the
    reference frame through ``quat`` (N, 4, the IMU's attitude in that frame)."""
    known = np.isfinite(quat).all(axis=1)
    up = _rotation(quat[known]).apply(np.asarray(acc)[known]).mean(axis=0)
    rotation, _ = Rotation.align_vectors(UP[None], (up / np.linalg.norm(up))[None])
    return _quaternion(rotation)


def align(gyro, acc, quat, dt: float, body: bool = True, vertical: bool = True) -> np.ndarray:
    """The reference ``quat`` (N, 4) turned into the IMU's attitude in an ENU frame up to a constant
    heading: ``q_e (x) quat (x) q_b`` with :func:`body_rotation` (``body``) and
    :func:`vertical_rotation` (``vertical``), fitted on ``gyro`` (rad/s) and ``acc`` (N, 3, body
    axes) sampled every ``dt`` (s). NaN rows stay NaN."""
    known = np.isfinite(quat).all(axis=1)
    out = np.full_like(np.asarray(quat, dtype=float), np.nan)
    r = _rotation(quat[known])
    if body:
        r = r * _rotation(body_rotation(gyro, quat, dt))
    out[known] = _quaternion(r)
    if vertical:
        out[known] = _quaternion(_rotation(vertical_rotation(acc, out)) * r)
    return out
