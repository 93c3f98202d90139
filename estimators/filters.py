"""Attitude estimators as a streaming block and as a function on recorded arrays.

Both call the compiled update of :mod:`estimators.core`, so the block and the batch path
compute the same numbers. Three filters:

``linear`` (lab report, section II)
    Per axis, ``dtheta_i = omega_m,i - k_i (theta_i - theta_i,meas)`` with
    ``theta1,meas = -a_m,y / g``, ``theta2,meas = a_m,x / g`` and the yaw of the
    magnetometer after removing the estimated roll and pitch,
    ``theta3,meas = atan2(-m_level,y, m_level,x)`` (the lab's ``-m_y / m_I,1`` for small
    angles). Gains ``k1, k2, k3`` (1/s), lab value 0.05. Explicit Euler. No bias estimate.
``explicit`` (Mahony, Hamel, Pflimlin 2008, eqs. 32/48; lab section III.1)
    ``dq = 0.5 q (x) (0, omega_m - b + kP omega_mes)``, ``omega_mes = sum k_i v_i x vhat_i``,
    ``db = -kI omega_mes``. The references are normalised: ``v_1 = a_m/|a_m|`` against
    ``vhat_1 = R^T (0, 0, -1)``, ``v_2 = m_m/|m_m|`` against ``vhat_2 = R^T m_I/|m_I|``.
    Gains ``k1, k2`` (1/s, lab: 0.002 and 0.2), ``kP`` (1), ``kI`` (1/s^2; 0 turns the
    bias estimate off).
``passive`` (Mahony 2008, eqs. 13/47; lab section III.2)
    ``dR = R S(omega_m - b + kP omega)``, ``db = -kI omega``, ``omega = vex(Pa(R^T R_y))``,
    with ``R_y`` the true rotation ``R_reel`` of the IMU (``ry="reel"``, as the lab did) or
    the TRIAD rotation of accelerometer and magnetometer (``ry="triad"``). Gains ``kP``
    (1/s) and ``kI`` (1/s^2), lab: 0.1 to 100.

Initial state: ``q0`` (default identity) and ``b0`` (default zero, rad/s).
"""

from __future__ import annotations

import math

import numpy as np

from estimators import core
from fmus import vehicle
from orchestrator.blocks import Block

DEFAULT_GAINS = {
    "linear": {"k1": 0.05, "k2": 0.05, "k3": 0.05},
    "explicit": {"k1": 0.2, "k2": 0.2, "kP": 1.0, "kI": 0.0},
    "passive": {"kP": 1.0, "kI": 1.0},
}
OUTPUTS = ("q_est0", "q_est1", "q_est2", "q_est3", "theta_est1", "theta_est2", "theta_est3",
           "b_est_x", "b_est_y", "b_est_z", "omega_est_x", "omega_est_y", "omega_est_z")
MEASUREMENTS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "magneto_x", "magneto_y", "magneto_z")
R_REEL = tuple(f"R_reel_{i}{j}" for i in range(1, 4) for j in range(1, 4))


def check_gains(kind: str, gains: dict | None) -> dict:
    """Gains of ``kind`` with defaults filled in; refuses unknown names and negative values."""
    if kind not in core.KINDS:
        raise ValueError(f"unknown estimator {kind!r}; use one of {', '.join(core.KINDS)}")
    merged = dict(DEFAULT_GAINS[kind])
    for name, value in (gains or {}).items():
        if name not in merged:
            raise ValueError(f"the {kind} estimator has no gain {name!r}; its gains are {', '.join(merged)}")
        merged[name] = value
    for name, value in merged.items():
        array = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(array)) or np.any(array < 0):
            raise ValueError(f"gain {name} = {value} must be finite and non-negative")
    return merged


def config_vector(discretisation: str = "exp", ry: str = "reel", earth_field=vehicle.EARTH_FIELD,
                  gravity: float = vehicle.GRAVITY) -> np.ndarray:
    if discretisation not in ("exp", "euler"):
        raise ValueError(f"discretisation {discretisation!r} must be 'exp' or 'euler'")
    if ry not in ("reel", "triad"):
        raise ValueError(f"ry {ry!r} must be 'reel' (the IMU's R_reel) or 'triad' (from acc and mag)")
    config = np.empty(core.CONFIG_SIZE)
    config[core.G] = gravity
    config[core.M_I:core.M_I + 3] = earth_field
    config[core.DISCRETE] = core.EXP if discretisation == "exp" else core.EULER
    config[core.RY] = core.REEL if ry == "reel" else core.TRIAD
    return config


class QuaternionEstim(Block):
    """The lab's ``Quaternion_estim`` block: one of the three filters, streaming.

    Inputs: ``acc_x/y/z`` (m/s^2), ``gyro_x/y/z`` (rad/s), ``magneto_x/y/z`` (T), and
    ``R_reel_11..33`` for the passive filter fed by the true rotation. Outputs: ``q_est0..3``,
    ``theta_est1..3`` (rad), ``b_est_x/y/z`` (rad/s), ``omega_est_x/y/z = gyro - b_est``.
    Runs every ``period`` macro steps, normally at the IMU's rate.
    """

    outputs = OUTPUTS

    def __init__(self, kind: str = "explicit", gains: dict | None = None, name: str = "Quaternion_estim",
                 period: int = 1, q0=(1.0, 0.0, 0.0, 0.0), b0=(0.0, 0.0, 0.0), discretisation: str = "exp",
                 ry: str = "reel"):
        super().__init__(name, period)
        self.kind = kind
        self.gains = check_gains(kind, gains)
        self.inputs = MEASUREMENTS + (R_REEL if kind == "passive" and ry == "reel" else ())
        self.config = config_vector(discretisation, ry)
        self.q0 = np.asarray(q0, dtype=float) / np.linalg.norm(q0)
        self.b0 = np.asarray(b0, dtype=float)
        self._gains = np.array(list(self.gains.values()), dtype=float)
        self._code = core.KINDS[kind]

    def start(self, t0, dt):
        self.dt = dt
        self.state = np.empty(core.STATE_SIZE)
        self.work = np.empty(core.WORK_SIZE)
        core.initial_state(self.q0, self.b0, self.state)
        update, code, state, gains, config, work = (core.update, self._code, self.state, self._gains,
                                                    self.config, self.work)

        def step(t, u, y):
            update(code, state, u, gains, config, dt, y, work)

        self.step = step  # bound once: the hot loop calls the compiled update directly
        _compile(code)


def _compile(code: int):
    """Compile the update before a run, so that the first sample is not the one that pays."""
    u = np.zeros(18)
    u[2], u[6] = -1.0, 1.0
    core.update(code, np.array([1.0, 0, 0, 0, 0, 0, 0, 0, 0, 0]), u, np.zeros(4), config_vector(), 1e-3,
                np.empty(core.OUTPUT_SIZE), np.empty(core.WORK_SIZE))


def estimate(kind: str, acc, gyro, mag, dt: float, gains: dict | None = None, R_reel=None,
             q0=(1.0, 0.0, 0.0, 0.0), b0=(0.0, 0.0, 0.0), discretisation: str = "exp", ry: str = "reel") -> dict:
    """Run a filter on recorded arrays.

    Parameters
    ----------
    kind : {"linear", "explicit", "passive"}
    acc, gyro, mag : (N, 3) arrays
        Body-frame measurements (m/s^2, rad/s, T), sample ``n`` at time ``n * dt``.
    dt : float
        Sample period (s).
    gains : dict
        Gain values; a value may be an array of G gain sets, so that one call evaluates G
        filters (all array-valued gains must have the same length; scalars are shared).
    R_reel : (N, 9) array, optional
        True rotation, row-major, for ``kind="passive"`` with ``ry="reel"``.

    Returns
    -------
    dict of arrays with a leading gain-set axis (G, N, ...): ``q`` (4), ``theta`` (3, rad),
    ``b`` (3, rad/s), ``omega`` (3, rad/s).
    """
    merged = check_gains(kind, gains)
    columns = [np.atleast_1d(np.asarray(v, dtype=float)) for v in merged.values()]
    sizes = {len(c) for c in columns if len(c) > 1}
    if len(sizes) > 1:
        raise ValueError(f"array-valued gains must share one length, not {sorted(sizes)}")
    count = sizes.pop() if sizes else 1
    table = np.column_stack([np.broadcast_to(c, count) for c in columns])
    parts = [np.asarray(acc, float), np.asarray(gyro, float), np.asarray(mag, float)]
    if kind == "passive" and ry == "reel":
        if R_reel is None:
            raise ValueError("the passive filter with ry='reel' needs R_reel (N, 9); or use ry='triad'")
        parts.append(np.asarray(R_reel, float))
    inputs = np.ascontiguousarray(np.column_stack(parts))
    if not np.isfinite(inputs).all():
        raise ValueError("the recorded measurements hold NaN or Inf")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt = {dt} s must be positive")
    outputs = np.empty((count, len(inputs), core.OUTPUT_SIZE))
    q0 = np.asarray(q0, dtype=float) / np.linalg.norm(q0)
    core.run_batch(core.KINDS[kind], inputs, table, config_vector(discretisation, ry), dt, q0,
                   np.asarray(b0, dtype=float), outputs)
    return {"q": outputs[..., 0:4], "theta": outputs[..., 4:7], "b": outputs[..., 7:10], "omega": outputs[..., 10:13]}
