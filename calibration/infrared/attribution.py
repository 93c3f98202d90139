"""The attribution fit of the infrared detector: which shape, a GPS step or an IR ramp, explains
a change of the consistency residual, with its onset and size.

The ring of the last ``RING_SIZE`` samples (the paired IR, the GPS turn rate and the residual's
variance, kept by :mod:`quadcosim.calibration.infrared.detection`) is seen against the calibration from
before its oldest sample (:func:`_ring`). Each shape is fitted there, onset and size free, beside
an error of that calibration, ``delta_b + delta_a u`` with a Gaussian prior on ``delta_a``
(:func:`_best`); :func:`evidence` gives both fits' log-likelihoods and :func:`attribute` declares
the better one once it is significant and clearly the better (the algorithm as a whole is
described in :mod:`quadcosim.calibration.infrared.detection`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from quadcosim.calibration.infrared.layout import (
    COMPLETE,
    CUSUM_CONS,
    DECISIVE,
    G_DOWN,
    G_UP,
    HELD_SCALE,
    MARGIN,
    PAST,
    PAST_COUNT,
    PAST_SIZE,
    RAMP,
    RING,
    RING_COUNT,
    RING_SIZE,
    RUN_PEAK,
    SD_A_HELD,
    SD_DRIFT,
    SIGNIFICANCE,
    TURN_MODE,
)


@njit(cache=True)
def _ring(s, c):
    """The ring's samples, oldest first (one per step since the last restart), against the
    calibration from before its oldest: the normalised consistency residual ``x``; three turn
    rates over its deviation: the mean of the GPS's and the IR's, the IR's, and the GPS's
    averaged over the GPS window, centred (``nan`` where there was none; ``c[TURN_MODE]`` says
    which the fit takes); and the sample's index from the ring's middle over its deviation (the
    time of a drift)."""
    count = int(s[RING_COUNT])
    n = n_ring(s)
    ref = PAST + (int(s[PAST_COUNT]) - n) % PAST_SIZE
    a, b = s[ref], s[ref + PAST_SIZE]
    x, mean, ir, gps, time = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for m in range(n):
        slot = RING + (count - n + m) % RING_SIZE
        ir_pair, rate, root = s[slot], s[slot + RING_SIZE], math.sqrt(s[slot + 2 * RING_SIZE])
        x[m] = (ir_pair - (a * rate + b)) / root
        ir[m] = (ir_pair - b) / a / root
        gps[m] = rate / root
        mean[m] = 0.5 * (gps[m] + ir[m])
        time[m] = (m - 0.5 * (n - 1)) / root
    smooth = np.empty(n)
    half = int(c[RAMP]) // 2
    total, used = np.zeros(n + 1), np.zeros(n + 1)
    for m in range(n):
        seen = gps[m] == gps[m]
        total[m + 1] = total[m] + (gps[m] if seen else 0.0)
        used[m + 1] = used[m] + (1.0 if seen else 0.0)
    for m in range(n):
        lo, hi = max(m - half, 0), min(m + half + 1, n)
        smooth[m] = (total[hi] - total[lo]) / (used[hi] - used[lo]) if used[hi] > used[lo] else 0.0
    return x, mean, ir, smooth, time


@njit(cache=True)
def n_ring(s):
    """How many samples the ring holds (fewer than ``RING_SIZE`` since a restart)."""
    count = int(s[RING_COUNT])
    return count if count < RING_SIZE else RING_SIZE


@njit(cache=True)
def _prefix(q, v):
    """Prefix sums of ``q`` and of ``m q`` over the valid samples (``v`` 1, else 0): entry ``j``
    sums the samples before ``j``."""
    n = q.shape[0]
    total, moment = np.zeros(n + 1), np.zeros(n + 1)
    for m in range(n):
        value = q[m] * v[m]
        total[m + 1] = total[m] + value
        moment[m + 1] = moment[m] + m * value
    return total, moment


@njit(cache=True)
def _shape_sums(total, moment, onset, ramp, n):
    """``sum_m f_m q_m`` for the signature ``f_m = min(1, (m - onset + 1) / ramp)`` (0 before
    ``onset``), from the prefix sums of ``q`` and ``m q`` (:func:`_prefix`)."""
    a0 = min(max(onset, 0), n)
    a1 = min(max(onset + int(ramp) - 1, 0), n)
    rising = (moment[a1] - moment[a0] - (onset - 1) * (total[a1] - total[a0])) / ramp
    return rising + total[n] - total[a1]


@njit(cache=True)
def _solve3(g00, g01, g02, g11, g12, g22, r0, r1, r2):
    """``G^-1 r`` for the symmetric positive definite 3x3 ``G`` (upper triangle given), by its
    cofactors; zeros when ``G`` is singular to rounding."""
    c00 = g11 * g22 - g12 * g12
    c01 = g02 * g12 - g01 * g22
    c02 = g01 * g12 - g02 * g11
    det = g00 * c00 + g01 * c01 + g02 * c02
    if not det > 1e-12 * g00 * g11 * g22:
        return 0.0, 0.0, 0.0
    c11 = g00 * g22 - g02 * g02
    c12 = g01 * g02 - g00 * g12
    c22 = g00 * g11 - g01 * g01
    return ((c00 * r0 + c01 * r1 + c02 * r2) / det, (c01 * r0 + c11 * r1 + c12 * r2) / det,
            (c02 * r0 + c12 * r1 + c22 * r2) / det)


@njit(cache=True)
def _best(x, u, w, ramp, sign, ridge_u, ridge_w):
    """The generalised likelihood ratio of an offset in the residuals ``x`` (unit variance),
    over every onset in the ring (a ramp may have started before it): the largest
    log-likelihood ratio, the offset's size and its onset.

    The offset ``d`` has the signature ``f_m = min(1, (m - onset + 1) / ramp)`` from sample
    ``onset`` on and the sign ``sign``; it must be what an error of the calibration the residuals
    are taken against and a drift, ``delta_b + delta_a u_m + beta w_m`` (``u``: a turn rate,
    ``w``: the time, :func:`_ring`), do not explain, fitted with it: a turn that exposes an error
    of ``a`` is no fault, nor is the cloud's steady change of ``b``. ``delta_a`` and ``beta`` have
    Gaussian priors (``ridge_u``, ``ridge_w``: the noise variance over their variances), so that
    an offset is not taken for an error of ``a`` of the size of ``a`` itself, nor for a drift
    faster than the sensor's. Samples where ``x`` is ``nan`` are left out. Sums over the ring by
    prefix sums, so that every onset costs the same few operations."""
    n = x.shape[0]
    v, xs, us, ws = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    for m in range(n):
        if x[m] == x[m]:
            v[m], xs[m], us[m], ws[m] = 1.0, x[m], u[m], w[m]
    count, su, sw, suu, suw, sww, sx, sux, swx = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for m in range(n):
        count += v[m]
        su += us[m]
        sw += ws[m]
        suu += us[m] * us[m]
        suw += us[m] * ws[m]
        sww += ws[m] * ws[m]
        sx += xs[m]
        sux += us[m] * xs[m]
        swx += ws[m] * xs[m]
    if count < 2.0:
        return 0.0, 0.0, 0
    g00, g01, g02, g11, g12, g22 = count, su, sw, suu + ridge_u, suw, sww + ridge_w
    bx0, bx1, bx2 = _solve3(g00, g01, g02, g11, g12, g22, sx, sux, swx)  # the nuisance fitted to x alone
    i00, i01, i02 = _solve3(g00, g01, g02, g11, g12, g22, 1.0, 0.0, 0.0)  # its normal matrix inverted
    _, i11, i12 = _solve3(g00, g01, g02, g11, g12, g22, 0.0, 1.0, 0.0)
    _, _, i22 = _solve3(g00, g01, g02, g11, g12, g22, 0.0, 0.0, 1.0)
    pv, pmv = _prefix(v, v)
    pu, pmu = _prefix(us, v)
    pw, pmw = _prefix(ws, v)
    px, pmx = _prefix(xs, v)
    squares = np.zeros(n + 1)  # prefix sums of m^2 over the valid samples, for the ramp's f^2
    for m in range(n):
        squares[m + 1] = squares[m] + m * m * v[m]
    best, size, at = 0.0, 0.0, 0
    for onset in range(1 - int(ramp), n):
        sf = _shape_sums(pv, pmv, onset, ramp, n)
        suf = _shape_sums(pu, pmu, onset, ramp, n)
        swf = _shape_sums(pw, pmw, onset, ramp, n)
        sfx = _shape_sums(px, pmx, onset, ramp, n)
        a0 = min(max(onset, 0), n)
        a1 = min(max(onset + int(ramp) - 1, 0), n)
        shift = onset - 1.0
        sff = ((squares[a1] - squares[a0] - 2.0 * shift * (pmv[a1] - pmv[a0]) + shift * shift * (pv[a1] - pv[a0]))
               / (ramp * ramp) + pv[n] - pv[a1])
        # the signature and the residuals projected off the nuisance (1, u, w)
        fx = sfx - (sf * bx0 + suf * bx1 + swf * bx2)
        ff = sff - (sf * (i00 * sf + i01 * suf + i02 * swf) + suf * (i01 * sf + i11 * suf + i12 * swf)
                    + swf * (i02 * sf + i12 * suf + i22 * swf))
        if ff <= 1e-9 * sff or fx * sign <= 0.0:
            continue
        llr = 0.5 * fx * fx / ff
        if llr > best:
            best, size, at = llr, fx / ff, onset
    return best, size, at


@njit(cache=True)
def evidence(s, c, sign, healthy=0):
    """The generalised likelihood ratios of the ring (:func:`attribute`), in units of the
    residual's own spread: ``(larger, step, ramp, step_size, ramp_size, step_onset,
    ramp_onset)``, the sizes in normalised units, of the sign ``sign`` (+1 or -1), the onsets as
    indices in the ring.

    The turn rate of the calibration's error: with ``healthy`` 1 (a GPS fault declared) the
    IR's, 2 (an IR fault) the GPS's averaged over its window, for both shapes; else by
    ``c[TURN_MODE]``: 0 the mean of the two sensors', 1 for each shape the sensor it holds
    healthy (the step, a GPS offset: the IR's; the ramp, an IR offset: the GPS's averaged over
    its window), 2 the GPS's averaged over its window."""
    x, mean, ir, smooth, time = _ring(s, c)
    scale = s[HELD_SCALE]
    ridge = scale / (c[SD_A_HELD] * c[SD_A_HELD])
    if c[SD_DRIFT] > 0.0:
        ridge_w = scale / (c[SD_DRIFT] * c[SD_DRIFT])
    else:  # no drift in the fit: its regressor zero, its coefficient pinned
        time[:] = 0.0
        ridge_w = 1.0
    if healthy == 1:
        step_turn, ramp_turn = ir, ir
    elif healthy == 2:
        step_turn, ramp_turn = smooth, smooth
    elif c[TURN_MODE] > 1.5:
        step_turn, ramp_turn = smooth, smooth
    elif c[TURN_MODE] > 0.5:
        step_turn, ramp_turn = ir, smooth
    else:
        step_turn, ramp_turn = mean, mean
    step, step_size, step_at = _best(x, step_turn, time, 1.0, sign, ridge, ridge_w)
    ramp, ramp_size, ramp_at = _best(x, ramp_turn, time, c[RAMP], sign, ridge, ridge_w)
    step, ramp = step / scale, ramp / scale
    return (step if step > ramp else ramp), step, ramp, step_size, ramp_size, step_at, ramp_at


@njit(cache=True)
def attribute(s, c, statistic):
    """Which sensor the consistency CUSUM's alarm comes from, by the shape of the residual in
    the ring: an offset of the GPS turn rate enters it as a step (the sample it starts), one of
    the IR as a ramp over the GPS window (``c[RAMP]`` samples, as the faulty samples fill the
    paired mean). A generalised likelihood ratio with each signature, the onset and size free,
    beyond an error of the calibration (:func:`_best`); log-likelihoods in units of
    the residual's own spread while no offset showed (``s[HELD_SCALE]``). A fault needs the
    better signature to reach ``c[SIGNIFICANCE]`` and to beat the other by ``c[MARGIN]``; once
    the CUSUM's ``statistic`` reaches ``c[DECISIVE]`` the better signature is declared whatever
    the margin and the significance. Returns ``(sensor, size, onset)``: 1 the GPS, 2 the IR, 0
    none or not yet told apart; the size in normalised units, the onset in the ring."""
    sign = 1.0 if s[CUSUM_CONS + G_UP] >= s[CUSUM_CONS + G_DOWN] else -1.0
    larger, step, ramp, step_size, ramp_size, step_at, ramp_at = evidence(s, c, sign)
    if larger > s[RUN_PEAK]:
        s[RUN_PEAK] = larger
    sensor, size, onset = (1, step_size, step_at) if step >= ramp else (2, ramp_size, ramp_at)
    if statistic >= c[DECISIVE] and larger > 0.0:
        return sensor, size, onset
    if larger < c[SIGNIFICANCE]:
        return 0, 0.0, 0
    if n_ring(s) - 1 - onset < c[COMPLETE]:  # too little of the shape yet: the other may still fit better
        return 0, 0.0, 0
    if abs(step - ramp) > c[MARGIN]:
        return sensor, size, onset
    return 0, 0.0, 0
