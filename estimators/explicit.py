"""The lab's ``explicit`` filter, the one recommended for real recordings: its gains, given as time
constants too, its corrections and its compiled correction.

After Mahony, Hamel, Pflimlin, "Nonlinear complementary filters on the special orthogonal group"
(2008, eqs. 32/48; lab section III.1): ``dq = 0.5 q (x) (0, omega_m - b + kP omega_mes)``,
``omega_mes = sum k_i v_i x vhat_i``, ``db = -kI omega_mes``. The directions are normalised: ``v_1 = a_m/|a_m|`` against
``vhat_1 = R^T (-g_I)/|g_I|``, ``v_2 = m_m/|m_m|`` against ``vhat_2 = R^T m_I/|m_I|``.
Gains ``k1, k2`` (1), ``kP`` (1/s), ``kI`` (1/s^2; 0 turns the bias estimate off).
**Gain convention**: ``kP`` multiplies ``k1`` and ``k2``, so Mahony's ``Kp`` (and the
``ahrs`` package's ``k_P``) is ``kP`` with ``k1 = k2 = 1``, and Mahony's ``Ki`` is
``kI`` with ``k1 = k2 = 1``. The lab wrote ``k1 = k2 = 0.2, kP = 1``: an effective
``Kp`` of 0.2 per direction.

Its step is the complementary filters' step of :mod:`quadcosim.estimators.core`, with the
correction :func:`correction`; by default it runs the corrections of :data:`CORRECTIONS`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.estimators.corrections import CORRECTIONS as SETTINGS
from quadcosim.estimators.kinds import Gain, Kind
from quadcosim.estimators.layout import HEADING_ANGLE, HEADING_LEVEL, HEADING_ONLY, K1, K2, SMALL_ANGLE
from quadcosim.estimators.quaternions import _cross, _norm, _norm3, _parts
from quadcosim.fmus import vehicle

#: Its branch of the compiled update (:func:`quadcosim.estimators.core.update`).
CODE = 1
TIME_CONSTANTS = ("tau_inclination", "tau_heading", "tau_bias")
# The recommended filter's defaults: time constants (s), magnetic thresholds (norm in uT at the lab's 47 uT, dip
# in deg) and times (s: the tracked reference's, and the longest rejection), chosen on four public datasets, each
# held out of the search in turn, each also with a 1 deg/s gyro bias (python -m quadcosim.benchmarks.tuning DATA;
# benchmarks/data/tuning_explicit.json).
DEFAULT_TIME_CONSTANTS = {"tau_inclination": 1.0, "tau_heading": 10.0, "tau_bias": 400.0}
DEFAULT_MAG = {"norm_uT": 18.8, "dip_deg": 20.0, "reference_s": 20.0, "rejection_s": 120.0}


def explicit_gains(tau_inclination, tau_heading, tau_bias) -> dict:
    """The explicit filter's gains from its time constants (s; scalars or arrays of gain sets).

    With ``heading_level`` (:mod:`quadcosim.estimators.corrections`), a tilt error decays as
    ``exp(-t / tau_inclination)``, a heading error as ``exp(-t / tau_heading)``, and a constant
    gyro bias is learnt in motion with the time constant ``tau_bias`` (the slow pole of the
    proportional-integral loop, for ``tau_bias >> tau_inclination``): ``k1 = 1``,
    ``kP = 1 / tau_inclination``, ``k2 = tau_inclination / tau_heading`` and
    ``kI = 1 / (tau_inclination tau_bias)`` (``tau_bias = inf``: no bias learnt in motion).
    Each correction, and so the bias it feeds, is weighed by its sensor's weight (the
    disturbance tests): the bias is learnt as fast as the corrections are trusted.
    """
    tau_i, tau_h, tau_b = (np.asarray(v, dtype=float) for v in (tau_inclination, tau_heading, tau_bias))
    if np.any(tau_i <= 0) or np.any(tau_h <= 0) or np.any(tau_b <= 0):
        raise ValueError("the time constants tau_inclination, tau_heading and tau_bias must be positive (s)")
    gains = {"k1": np.ones_like(tau_i), "k2": tau_i / tau_h, "kP": 1.0 / tau_i, "kI": 1.0 / (tau_i * tau_b)}
    return {k: (float(v) if np.ndim(v) == 0 else v) for k, v in gains.items()}


def time_constants(gains: dict) -> dict:
    """The time constants (s) of the explicit filter's gains ``k1, k2, kP, kI`` (the inverse of
    :func:`explicit_gains`; ``tau_bias`` is ``inf`` when ``kI`` is 0)."""
    k1, k2, kp, ki = (float(gains[k]) for k in ("k1", "k2", "kP", "kI"))
    return {"tau_inclination": 1.0 / (k1 * kp), "tau_heading": 1.0 / (k2 * kp),
            "tau_bias": math.inf if ki == 0 else kp / ki}


#: The corrections it runs by default: all, its magnetic reference tracked, the first reference the first field
#: that lasted, a lasting new field adopted turning or not (VQF's rule less its gyro test), the heading corrected
#: by its angle, a field that only changed its norm adopted after 5 s: a reference fixed at the first second rejected
#: the iPhones' clean field, and their magnetometer is calibrated while it records (quadcosim.benchmarks.magnetic,
#: the ablations of real_recordings).
CORRECTIONS = SETTINGS | {
    "mag_reference_time": DEFAULT_MAG["reference_s"], "mag_rejection_time": DEFAULT_MAG["rejection_s"],
    "mag_norm_tolerance": DEFAULT_MAG["norm_uT"] * 1e-6 / vehicle.EARTH_FIELD_NORM,
    "mag_dip_tolerance": math.radians(DEFAULT_MAG["dip_deg"]), "mag_new_min_gyro": 0.0}
_DEFAULTS = explicit_gains(**DEFAULT_TIME_CONSTANTS)
LAB_WEIGHT = 0.2  # the lab report's k1 and k2

KIND = Kind("explicit", "explicit", lab=True, bias=True, rank=1, code=CODE, corrections=CORRECTIONS,
            time_constants=DEFAULT_TIME_CONSTANTS, from_time_constants=explicit_gains, gains={
                "k1": Gain(_DEFAULTS["k1"], "1", "accelerometer weight (Mahony's Kp = kP k1)", lab=LAB_WEIGHT),
                "k2": Gain(_DEFAULTS["k2"], "1", "magnetometer weight", lab=LAB_WEIGHT),
                "kP": Gain(_DEFAULTS["kP"], "1/s", "proportional gain", lab=1.0),
                "kI": Gain(_DEFAULTS["kI"], "1/s^2", "bias gain; 0 turns the bias estimate off", lab=0.0),
            })


@njit(cache=True, error_model="numpy", inline="always")
def correction(acc, mag, gains, acc_weight, mag_weight, v_up, v_field):
    """The explicit filter's correction ``omega_mes = sum k_i v_i x vhat_i`` as a 3-tuple (``kP omega_mes`` in rad/s).

    ``acc`` and ``mag`` are the (low-passed) measurements, body frame; ``gains`` the gain vector
    (:mod:`quadcosim.estimators.layout`); ``acc_weight`` and ``mag_weight`` (0..1) weigh each
    direction; ``v_up`` and ``v_field`` are the unit directions of the specific force at rest and
    of the Earth field the estimate predicts, body frame. The magnetometer's part is kept
    vertical when heading only.
    """
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
            scale = 1.0
            if gains[HEADING_ANGLE] > 0.0:
                # the angle itself, not its sine: a heading error near 180 deg is corrected at full rate
                u = _cross(h, norms, f, 1.0)
                sine = _norm(u[0], u[1], u[2])
                cosine = (h[0] * f[0] + h[1] * f[1] + h[2] * f[2]) / norms
                if sine > SMALL_ANGLE:  # below, the angle is its sine
                    scale = math.atan2(sine, cosine) / sine
            c = _cross(h, norms, f, gains[K2] * mag_weight * scale)
            w0, w1, w2 = w0 + c[0], w1 + c[1], w2 + c[2]
    elif mag_weight > 0.0:
        c = _cross(mag, _norm3(mag), v_field, gains[K2] * mag_weight)
        if gains[HEADING_ONLY] > 0.0:
            # the magnetometer's correction kept along the vertical: it turns the heading only
            c = _parts((0.0 + c[0], 0.0 + c[1], 0.0 + c[2]), v_up, 0.0, 1.0)
        w0, w1, w2 = w0 + c[0], w1 + c[1], w2 + c[2]
    return w0, w1, w2
