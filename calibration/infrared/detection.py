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

from numba import njit

from calibration.infrared.layout import (
    A_SAFE,
    B_SAFE,
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
    GATE_GPS,
    GATE_IR,
    GATE_NOW,
    GPS_FAULT,
    HOLD,
    IR_FAULT,
    IR_SUSPECT,
    LAG,
    N_DOWN,
    N_UP,
    NOW_H,
    NOW_K,
    NU_GPS,
    NU_IR,
    NU_NOW,
    PA0,
    PAA,
    PAB,
    PAR,
    PB0,
    PBB,
    PBR,
    PRR,
    RI1,
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
    for base in (CUSUM_GPS, CUSUM_PAIR, CUSUM_NOW):
        for j in range(CUSUM_SIZE):
            s[base + j] = 0.0


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
    for base in (CUSUM_GPS, CUSUM_PAIR, CUSUM_NOW):
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
        return
    gps = cusum(s, CUSUM_GPS, s[NU_GPS], s[GATE_GPS], c[CUSUM_K], c[CUSUM_H]) if gps_seen else -1.0
    pair = cusum(s, CUSUM_PAIR, s[NU_IR], s[GATE_IR], c[CUSUM_K], c[CUSUM_H]) if pair_seen else -1.0
    now = cusum(s, CUSUM_NOW, s[NU_NOW], s[GATE_NOW], c[NOW_K], c[NOW_H])
    ir = pair if pair > now else now
    if gps <= 0.0 and ir <= 0.0:
        if _quiet(s):
            s[A_SAFE], s[B_SAFE] = s[A], s[B]
        return
    s[A], s[B] = s[A_SAFE], s[B_SAFE]  # what the faulty sensor pulled a and b by before the alarm, undone
    if gps > ir:
        s[GPS_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_GPS)
    else:
        s[IR_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_PAIR) if pair > now else run_mean(s, CUSUM_NOW)
    s[END_STAT] = 0.0
    s[END_PAIR] = -1.0  # not armed
    restart(s)
