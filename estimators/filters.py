"""Attitude estimators as a streaming block and as a function on recorded arrays.

Both call the compiled update of :mod:`quadcosim.estimators.core`, so the block and the batch path
compute the same numbers. Three filters of the lab, and two published ones for comparison
(:mod:`quadcosim.estimators.reference`: ``vqf``, ``madgwick``).

``linear`` (lab report, section II)
    Per axis, ``dtheta_i = omega_m,i - k_i (theta_i - theta_i,meas)`` with
    ``theta1,meas = -a_m,y / g``, ``theta2,meas = a_m,x / g`` and the yaw of the
    magnetometer after removing the estimated roll and pitch,
    ``theta3,meas = atan2(-m_level,y, m_level,x)`` (the lab's ``-m_y / m_I,1`` for small
    angles). Gains ``k1, k2, k3`` (1/s). Explicit Euler. No bias estimate. NED only (gravity
    along +z).
``explicit`` (Mahony, Hamel, Pflimlin, "Nonlinear complementary filters on the special
orthogonal group", 2008, eqs. 32/48; lab section III.1)
    ``dq = 0.5 q (x) (0, omega_m - b + kP omega_mes)``, ``omega_mes = sum k_i v_i x vhat_i``,
    ``db = -kI omega_mes``. The directions are normalised: ``v_1 = a_m/|a_m|`` against
    ``vhat_1 = R^T (-g_I)/|g_I|``, ``v_2 = m_m/|m_m|`` against ``vhat_2 = R^T m_I/|m_I|``.
    Gains ``k1, k2`` (1), ``kP`` (1/s), ``kI`` (1/s^2; 0 turns the bias estimate off).
    **Gain convention**: ``kP`` multiplies ``k1`` and ``k2``, so Mahony's ``Kp`` (and the
    ``ahrs`` package's ``k_P``) is ``kP`` with ``k1 = k2 = 1``, and Mahony's ``Ki`` is
    ``kI`` with ``k1 = k2 = 1``. The lab wrote ``k1 = k2 = 0.2, kP = 1``: an effective
    ``Kp`` of 0.2 per direction.
``passive`` (Mahony 2008, eqs. 13/47; lab section III.2)
    ``dR = R S(omega_m - b + kP omega)``, ``db = -kI omega``, ``omega = vex(Pa(R^T R_y))``,
    with ``R_y`` the true rotation ``R_reel`` of the IMU (``ry="reel"``, as the lab did) or
    the TRIAD rotation of accelerometer and magnetometer (``ry="triad"``). Gains ``kP``
    (1/s) and ``kI`` (1/s^2); ``k1`` and ``k2`` (1) weigh the tilt part of ``omega`` (normal
    to the estimated vertical) and its heading part (along it): 1 and 1 are the lab's filter.

Disturbance-aware corrections (explicit and passive; the passive filter's only with TRIAD),
each switched by its own setting, off when 0. By default each filter runs those of
:data:`DEFAULT_CORRECTIONS` (the explicit filter all but the magnetic reference tracking, the
passive filter those it was tuned with) at the values of :data:`CORRECTIONS`;
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

The outputs ``weights`` are the accelerometer and magnetometer weights in use and the rest flag.

References: ``gravity`` (m/s^2, the acceleration of gravity in the inertial frame, NED by
default, or its magnitude along +z) and the Earth field ``earth_field`` (T, inertial frame),
or ``dip`` and ``declination`` (rad) with ``field_norm`` (T). Any right-handed inertial frame
works (ENU: ``gravity=(0, 0, -9.81)``); default: the lab's (Paris, 65 deg dip, no declination).

Initial state: ``q0`` (default identity) or ``initial="triad"`` (the TRIAD attitude of the
first sample; the batch path also takes a function ``(gyro, acc, mag) -> q0``), and ``b0``
(rad/s, default zero).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from quadcosim.estimators import core
from quadcosim.estimators.checks import check_finite, check_measurements, check_stability
from quadcosim.fmus import vehicle
from quadcosim.orchestrator.blocks import Block

FILTERS = tuple(core.OBSERVER_CODES)
RECOMMENDED = "explicit"  # the lab's filter recommended for real recordings, at DEFAULT_GAINS
RECORDED = "vqf"  # estimate()'s default: RECOMMENDED loses to it out of sample
# (quadcosim.benchmarks.tuning --score-folds)
TIME_CONSTANTS = ("tau_inclination", "tau_heading", "tau_bias")
# The recommended filter's defaults: time constants (s), magnetic thresholds (norm in uT at the lab's 47 uT, dip
# in deg) and times (s: the tracked reference's, and the longest rejection), chosen on four public datasets, each
# held out of the search in turn (python -m quadcosim.benchmarks.tuning DATA; benchmarks/data/tuning_explicit.json).
DEFAULT_TIME_CONSTANTS = {"tau_inclination": 1.0, "tau_heading": 5.0, "tau_bias": 100.0}
DEFAULT_MAG = {"norm_uT": 9.4, "dip_deg": 20.0, "reference_s": 10.0, "rejection_s": 120.0}


def explicit_gains(tau_inclination, tau_heading, tau_bias) -> dict:
    """The explicit filter's gains from its time constants (s; scalars or arrays of gain sets).

    With ``heading_level`` (see the module docstring), a tilt error decays as
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


DEFAULT_GAINS = {
    "linear": {"k1": 0.05, "k2": 0.05, "k3": 0.05},
    "explicit": explicit_gains(**DEFAULT_TIME_CONSTANTS),
    # chosen on three public datasets by a cross-validation over a grid of kP, kI, k2 and the rest gain, with the
    # corrections of DEFAULT_CORRECTIONS["passive"]; not re-tuned since the explicit filter became the recommended one
    "passive": {"k1": 1.0, "k2": 0.1, "kP": 0.25, "kI": 0.0003},
}
# The lab report's values
LAB_GAINS = {
    "linear": {"k1": 0.05, "k2": 0.05, "k3": 0.05},
    "explicit": {"k1": 0.2, "k2": 0.2, "kP": 1.0, "kI": 0.0},
    "passive": {"k1": 1.0, "k2": 1.0, "kP": 1.0, "kI": 1.0},
}
#: Unit and meaning of each filter's gains (the names :data:`DEFAULT_GAINS` and :data:`LAB_GAINS` use).
GAIN_MEANINGS = {
    "linear": {"k1": ("1/s", "roll gain"), "k2": ("1/s", "pitch gain"), "k3": ("1/s", "yaw gain")},
    "explicit": {"k1": ("1", "accelerometer weight (Mahony's Kp = kP k1)"), "k2": ("1", "magnetometer weight"),
                 "kP": ("1/s", "proportional gain"), "kI": ("1/s^2", "bias gain; 0 turns the bias estimate off")},
    "passive": {"k1": ("1", "weight of the tilt part of the correction"),
                "k2": ("1", "weight of the heading part of the correction"),
                "kP": ("1/s", "proportional gain"), "kI": ("1/s^2", "bias gain; 0 turns the bias estimate off")},
}
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
}
CORRECTIONS_OFF = dict.fromkeys(CORRECTIONS, 0.0)
# The corrections each filter runs with by default (corrections=None or True), at the values of CORRECTIONS.
# The explicit filter tracks its magnetic reference and adopts a lasting new field, turning or not (VQF's rule
# less its gyro test): a reference fixed at the first second rejected the iPhones' clean field
# (quadcosim.benchmarks.magnetic,
# the fixed_reference ablation); the passive filter keeps the corrections it was tuned with.
NEW_FOR_EXPLICIT = ("heading_level", "rest_deviation", "mag_new_min_gyro", "mag_rejection_time",
                    "correct_at_sample")
DEFAULT_CORRECTIONS = {
    "explicit": CORRECTIONS | {
        "mag_reference_time": DEFAULT_MAG["reference_s"], "mag_rejection_time": DEFAULT_MAG["rejection_s"],
        "mag_norm_tolerance": DEFAULT_MAG["norm_uT"] * 1e-6 / vehicle.EARTH_FIELD_NORM,
        "mag_dip_tolerance": math.radians(DEFAULT_MAG["dip_deg"]), "mag_new_min_gyro": 0.0},
    "passive": CORRECTIONS | dict.fromkeys(NEW_FOR_EXPLICIT, 0.0),
}
OUTPUT_NAMES = tuple(name for name, _ in core.OUTPUT_LAYOUT)
OUTPUTS = ("q_est0", "q_est1", "q_est2", "q_est3", "theta_est1", "theta_est2", "theta_est3",
           "b_est_x", "b_est_y", "b_est_z", "omega_est_x", "omega_est_y", "omega_est_z",
           "acc_weight", "mag_weight", "at_rest")
UNITS = {name: "1" if name.startswith("q_est") or name in ("acc_weight", "mag_weight", "at_rest")
         else "rad" if name.startswith("theta_est") else "rad/s" for name in OUTPUTS}  # as the variable tables
MEASUREMENTS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "magneto_x", "magneto_y", "magneto_z")
R_REEL = tuple(f"R_reel_{i}{j}" for i in range(1, 4) for j in range(1, 4))
assert len(OUTPUTS) == core.OUTPUT_SIZE and len(MEASUREMENTS) + len(R_REEL) == core.INPUT_SIZE
WARM_UP_STEP = 1e-3  # s, step of the throw-away update that compiles the kernel before a run


def _reference_kinds():
    from quadcosim.estimators import reference

    return reference.REFERENCE_FILTERS


def check_gains(kind: str, gains: dict | None = None, corrections=None) -> dict:
    """Gains and correction settings of ``kind`` by name, defaults filled in.

    Parameters
    ----------
    kind : {"linear", "explicit", "passive"}
    gains : dict, optional
        Gain values by name (see the module docstring); a value may be an array of gain sets.
        Correction settings may be given here too, to vary them across gain sets. The explicit
        filter also takes its time constants ``tau_inclination``, ``tau_heading`` and
        ``tau_bias`` (s; :func:`explicit_gains`; those not given at their defaults), which set
        ``k1, k2, kP, kI`` unless those are given too.
    corrections : bool or dict, optional
        ``None`` (default) or ``True``: the filter's own, :data:`DEFAULT_CORRECTIONS`, at the
        values of :data:`CORRECTIONS`; ``False``: all off (the lab's filters); a dict: those
        given on (``True`` for the value of :data:`CORRECTIONS`, or a value), the others off.

    Returns
    -------
    dict
        Every name the filter reads, with its value. Unknown names and negative or
        non-finite values are refused with a ``ValueError``.
    """
    if kind not in core.OBSERVER_CODES:
        raise ValueError(f"unknown estimator {kind!r}; use one of {', '.join(FILTERS + _reference_kinds())}")
    merged = dict(DEFAULT_GAINS[kind])
    if kind != "linear":
        merged |= _corrections(corrections, kind)
    elif corrections:
        raise ValueError("the linear filter has no disturbance-aware corrections; use corrections=False")
    gains = dict(gains or {})
    taus = {name: gains.pop(name) for name in TIME_CONSTANTS if name in gains}
    if taus and kind != "explicit":
        raise ValueError(f"the time constants {', '.join(taus)} set the explicit filter's gains; give the {kind} "
                         "filter its gains by name")
    if taus:
        merged |= explicit_gains(**(DEFAULT_TIME_CONSTANTS | taus))
    for name, value in gains.items():
        if name not in merged:
            raise ValueError(f"the {kind} estimator has no gain {name!r}; its gains are {', '.join(merged)}")
        merged[name] = value
    for name, value in merged.items():
        array = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(array)) or np.any(array < 0):
            raise ValueError(f"gain {name} = {value} must be finite and non-negative")
    return merged


def _corrections(corrections, kind: str = "explicit") -> dict:
    if corrections is False:
        return dict(CORRECTIONS_OFF)
    if corrections is None or corrections is True:
        return dict(DEFAULT_CORRECTIONS[kind])
    if not isinstance(corrections, dict):
        raise ValueError(f"corrections={corrections!r}: give True, False or a dict of {', '.join(CORRECTIONS)}")
    chosen = dict(CORRECTIONS_OFF)
    for name, value in corrections.items():
        if name not in CORRECTIONS:
            raise ValueError(f"unknown correction {name!r}; the corrections are {', '.join(CORRECTIONS)}")
        if value is True and name.startswith("rest_"):
            chosen |= {k: v for k, v in CORRECTIONS.items() if k.startswith("rest_")}
        else:
            chosen[name] = CORRECTIONS[name] if value is True else float(value)
    return chosen


def parse_corrections(text: str):
    """Corrections from text: ``"on"`` (all), ``"off"``, or comma-separated names of :data:`CORRECTIONS`,
    each optionally ``name=value`` (``"heading_only,mag_norm_tolerance=0.3"``); for command lines."""
    text = str(text).strip().lower()
    if text in ("on", "true", "1", "yes"):
        return True
    if text in ("off", "false", "0", "no", ""):
        return False
    chosen = {}
    for item in text.split(","):
        name, _, value = item.strip().partition("=")
        chosen[name] = float(value) if value else True
    _corrections(chosen)  # refuses unknown names here, before a run
    return chosen


def gain_table(kind: str, gains: dict | None = None, corrections=None) -> np.ndarray:
    """(G, core.GAIN_SIZE) table of gain sets of the filter ``kind``, each column placed by its
    name: ``gains`` maps names to a value or a sequence of G values (None: the defaults), and
    ``corrections`` sets the disturbance corrections, both as in :func:`check_gains`."""
    merged = check_gains(kind, gains, corrections)
    columns = {name: np.atleast_1d(np.asarray(v, dtype=float)) for name, v in merged.items()}
    sizes = {len(c) for c in columns.values() if len(c) > 1}
    if len(sizes) > 1:
        raise ValueError(f"array-valued gains must share one length, not {sorted(sizes)}; gain_grid() builds "
                         "a Cartesian product")
    count = sizes.pop() if sizes else 1
    table = np.zeros((count, core.GAIN_SIZE))
    for name, column in columns.items():
        table[:, core.GAIN_SLOTS[name]] = column
    return table


def gain_grid(**axes) -> dict:
    """Cartesian product of named gain values, as equal-length arrays for :func:`estimate`.

    ``gain_grid(kP=[0.1, 1], kI=[0, 0.01, 0.1])`` gives six gain sets; the first name varies
    slowest, so a result over the sets reshapes to ``(2, 3)``, the lengths in the order given.
    """
    if not axes:
        raise ValueError("gain_grid needs at least one named axis, e.g. gain_grid(kP=[0.1, 1])")
    values = [np.atleast_1d(np.asarray(v, dtype=float)) for v in axes.values()]
    product = np.array(list(itertools.product(*values)), dtype=float).reshape(-1, len(values))
    return {name: product[:, k] for k, name in enumerate(axes)}


def references(gravity=vehicle.GRAVITY, earth_field=None, dip=None, declination=0.0,
               field_norm=vehicle.EARTH_FIELD_NORM) -> tuple[np.ndarray, np.ndarray]:
    """Gravity (m/s^2) and Earth field vectors in the inertial frame.

    Parameters
    ----------
    gravity : float or (3,) array
        Acceleration of gravity, inertial frame (m/s^2); a number is its magnitude along +z
        (NED's down).
    earth_field : (3,) array, optional
        Earth field, inertial frame (T or the magnetometer's unit). Default: from ``dip``, or
        the lab's field.
    dip, declination : float, optional
        Inclination below the horizontal and declination east of north (rad), for a NED
        frame, with ``field_norm`` (T).
    """
    g = np.array([0.0, 0.0, float(gravity)]) if np.ndim(gravity) == 0 else np.asarray(gravity, dtype=float)
    if g.shape != (3,) or not np.all(np.isfinite(g)) or np.linalg.norm(g) == 0:
        raise ValueError(f"gravity {gravity!r} must be a non-zero number (m/s^2, along +z) or a 3-vector")
    if earth_field is not None and dip is not None:
        raise ValueError("give either earth_field or dip (and declination), not both")
    if dip is not None:
        m = field_norm * np.array([math.cos(dip) * math.cos(declination), math.cos(dip) * math.sin(declination),
                                   math.sin(dip)])
    else:
        m = np.asarray(vehicle.EARTH_FIELD if earth_field is None else earth_field, dtype=float)
    if m.shape != (3,) or not np.all(np.isfinite(m)) or np.linalg.norm(np.cross(m, g)) == 0:
        raise ValueError(f"earth_field {m} must be a finite 3-vector not parallel to gravity")
    return g, m


def config_vector(discretisation: str = "exp", ry: str = "reel", earth_field=None, gravity=vehicle.GRAVITY,
                  dip=None, declination=0.0) -> np.ndarray:
    """The configuration of the compiled filters (layout ``core.CONFIG_LAYOUT``).

    ``discretisation`` ``"exp"`` (exponential map) or ``"euler"`` (Euler step plus
    renormalisation); ``ry`` ``"reel"`` or ``"triad"`` for the passive filter; references as in
    :func:`references`: ``gravity`` (m/s^2, or a 3-vector in the inertial frame) and the Earth
    field, given as ``earth_field`` (3, inertial frame) or by its ``dip`` and ``declination``
    (rad).
    """
    if discretisation not in ("exp", "euler"):
        raise ValueError(f"discretisation {discretisation!r} must be 'exp' or 'euler'")
    if ry not in ("reel", "triad"):
        raise ValueError(f"ry {ry!r} must be 'reel' (the IMU's R_reel) or 'triad' (from acc and mag)")
    g, m = references(gravity, earth_field, dip, declination)
    config = np.empty(core.CONFIG_SIZE)
    config[core.GRAVITY:core.GRAVITY + 3] = g
    config[core.FIELD:core.FIELD + 3] = m
    config[core.DISCRETE] = core.EXP if discretisation == "exp" else core.EULER
    config[core.RY] = core.REEL if ry == "reel" else core.TRIAD
    return config


def _initial(q0, initial) -> tuple[np.ndarray, bool]:
    if initial not in (None, "triad") and not callable(initial):
        raise ValueError(f"initial={initial!r} must be None (use q0), 'triad' or a function (gyro, acc, mag) -> q0")
    q = np.asarray((1.0, 0.0, 0.0, 0.0) if q0 is None else q0, dtype=float)
    if q.shape != (4,) or not np.isfinite(q).all() or np.linalg.norm(q) == 0:
        raise ValueError(f"q0 {q0!r} must be a non-zero quaternion (q0, q1, q2, q3)")
    return q / np.linalg.norm(q), initial == "triad"


class QuaternionEstim(Block):
    """The lab's ``Quaternion_estim`` block: one of the filters, streaming.

    Parameters
    ----------
    kind : {"linear", "explicit", "passive", "vqf", "madgwick"}
    gains : dict, optional
        Gains by name (scalars); see the module docstring and :func:`check_gains`.
    name : str
    period : int
        Runs every ``period`` macro steps, normally at the IMU's rate.
    q0 : (4,) array, optional
        Initial attitude, body to inertial (default identity).
    b0 : (3,) array
        Initial gyro-bias estimate (rad/s).
    initial : {None, "triad"}
        ``"triad"``: start from the TRIAD attitude of the first sample instead of ``q0``.
    corrections : bool or dict, optional
        Disturbance-aware corrections, see :func:`check_gains`.
    discretisation : {"exp", "euler"}
    ry : {"reel", "triad"}
        Passive filter: ``R_y`` from the IMU's ``R_reel`` or from TRIAD.
    gravity, earth_field, dip, declination
        Reference vectors, see :func:`references`.

    Notes
    -----
    Inputs: ``acc_x/y/z`` (m/s^2), ``gyro_x/y/z`` (rad/s), ``magneto_x/y/z`` (T), and
    ``R_reel_11..33`` for the passive filter fed by the true rotation. Outputs: ``q_est0..3``,
    ``theta_est1..3`` (rad, Z-Y-X), ``b_est_x/y/z`` (rad/s), ``omega_est_x/y/z = gyro - b_est``
    (rad/s), ``acc_weight``, ``mag_weight`` (1) and ``at_rest`` (0 or 1).
    """

    outputs = OUTPUTS
    units = UNITS

    def __init__(self, kind: str = "explicit", gains: dict | None = None, *, name: str = "Quaternion_estim",
                 period: int = 1, q0=None, b0=(0.0, 0.0, 0.0), initial=None, corrections=None,
                 discretisation: str = "exp", ry: str = "reel", gravity=vehicle.GRAVITY, earth_field=None, dip=None,
                 declination=0.0):
        super().__init__(name, period)
        self.kind = kind
        self.q0, self.from_triad = _initial(q0, initial)
        if callable(initial):
            raise ValueError("the streaming block starts from q0 or initial='triad'; a function needs the recording")
        self.b0 = np.asarray(b0, dtype=float)
        self.config = config_vector(discretisation, ry, earth_field, gravity, dip, declination)
        if kind in _reference_kinds():
            from quadcosim.estimators import reference

            self.gains = reference.check_gains(kind, gains)
            self.inputs = MEASUREMENTS
            return
        self.gains = check_gains(kind, gains, corrections)
        _check_frame(kind, self.config)
        self.inputs = MEASUREMENTS + (R_REEL if kind == "passive" and ry == "reel" else ())
        self._gains = gain_table(kind, self.gains)[0]
        self._code = core.OBSERVER_CODES[kind]

    def start(self, t0, dt):
        self.dt = dt
        if self.kind in _reference_kinds():
            from quadcosim.estimators import reference

            self.step = reference.streaming_step(self.kind, self.gains, self.config, dt, self.q0, self.b0,
                                                 self.from_triad)
            return
        check_stability(self.kind, self._gains[None], dt)
        self.data = np.zeros(_DATA_SIZE)  # shared by the Python step and the compiled step
        self.data[_D_KIND], self.data[_D_DT] = self._code, dt
        self.state, gains, config, self.work = (self.data[a:b] for a, b in _D_PARTS)
        gains[:], config[:] = self._gains, self.config
        core.initial_state(self.q0, self.b0, self.from_triad, self.state)
        update, code, state, work = core.update, self._code, self.state, self.work
        sample = self.sample = np.zeros(core.INPUT_SIZE)  # the inputs may omit R_reel: padded once here
        width = len(self.inputs)

        def step(t, u, y):
            sample[:width] = u
            update(code, state, sample, gains, config, dt, y, work)

        self.step = step  # bound once: the hot loop calls the compiled update directly
        _compile(code)

    def compiled(self):
        """The update as a C-callable step on the block's memory (see :meth:`Block.compiled`);
        ``None`` for the published filters, which run in Python."""
        if self.kind in _reference_kinds():
            return None
        from quadcosim.orchestrator.blocks import CompiledStep

        function = _compiled_step()
        return CompiledStep(function.address, self.sample, self.data, function)


# the streaming block's memory: filter code, period (s), state, gains, configuration, scratch
_D_KIND, _D_DT = 0, 1
_D_PARTS = tuple(itertools.pairwise(itertools.accumulate((2, core.STATE_SIZE, core.GAIN_SIZE, core.CONFIG_SIZE,
                                                          core.WORK_SIZE))))
_DATA_SIZE = _D_PARTS[-1][1]
_COMPILED = None


def _compiled_step():
    """The numba ``cfunc`` of the streaming update, compiled (or loaded from numba's cache) on first use."""
    global _COMPILED
    if _COMPILED is None:
        from numba import carray, cfunc
        from quadcosim.orchestrator.blocks import COMPILED_SIGNATURE, source_fingerprint

        (s0, s1), (g0, g1), (c0, c1), (w0, w1) = _D_PARTS
        sources = source_fingerprint(core)  # the update's file: in numba's cache key with the layout above

        @cfunc(COMPILED_SIGNATURE, cache=True, error_model="numpy")
        def step(t, u, y, data):
            memory = carray(data, _DATA_SIZE)
            core.update(int(memory[_D_KIND]), memory[s0:s1], carray(u, core.INPUT_SIZE), memory[g0:g1],
                        memory[c0:c1], memory[_D_DT], carray(y, core.OUTPUT_SIZE), memory[w0:w1])
            return sources & 0  # 0: done

        _COMPILED = step
    return _COMPILED


def _check_frame(kind, config):
    gx, gy, gz = config[core.GRAVITY:core.GRAVITY + 3]
    if kind == "linear" and (gx or gy or gz <= 0):
        raise ValueError("the linear filter works in NED only: give gravity along +z")


def _compile(code: int):
    """Compile the update before a run, so that the first sample is not the one that pays."""
    u = np.zeros(core.INPUT_SIZE)
    u[core.ACC + 2], u[core.MAG] = -1.0, 1.0
    x = np.zeros(core.STATE_SIZE)
    x[core.Q] = 1.0
    core.update(code, x, u, np.zeros(core.GAIN_SIZE), config_vector(), WARM_UP_STEP, np.empty(core.OUTPUT_SIZE),
                np.empty(core.WORK_SIZE))


def estimate(kind: str = RECORDED, *, gyro, acc, mag, dt: float, gains: dict | None = None, corrections=None,
             R_reel=None, q0=None, b0=(0.0, 0.0, 0.0), initial=None, discretisation: str = "exp", ry: str = "reel",
             gravity=vehicle.GRAVITY, earth_field=None, dip=None, declination=0.0, outputs=OUTPUT_NAMES,
             reference=None, scored=None, align_heading: bool = False, check_units: bool = True) -> dict:
    """Run a filter on recorded arrays, for one or many gain sets at once.

    Parameters
    ----------
    kind : {"explicit", "linear", "passive", "vqf", "madgwick", "mahony"}
        The filter (see the module docstring; ``vqf``, ``madgwick`` and ``mahony`` are the
        published filters of :mod:`quadcosim.estimators.reference`). Default: :data:`RECORDED`, ``"vqf"``,
        the filter for recorded data (:data:`RECOMMENDED` loses to it out of sample).
    gyro, acc, mag : (N, 3) arrays, keyword-only
        Body-frame measurements: rad/s, m/s^2 (specific force: ``-g`` rotated into the body at
        rest), and T (or the unit of ``earth_field``); sample ``n`` at time ``n * dt``. A
        transposed (3, N) array is refused. ``mag=None`` or all zeros: a 6-axis estimate (tilt
        corrected, heading from the gyro alone), with a ``NoMagnetometerWarning``.
    dt : float
        Sample period (s).
    gains : dict, optional
        Gains by name; a value may be an array of G gain sets, so that one call evaluates G
        filters (array-valued gains share one length; scalars are shared; :func:`gain_grid`
        builds a Cartesian product). Defaults: :data:`DEFAULT_GAINS`.
    corrections : bool or dict, optional
        Disturbance-aware corrections (explicit, passive), see :func:`check_gains`.
    R_reel : (N, 9) array, optional
        True rotation, row-major, for ``kind="passive"`` with ``ry="reel"``.
    q0 : (4,) array, optional
        Initial attitude, body to inertial, scalar first (default identity).
    b0 : (3,) array
        Initial gyro-bias estimate (rad/s).
    initial : {None, "triad"} or callable
        ``"triad"``: start from the TRIAD attitude of the first sample; a function
        ``(gyro, acc, mag) -> q0`` computes ``q0`` from the recording.
    discretisation : {"exp", "euler"}
        Quaternion update: exponential map, or Euler step plus renormalisation (see
        :mod:`quadcosim.estimators.core`).
    ry : {"reel", "triad"}
        Passive filter's measured rotation: the true one (``R_reel``) or TRIAD.
    gravity, earth_field, dip, declination
        Reference vectors in the inertial frame, see :func:`references`.
    outputs : sequence of {"q", "theta", "b", "omega", "weights"}
        Time series to return; ``("q",)`` keeps memory to 32 bytes per sample and gain set,
        ``()`` keeps none (with ``reference``, for studies over thousands of gain sets).
    reference : (N, 4) array, optional
        True attitude; the errors against it are reduced inside the compiled loop. Samples
        whose reference is NaN (an occluded marker) are not scored.
    scored : (N,) bool array, optional
        Samples that count in the errors (default all), e.g. the movement phases.
    align_heading : bool
        Remove each gain set's mean heading offset before scoring (for a reference whose
        inertial frame differs from the filter's by a constant heading); costs a second pass.
    check_units : bool
        Refuse an ``acc`` whose specific force at rest is far from g, a unit error (see
        :func:`quadcosim.estimators.checks.check_measurements`); running or vibrating recordings pass.

    Returns
    -------
    dict
        For each requested output an array (G, N, size): ``q`` (4), ``theta`` (3, rad, Z-Y-X),
        ``b`` (3, rad/s), ``omega`` (3, rad/s), ``weights`` (3: accelerometer and
        magnetometer weights, rest flag). With ``reference``, ``errors``: a dict of (G,)
        arrays ``total_rmse_deg``, ``inclination_rmse_deg``, ``heading_rmse_deg`` and
        ``heading_offset_deg`` (the offset removed).
    """
    config = config_vector(discretisation, ry, earth_field, gravity, dip, declination)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt} s must be positive")
    inputs = check_measurements(gyro, acc, mag, float(np.linalg.norm(config[core.GRAVITY:core.GRAVITY + 3])),
                                check_units, dt)
    unknown = [name for name in outputs if name not in OUTPUT_NAMES]
    if unknown:
        raise ValueError(f"unknown output {unknown[0]!r}; the outputs are {', '.join(OUTPUT_NAMES)}")
    q_start, from_triad = _initial(q0, initial)
    if callable(initial):
        q_start, _ = _initial(initial(inputs[:, core.GYRO:core.GYRO + 3], inputs[:, core.ACC:core.ACC + 3],
                                      inputs[:, core.MAG:core.MAG + 3]), None)
    reference, scored = _scoring(reference, scored, len(inputs))
    if kind in _reference_kinds():
        from quadcosim.estimators import reference as published

        series = published.estimate(kind, inputs, dt, gains, config, q_start, np.asarray(b0, float), from_triad,
                                    outputs)
        return _with_errors(series, reference, scored, config, align_heading)
    table = gain_table(kind, gains, corrections)
    _check_frame(kind, config)
    check_stability(kind, table, dt)
    if kind == "passive" and ry == "reel":
        if R_reel is None:
            raise ValueError("the passive filter with ry='reel' needs R_reel (N, 9); or use ry='triad'")
        rotations = np.asarray(R_reel, dtype=float).reshape(len(inputs), 9)
    else:
        rotations = np.zeros((len(inputs), 9))
    inputs = np.ascontiguousarray(np.column_stack([inputs, rotations]))
    if not np.isfinite(inputs).all():
        raise ValueError("R_reel holds NaN or Inf")
    columns = np.concatenate([np.arange(*core.OUTPUT_SLOTS[name]) for name in outputs] or [np.zeros(0, int)])
    stored = np.empty((len(table), len(inputs) if len(columns) else 0, len(columns)))
    sums = np.zeros((len(table), core.ERROR_SIZE))
    offsets = np.zeros(len(table))
    args = (core.OBSERVER_CODES[kind], inputs, table, config, dt, q_start, np.asarray(b0, dtype=float), from_triad,
            columns.astype(np.int64))
    core.run_batch(*args, stored, reference, scored, offsets, sums)
    check_finite(kind, table, stored, sums)
    result, start = {}, 0
    for name in outputs:
        size = core.OUTPUT_SLOTS[name][1] - core.OUTPUT_SLOTS[name][0]
        result[name] = stored[..., start:start + size]
        start += size
    if len(reference):
        if align_heading:
            offsets = np.arctan2(sums[:, core.E_SIN], sums[:, core.E_COS])
            sums[:] = 0.0
            core.run_batch(*args, np.empty((len(table), 0, 0)), reference, scored, offsets, sums)
        result["errors"] = _errors(sums, offsets)
    return result


def _scoring(reference, scored, count, allow_empty=False):
    if reference is None:
        return np.zeros((0, 4)), np.zeros(0, dtype=bool)
    reference = np.array(reference, dtype=float)
    if reference.shape != (count, 4):
        raise ValueError(f"reference must be a ({count}, 4) array of quaternions, not shape {reference.shape}")
    scored = np.ones(count, dtype=bool) if scored is None else np.asarray(scored, dtype=bool).reshape(-1)
    if scored.shape != (count,):
        raise ValueError(f"scored must be a ({count},) boolean array, not shape {scored.shape}")
    # samples without a reference (NaN: an occluded optical marker) are not scored
    known = np.isfinite(reference).all(axis=1) & (np.linalg.norm(np.nan_to_num(reference), axis=1) > 0)
    scored = scored & known
    if not scored.any() and not allow_empty:
        raise ValueError("no sample is both scored and given a finite reference")
    reference[~known] = (1.0, 0.0, 0.0, 0.0)
    reference /= np.linalg.norm(reference, axis=1, keepdims=True)
    return np.ascontiguousarray(reference), scored


def _errors(sums, offsets) -> dict:
    count = sums[:, core.E_COUNT]
    return {
        "total_rmse_deg": np.degrees(np.sqrt(sums[:, core.E_TOTAL] / count)),
        "inclination_rmse_deg": np.degrees(np.sqrt(sums[:, core.E_INCL] / count)),
        "heading_rmse_deg": np.degrees(np.sqrt(sums[:, core.E_HEAD] / count)),
        "heading_offset_deg": np.degrees(offsets),
    }


def _with_errors(series, reference, scored, config, align_heading):
    """Errors of stored estimates (the published filters), by the same compiled reduction."""
    if len(reference):
        q = np.ascontiguousarray(series["q_all"])
        gravity = config[core.GRAVITY:core.GRAVITY + 3].copy()
        offsets = np.zeros(len(q))
        sums = np.zeros((len(q), core.ERROR_SIZE))
        core.score_series(q, reference, scored, gravity, offsets, sums)
        if align_heading:
            offsets = np.arctan2(sums[:, core.E_SIN], sums[:, core.E_COS])
            sums[:] = 0.0
            core.score_series(q, reference, scored, gravity, offsets, sums)
        series["errors"] = _errors(sums, offsets)
    series.pop("q_all")
    return series


def score(q, reference, scored=None, gravity=vehicle.GRAVITY, align_heading: bool = False) -> dict:
    """Quaternion-error RMSE of estimates ``q`` (N, 4) or (G, N, 4) against ``reference`` (N, 4).

    The same reduction as :func:`estimate`'s ``reference`` (total, inclination and heading
    RMSE in degrees, over the ``scored`` samples; see :func:`quadcosim.estimators.core.error_angles`),
    taken a block of samples at a time so that it adds little memory to a long record.
    ``gravity`` (m/s^2, or a 3-vector, inertial frame) gives the vertical; with
    ``align_heading`` the constant heading offset between the two frames is removed first.
    """
    q = np.asarray(q)
    single = q.ndim == 2
    count = q.shape[-2]
    scored = np.ones(count, dtype=bool) if scored is None else np.asarray(scored, dtype=bool).reshape(-1)
    g, _ = references(gravity)
    sets = 1 if single else q.shape[0]
    offsets, sums = np.zeros(sets), np.zeros((sets, core.ERROR_SIZE))
    for attempt in range(2 if align_heading else 1):
        if attempt:
            offsets = np.arctan2(sums[:, core.E_SIN], sums[:, core.E_COS])
            sums[:] = 0.0
        for start in range(0, count, _SCORE_BLOCK):
            block = slice(start, min(count, start + _SCORE_BLOCK))
            part = np.ascontiguousarray((q[None, block] if single else q[:, block]), dtype=float)
            ref, mask = _scoring(np.asarray(reference)[block], scored[block], part.shape[1], allow_empty=True)
            core.score_series(part, ref, mask, g, offsets, sums)
    if not sums[:, core.E_COUNT].all():
        raise ValueError("no sample is both scored and given a finite reference")
    errors = _errors(sums, offsets)
    return {k: (float(v[0]) if single else v) for k, v in errors.items()}


_SCORE_BLOCK = 65536  # samples per block of score()
