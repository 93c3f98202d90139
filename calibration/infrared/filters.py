"""The estimators' step functions: the Kalman filter (sequential and joint), the regression, the RLS.

Each takes the state ``s`` and configuration ``c`` vectors of :mod:`quadcosim.calibration.infrared.layout`,
the paired IR, the GPS turn rate, whether the GPS is to be used and the present IR, and
updates ``s`` in place. Compiled with numba; :mod:`quadcosim.calibration.infrared.cost` runs the same
Python source on counting numbers.
"""

from __future__ import annotations

import math

from numba import njit
from quadcosim.calibration.infrared.detection import check_present, consistency, detect, remember_calibration
from quadcosim.calibration.infrared.layout import (
    AIRSPEED,
    BANK_MAX,
    BANK_MIN,
    COUNT,
    FIT_A,
    FIT_B,
    FIT_SD,
    FITTED,
    GAMMA2,
    GATE_GPS,
    GATE_IR,
    GPS_FAULT,
    GPS_USED,
    GRAVITY,
    HOLD,
    IR_FAULT,
    IR_SUSPECT,
    IR_USED,
    LOST_PD,
    MAX_RATE,
    MIN_N,
    MIN_SPREAD,
    NU_GPS,
    NU_IR,
    PAA,
    PAB,
    PAR,
    PBB,
    PBR,
    PERIOD,
    PRR,
    QA,
    QB,
    QR,
    RATE,
    RAW_PAIR,
    RAW_SEEN,
    REG_RATE,
    REJECT_K,
    REJECTED,
    RG,
    RHO,
    RI,
    RLS_A,
    RLS_B,
    RLS_P00,
    RLS_P01,
    RLS_P11,
    RLS_RATE,
    SD_FLOOR,
    SR,
    SRR,
    SRY,
    STATUS,
    SY,
    SYY,
    ZERO_GAIN,
    A,
    B,
    N,
    R,
)


@njit(cache=True)
def pair_at(buffer, k, delay, window):
    """Mean IR over the samples ``[k - delay - window, k - delay)``, the GPS window of sample
    ``k``, from the ring buffer that :func:`push` fills; ``nan`` before the window is filled or
    while it holds a sample flagged suspect. The mean of every sample, suspect or not, is kept
    in the buffer's last entry (:func:`raw_pair`).

    ``buffer`` holds ``2 (delay + window + 2) + 3`` values: the last ``delay + window + 2``
    samples, their suspect flags, the running sum, the running count of flags and the mean.
    """
    size = delay + window
    kept = size + 2
    if k < size:
        buffer[2 * kept + 2] = math.nan
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
    buffer[2 * kept + 2] = total / window
    return total / window if flagged == 0.0 else math.nan


@njit(cache=True)
def raw_pair(buffer, delay, window):
    """The mean IR over the GPS window of the last :func:`pair_at`, suspect samples included
    (count); ``nan`` before the window is filled. ``buffer`` is the pairing buffer of
    :func:`push`, ``delay`` and ``window`` the GPS delay and averaging window (samples)."""
    return buffer[2 * (delay + window + 2) + 2]


def buffer_size(delay: int, window: int) -> int:
    """Length of the pairing buffer for a GPS ``delay`` and ``window`` (samples)."""
    return 2 * (delay + window + 2) + 3


@njit(cache=True)
def push(buffer, k, ir, suspect, delay, window):
    """Store sample ``k`` in ``buffer``: its IR ``ir`` (count) and whether it is ``suspect`` (1.0)
    or not (0.0). The buffer is circular over ``delay + window + 2`` samples (the GPS delay and
    averaging window, in samples)."""
    kept = delay + window + 2
    buffer[k % kept] = ir
    buffer[kept + k % kept] = suspect


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
    """One sample of the EKF on (a, b, r), sequential scalar updates, gated, with fault
    detection (:mod:`quadcosim.calibration.infrared.detection`).

    Parameters
    ----------
    s : (EKF_SIZE,) float array
        State, updated in place (layout: :mod:`quadcosim.calibration.infrared.layout`).
    c : (EKF_CONFIG_SIZE,) float array
        Configuration; ``c[GAMMA2] = 0`` turns gating and fault detection off.
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
    gps_usable = gps_available and s[GPS_FAULT] < 0.5  # a declared fault: watched, not fused
    pair_usable = have_pair and s[IR_FAULT] < 0.5 and s[HOLD] <= 0.0  # HOLD: the window holds a past fault
    gps_pass = False
    if gps_available:
        gps_pass = _test_gps(s, c, gps) and gps_usable
        if gps_pass and pair_usable:
            _fuse_gps(s, s[NU_GPS], s[GATE_GPS])
    if pair_usable:
        _, gps_pass = _pair_update(s, c, ir_pair, gps, gps_usable, gps_pass)
    elif gps_pass:
        _fuse_gps(s, s[NU_GPS], s[GATE_GPS])  # no clean pair: the GPS alone
    if have_pair and not pair_usable:
        _pair_innovation(s, c, ir_pair)  # the faulty IR, watched
    s[GPS_USED] = 1.0 if gps_pass else 0.0
    if gamma2 > 0.0:
        check_present(s, c, ir_now)
        watched = s[RAW_PAIR] if c[RAW_SEEN] > 0.5 else ir_pair  # the IR the consistency residual takes
        raw_seen = watched == watched
        if raw_seen and gps_available:
            consistency(s, c, watched, gps)
        detect(s, c, gps_available, have_pair, raw_seen)
        remember_calibration(s, c)
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
def _pair_innovation(s, c, ir_pair):
    """The paired IR against the state, H = (r, 1, a): stores the innovation and its variance,
    returns ``P H^T`` as ``(ha, hb, hr)``."""
    a, b, r = s[A], s[B], s[R]
    ha = s[PAA] * r + s[PAB] + s[PAR] * a
    hb = s[PAB] * r + s[PBB] + s[PBR] * a
    hr = s[PAR] * r + s[PBR] + s[PRR] * a
    s[GATE_IR] = r * ha + hb + a * hr + c[RI]
    s[NU_IR] = ir_pair - (a * r + b)
    return ha, hb, hr


@njit(cache=True)
def _pair_update(s, c, ir_pair, gps, gps_available, gps_pass):
    """The paired IR against the state (after the GPS when it was fused), fused by the
    attribution rules. Returns whether the IR and the GPS passed."""
    ha, hb, hr = _pair_innovation(s, c, ir_pair)
    nu_i, S_i = s[NU_IR], s[GATE_IR]
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


