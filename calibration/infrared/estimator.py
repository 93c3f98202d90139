"""The :class:`Estimator` on arrays or sample by sample, and its streaming block.

Its settings are in :mod:`quadcosim.calibration.infrared.settings`. Units: turn rate rad/s, IR in counts,
``a`` in counts per rad/s.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.calibration.infrared.filters import (
    buffer_size,
    ekf_joint_step,
    ekf_step,
    pair_at,
    push,
    raw_pair,
    regression_step,
    rls_step,
)
from quadcosim.calibration.infrared.layout import (
    CUSUM_CONS,
    END_LLR,
    FAULT_SIZE,
    FIT_A,
    FIT_B,
    G_DOWN,
    G_UP,
    GATE_CONS,
    GATE_GPS,
    GATE_IR,
    GATE_NOW,
    GPS_FAULT,
    GPS_USED,
    HELD_SCALE,
    IR_FAULT,
    IR_SUSPECT,
    IR_USED,
    LOST_PD,
    NU_CONS,
    NU_GPS,
    NU_IR,
    NU_NOW,
    PAA,
    PBB,
    PRR,
    RAMP,
    RATE,
    RAW_PAIR,
    REG_RATE,
    REJECTED,
    RLS_A,
    RLS_B,
    RLS_RATE,
    RUN_PEAK,
    STATUS,
    WINDOW_SPAN,
    ZERO_GAIN,
    A,
    B,
    R,
)
from quadcosim.calibration.infrared.settings import EKFSettings, RegressionSettings, RLSSettings
from quadcosim.orchestrator.blocks import Block

from quadcosim.infra.errors import UsageError

METHODS = ("kalman", "regression", "rls")
_EKF_FIELDS = {"a": A, "b": B, "r": R, "turn_rate": RATE, "nu_gps": NU_GPS, "S_gps": GATE_GPS, "nu_ir": NU_IR,
               "S_ir": GATE_IR, "gps_fault": GPS_FAULT, "ir_fault": IR_FAULT, "gps_used": GPS_USED,
               "ir_used": IR_USED, "ir_suspect": IR_SUSPECT, "nu_ir_now": NU_NOW,
               "S_ir_now": GATE_NOW, "var_a": PAA, "var_b": PBB, "var_r": PRR, "status": STATUS,
               "fault_size": FAULT_SIZE, "nu_held": NU_CONS, "S_held": GATE_CONS,
               "held_up": CUSUM_CONS + G_UP, "held_down": CUSUM_CONS + G_DOWN,
               "held_scale": HELD_SCALE, "run_peak": RUN_PEAK, "end_llr": END_LLR}
_REG_FIELDS = {"a": FIT_A, "b": FIT_B, "turn_rate": REG_RATE, "rejected": REJECTED}
_RLS_FIELDS = {"a": RLS_A, "b": RLS_B, "turn_rate": RLS_RATE}
_STATUS_TEXT = {LOST_PD: "the covariance lost positive definiteness (a variance fell to zero or below); "
                         "raise the process noise q_a, q_b, q_r or the measurement noise",
                ZERO_GAIN: "the gain a reached zero, so the turn rate (IR - b) / a is undefined; "
                           "check the initial a0 and the IR data"}


class InfraredCalibrationError(UsageError, ValueError):
    """An infrared calibration estimator was given data or settings it cannot use."""


# the step each estimator takes; by number, so that the compiled loops are cached (numba's cache
# cannot key a function passed as an argument across processes)
EKF_SEQUENTIAL, EKF_JOINT, REGRESSION, RLS = 0, 1, 2, 3


@njit(cache=True)
def _step(kind, s, c, ir_pair, gps, gps_use, ir):
    """One step of the estimator ``kind`` (:data:`EKF_SEQUENTIAL` ... :data:`RLS`)."""
    if kind == EKF_SEQUENTIAL:
        ekf_step(s, c, ir_pair, gps, gps_use, ir)
    elif kind == EKF_JOINT:
        ekf_joint_step(s, c, ir_pair, gps, gps_use, ir)
    elif kind == REGRESSION:
        regression_step(s, c, ir_pair, gps, gps_use, ir)
    else:
        rls_step(s, c, ir_pair, gps, gps_use, ir)


@njit(cache=True)
def _sample(kind, s, c, buffer, k, ir, gps, gps_use, delay, window, suspect):
    """One sample of any estimator: pair the IR with the GPS window, step, store the IR. The
    Kalman filter's consistency detector also takes the window's mean of every sample, suspect
    or not (``s[RAW_PAIR]``)."""
    pair = pair_at(buffer, k, delay, window)
    if kind == EKF_SEQUENTIAL:
        s[RAW_PAIR] = raw_pair(buffer, delay, window)
    _step(kind, s, c, pair, gps, gps_use, ir)
    push(buffer, k, ir, s[suspect] if suspect >= 0 else 0.0, delay, window)


@njit(cache=True)
def _run(kind, s, c, buffer, delay, window, ir, gps, gps_use, fields, status, suspect, out):
    """The batch path: the step over recorded arrays. Returns the samples done."""
    for k in range(ir.shape[0]):
        _sample(kind, s, c, buffer, k, ir[k], gps[k], gps_use[k], delay, window, suspect)
        for j in range(fields.shape[0]):
            out[k, j] = s[fields[j]]
        if status >= 0 and s[status] != 0.0:
            return k + 1
    return ir.shape[0]


def _finite(name: str, values) -> np.ndarray:
    values = np.ascontiguousarray(values, dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InfraredCalibrationError(f"{name} holds a non-finite value ({values[k]!r}) at sample {k}; "
                                       "the estimators take finite readings only: drop or repair that sample")
    return values


class Estimator:
    """One estimator of ``(a, b)`` and of the present turn rate, on arrays or sample by sample.

    Parameters
    ----------
    method : {"kalman", "regression", "rls"}
        Which estimator.
    settings : EKFSettings, RegressionSettings or RLSSettings, optional
        Its settings; defaults for the method when omitted.
    delay, window : int
        GPS delay and window in samples (1 s each at 20 Hz).
    covariance : (3, 3) array, optional
        Initial covariance of the Kalman filter's (a, b, r), instead of the settings' diagonal.
    """

    def __init__(self, method: str = "kalman", settings=None, delay: int = 20, window: int = 20,
                 covariance=None):
        if method not in METHODS:
            raise InfraredCalibrationError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
        if int(delay) != delay or delay < 0 or int(window) != window or window < 1:
            raise InfraredCalibrationError(f"delay = {delay!r} and window = {window!r} must be whole numbers of "
                                           "samples, delay >= 0 and window >= 1")
        self.method, self.delay, self.window = method, int(delay), int(window)
        if method == "kalman":
            self.settings = settings or EKFSettings()
            self._kind = EKF_SEQUENTIAL if self.settings.form == "sequential" else EKF_JOINT
            self._fields, self._status = _EKF_FIELDS, STATUS
            self._suspect = IR_SUSPECT if self.settings.form == "sequential" else -1
            self._initial = self.settings.initial_state(covariance)
        elif method == "regression":
            self.settings = settings or RegressionSettings()
            self._kind, self._fields, self._status, self._suspect = REGRESSION, _REG_FIELDS, -1, -1
            self._initial = self.settings.initial_state()
        else:
            self.settings = settings or RLSSettings()
            self._kind, self._fields, self._status, self._suspect = RLS, _RLS_FIELDS, -1, -1
            self._initial = self.settings.initial_state()
        self.config = self.settings.config()
        if method == "kalman":
            self.config[WINDOW_SPAN] = self.delay + self.window
            self.config[RAMP] = self.window
        self.names = tuple(self._fields)
        self._index = np.array(list(self._fields.values()), dtype=np.int64)
        self.reset()

    def reset(self):
        """Back to the initial state, before any sample."""
        self.state = self._initial.copy()
        self.buffer = np.zeros(buffer_size(self.delay, self.window))
        self.k = 0

    def update(self, ir: float, gps: float, gps_use: bool = True) -> np.ndarray:
        """Take one sample: the IR ``ir`` (count), the GPS turn rate ``gps`` (rad/s) and whether to
        use it, ``gps_use``.

        Returns the state vector (see the module's index constants); ``state[...]`` holds
        ``a``, ``b`` and the present turn rate.
        """
        if not (math.isfinite(ir) and math.isfinite(gps)):
            raise InfraredCalibrationError(f"sample {self.k}: IR = {ir!r}, GPS turn rate = {gps!r}; the estimators "
                                           "take finite readings only: drop or repair that sample")
        _sample(self._kind, self.state, self.config, self.buffer, self.k, float(ir), float(gps), bool(gps_use),
                self.delay, self.window, self._suspect)
        self.k += 1
        if self._status >= 0 and self.state[self._status] != 0.0:
            raise InfraredCalibrationError(f"{self.method} at sample {self.k - 1}: "
                                           f"{_STATUS_TEXT[self.state[self._status]]}")
        return self.state

    def run(self, ir, gps, gps_use=None) -> dict[str, np.ndarray]:
        """The estimator over recorded arrays, from its initial state.

        Parameters
        ----------
        ir : (n,) array
            IR readings (count), one per sample.
        gps : (n,) array
            GPS turn rate (rad/s), one per sample.
        gps_use : (n,) bool array, optional
            Samples whose GPS is valid and to be used (default: all).

        Returns
        -------
        dict of (n,) arrays
            ``a``, ``b``, ``turn_rate`` (the present turn rate ``(IR - b) / a``, rad/s) and, for
            the Kalman filter, ``r`` (paired turn rate), innovations ``nu_gps``, ``nu_ir`` and
            their variances ``S_gps``, ``S_ir``, fault flags ``gps_fault``, ``ir_fault``, and
            whether each measurement was fused (``gps_used``, ``ir_used``).
        """
        ir = _finite("IR", ir)
        gps = _finite("GPS turn rate", gps)
        if gps.shape != ir.shape or ir.ndim != 1:
            raise InfraredCalibrationError(f"IR {ir.shape} and GPS {gps.shape} must be 1-D arrays of the same length")
        use = np.ones(ir.shape, dtype=np.bool_) if gps_use is None else np.asarray(gps_use, dtype=np.bool_)
        if use.shape != ir.shape:
            raise InfraredCalibrationError(f"gps_use {use.shape} must have the shape of IR {ir.shape}")
        self.reset()
        out = np.full((ir.shape[0], self._index.shape[0]), np.nan)
        done = _run(self._kind, self.state, self.config, self.buffer, self.delay, self.window, ir, gps, use,
                    self._index, self._status, self._suspect, out)
        self.k = done
        if done < ir.shape[0]:
            raise InfraredCalibrationError(f"{self.method} at sample {done - 1}: "
                                           f"{_STATUS_TEXT[self.state[self._status]]}")
        return {name: out[:, j] for j, name in enumerate(self.names)}


class InfraredCalibration(Block):
    """Streaming block around one :class:`Estimator`, at the sensor's rate.

    Inputs ``ir`` (count), ``gps_turn_rate`` (rad/s), ``gps_valid`` (1 when valid); outputs
    the estimator's named values (``a``, ``b``, ``turn_rate`` and, for the Kalman filter, the
    innovations, their variances and the fault flags). The GPS is used until ``gps_until``
    (s; the slides' "real case" stops it after a calibration phase).

    Parameters
    ----------
    name : str
        Block name.
    estimator : Estimator
        The estimator, shared with the batch path.
    gps_until : float
        Time after which the GPS is no longer used (s); ``inf`` for always.
    period : int
        Runs every ``period`` macro steps (one sample of the sensor).
    """

    inputs = ("ir", "gps_turn_rate", "gps_valid")
    feedthrough = True

    def __init__(self, name: str, estimator: Estimator, gps_until: float = math.inf, period: int = 1):
        super().__init__(name, period)
        self.estimator = estimator
        self.gps_until = float(gps_until)
        self.outputs = estimator.names
        self._index = estimator._index

    def start(self, t0, dt):
        self.estimator.reset()

    def step(self, t, u, y):
        use = u[2] > 0.5 and t < self.gps_until
        s = self.estimator.update(u[0], u[1], use)
        y[:] = s[self._index]


