"""The disturbance-aware corrections of the lab's complementary filters: their settings, with
units, and their compiled arithmetic (weights, rest detection, low-passes, magnetic reference
tracking), shared by the explicit and the passive filter.

Disturbance-aware corrections (explicit and passive; the passive filter's only with TRIAD),
each switched by its own setting, off when 0. By default each filter runs those of
:data:`quadcosim.estimators.filters.DEFAULT_CORRECTIONS` (each filter's module says which) at the
values of :data:`CORRECTIONS`;
``corrections=False`` turns all off (the lab's filters, as ``tp`` runs them); a dict switches
or tunes each:

``heading_only`` (0 or 1)
    The magnetometer's correction is kept along the estimated vertical, so a magnetic error
    turns the heading and never tilts the estimate. Passive: the tilt correction comes from
    ``R_y``'s vertical alone (the accelerometer, for TRIAD).
``acc_tolerance`` (m/s^2)
    The accelerometer's weight falls linearly from 1 to 0 as ``||a_m| - g|`` grows to this
    value (linear accelerations, vibration).
``mag_norm_tolerance`` (1, relative), ``mag_dip_tolerance`` (rad)
    The magnetometer's weight falls linearly to 0 as ``|m_m|/|m_I| - 1`` or the measured dip
    (against the estimate's vertical) minus the reference dip grows to these values.
``acc_lowpass`` (s), ``mag_lowpass`` (s)
    The accelerometer (and magnetometer) enter the corrections through a second-order
    Butterworth low-pass of time constant ``tau`` (cut-off ``sqrt(2) / (2 pi tau)`` Hz) run in
    the frame that turns with the corrected gyro ``omega_m - b``, an almost inertial frame:
    linear accelerations, which average out there, are filtered while gravity, fixed there,
    is not delayed by the body's rotation (the accelerometer filter of VQF, Laidig and Seel,
    "VQF: highly accurate IMU orientation estimation with bias estimation and magnetic
    disturbance rejection", 2023). The weights above are taken on the filtered vectors.
``mag_reference_time`` (s)
    Magnetic reference tracking (after VQF): the reference norm and dip of the two ramps above
    start at the configured field's, follow the measured field with this time constant while
    it agrees with them (within half the tolerances), and are replaced by a new field that has kept its own norm and dip
    within the tolerances for this long while rejected. A short disturbance (a fault, a magnet
    passed by) stays rejected; a lasting one (an uncompensated motor field) is accepted, so
    the heading keeps its correction. 0: the configured field, for ever.
``bias_clip`` (rad/s)
    Each axis of the bias estimate is kept within this bound (VQF's choice too): a slow
    rotation taken for rest, or a lasting disturbance, cannot leave a bias estimate larger than
    a MEMS gyro's.
``rest_gyro`` (rad/s), ``rest_acc`` (m/s^2), ``rest_time`` (s), ``rest_gain`` (1/s)
    Rest detection: once the low-passed gyro norm stays under ``rest_gyro`` and the low-passed
    specific force within ``rest_acc`` of g for ``rest_time``, the bias follows the gyro,
    ``db = rest_gain (omega_m - b)``.
``rest_deviation`` (0 or 1)
    The rest detector's deviation test (VQF's): rest is the gyro and the specific force each
    staying within ``rest_gyro`` and ``rest_acc`` of their own low-passes (time constant 0.5 s),
    with the low-passed gyro within ``bias_clip`` (a bias, not a slow turn). Without it, the
    low-passes themselves are tested (a slow turn under ``rest_gyro`` passes for rest).
``heading_level`` (0 or 1), explicit filter
    The magnetometer's correction is ``k2 sin(psi)`` about the estimated vertical, ``psi`` the
    angle between the horizontal parts of the measured and the predicted field: a heading
    correction only (it never tilts the estimate), whose rate ``k2 kP`` does not depend on the
    dip. Without it (and with ``heading_only``), the rate is ``k2 kP cos^2(dip)``.
``mag_new_min_gyro`` (rad/s)
    With ``mag_reference_time``: the time a candidate field must hold runs only while the
    low-passed gyro norm reaches this rate. A field that keeps its norm and dip while the body
    turns is fixed in the inertial frame and may become the reference; one carried by the body
    (a magnet on it) changes its dip as the body turns and never does, so the heading is not
    pulled to it (VQF's test).
``correct_at_sample`` (0 or 1)
    The corrections and the weights are taken against the attitude at the sample (the previous
    estimate advanced by the corrected gyro), not the previous estimate: otherwise a turn of
    ``omega dt`` during the sample reads as an error of that size (1.4 deg at 1.2 rad/s and
    50 Hz), which fast time constants turn into an error that grows with the sample period.
``mag_rejection_time`` (s)
    A magnetometer rejected (weight under 0.5) for longer than this corrects the heading again at
    half its weight, so that a lasting disturbance bounds the gyro's heading drift; the time
    spent rejected runs back twice as fast while the field is accepted (VQF's choice).
``mag_new_time`` (s)
    With ``mag_reference_time``: how long a candidate field must hold to replace a rejected
    reference (VQF's ``magNewTime``); 0: ``mag_reference_time``.
``mag_first_time`` (s)
    With ``mag_reference_time``: the configured field is not the reference; the first field that
    keeps its own norm and dip for this long is (VQF's ``magNewFirstTime``), and until then the
    magnetometer corrects the heading at half its weight. A magnetometer whose first seconds are
    not yet calibrated (a phone's) or read while the attitude is still converging gives no
    reference.
``mag_scale_time`` (s)
    With ``mag_reference_time``: a candidate field whose dip agrees with the rejected reference's
    (within half ``mag_dip_tolerance``: only its norm moved, as when a phone recalibrates its
    magnetometer's scale while recording) replaces the reference after this long instead of
    ``mag_new_time``.
``heading_angle`` (0 or 1), explicit filter with ``heading_level``
    The heading correction is ``k2 psi``, the angle itself, not ``k2 sin(psi)``: an error near
    180 deg (a first heading taken from a magnetometer not yet calibrated) is corrected at full
    rate instead of lingering where the sine vanishes (VQF corrects by the angle too).

"""

from __future__ import annotations

import math

from numba import njit
from quadcosim.estimators.layout import (
    ACC_LP,
    ACC_TOL,
    BIAS_CLIP,
    CANDIDATE_TIME,
    FIELD_CANDIDATE,
    FIELD_REF,
    GYRO_LP,
    MAG_DIP_TOL,
    MAG_FIRST_TIME,
    MAG_NEW_MIN_GYRO,
    MAG_NEW_TIME,
    MAG_NORM_TOL,
    MAG_REF_TIME,
    MAG_REJECTION_TIME,
    MAG_SCALE_TIME,
    REJECTION_RECOVERY,
    REJECTION_SLOWDOWN,
    REJECTION_TIME,
    REST_ACC,
    REST_DEVIATION,
    REST_GYRO,
    REST_LOWPASS_TAU,
    REST_MIN_TIME,
    REST_TIME,
    SMALL_ANGLE,
)
from quadcosim.estimators.quaternions import _asin, _norm, _norm3

#: Every correction setting, at the value it takes when switched on (units in the comments; 0 is off).
CORRECTIONS = {
    "heading_only": 1.0,
    "acc_tolerance": 2.0,  # m/s^2
    "mag_norm_tolerance": 0.2,  # 1, relative to |m_I|
    "mag_dip_tolerance": math.radians(20.0),  # rad
    "rest_gyro": math.radians(2.0),  # rad/s
    "rest_acc": 0.5,  # m/s^2
    "rest_time": 1.5,  # s
    "rest_gain": 0.1,  # 1/s
    "acc_lowpass": 1.0,  # s
    "mag_lowpass": 1.0,  # s
    "mag_reference_time": 2.0,  # s
    "bias_clip": math.radians(2.0),  # rad/s
    "heading_level": 1.0,
    "rest_deviation": 1.0,
    "mag_new_min_gyro": math.radians(20.0),  # rad/s
    "mag_rejection_time": 60.0,  # s
    "correct_at_sample": 1.0,
    "mag_new_time": 20.0,  # s
    "mag_first_time": 5.0,  # s
    "heading_angle": 1.0,
    "mag_scale_time": 5.0,  # s
}
CORRECTIONS_OFF = dict.fromkeys(CORRECTIONS, 0.0)
#: The corrections added for the explicit filter after the passive filter was tuned (off in the passive filter's
#: defaults).
NEW_FOR_EXPLICIT = ("heading_level", "rest_deviation", "mag_new_min_gyro", "mag_rejection_time",
                    "correct_at_sample", "mag_new_time", "mag_first_time", "heading_angle", "mag_scale_time")


def chosen(corrections, defaults: dict | None) -> dict:
    """The correction settings in force: ``corrections`` as :func:`quadcosim.estimators.filters.check_gains`
    takes them (None or True: the filter's ``defaults``; False: all off; a dict: those given on, the
    others off)."""
    if corrections is False:
        return dict(CORRECTIONS_OFF)
    if corrections is None or corrections is True:
        return dict(CORRECTIONS if defaults is None else defaults)
    if not isinstance(corrections, dict):
        raise ValueError(f"corrections={corrections!r}: give True, False or a dict of {', '.join(CORRECTIONS)}")
    settings = dict(CORRECTIONS_OFF)
    for name, value in corrections.items():
        if name not in CORRECTIONS:
            raise ValueError(f"unknown correction {name!r}; the corrections are {', '.join(CORRECTIONS)}")
        if value is True and name.startswith("rest_"):
            settings |= {k: v for k, v in CORRECTIONS.items() if k.startswith("rest_")}
        else:
            settings[name] = CORRECTIONS[name] if value is True else float(value)
    return settings


def parse_corrections(text: str):
    """Corrections from text: ``"on"`` (all), ``"off"``, or comma-separated names of :data:`CORRECTIONS`,
    each optionally ``name=value`` (``"heading_only,mag_norm_tolerance=0.3"``); for command lines."""
    text = str(text).strip().lower()
    if text in ("on", "true", "1", "yes"):
        return True
    if text in ("off", "false", "0", "no", ""):
        return False
    settings = {}
    for item in text.split(","):
        name, _, value = item.strip().partition("=")
        settings[name] = float(value) if value else True
    chosen(settings, None)  # refuses unknown names here, before a run
    return settings


@njit(cache=True, error_model="numpy", inline="always")
def _ramp(deviation, tolerance):
    """Weight 1 at no deviation, falling linearly to 0 at ``tolerance``; 1 when tolerance is 0 (off)."""
    if tolerance <= 0.0:
        return 1.0
    return max(0.0, 1.0 - abs(deviation) / tolerance)


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
    field that has held its own norm and dip (within the tolerances) for ``mag_new_time`` (or
    ``mag_reference_time``) while the reference is rejected becomes the reference. A short
    disturbance stays rejected, a lasting new field (an uncompensated motor field, a room's iron)
    is accepted instead of being rejected for ever. With ``mag_new_min_gyro`` (rad/s) the
    candidate's time runs only while the low-passed gyro norm reaches it (VQF's test). With
    ``mag_first_time`` the reference starts unset (norm 0) and is the first candidate that held
    that long."""
    if first:
        unset = gains[MAG_FIRST_TIME] > 0.0
        x[FIELD_REF], x[FIELD_REF + 1] = (0.0, 0.0) if unset else (field, field_dip)
        x[FIELD_CANDIDATE], x[FIELD_CANDIDATE + 1], x[CANDIDATE_TIME] = norm, dip, 0.0
    span = gains[MAG_REF_TIME]
    k = min(1.0, dt / span)
    unset = x[FIELD_REF] <= 0.0
    accepted = not unset and _field_weight(norm, dip, x[FIELD_REF], x[FIELD_REF + 1], gains) > 0.5
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
    if accepted:  # the candidate replaces a rejected (or unset) reference only
        return
    if unset:
        needed = gains[MAG_FIRST_TIME]
    else:
        needed = gains[MAG_NEW_TIME] if gains[MAG_NEW_TIME] > 0.0 else span
        if gains[MAG_SCALE_TIME] > 0.0 and _ramp(x[FIELD_CANDIDATE + 1] - x[FIELD_REF + 1], gains[MAG_DIP_TOL]) > 0.5:
            # the candidate keeps the reference's dip: only the norm moved, a magnetometer's scale recalibrated
            needed = min(needed, gains[MAG_SCALE_TIME])
    if x[CANDIDATE_TIME] >= needed:
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
        if x[FIELD_REF] <= 0.0:  # no reference yet (mag_first_time): half weight, as after a bounded rejection
            return acc_weight, REJECTION_SLOWDOWN
        mag_weight = _field_weight(nm, _asin(sin_dip), x[FIELD_REF], x[FIELD_REF + 1], gains)
    else:
        mag_weight = _ramp(nm / field - 1.0, gains[MAG_NORM_TOL])
        if gains[MAG_DIP_TOL] > 0.0:
            sin_ref = -(v_field[0] * v_up[0] + v_field[1] * v_up[1] + v_field[2] * v_up[2])
            mag_weight *= _ramp(_asin(sin_dip) - _asin(sin_ref), gains[MAG_DIP_TOL])
    if gains[MAG_REJECTION_TIME] > 0.0:
        mag_weight = _rejection(x, mag_weight, gains[MAG_REJECTION_TIME], dt)
    return acc_weight, mag_weight
