"""The lab's ``passive`` filter: its gains, its corrections and its compiled correction.

After Mahony, Hamel, Pflimlin, "Nonlinear complementary filters on the special orthogonal group"
(2008, eqs. 13/47; lab section III.2): ``dR = R S(omega_m - b + kP omega)``, ``db = -kI omega``,
``omega = vex(Pa(R^T R_y))``, with ``R_y`` the true rotation ``R_reel`` of the IMU (``ry="reel"``,
as the lab did) or the TRIAD rotation of accelerometer and magnetometer (``ry="triad"``). Gains
``kP`` (1/s) and ``kI`` (1/s^2); ``k1`` and ``k2`` (1) weigh the tilt part of ``omega`` (normal to
the estimated vertical) and its heading part (along it): 1 and 1 are the lab's filter.

Its step is the complementary filters' step of :mod:`quadcosim.estimators.core`, with the
correction :func:`correction`; its disturbance-aware corrections act with TRIAD only.
"""

from __future__ import annotations

from numba import njit
from quadcosim.estimators.corrections import CORRECTIONS as SETTINGS
from quadcosim.estimators.corrections import NEW_FOR_EXPLICIT
from quadcosim.estimators.kinds import Gain, Kind
from quadcosim.estimators.layout import (
    FIELD,
    GRAVITY,
    HEADING_ONLY,
    K1,
    K2,
    R_Y,
    RY,
    TRIAD,
    W_ACC,
    W_FIELD,
    W_MAG,
    W_OMEGA,
    W_R,
    W_RY,
    W_SCRATCH,
    W_UP,
)
from quadcosim.estimators.quaternions import _add_cross, _body, _split, triad

#: Its branch of the compiled update (:func:`quadcosim.estimators.core.update`).
CODE = 2
#: The corrections it runs by default: those it was tuned with.
CORRECTIONS = SETTINGS | dict.fromkeys(NEW_FOR_EXPLICIT, 0.0)

# Its gains on recordings: chosen on three public datasets by a cross-validation over a grid of kP, kI, k2 and
# the rest gain, with its CORRECTIONS; not re-tuned since the explicit filter became the recommended one.
KIND = Kind("passive", "passive", lab=True, bias=True, rank=2, code=CODE, corrections=CORRECTIONS, reads_reel=True,
            compared={"ry": "triad"}, gains={
                "k1": Gain(1.0, "1", "weight of the tilt part of the correction", lab=1.0),
                "k2": Gain(0.1, "1", "weight of the heading part of the correction", lab=1.0),
                "kP": Gain(0.25, "1/s", "proportional gain", lab=1.0),
                "kI": Gain(0.0003, "1/s^2", "bias gain; 0 turns the bias estimate off", lab=1.0),
            })


@njit(cache=True, error_model="numpy")
def _correction(acc, mag, u, config, gains, acc_weight, mag_weight, r, work, w):
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
def correction(acc, mag, u, config, gains, acc_weight, mag_weight, r, v_up, work):
    """The passive filter's correction (3-tuple), through the scratch arrays of ``work``.

    ``acc`` and ``mag`` are the (low-passed) measurements, body frame; ``u`` the sample (its
    ``R_reel``); ``config`` the configuration and ``gains`` the gain vector
    (:mod:`quadcosim.estimators.layout`); ``acc_weight`` and ``mag_weight`` (0..1) weigh the tilt
    and heading parts; ``r`` is the estimate's rotation (9-tuple, row-major) and ``v_up`` its
    vertical, body frame.
    """
    rm, w = work[W_R:W_R + 9].reshape((3, 3)), work[W_OMEGA:W_OMEGA + 3]
    for i in range(9):
        rm[i // 3, i % 3] = r[i]
    for i in range(3):
        work[W_UP + i], work[W_ACC + i], work[W_MAG + i] = v_up[i], acc[i], mag[i]
    w[:] = 0.0
    _correction(work[W_ACC:W_ACC + 3], work[W_MAG:W_MAG + 3], u, config, gains, acc_weight, mag_weight, rm,
                        work, w)
    return w[0], w[1], w[2]
