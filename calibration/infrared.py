"""In-flight calibration of an infrared horizon sensor against the GPS turn rate.

After "Calibration d'un récepteur Infra-Rouge pour Micro Drone" (Paparazzi project, 2004): the
infrared reading is linear in the turn rate for small bank angles, ``IR = a r + b``, with ``a``
and ``b`` drifting with time of day, temperature and cloud. The GPS gives a reliable but late
turn rate. Three estimators of ``(a, b)`` and of the present turn rate ``(IR - b) / a``:

- ``Estimator("kalman")`` (:class:`EKFSettings`, :func:`ekf_step`): the slides' extended Kalman
  filter on ``(a, b, r)``, measurements the GPS turn rate and the IR, random-walk model
  (``F = I``). It is written as two sequential scalar updates (``form="sequential"``, cheaper,
  the default) or as the slides' joint update (``form="joint"``, :func:`ekf_joint_step`).
  Beyond the slides: innovation gating as in PX4's EKF2 (test ratio
  ``nu^2 / (gamma^2 S)``, a rejected measurement is not fused), a fault declared after
  ``declare`` consecutive rejections, attributed to the IR or the GPS by which one disagrees
  with the state and the other sensor, and cleared after ``clear`` consecutive consistent
  samples. The present IR is also checked against the state, so that an IR fault is declared
  before it reaches the paired window. While the GPS is not fused, the IR updates the turn rate
  only, so ``a`` and ``b`` keep their calibration; when a fault ends their variances are
  raised back to the initial ones.
- ``Estimator("regression")`` (:class:`RegressionSettings`, :func:`regression_step`): the
  slides' baseline, the least-squares line through all the paired samples since take-off,
  recomputed every second, unrealistic points rejected.
- ``Estimator("rls")`` (:class:`RLSSettings`, :func:`rls_step`): the recursive least squares
  with forgetting factor 0.995 of Paparazzi's flight code, updated only when the GPS bank angle
  lies in [0.05, 1] rad.

Pairing: the GPS turn rate at sample ``k`` is the heading difference over the ``window``
samples ``[k - delay - window, k - delay)``, i.e. the mean turn rate there. Every estimator is
fed the mean IR over the same samples (:func:`pair_at`), so that the pair refers to one
stretch of flight, as the slides pair IR and GPS "without offset".

Each estimator's arithmetic is one compiled step function, called by the batch path (a
compiled loop over recorded arrays, :meth:`Estimator.run`) and by the streaming block
(:class:`InfraredCalibration`, an :class:`orchestrator.Block`). :func:`cost` counts the
operations of each step by running the same Python source on counting numbers, and times it.

Units: turn rate rad/s, IR in counts, ``a`` in counts per rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from orchestrator.blocks import Block

# ----------------------------------------------------------------------------- state layouts
# EKF state vector s: estimate, covariance (upper triangle), fault logic, last innovations.
A, B, R = 0, 1, 2
PAA, PAB, PAR, PBB, PBR, PRR = 3, 4, 5, 6, 7, 8
GPS_BAD, GPS_GOOD, GPS_FAULT, IR_BAD, IR_GOOD, IR_FAULT = 9, 10, 11, 12, 13, 14
NU_GPS, GATE_GPS, NU_IR, GATE_IR, RATE, STATUS = 15, 16, 17, 18, 19, 20
GPS_USED, IR_USED, IR_SUSPECT, NU_NOW, GATE_NOW = 21, 22, 23, 24, 25
EKF_SIZE = 26
# EKF configuration c: process noise variances per sample, measurement variances, gate, rules.
QA, QB, QR, RG, RI, GAMMA2, DECLARE, CLEAR, LAG, RI1, PA0, PB0 = range(12)
EKF_CONFIG_SIZE = 12
# status codes
OK, LOST_PD, ZERO_GAIN = 0.0, 1.0, 2.0

# Regression state: sums of the accepted pairs, the fit and its residual spread.
N, SR, SRR, SY, SRY, SYY, FIT_A, FIT_B, FIT_SD, COUNT, REG_RATE, REJECTED, FITTED = range(13)
REG_SIZE = 13
# Regression configuration: recompute period (samples), largest realistic turn rate (rad/s),
# rejection threshold (residual standard deviations), floor of that deviation (count),
# samples and turn-rate spread (rad/s) needed before the first fit.
PERIOD, MAX_RATE, REJECT_K, SD_FLOOR, MIN_N, MIN_SPREAD = range(6)
REG_CONFIG_SIZE = 6

# RLS state: (a, b), its covariance (upper triangle), the present turn rate.
RLS_A, RLS_B, RLS_P00, RLS_P01, RLS_P11, RLS_RATE = range(6)
RLS_SIZE = 6
# RLS configuration: forgetting factor, airspeed (m/s) and gravity (m/s^2) for the bank angle,
# bank-angle band (rad) in which it updates.
RHO, AIRSPEED, GRAVITY, BANK_MIN, BANK_MAX = range(5)
RLS_CONFIG_SIZE = 5


# ----------------------------------------------------------------------------- step functions
@njit(cache=True)
def pair_at(buffer, k, delay, window):
    """Mean IR over the samples ``[k - delay - window, k - delay)``, the GPS window of sample
    ``k``, from the ring buffer that :func:`push` fills; ``nan`` before the window is filled or
    while it holds a sample flagged suspect.

    ``buffer`` holds ``2 (delay + window + 2) + 2`` values: the last ``delay + window + 2``
    samples, their suspect flags, the running sum and the running count of flags.
    """
    size = delay + window
    kept = size + 2
    if k < size:
        return math.nan
    if k == size:
        total, flagged = 0.0, 0.0
        for j in range(0, window):
            total += buffer[j]
            flagged += buffer[kept + j]
    else:
        # in comes sample k - delay - 1, out goes k - delay - window - 1
        i, o = (k - delay - 1) % kept, (k - delay - window - 1) % kept
        total = buffer[2 * kept] + buffer[i] - buffer[o]
        flagged = buffer[2 * kept + 1] + buffer[kept + i] - buffer[kept + o]
    buffer[2 * kept] = total
    buffer[2 * kept + 1] = flagged
    return total / window if flagged == 0.0 else math.nan


@njit(cache=True)
def push(buffer, k, ir, suspect, delay, window):
    """Store sample ``k`` in ``buffer``: its IR ``ir`` (count) and whether it is ``suspect`` (1.0)
    or not (0.0). The buffer is circular over ``delay + window + 2`` samples (the GPS delay and
    averaging window, in samples)."""
    kept = delay + window + 2
    buffer[k % kept] = ir
    buffer[kept + k % kept] = suspect


@njit(cache=True)
def _record(s, passed, bad, good, fault, declare, clear):
    """Persistence rule: ``declare`` rejections in a row declare a fault, ``clear``
    consistent samples in a row end it. Returns whether the fault ended at this sample."""
    if passed:
        s[bad] = 0.0
        s[good] += 1.0
        if s[fault] > 0.5 and s[good] >= clear:
            s[fault] = 0.0
            return True
    else:
        s[good] = 0.0
        s[bad] += 1.0
        if s[bad] >= declare:
            s[fault] = 1.0
    return False


@njit(cache=True)
def _reopen(s, c):
    """After a fault a and b have gone unobserved for its length, under drift the random walk
    understates: their variances are raised back to the initial ones and their correlations
    dropped (P stays positive definite), so the next turns recalibrate them."""
    if s[PAA] < c[PA0]:
        s[PAA] = c[PA0]
    if s[PBB] < c[PB0]:
        s[PBB] = c[PB0]
    s[PAB] = 0.0
    s[PAR] = 0.0
    s[PBR] = 0.0


@njit(cache=True)
def _fuse_gps(s, nu, S):
    """Scalar update with H = (0, 0, 1)."""
    ka, kb, kr = s[PAR] / S, s[PBR] / S, s[PRR] / S
    s[A] += ka * nu
    s[B] += kb * nu
    s[R] += kr * nu
    s[PAA] -= ka * s[PAR]
    s[PAB] -= ka * s[PBR]
    s[PBB] -= kb * s[PBR]
    s[PAR] -= ka * s[PRR]
    s[PBR] -= kb * s[PRR]
    s[PRR] -= kr * s[PRR]


@njit(cache=True)
def ekf_step(s, c, ir_pair, gps, gps_available, ir_now):
    """One sample of the EKF on (a, b, r), sequential scalar updates, gated.

    Parameters
    ----------
    s : (EKF_SIZE,) float array
        State, updated in place (layout: the module's ``A ... IR_SUSPECT`` indices).
    c : (EKF_CONFIG_SIZE,) float array
        Configuration; ``c[GAMMA2] = 0`` turns gating off.
    ir_pair : float
        Mean IR over the GPS window (count); ``nan`` when there is none to fuse.
    gps : float
        GPS turn rate (rad/s).
    gps_available : bool
        Whether the GPS turn rate is valid and to be used.
    ir_now : float
        Present IR (count): checked against the state, and gives the present turn rate
        ``(ir_now - b) / a``.
    """
    s[PAA] += c[QA]
    s[PBB] += c[QB]
    s[PRR] += c[QR]
    gamma2 = c[GAMMA2]
    s[GPS_USED] = 0.0
    s[IR_USED] = 0.0
    s[NU_GPS] = s[GATE_GPS] = s[NU_IR] = s[GATE_IR] = 0.0  # S = 0: not computed at this sample
    have_pair = ir_pair == ir_pair
    gps_pass = False
    if gps_available:
        gps_pass = _test_gps(s, c, gps)
        if gps_pass and have_pair:
            _fuse_gps(s, s[NU_GPS], s[GATE_GPS])
    ir_pass = True
    if have_pair:
        ir_pass, gps_pass = _pair_update(s, c, ir_pair, gps, gps_available, gps_pass)
    elif gps_available and gps_pass:
        _fuse_gps(s, s[NU_GPS], s[GATE_GPS])  # no clean pair: the GPS alone
    if gps_available:
        s[GPS_USED] = 1.0 if gps_pass else 0.0
        if gamma2 > 0.0 and _record(s, gps_pass, GPS_BAD, GPS_GOOD, GPS_FAULT, c[DECLARE], c[CLEAR]):
            _reopen(s, c)
    if gamma2 > 0.0:
        _check_present(s, c, ir_now, ir_pass)
    _finish(s, ir_now)


@njit(cache=True)
def _test_gps(s, c, gps):
    """GPS innovation against the predicted state, and whether it passes the gate."""
    nu = gps - s[R]
    S = s[PRR] + c[RG]
    s[NU_GPS] = nu
    s[GATE_GPS] = S
    return c[GAMMA2] == 0.0 or nu * nu <= c[GAMMA2] * S


@njit(cache=True)
def _pair_update(s, c, ir_pair, gps, gps_available, gps_pass):
    """The paired IR against the state (after the GPS when it was fused), H = (r, 1, a); fused
    by the attribution rules. Returns whether the IR and the GPS passed."""
    a, b, r = s[A], s[B], s[R]
    ha = s[PAA] * r + s[PAB] + s[PAR] * a
    hb = s[PAB] * r + s[PBB] + s[PBR] * a
    hr = s[PAR] * r + s[PBR] + s[PRR] * a
    S_i = r * ha + hb + a * hr + c[RI]
    nu_i = ir_pair - (a * r + b)
    s[NU_IR] = nu_i
    s[GATE_IR] = S_i
    ir_pass = c[GAMMA2] == 0.0 or nu_i * nu_i <= c[GAMMA2] * S_i
    if gps_available and not gps_pass:
        if not ir_pass:
            if _manoeuvre(s, c, gps, nu_i):
                return True, True
        else:
            _fuse_ir(s, nu_i, S_i, ha, hb, hr, False)  # the GPS alone disagrees: a and b held
    elif ir_pass:
        _fuse_ir(s, nu_i, S_i, ha, hb, hr, gps_available)  # without the GPS a and b are held
    return ir_pass, gps_pass


@njit(cache=True)
def _manoeuvre(s, c, gps, nu_i):
    """Both sensors disagree with the state. If they agree with each other the aircraft
    manoeuvred beyond the model: r is reset to the GPS and True returned. Otherwise neither
    is fused."""
    a, r = s[A], s[R]
    d = gps - nu_i / a - r
    S_d = c[RG] + (c[RI] + s[PBB] + r * r * s[PAA]) / (a * a)
    if d * d <= c[GAMMA2] * S_d:
        s[R] = gps
        s[PAR] = 0.0
        s[PBR] = 0.0
        s[PRR] = c[RG]
        return True
    return False


@njit(cache=True)
def _fuse_ir(s, nu, S, ha, hb, hr, calibrate):
    """Scalar update with H = (r, 1, a), ``ha, hb, hr = P H^T``. Without ``calibrate`` only r
    is updated (a Schmidt update: a and b are held, their covariance with r kept right)."""
    if calibrate:
        ka, kb, kr = ha / S, hb / S, hr / S
        s[A] += ka * nu
        s[B] += kb * nu
        s[R] += kr * nu
        s[PAA] -= ka * ha
        s[PAB] -= ka * hb
        s[PAR] -= ka * hr
        s[PBB] -= kb * hb
        s[PBR] -= kb * hr
        s[PRR] -= kr * hr
    else:
        k = hr / S
        s[R] += k * nu
        s[PAR] -= k * ha
        s[PBR] -= k * hb
        s[PRR] -= k * hr
    s[IR_USED] = 1.0


@njit(cache=True)
def _check_present(s, c, ir_now, pair_passed):
    """The present IR against the state: the paired turn rate is delay + window / 2 old, so the
    turn may have changed by c[LAG] (a variance) since. Flags the sample suspect and records
    the IR's consistency for the fault rule."""
    a, b, r = s[A], s[B], s[R]
    nu = ir_now - (a * r + b)
    S = a * a * (s[PRR] + c[LAG]) + r * r * s[PAA] + s[PBB] + c[RI1]
    s[NU_NOW] = nu
    s[GATE_NOW] = S
    s[IR_SUSPECT] = 0.0 if nu * nu <= c[GAMMA2] * S else 1.0
    if _record(s, pair_passed and s[IR_SUSPECT] == 0.0, IR_BAD, IR_GOOD, IR_FAULT, c[DECLARE], c[CLEAR]):
        _reopen(s, c)


@njit(cache=True)
def _finish(s, ir_now):
    """Covariance check, and the present turn rate (IR - b) / a, or the paired one when the IR
    is faulty or suspect."""
    if not (s[PAA] > 0.0 and s[PBB] > 0.0 and s[PRR] > 0.0):
        s[STATUS] = LOST_PD
    if s[A] == 0.0:
        s[STATUS] = ZERO_GAIN
        s[RATE] = math.nan
    elif s[IR_FAULT] > 0.5 or s[IR_SUSPECT] > 0.5:
        s[RATE] = s[R]
    else:
        s[RATE] = (ir_now - s[B]) / s[A]


@njit(cache=True)
def ekf_joint_step(s, c, ir_pair, gps, gps_available, ir_now):
    """One sample of the slides' EKF: both measurements in one update with a 2x2 innovation
    covariance; no gating. Same state and configuration as :func:`ekf_step`.

    Parameters
    ----------
    s, c : float arrays
        State (updated in place) and configuration.
    ir_pair : float
        Mean IR over the GPS window (count); ``nan`` when there is none to fuse.
    gps : float
        GPS turn rate (rad/s).
    gps_available : bool
        Whether the GPS turn rate is valid and to be used.
    ir_now : float
        Present IR (count), which gives the present turn rate ``(ir_now - b) / a``.
    """
    s[PAA] += c[QA]
    s[PBB] += c[QB]
    s[PRR] += c[QR]
    s[GPS_USED] = 0.0
    s[IR_USED] = 0.0
    s[NU_GPS] = s[GATE_GPS] = s[NU_IR] = s[GATE_IR] = 0.0  # S = 0: not computed at this sample
    if ir_pair == ir_pair:
        a, b, r = s[A], s[B], s[R]
        # P H^T, columns for the GPS (0, 0, 1) and the IR (r, 1, a)
        ga, gb, gr = s[PAR], s[PBR], s[PRR]
        ha = s[PAA] * r + s[PAB] + s[PAR] * a
        hb = s[PAB] * r + s[PBB] + s[PBR] * a
        hr = s[PAR] * r + s[PBR] + s[PRR] * a
        nu_i = ir_pair - (a * r + b)
        s[NU_IR] = nu_i
        s[IR_USED] = 1.0
        if gps_available:
            nu_g = gps - r
            s[NU_GPS] = nu_g
            s11 = gr + c[RG]
            s12 = hr
            s22 = r * ha + hb + a * hr + c[RI]
            s[GATE_GPS] = s11
            s[GATE_IR] = s22
            det = s11 * s22 - s12 * s12
            # K = P H^T S^-1
            i11, i12, i22 = s22 / det, -s12 / det, s11 / det
            ka1, ka2 = ga * i11 + ha * i12, ga * i12 + ha * i22
            kb1, kb2 = gb * i11 + hb * i12, gb * i12 + hb * i22
            kr1, kr2 = gr * i11 + hr * i12, gr * i12 + hr * i22
            s[A] += ka1 * nu_g + ka2 * nu_i
            s[B] += kb1 * nu_g + kb2 * nu_i
            s[R] += kr1 * nu_g + kr2 * nu_i
            # P -= K (H P)
            s[PAA] -= ka1 * ga + ka2 * ha
            s[PAB] -= ka1 * gb + ka2 * hb
            s[PAR] -= ka1 * gr + ka2 * hr
            s[PBB] -= kb1 * gb + kb2 * hb
            s[PBR] -= kb1 * gr + kb2 * hr
            s[PRR] -= kr1 * gr + kr2 * hr
            s[GPS_USED] = 1.0
        else:
            S_i = r * ha + hb + a * hr + c[RI]
            s[GATE_IR] = S_i
            k = hr / S_i
            s[R] += k * nu_i
            s[PAR] -= k * ha
            s[PBR] -= k * hb
            s[PRR] -= k * hr
    if not (s[PAA] > 0.0 and s[PBB] > 0.0 and s[PRR] > 0.0):
        s[STATUS] = LOST_PD
    if s[A] == 0.0:
        s[STATUS] = ZERO_GAIN
        s[RATE] = math.nan
    else:
        s[RATE] = (ir_now - s[B]) / s[A]


@njit(cache=True)
def regression_step(s, c, ir_pair, gps, gps_available, ir_now):
    """One sample of the accumulated least-squares line, refitted every ``c[PERIOD]`` samples.

    A pair is unrealistic, and left out, when its turn rate exceeds ``c[MAX_RATE]`` or, once
    a line has been fitted to the data, when it lies more than ``c[REJECT_K]`` residual
    deviations off it.

    Parameters
    ----------
    s, c : float arrays
        State (updated in place) and configuration.
    ir_pair : float
        Mean IR over the GPS window (count); ``nan`` when there is none to fuse.
    gps : float
        GPS turn rate (rad/s).
    gps_available : bool
        Whether the GPS turn rate is valid and to be used.
    ir_now : float
        Present IR (count), which gives the present turn rate ``(ir_now - b) / a``.
    """
    if ir_pair == ir_pair and gps_available:
        realistic = abs(gps) <= c[MAX_RATE]
        if realistic and s[FITTED] > 0.5:  # the initial line is no reference for rejection
            spread = s[FIT_SD] if s[FIT_SD] > c[SD_FLOOR] else c[SD_FLOOR]
            residual = ir_pair - (s[FIT_A] * gps + s[FIT_B])
            realistic = residual * residual <= c[REJECT_K] * c[REJECT_K] * spread * spread
        if realistic:
            s[N] += 1.0
            s[SR] += gps
            s[SRR] += gps * gps
            s[SY] += ir_pair
            s[SRY] += gps * ir_pair
            s[SYY] += ir_pair * ir_pair
        else:
            s[REJECTED] += 1.0
    s[COUNT] += 1.0
    if s[COUNT] >= c[PERIOD]:
        s[COUNT] = 0.0
        n = s[N]
        if n >= c[MIN_N]:
            mean_r, mean_y = s[SR] / n, s[SY] / n
            var_r = s[SRR] / n - mean_r * mean_r
            if var_r >= c[MIN_SPREAD] * c[MIN_SPREAD]:
                cov = s[SRY] / n - mean_r * mean_y
                s[FIT_A] = cov / var_r
                s[FIT_B] = mean_y - s[FIT_A] * mean_r
                var_res = s[SYY] / n - mean_y * mean_y - s[FIT_A] * cov
                s[FIT_SD] = math.sqrt(var_res) if var_res > 0.0 else 0.0
                s[FITTED] = 1.0
    s[REG_RATE] = (ir_now - s[FIT_B]) / s[FIT_A]


@njit(cache=True)
def rls_step(s, c, ir_pair, gps, gps_available, ir_now):
    """One sample of the recursive least squares with forgetting on ``IR = a r + b``,
    updated only when the GPS bank angle ``atan(r V / g)`` lies in the configured band.

    Parameters
    ----------
    s, c : float arrays
        State (updated in place) and configuration.
    ir_pair : float
        Mean IR over the GPS window (count); ``nan`` when there is none to fuse.
    gps : float
        GPS turn rate (rad/s).
    gps_available : bool
        Whether the GPS turn rate is valid and to be used.
    ir_now : float
        Present IR (count), which gives the present turn rate ``(ir_now - b) / a``.
    """
    if ir_pair == ir_pair and gps_available:
        bank = abs(math.atan(gps * c[AIRSPEED] / c[GRAVITY]))
        if c[BANK_MIN] <= bank <= c[BANK_MAX]:
            p0 = s[RLS_P00] * gps + s[RLS_P01]
            p1 = s[RLS_P01] * gps + s[RLS_P11]
            den = c[RHO] + gps * p0 + p1
            k0, k1 = p0 / den, p1 / den
            e = ir_pair - (s[RLS_A] * gps + s[RLS_B])
            s[RLS_A] += k0 * e
            s[RLS_B] += k1 * e
            s[RLS_P00] = (s[RLS_P00] - k0 * p0) / c[RHO]
            s[RLS_P01] = (s[RLS_P01] - k0 * p1) / c[RHO]
            s[RLS_P11] = (s[RLS_P11] - k1 * p1) / c[RHO]
    s[RLS_RATE] = (ir_now - s[RLS_B]) / s[RLS_A]


# ----------------------------------------------------------------------------- configuration
def _check_positive(name: str, value: float, unit: str, fix: str):
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} = {value!r} {unit} must be positive and finite; {fix}")


@dataclass(frozen=True)
class EKFSettings:
    """Settings of :class:`TurnRateEKF`; standard deviations, per sample of 1 / rate.

    Attributes
    ----------
    a0, b0 : float
        Initial ``a`` (count per rad/s) and ``b`` (count): the last calibration, by default the
        slides' regression ``IR = -400 r + 990``.
    sd_a0, sd_b0, sd_r0 : float
        Their initial standard deviations (count/(rad/s), count, rad/s).
    q_a, q_b, q_r : float
        Random-walk standard deviations per sample of ``a``, ``b`` and the paired turn rate.
    sd_gps : float
        GPS turn-rate noise (rad/s); the slides trust the GPS more than the IR.
    sd_ir : float
        Noise of the window-mean IR (count), inflated for the overlap of successive windows.
    sd_ir_sample : float
        Noise of one IR sample (count), for the check of the present IR.
    sd_lag : float
        How much the turn rate may change over the GPS lag (rad/s), for the check of the
        present IR against the paired turn rate; it lets a fault of the IR be declared before
        it reaches the paired window, 1 s later.
    gate : float
        Innovation gate gamma in standard deviations; 0 turns gating and fault logic off.
    declare, clear : int
        Consecutive rejections that declare a fault; consecutive consistent samples that end it.
        When a fault ends, the variances of a and b are raised back to ``sd_a0^2, sd_b0^2``.
    form : str
        ``"sequential"`` (two scalar updates, gated) or ``"joint"`` (the slides' 2x2 update,
        never gated).
    """

    a0: float = -400.0
    b0: float = 990.0
    sd_a0: float = 25.0
    sd_b0: float = 60.0
    sd_r0: float = 0.3
    q_a: float = 0.5
    q_b: float = 1.0
    q_r: float = 0.02
    sd_gps: float = 0.04
    sd_ir: float = 5.0
    sd_ir_sample: float = 6.0
    sd_lag: float = 0.3
    gate: float = 5.0
    declare: int = 10
    clear: int = 20
    form: str = "sequential"

    def __post_init__(self):
        for name in ("sd_a0", "sd_b0", "sd_r0", "q_a", "q_b", "q_r", "sd_gps", "sd_ir", "sd_ir_sample", "sd_lag"):
            _check_positive(name, getattr(self, name), "", "a covariance must be positive definite")
        if not (math.isfinite(self.a0) and self.a0 != 0.0 and math.isfinite(self.b0)):
            raise ValueError(f"a0 = {self.a0!r}, b0 = {self.b0!r}: a0 must be finite and non-zero, b0 finite")
        if not (self.gate == 0.0 or (math.isfinite(self.gate) and self.gate > 0.0)):
            raise ValueError(f"gate = {self.gate!r} standard deviations must be positive, or 0 for no gating")
        if self.declare < 1 or self.clear < 1:
            raise ValueError(f"declare = {self.declare}, clear = {self.clear}: both must be at least 1 sample")
        if self.form not in ("sequential", "joint"):
            raise ValueError(f"form = {self.form!r} must be 'sequential' or 'joint'")
        if self.form == "joint" and self.gate:
            raise ValueError("the joint form is the slides' filter and is not gated: set gate=0 or form='sequential'")

    def config(self) -> np.ndarray:
        """The configuration vector of the step functions (variances per sample, gate, rules)."""
        c = np.zeros(EKF_CONFIG_SIZE)
        c[[QA, QB, QR, RG, RI]] = np.square([self.q_a, self.q_b, self.q_r, self.sd_gps, self.sd_ir])
        c[GAMMA2] = self.gate**2
        c[DECLARE], c[CLEAR] = self.declare, self.clear
        c[LAG], c[RI1] = self.sd_lag**2, self.sd_ir_sample**2
        c[PA0], c[PB0] = self.sd_a0**2, self.sd_b0**2
        return c

    def initial_state(self, covariance=None) -> np.ndarray:
        """The state vector before the first sample.

        Parameters
        ----------
        covariance : (3, 3) array, optional
            Covariance of (a, b, r) (count^2 s^2/rad^2, count^2, rad^2/s^2 on the diagonal);
            default ``diag(sd_a0^2, sd_b0^2, sd_r0^2)``. Refused unless finite, symmetric and
            positive definite.
        """
        s = np.zeros(EKF_SIZE)
        s[A], s[B] = self.a0, self.b0
        P = np.diag(np.square([self.sd_a0, self.sd_b0, self.sd_r0])) if covariance is None else covariance
        P = np.asarray(P, dtype=float)
        if P.shape != (3, 3) or not np.isfinite(P).all() or not np.allclose(P, P.T):
            raise ValueError(f"initial covariance must be a finite symmetric 3x3 matrix, not {P!r}")
        if np.linalg.eigvalsh(P).min() <= 0.0:
            raise ValueError(f"initial covariance is not positive definite (eigenvalues {np.linalg.eigvalsh(P)}); "
                             "give positive variances")
        s[[PAA, PAB, PAR, PBB, PBR, PRR]] = P[0, 0], P[0, 1], P[0, 2], P[1, 1], P[1, 2], P[2, 2]
        return s


@dataclass(frozen=True)
class RegressionSettings:
    """Settings of :class:`Regression` (the slides' baseline).

    Attributes
    ----------
    a0, b0 : float
        Line used until the first fit (count per rad/s, count).
    period : int
        Samples between refits (20: every second at 20 Hz).
    max_rate : float
        Largest realistic turn rate (rad/s).
    reject : float
        A pair further than this many residual deviations from the line is left out.
    sd_floor : float
        Floor of the residual deviation (count).
    min_samples : int
        Pairs needed before the first fit.
    min_spread : float
        Turn-rate standard deviation needed before the first fit (rad/s).
    """

    a0: float = -400.0
    b0: float = 990.0
    period: int = 20
    max_rate: float = 1.5
    reject: float = 4.0
    sd_floor: float = 10.0
    min_samples: int = 100
    min_spread: float = 0.05

    def config(self) -> np.ndarray:
        """The configuration vector of :func:`regression_step`."""
        _check_positive("period", self.period, "samples", "refit at least every sample")
        _check_positive("max_rate", self.max_rate, "rad/s", "give the largest realistic turn rate")
        return np.array([self.period, self.max_rate, self.reject, self.sd_floor, self.min_samples,
                         self.min_spread], dtype=float)

    def initial_state(self) -> np.ndarray:
        """The state vector before the first sample: no data, the initial line."""
        s = np.zeros(REG_SIZE)
        s[FIT_A], s[FIT_B] = self.a0, self.b0
        return s


@dataclass(frozen=True)
class RLSSettings:
    """Settings of :class:`ForgettingRLS` (Paparazzi's flight code).

    Attributes
    ----------
    a0, b0, sd_a0, sd_b0 : float
        Initial line and its standard deviations (count per rad/s, count).
    forgetting : float
        Forgetting factor rho, in (0, 1].
    airspeed, gravity : float
        For the GPS bank angle ``atan(r V / g)`` (m/s, m/s^2).
    bank_min, bank_max : float
        The RLS updates only when the absolute GPS bank angle lies in this band (rad).
    """

    a0: float = -400.0
    b0: float = 990.0
    sd_a0: float = 60.0
    sd_b0: float = 60.0
    forgetting: float = 0.995
    airspeed: float = 12.0
    gravity: float = 9.81
    bank_min: float = 0.05
    bank_max: float = 1.0

    def config(self) -> np.ndarray:
        """The configuration vector of :func:`rls_step`."""
        if not 0.0 < self.forgetting <= 1.0:
            raise ValueError(f"forgetting factor {self.forgetting!r} must lie in (0, 1]")
        _check_positive("airspeed", self.airspeed, "m/s", "the bank angle needs a flying aircraft")
        return np.array([self.forgetting, self.airspeed, self.gravity, self.bank_min, self.bank_max])

    def initial_state(self) -> np.ndarray:
        """The state vector before the first sample: the initial line and its covariance."""
        for name in ("sd_a0", "sd_b0"):
            _check_positive(name, getattr(self, name), "", "a covariance must be positive definite")
        return np.array([self.a0, self.b0, self.sd_a0**2, 0.0, self.sd_b0**2, 0.0])


# ----------------------------------------------------------------------------- the estimators
METHODS = ("kalman", "regression", "rls")
_EKF_FIELDS = {"a": A, "b": B, "r": R, "turn_rate": RATE, "nu_gps": NU_GPS, "S_gps": GATE_GPS, "nu_ir": NU_IR,
               "S_ir": GATE_IR, "gps_fault": GPS_FAULT, "ir_fault": IR_FAULT, "gps_used": GPS_USED,
               "ir_used": IR_USED, "ir_suspect": IR_SUSPECT, "nu_ir_now": NU_NOW,
               "S_ir_now": GATE_NOW, "var_a": PAA, "var_b": PBB, "var_r": PRR, "status": STATUS}
_REG_FIELDS = {"a": FIT_A, "b": FIT_B, "turn_rate": REG_RATE, "rejected": REJECTED}
_RLS_FIELDS = {"a": RLS_A, "b": RLS_B, "turn_rate": RLS_RATE}
_STATUS_TEXT = {LOST_PD: "the covariance lost positive definiteness (a variance fell to zero or below); "
                         "raise the process noise q_a, q_b, q_r or the measurement noise",
                ZERO_GAIN: "the gain a reached zero, so the turn rate (IR - b) / a is undefined; "
                           "check the initial a0 and the IR data"}


class CalibrationError(ValueError):
    """An estimator was given data or settings it cannot use."""


@njit(cache=True)
def _sample(step, s, c, buffer, k, ir, gps, gps_use, delay, window, suspect):
    """One sample of any estimator: pair the IR with the GPS window, step, store the IR."""
    step(s, c, pair_at(buffer, k, delay, window), gps, gps_use, ir)
    push(buffer, k, ir, s[suspect] if suspect >= 0 else 0.0, delay, window)


@njit(cache=True)
def _run(step, s, c, buffer, delay, window, ir, gps, gps_use, fields, status, suspect, out):
    """The batch path: the step function over recorded arrays. Returns the samples done."""
    for k in range(ir.shape[0]):
        _sample(step, s, c, buffer, k, ir[k], gps[k], gps_use[k], delay, window, suspect)
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
        raise CalibrationError(f"{name} holds a non-finite value ({values[k]!r}) at sample {k}; "
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
            raise CalibrationError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
        if int(delay) != delay or delay < 0 or int(window) != window or window < 1:
            raise CalibrationError(f"delay = {delay!r} and window = {window!r} must be whole numbers of samples, "
                                   "delay >= 0 and window >= 1")
        self.method, self.delay, self.window = method, int(delay), int(window)
        if method == "kalman":
            self.settings = settings or EKFSettings()
            self._step = ekf_step if self.settings.form == "sequential" else ekf_joint_step
            self._fields, self._status = _EKF_FIELDS, STATUS
            self._suspect = IR_SUSPECT if self.settings.form == "sequential" else -1
            self._initial = self.settings.initial_state(covariance)
        elif method == "regression":
            self.settings = settings or RegressionSettings()
            self._step, self._fields, self._status, self._suspect = regression_step, _REG_FIELDS, -1, -1
            self._initial = self.settings.initial_state()
        else:
            self.settings = settings or RLSSettings()
            self._step, self._fields, self._status, self._suspect = rls_step, _RLS_FIELDS, -1, -1
            self._initial = self.settings.initial_state()
        self.config = self.settings.config()
        self.names = tuple(self._fields)
        self._index = np.array(list(self._fields.values()), dtype=np.int64)
        self.reset()

    def reset(self):
        """Back to the initial state, before any sample."""
        self.state = self._initial.copy()
        self.buffer = np.zeros(2 * (self.delay + self.window + 2) + 2)
        self.k = 0

    def update(self, ir: float, gps: float, gps_use: bool = True) -> np.ndarray:
        """Take one sample: the IR ``ir`` (count), the GPS turn rate ``gps`` (rad/s) and whether to
        use it, ``gps_use``.

        Returns the state vector (see the module's index constants); ``state[...]`` holds
        ``a``, ``b`` and the present turn rate.
        """
        if not (math.isfinite(ir) and math.isfinite(gps)):
            raise CalibrationError(f"sample {self.k}: IR = {ir!r}, GPS turn rate = {gps!r}; the estimators take "
                                   "finite readings only: drop or repair that sample")
        _sample(self._step, self.state, self.config, self.buffer, self.k, float(ir), float(gps), bool(gps_use),
                self.delay, self.window, self._suspect)
        self.k += 1
        if self._status >= 0 and self.state[self._status] != 0.0:
            raise CalibrationError(f"{self.method} at sample {self.k - 1}: {_STATUS_TEXT[self.state[self._status]]}")
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
            raise CalibrationError(f"IR {ir.shape} and GPS {gps.shape} must be 1-D arrays of the same length")
        use = np.ones(ir.shape, dtype=np.bool_) if gps_use is None else np.asarray(gps_use, dtype=np.bool_)
        if use.shape != ir.shape:
            raise CalibrationError(f"gps_use {use.shape} must have the shape of IR {ir.shape}")
        self.reset()
        out = np.full((ir.shape[0], self._index.shape[0]), np.nan)
        done = _run(self._step, self.state, self.config, self.buffer, self.delay, self.window, ir, gps, use,
                    self._index, self._status, self._suspect, out)
        self.k = done
        if done < ir.shape[0]:
            raise CalibrationError(f"{self.method} at sample {done - 1}: {_STATUS_TEXT[self.state[self._status]]}")
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


# ----------------------------------------------------------------------------- cost per iteration
SLIDES_OPERATIONS = 300  # per iteration, counted by the slides
SLIDES_RATE = 20.0  # Hz
SLIDES_PROCESSOR = 20e6  # Hz, the aircraft's processor in the slides


class _Tally:
    def __init__(self):
        self.flops = self.comparisons = self.functions = 0


_TALLY = _Tally()


class _Counted(float):
    """A float that counts the operations made on it (the cost model of :func:`cost`)."""

    def _arith(self, other, op):
        _TALLY.flops += 1
        return _Counted(op(float(self), float(other)))

    def __add__(self, o):
        return self._arith(o, float.__add__)

    def __radd__(self, o):
        return self._arith(o, lambda x, y: y + x)

    def __sub__(self, o):
        return self._arith(o, float.__sub__)

    def __rsub__(self, o):
        return self._arith(o, lambda x, y: y - x)

    def __mul__(self, o):
        return self._arith(o, float.__mul__)

    def __rmul__(self, o):
        return self._arith(o, lambda x, y: y * x)

    def __truediv__(self, o):
        return self._arith(o, float.__truediv__)

    def __rtruediv__(self, o):
        return self._arith(o, lambda x, y: y / x)

    def __neg__(self):
        _TALLY.flops += 1
        return _Counted(-float(self))

    def __abs__(self):
        _TALLY.functions += 1
        return _Counted(abs(float(self)))

    def _compare(self, other, op):
        _TALLY.comparisons += 1
        return op(float(self), float(other))

    def __lt__(self, o):
        return self._compare(o, float.__lt__)

    def __le__(self, o):
        return self._compare(o, float.__le__)

    def __gt__(self, o):
        return self._compare(o, float.__gt__)

    def __ge__(self, o):
        return self._compare(o, float.__ge__)

    def __eq__(self, o):
        return self._compare(o, float.__eq__)

    def __ne__(self, o):
        return self._compare(o, float.__ne__)

    __hash__ = float.__hash__


_REAL_MATH = math  # the counting run swaps the module's math for _CountedMath


class _CountedMath:
    nan = math.nan

    @staticmethod
    def sqrt(x):
        _TALLY.functions += 1
        return _Counted(_REAL_MATH.sqrt(x))

    @staticmethod
    def atan(x):
        _TALLY.functions += 1
        return _Counted(_REAL_MATH.atan(x))


_COMPILED = ("pair_at", "push", "_record", "_reopen", "_fuse_gps", "_test_gps", "_pair_update", "_manoeuvre",
             "_fuse_ir", "_check_present", "_finish", "ekf_step", "ekf_joint_step", "regression_step", "rls_step",
             "_sample")


def _count_operations(estimator: Estimator, ir, gps, use) -> np.ndarray:
    """Operations of each sample (flops, comparisons, functions), running the step functions'
    Python source on counting numbers: the arithmetic counted is the arithmetic compiled."""
    namespace = globals()
    saved = {name: namespace[name] for name in _COMPILED}
    saved_math = namespace["math"]
    try:
        for name in _COMPILED:
            namespace[name] = saved[name].py_func
        namespace["math"] = _CountedMath
        state = [_Counted(v) for v in estimator._initial]
        config = [_Counted(v) for v in estimator.config]
        buffer = [_Counted(0.0) for _ in range(2 * (estimator.delay + estimator.window + 2) + 2)]
        step = namespace[estimator._step.__name__]
        counts = np.zeros((len(ir), 3), dtype=np.int64)
        for k in range(len(ir)):
            _TALLY.flops = _TALLY.comparisons = _TALLY.functions = 0
            namespace["_sample"](step, state, config, buffer, k, _Counted(ir[k]), _Counted(gps[k]), bool(use[k]),
                                 estimator.delay, estimator.window, estimator._suspect)
            counts[k] = _TALLY.flops, _TALLY.comparisons, _TALLY.functions
        return counts
    finally:
        namespace.update(saved)
        namespace["math"] = saved_math


def cost(ir, gps, gps_use=None, repeats: int = 3, methods=None) -> dict[str, dict]:
    """Operations per iteration and time per update of each estimator, on a recorded flight.

    Parameters
    ----------
    ir, gps : (n,) arrays
        IR readings (count) and GPS turn rates (rad/s), one per sample.
    gps_use : (n,) bool array, optional
        Samples whose GPS is used (default: all).
    repeats : int
        Timings are the best of this many runs.
    methods : sequence of str, optional
        Which of the variants below to measure (default: all).

    Returns
    -------
    dict
        For ``kalman`` (sequential, gated), ``kalman_ungated``, ``kalman_joint`` (the slides'
        2x2 update), ``regression`` and ``rls``: ``operations_mean`` and ``operations_max`` per
        iteration (flops + comparisons + functions), ``flops_mean``, ``comparisons_mean``,
        ``functions_mean``; ``us_per_update_batch`` (compiled loop over the arrays) and
        ``us_per_update_streaming`` (one :meth:`Estimator.update` call from Python); and
        ``operations_per_s`` at the slides' 20 Hz. ``slides`` holds their figures: 300
        operations per iteration at 20 Hz on a 20 MHz processor.
    """
    import time

    ir = _finite("IR", ir)
    gps = _finite("GPS turn rate", gps)
    use = np.ones(ir.shape, dtype=np.bool_) if gps_use is None else np.asarray(gps_use, dtype=np.bool_)
    variants = {"kalman": ("kalman", EKFSettings()), "kalman_ungated": ("kalman", EKFSettings(gate=0.0)),
                "kalman_joint": ("kalman", EKFSettings(gate=0.0, form="joint")),
                "regression": ("regression", None), "rls": ("rls", None)}
    unknown = set(methods or ()) - set(variants)
    if unknown:
        raise CalibrationError(f"unknown estimators {sorted(unknown)}; choose among {', '.join(variants)}")
    out = {}
    for label, (method, settings) in variants.items():
        if methods is not None and label not in methods:
            continue
        estimator = Estimator(method, settings)
        counts = _count_operations(estimator, ir, gps, use)
        total = counts.sum(axis=1)
        estimator.run(ir[:100], gps[:100], use[:100])  # compile
        batch = min(_timed(lambda e=estimator: e.run(ir, gps, use), time) for _ in range(repeats)) / len(ir)
        streaming = min(_timed(lambda e=estimator: _stream(e, ir, gps, use), time) for _ in range(repeats)) / len(ir)
        out[label] = {"operations_mean": float(total.mean()), "operations_max": int(total.max()),
                      "flops_mean": float(counts[:, 0].mean()), "comparisons_mean": float(counts[:, 1].mean()),
                      "functions_mean": float(counts[:, 2].mean()),
                      "operations_per_s": float(total.mean() * SLIDES_RATE),
                      "us_per_update_batch": batch * 1e6, "us_per_update_streaming": streaming * 1e6}
    out["slides"] = {"operations_per_iteration": SLIDES_OPERATIONS, "rate_hz": SLIDES_RATE,
                     "processor_hz": SLIDES_PROCESSOR, "operations_per_s": SLIDES_OPERATIONS * SLIDES_RATE}
    return out


def _timed(function, time) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def _stream(estimator: Estimator, ir, gps, use):
    estimator.reset()
    for k in range(len(ir)):
        estimator.update(ir[k], gps[k], use[k])
