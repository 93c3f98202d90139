"""Fault detection of the Kalman filter: which sensor is wrong, from when to when.

Beside the gate (a single measurement outside ``gamma`` standard deviations is not fused), a
two-sided CUSUM (Page, "Continuous inspection schemes", Biometrika 1954) runs on each
normalised innovation ``z = nu / sqrt(S)``: the GPS turn rate against the state, the paired IR
against the state, and the present IR against the state. Upwards ``g = max(0, g + z - k)``,
downwards the same on ``-z``; a fault is declared when a statistic exceeds ``h``. It finds the
small offsets the gate lets through (and that the filter would otherwise absorb into ``b`` or
``r``), and the large ones at their first samples.

- Only while both sensors are in use: with the GPS alone gone (not valid, or not used after a
  calibration phase) an offset of the IR cannot be told from a drift of ``b``, and nothing
  would replace the IR.
- Attribution: an IR fault shows first in the IR's innovations (the present IR at once, the
  paired IR when the faulty samples reach the GPS window), a GPS fault first in the GPS's. The
  first statistic over its threshold names the sensor; at the same sample, the one furthest
  over it (in units of its threshold).
- The detectors' runs start before their alarm: meanwhile the faulty sensor was fused and
  pulled ``a`` and ``b``. When a fault is declared they are set back to their values at the
  last sample where every statistic was zero.
- While a fault is declared, the faulty sensor is not fused (the IR: ``a`` and ``b`` held, the
  turn rate from the GPS; the GPS: the IR alone, ``a`` and ``b`` held), and its innovation is
  still computed against the state.
- The filter's own innovations show a small offset only while ``b`` and ``a`` absorb it (within
  seconds: the random walks that follow the drift follow an offset too). A fourth CUSUM runs on
  the GPS-IR consistency residual ``IR_pair - (a gps + b)`` against the calibration of
  ``held_lag`` samples before (:func:`consistency`), which has not absorbed it yet. Its alarm is
  attributed by the residual's shape over the last ``RING_SIZE`` samples (:func:`attribute`): a
  GPS offset enters it as a step, an IR offset as a ramp over the GPS window; a generalised
  likelihood ratio fits each, onset and size free, beyond a constant error of the calibration
  (``delta_b + delta_a r``, which a change of the turn exposes), and names the sensor only when
  one shape is clearly the better; until then nothing is declared. The fault then proceeds as
  below, ``a`` and ``b`` set back to that held calibration.
- The fault ends when that sensor is consistent again: a CUSUM of the log-likelihood ratio of
  "no offset" against "the offset ``d`` estimated" (the mean innovation over the run that
  raised the alarm, then a running mean while the evidence favours the fault),
  ``g = max(0, g + d (d / 2 - nu) / S)``, ending the fault when it exceeds ``end_h``. For the
  GPS, on its innovation; for the IR, on the paired IR, once the faulty samples fill the GPS
  window (the present IR varies with the turn over the lag, too much to end a small fault on).
  An offset that persists keeps it at zero, whatever the variance grows to
  meanwhile: a fault is not ended while the sensor is still faulty. When it ends, every CUSUM
  restarts from zero (the end of a fault is no new fault: after an IR fault the paired IR is not
  watched until its window is clean) and the variances of ``a`` and ``b`` are raised back to
  their initial values, so that the next turns recalibrate them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from calibration.infrared.layout import (
    A_SAFE,
    B_SAFE,
    CONS_H,
    CONS_K,
    CUSUM_CONS,
    CUSUM_GPS,
    CUSUM_H,
    CUSUM_K,
    CUSUM_NOW,
    CUSUM_PAIR,
    CUSUM_SIZE,
    END_H,
    END_PAIR,
    END_STAT,
    FAULT_SIZE,
    G_DOWN,
    G_UP,
    GAMMA2,
    GATE_CONS,
    GATE_GPS,
    GATE_IR,
    GATE_NOW,
    GPS_FAULT,
    HELD_GPS,
    HELD_IR,
    HELD_LAG,
    HELD_SCALE,
    HOLD,
    IR_FAULT,
    IR_SUSPECT,
    LAG,
    MARGIN,
    N_DOWN,
    N_UP,
    NOW_H,
    NOW_K,
    NU_CONS,
    NU_GPS,
    NU_IR,
    NU_NOW,
    PA0,
    PAA,
    PAB,
    PAR,
    PAST,
    PAST_COUNT,
    PAST_SIZE,
    PB0,
    PBB,
    PBR,
    PRR,
    RAMP,
    RG,
    RI,
    RI1,
    RING,
    RING_COUNT,
    RING_SIZE,
    SCALE_GAIN,
    SD_A_HELD,
    SIGNIFICANCE,
    SIZE_GAIN,
    SUM_DOWN,
    SUM_UP,
    WINDOW_SPAN,
    A,
    B,
    R,
)


@njit(cache=True)
def _side(s, g, total, count, z, nu, k):
    """One side of a CUSUM: ``g = max(0, g + z - k)``; a new run (from zero) restarts the sum
    and the count of its raw innovations ``nu``."""
    value = s[g] + z - k
    if value > 0.0:
        if s[g] == 0.0:
            s[total] = 0.0
            s[count] = 0.0
        s[g] = value
        s[total] += nu
        s[count] += 1.0
    else:
        s[g] = 0.0


@njit(cache=True)
def cusum(s, base, nu, S, k, h):
    """Update the two-sided CUSUM at ``base`` with the innovation ``nu`` of variance ``S``
    (allowance ``k`` and threshold ``h`` in standard deviations). Returns how far its larger
    statistic is over the threshold, in thresholds (``<= 0``: no alarm)."""
    z = nu / math.sqrt(S)
    _side(s, base + G_UP, base + SUM_UP, base + N_UP, z, nu, k)
    _side(s, base + G_DOWN, base + SUM_DOWN, base + N_DOWN, -z, nu, k)
    top = s[base + G_UP] if s[base + G_UP] > s[base + G_DOWN] else s[base + G_DOWN]
    return top / h - 1.0


@njit(cache=True)
def run_mean(s, base):
    """Mean raw innovation over the run of the side of the CUSUM at ``base`` that is higher:
    the size of the offset it detected."""
    if s[base + G_UP] >= s[base + G_DOWN]:
        return s[base + SUM_UP] / s[base + N_UP]
    return s[base + SUM_DOWN] / s[base + N_DOWN]


@njit(cache=True)
def restart(s):
    """Every CUSUM of the state ``s`` back to zero."""
    for base in (CUSUM_GPS, CUSUM_PAIR, CUSUM_NOW, CUSUM_CONS):
        for j in range(CUSUM_SIZE):
            s[base + j] = 0.0
    s[RING_COUNT] = 0.0  # the consistency residuals before the restart are no evidence after it


@njit(cache=True)
def reopen(s, c):
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
def consistency(s, c, ir_pair, gps):
    """The paired IR ``ir_pair`` (count) against the GPS turn rate ``gps`` (rad/s) through the
    calibration of ``c[HELD_LAG]`` samples before (:func:`remember_calibration`): the residual
    ``ir_pair - (a gps + b)`` (count) and its variance (count^2) under the filter's noise model
    and the covariance that calibration had, stored in the state ``s``. The filter itself
    absorbs an offset into ``b`` (and ``a``) within a few seconds; the calibration held from
    before the offset does not, and drifts by at most the drift of ``a`` and ``b`` over the lag."""
    held = PAST + (int(s[PAST_COUNT]) - int(c[HELD_LAG])) % PAST_SIZE
    a = s[held]
    s[NU_CONS] = ir_pair - (a * gps + s[held + PAST_SIZE])
    s[HELD_GPS] = gps
    s[HELD_IR] = ir_pair
    var_a, cov_ab, var_b = s[held + 2 * PAST_SIZE], s[held + 3 * PAST_SIZE], s[held + 4 * PAST_SIZE]
    s[GATE_CONS] = a * a * c[RG] + c[RI] + gps * (gps * var_a + 2.0 * cov_ab) + var_b


@njit(cache=True)
def remember_calibration(s):
    """Keep this sample's ``a``, ``b`` and their covariance in the ring of past calibrations."""
    count = int(s[PAST_COUNT])
    slot = PAST + count % PAST_SIZE
    s[slot] = s[A]
    s[slot + PAST_SIZE] = s[B]
    s[slot + 2 * PAST_SIZE] = s[PAA]
    s[slot + 3 * PAST_SIZE] = s[PAB]
    s[slot + 4 * PAST_SIZE] = s[PBB]
    s[PAST_COUNT] = count + 1


@njit(cache=True)
def _remember(s, ir_pair, gps, S):
    """Keep the paired IR ``ir_pair`` (count), the GPS turn rate ``gps`` (rad/s) and the
    consistency residual's variance ``S`` (count^2) in the ring; ``nan`` for a sample without."""
    count = int(s[RING_COUNT])
    slot = RING + count % RING_SIZE
    s[slot] = ir_pair
    s[slot + RING_SIZE] = gps
    s[slot + 2 * RING_SIZE] = S
    s[RING_COUNT] = count + 1


@njit(cache=True)
def _ring(s):
    """The ring's samples, oldest first, against the calibration from before its oldest (one
    sample per step since the last restart): the normalised consistency residual ``x`` and the
    turn rate over its deviation, the mean of the GPS's and the IR's (``nan`` where there was
    none). Both hypotheses take the same turn rate: half of either sensor's offset is in it, and
    a turn that really happened is in it whole."""
    count = int(s[RING_COUNT])
    n = count if count < RING_SIZE else RING_SIZE
    ref = PAST + (int(s[PAST_COUNT]) - n) % PAST_SIZE
    a, b = s[ref], s[ref + PAST_SIZE]
    x, turn = np.empty(n), np.empty(n)
    for m in range(n):
        slot = RING + (count - n + m) % RING_SIZE
        ir_pair, gps, root = s[slot], s[slot + RING_SIZE], math.sqrt(s[slot + 2 * RING_SIZE])
        x[m] = (ir_pair - (a * gps + b)) / root
        turn[m] = 0.5 * (gps + (ir_pair - b) / a) / root
    return x, turn


@njit(cache=True)
def _fit(x, u, onset, ramp, sign, ridge):
    """Log-likelihood ratio (unit variance) and size of the best offset ``d`` of sign ``sign``
    with the signature ``f_m = min(1, (m - onset + 1) / ramp)`` from sample ``onset`` on, in the
    residuals ``x``, beyond an error of the calibration they are taken against, ``delta_b +
    delta_a u_m`` (``u``: the turn rate, :func:`_ring`), fitted with it. The offset must be what
    the calibration's error, present all along the ring, does not explain: a turn that exposes
    an error of ``a`` is no fault. ``delta_a`` has a Gaussian prior (``ridge``: the noise
    variance over its variance), so that an offset is not taken for an error of ``a`` of the
    size of ``a`` itself."""
    n, su, suu, sx, sux, sf, suf, sff, sfx = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for m in range(x.shape[0]):
        if x[m] == x[m]:
            f = 0.0 if m < onset else min(1.0, (m - onset + 1) / ramp)
            n += 1.0
            su += u[m]
            suu += u[m] * u[m]
            sx += x[m]
            sux += u[m] * x[m]
            sf += f
            suf += u[m] * f
            sff += f * f
            sfx += f * x[m]
    suu += ridge
    det = n * suu - su * su
    if det > 1e-9 * n * suu:  # project the offset's signature and the residuals off (1, u)
        fx = sfx - (sf * (suu * sx - su * sux) + suf * (n * sux - su * sx)) / det
        ff = sff - (sf * (suu * sf - su * suf) + suf * (n * suf - su * sf)) / det
    else:  # a steady turn: u is a constant, the calibration's error one offset
        fx = sfx - sf * sx / n if n > 0.0 else 0.0
        ff = sff - sf * sf / n if n > 0.0 else 0.0
    if ff <= 1e-9 * sff or fx * sign <= 0.0:
        return 0.0, 0.0
    return 0.5 * fx * fx / ff, fx / ff


@njit(cache=True)
def _best(x, u, ramp, sign, ridge):
    """The generalised likelihood ratio over every onset in the ring (a ramp may have started
    before it): the largest log-likelihood ratio and its offset (:func:`_fit`)."""
    best, size = 0.0, 0.0
    for onset in range(1 - int(ramp), x.shape[0]):
        llr, d = _fit(x, u, onset, ramp, sign, ridge)
        if llr > best:
            best, size = llr, d
    return best, size


@njit(cache=True)
def evidence(s, c):
    """The generalised likelihood ratios of the ring (:func:`attribute`), in units of the
    residual's own spread: ``(larger, step, ramp, step_size, ramp_size)``, the sizes in
    normalised units, of the sign of the consistency CUSUM's higher side."""
    sign = 1.0 if s[CUSUM_CONS + G_UP] >= s[CUSUM_CONS + G_DOWN] else -1.0
    x, turn = _ring(s)
    scale = s[HELD_SCALE]
    ridge = scale / (c[SD_A_HELD] * c[SD_A_HELD])
    step, step_size = _best(x, turn, 1.0, sign, ridge)
    ramp, ramp_size = _best(x, turn, c[RAMP], sign, ridge)
    step, ramp = step / scale, ramp / scale
    return (step if step > ramp else ramp), step, ramp, step_size, ramp_size


@njit(cache=True)
def attribute(s, c):
    """Which sensor the consistency CUSUM's alarm comes from, by the shape of the residual in
    the ring: an offset of the GPS turn rate enters it as a step (the sample it starts), one of
    the IR as a ramp over the GPS window (``c[RAMP]`` samples, as the faulty samples fill the
    paired mean). A generalised likelihood ratio with each signature, the onset and size free,
    beyond an error of the calibration (:func:`_fit`); log-likelihoods in units of the
    residual's own spread while no offset showed (``s[HELD_SCALE]``). A fault needs the better
    signature to reach ``c[SIGNIFICANCE]`` and to beat the other by ``c[MARGIN]``. Returns
    ``(sensor, size)``: 1 the GPS, 2 the IR, 0 none or not yet told apart; the size in
    normalised units."""
    larger, step, ramp, step_size, ramp_size = evidence(s, c)
    if larger < c[SIGNIFICANCE]:
        return 0, 0.0
    if step - ramp > c[MARGIN]:
        return 1, step_size
    if ramp - step > c[MARGIN]:
        return 2, ramp_size
    return 0, 0.0


@njit(cache=True)
def check_present(s, c, ir_now):
    """The present IR ``ir_now`` (count) against the state ``s`` (configuration ``c``): the
    paired turn rate is delay + window / 2 old, so the turn may have changed by c[LAG] (a
    variance) since. Stores the innovation and its variance, and flags the sample suspect (kept
    out of the paired window) when outside the gate."""
    a, b, r = s[A], s[B], s[R]
    nu = ir_now - (a * r + b)
    S = a * a * (s[PRR] + c[LAG]) + r * r * s[PAA] + s[PBB] + c[RI1]
    s[NU_NOW] = nu
    s[GATE_NOW] = S
    s[IR_SUSPECT] = 0.0 if nu * nu <= c[GAMMA2] * S else 1.0


@njit(cache=True)
def _evidence(s, stat, d, nu, S):
    """Add to the end statistic ``stat`` the log-likelihood ratio of no offset against the
    offset ``d``, for the innovation ``nu`` of variance ``S``; returns the statistic."""
    g = s[stat] + d * (0.5 * d - nu) / S
    s[stat] = g if g > 0.0 else 0.0
    return s[stat]


@njit(cache=True)
def _follow(s, c, nu):
    """The declared fault's offset estimate follows the innovation ``nu`` (a running mean)."""
    s[FAULT_SIZE] += c[SIZE_GAIN] * (nu - s[FAULT_SIZE])


@njit(cache=True)
def _end_gps(s, c):
    """The end test of a GPS fault, on the GPS innovation."""
    if _evidence(s, END_STAT, s[FAULT_SIZE], s[NU_GPS], s[GATE_GPS]) > c[END_H]:
        _ended(s, c, GPS_FAULT)
    elif s[END_STAT] == 0.0:
        _follow(s, c, s[NU_GPS])


@njit(cache=True)
def _end_ir(s, c, pair_seen):
    """The end test of an IR fault, on the paired IR: armed once the faulty samples fill the
    GPS window (until then the offset estimate follows the present IR)."""
    d = s[FAULT_SIZE]
    if not pair_seen or s[END_PAIR] < 0.0:
        if pair_seen and d * (s[NU_IR] - 0.5 * d) > 0.0:
            s[END_PAIR] = 0.0
        _follow(s, c, s[NU_NOW])
    elif _evidence(s, END_PAIR, d, s[NU_IR], s[GATE_IR]) > c[END_H]:
        _ended(s, c, IR_FAULT)
        s[HOLD] = c[WINDOW_SPAN]  # the window still holds faulty samples
    elif s[END_PAIR] == 0.0:
        _follow(s, c, s[NU_IR])


@njit(cache=True)
def _ended(s, c, flag):
    """End the fault ``flag``: detectors restarted, a and b reopened."""
    s[flag] = 0.0
    s[END_STAT] = 0.0
    s[END_PAIR] = 0.0
    restart(s)
    reopen(s, c)


@njit(cache=True)
def _quiet(s):
    """Whether every CUSUM statistic is zero: no sensor shows the start of an offset."""
    for base in (CUSUM_GPS, CUSUM_PAIR, CUSUM_NOW, CUSUM_CONS):
        if s[base + G_UP] > 0.0 or s[base + G_DOWN] > 0.0:
            return False
    return True


@njit(cache=True)
def detect(s, c, gps_seen, pair_seen):
    """Declare, attribute and end faults from this sample's innovations (see the module).

    Parameters
    ----------
    s, c : float arrays
        EKF state (updated in place) and configuration.
    gps_seen : bool
        A GPS innovation was computed at this sample (``s[NU_GPS]``, ``s[GATE_GPS]``).
    pair_seen : bool
        A paired IR innovation was computed (``s[NU_IR]``, ``s[GATE_IR]``).
    """
    if s[GPS_FAULT] > 0.5:
        if gps_seen:
            _end_gps(s, c)
        return
    if s[IR_FAULT] > 0.5:
        s[IR_SUSPECT] = 0.0  # the IR is not fused: its samples may fill the window the end test watches
        _end_ir(s, c, pair_seen)
        return
    if s[HOLD] > 0.0:
        s[HOLD] -= 1.0
        pair_seen = False
    if not gps_seen:  # one sensor alone: a drift and a fault look alike, and nothing would replace it
        _remember(s, math.nan, math.nan, math.nan)
        return
    gps = cusum(s, CUSUM_GPS, s[NU_GPS], s[GATE_GPS], c[CUSUM_K], c[CUSUM_H]) if gps_seen else -1.0
    pair = cusum(s, CUSUM_PAIR, s[NU_IR], s[GATE_IR], c[CUSUM_K], c[CUSUM_H]) if pair_seen else -1.0
    now = cusum(s, CUSUM_NOW, s[NU_NOW], s[GATE_NOW], c[NOW_K], c[NOW_H])
    held = _held(s, c, pair_seen)
    ir = pair if pair > now else now
    if gps <= 0.0 and ir <= 0.0:
        sensor, size = attribute(s, c) if held > 0.0 else (0, 0.0)
        if sensor == 0:  # nothing, or a small offset whose sensor the residual does not tell yet
            if _quiet(s):
                s[A_SAFE], s[B_SAFE] = s[A], s[B]
            return
        _declare_held(s, c, sensor, size)
    else:
        _declare(s, gps, pair, now, ir)
    s[END_STAT] = 0.0
    s[END_PAIR] = -1.0  # not armed
    restart(s)


@njit(cache=True)
def _held(s, c, pair_seen):
    """The consistency CUSUM on this sample's residual (how far over its threshold, in
    thresholds; -1 when it is zero or there is no residual), the sample kept in the ring, and
    the residual's spread followed while its statistic is zero."""
    if not pair_seen:
        _remember(s, math.nan, math.nan, math.nan)
        return -1.0
    _remember(s, s[HELD_IR], s[HELD_GPS], s[GATE_CONS])
    held = cusum(s, CUSUM_CONS, s[NU_CONS], s[GATE_CONS], c[CONS_K], c[CONS_H])
    if held == -1.0:  # its statistic is zero: no offset shows, the residual is noise and drift
        z = s[NU_CONS] / math.sqrt(s[GATE_CONS])
        s[HELD_SCALE] += c[SCALE_GAIN] * (z * z - s[HELD_SCALE])
    return held


@njit(cache=True)
def _declare(s, gps, pair, now, ir):
    """A fault declared by the CUSUM of the GPS, the paired IR or the present IR (how far each
    is over its threshold): the furthest names the sensor, its run the offset."""
    s[A], s[B] = s[A_SAFE], s[B_SAFE]  # what the faulty sensor pulled a and b by before the alarm, undone
    if gps > ir:
        s[GPS_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_GPS)
    else:
        s[IR_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_PAIR) if pair > now else run_mean(s, CUSUM_NOW)


@njit(cache=True)
def _declare_held(s, c, sensor, size):
    """A fault declared by the consistency CUSUM, on the ``sensor`` :func:`attribute` named
    (1 the GPS, 2 the IR), of normalised ``size``: the offset in the units of that sensor's
    end test (the GPS: rad/s, ``-d / a``; the IR: count)."""
    offset = size * math.sqrt(s[GATE_CONS])
    held = PAST + (int(s[PAST_COUNT]) - int(c[HELD_LAG])) % PAST_SIZE
    s[A], s[B] = s[held], s[held + PAST_SIZE]  # the calibration from before the offset
    if sensor == 1:
        s[GPS_FAULT] = 1.0
        s[FAULT_SIZE] = -offset / s[A]
    else:
        s[IR_FAULT] = 1.0
        s[FAULT_SIZE] = offset
