"""Fault detection of the Kalman filter: which sensor is wrong, from when to when.

The filter follows the drift of ``a`` and ``b`` with random walks fast enough for a cloud, so
it absorbs a small offset of either sensor into ``b`` (and ``a``) within a second or two, and
its own innovations show the offset only meanwhile. The detector therefore watches what the
filter cannot absorb: the GPS-IR consistency residual ``IR_pair - (a gps + b)`` against a
calibration *held* from before (:func:`consistency`).

- **The held calibration.** The filter's of ``held_lag`` samples before; once the residual's
  two-sided CUSUM (Page, "Continuous inspection schemes", Biometrika 1954; ``g = max(0, g + z -
  k)`` on ``z = nu / sqrt(S)`` and on ``-z``) leaves zero, it stays the one the run started
  against (``freeze``), so an offset keeps showing for as long as it lasts, however much the
  filter absorbs; the run restarts when it outlasts the ring of past calibrations.
- **The IR it takes.** The mean over the GPS window of every IR sample, those the present-IR
  gate keeps out of the filter included (``raw``): a large IR offset is gated out of the
  filter's pairs, not out of the detector's view.
- **Declaration and attribution.** Above its threshold the CUSUM's alarm is examined by a
  generalised likelihood ratio on the residual's last ``RING_SIZE`` samples, against the
  calibration from before them (:func:`attribute`): a GPS offset enters the residual as a step,
  an IR offset as a ramp over the GPS window (the faulty samples fill the paired mean). Each
  shape is fitted, onset and size free, beside an error of that calibration, ``delta_b +
  delta_a u`` (a turn exposes an error of ``a``), ``delta_a`` with a Gaussian prior; ``u`` is the
  GPS turn rate averaged over the GPS window (``turn="smoothed"``): the residual holds the GPS
  noise, which the raw GPS or the mean of the sensors' rates would carry into ``u`` and let
  ``delta_a`` explain, offset and all, in straight flight. A fault is declared on the better
  shape once it is significant and clearly the better. ``a`` and ``b`` go back to the held
  calibration; the faulty sensor is no longer fused (the IR: ``a`` and ``b`` held, the turn
  rate from the GPS; the GPS: the IR alone, ``a`` and ``b`` held).
- **The end** (``end="consistency"``): the same residual, the same ring and fit, watched for
  the residual stepping back against the offset's sign by at least half of it; a turn that
  exposes the held calibration's error of ``a`` meanwhile is no end. Then every detector
  restarts, ``a`` and ``b`` are reopened (their variances raised back to the initial ones) and,
  after an IR fault, the pairs are not fused until the window is clean.
  (``end="innovation"``: a CUSUM of the log-likelihood ratio "no offset" against "the offset
  estimated" on the faulty sensor's innovation, which a turn exposing that error of ``a`` can
  end early.)
- **Only while both sensors are in use**: with the GPS gone (not valid, or not used after a
  calibration phase) an offset of the IR cannot be told from a drift of ``b``, and nothing
  would replace the IR.
- **The filter's innovations.** Beside the gate (a single measurement outside ``gamma``
  standard deviations is not fused), CUSUMs on the normalised innovations: the present IR
  against the state declares a large IR offset at its first samples, a second before it reaches
  the pairs (its allowance ``now_k`` above what a turn reversal over the GPS lag gives); the
  GPS and the paired IR (``cusum_h``, off by default: the consistency residual sees the same
  offsets without the turn's lag, which made them declare faults in hard turns). When one
  declares a fault, ``a`` and ``b`` are set back to their values at the last sample where every
  statistic was zero.
- **The end of an absorbed offset** (``alt_ended``): when a declaration ends, the calibration
  it held, from before the offset, is remembered for longer than an offset lasts
  (:func:`_remember_alt`). If the end came early, the filter absorbs the rest of the offset; when
  the offset then stops, the change back is taken for a return to that calibration (it is put
  back, no fault declared, :func:`_returned`) rather than for a new fault, which, ``a`` and
  ``b`` held at the absorbed calibration, would never clear. Tested on the faults of both the
  consistency residual and the innovations' CUSUMs (``alt_innovation``).
- **The end of an offset missed from its start** (``plateau``): no declaration ever held a
  calibration for it, so nothing is remembered; the filter absorbed it in a few seconds and sat
  at the absorbed calibration until it ended. A slow ring keeps ``a`` and ``b`` once a second
  for 160 s; a change about to be declared is taken for a return when, at the present turn
  rate, those calibrations show a plateau at the present one for at least 30 s and, just before
  it, a calibration the change brings the sensors back to (:func:`_plateau_return`). The
  cloud's ramps and the filter's catching up after them leave no plateau that long before a
  GPS fault 10 s after the cloud's exit, and the plateau may stray by a bounded number of counts
  only, whatever the change, so that a large fault does not take the cloud's full cover for one.
  After any return the paired IR is left unwatched for the GPS window's span
  (``return_hold``): after an IR offset's end the window still holds offset samples.
- **Options measured and left off**: ``decisive`` (declare on the better shape whatever the
  fit, once the CUSUM's statistic is that strong: under a frozen calibration the statistic grows
  with the cloud's drift too) and ``alt_level`` (remember the calibration from before a change
  the fit saw but could not confirm, and take a later opposite change back to it for the end of
  an absorbed offset rather than a fault: it also takes real faults for returns), and
  likewise ``alt_restart`` (the calibration of a run that outlasts the ring) and ``alt_moved``
  (the calibration of 10 s before a fast move of ``a`` and ``b``): both end missed offsets
  without a fault, and both remember the cloud's calibration, which a real GPS fault 10 s after
  the cloud's exit then returns to.
  ``studies/ir_detection.py`` measures each choice.
"""

from __future__ import annotations

import math

from numba import njit
from quadcosim.calibration.infrared.attribution import attribute, evidence, n_ring
from quadcosim.calibration.infrared.layout import (
    A_SAFE,
    ALT_A,
    ALT_B,
    ALT_CHECK,
    ALT_ENDED,
    ALT_FRACTION,
    ALT_INNOVATION,
    ALT_LEFT,
    ALT_LEVEL,
    ALT_LIFE,
    ALT_MOVED,
    ALT_NEEDS_RUN,
    ALT_RESTART,
    ALT_RUN,
    ALT_SHIFT,
    ALT_SPAN,
    ALT_WAIT,
    ANCHOR,
    B_SAFE,
    CONS_H,
    CONS_K,
    CONS_OFFSET,
    CUSUM_CONS,
    CUSUM_GPS,
    CUSUM_H,
    CUSUM_K,
    CUSUM_NOW,
    CUSUM_PAIR,
    CUSUM_SIZE,
    END_H,
    END_LLR,
    END_MODE,
    END_PAIR,
    END_SIGNIFICANCE,
    END_STAT,
    END_TURN,
    FAULT_SIZE,
    FREEZE,
    G_DOWN,
    G_UP,
    GAMMA2,
    GATE_CONS,
    GATE_GPS,
    GATE_IR,
    GATE_NOW,
    GPS_FAULT,
    HELD_FAULT,
    HELD_GPS,
    HELD_IR,
    HELD_LAG,
    HELD_SCALE,
    HOLD,
    IR_FAULT,
    IR_SUSPECT,
    LAG,
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
    PLATEAU_FLAT,
    PLATEAU_FLAT_MAX,
    PLATEAU_MATCH,
    PLATEAU_MIN,
    PLATEAU_MOVE,
    PLATEAU_SKIP,
    PLATEAU_VAR,
    PRR,
    RAMP,
    RETURN_HOLD,
    RG,
    RI,
    RI1,
    RING,
    RING_COUNT,
    RING_SIZE,
    RUN_PEAK,
    SCALE_GAIN,
    SETTLING,
    SIZE_GAIN,
    SLOW,
    SLOW_COUNT,
    SLOW_EVERY,
    SLOW_SIZE,
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
    """The paired IR ``ir_pair`` (count) against the GPS turn rate ``gps`` (rad/s) through a
    held calibration (:func:`remember_calibration`): the residual ``ir_pair - (a gps + b)``
    (count) and its variance (count^2) under the filter's noise model and the covariance that
    calibration had, stored in the state ``s``. The filter itself absorbs an offset into ``b``
    (and ``a``) within a second or two; the calibration held from before the offset does not.

    The held calibration is that of ``c[HELD_LAG]`` samples before; with ``c[FREEZE]``, once the
    residual's CUSUM runs (its statistic above zero) it stays the one the run started against,
    so that an offset the filter absorbs meanwhile keeps showing, until the statistic falls back
    to zero, or the run outlasts the ring of past calibrations (it then restarts)."""
    count = int(s[PAST_COUNT])
    running = s[CUSUM_CONS + G_UP] > 0.0 or s[CUSUM_CONS + G_DOWN] > 0.0
    if c[FREEZE] > 0.5 and running and count - int(s[ANCHOR]) < PAST_SIZE - 1:
        index = int(s[ANCHOR])
    else:
        if c[FREEZE] > 0.5 and running:  # too long a run to keep its calibration: it starts again
            _run_over(s, c, True)
            for j in range(CUSUM_SIZE):
                s[CUSUM_CONS + j] = 0.0
        index = count - int(c[HELD_LAG])
        s[ANCHOR] = index
    held = PAST + index % PAST_SIZE
    a = s[held]
    s[NU_CONS] = ir_pair - (a * gps + s[held + PAST_SIZE]) - s[CONS_OFFSET]
    s[HELD_GPS] = gps
    s[HELD_IR] = ir_pair
    var_a, cov_ab, var_b = s[held + 2 * PAST_SIZE], s[held + 3 * PAST_SIZE], s[held + 4 * PAST_SIZE]
    s[GATE_CONS] = a * a * c[RG] + c[RI]
    if s[HELD_FAULT] < 0.5:  # during a fault the offset followed holds the calibration's error, whose variance grows
        s[GATE_CONS] += gps * (gps * var_a + 2.0 * cov_ab) + var_b


@njit(cache=True)
def _run_over(s, c, restarted):
    """The consistency CUSUM's run ends (its statistic back to zero, or ``restarted`` after
    outlasting the ring of past calibrations) without a fault declared. The filter has absorbed
    what the run saw if the attribution saw an abrupt change in it (a log-likelihood of at least
    ``c[ALT_LEVEL]``) that it could not confirm, or (with ``c[ALT_RESTART]``) if the residual
    stayed off the calibration the run was held against for as long as the ring lasts: that
    calibration, from before the change, is remembered (:func:`_remember_alt`)."""
    peaked = s[RUN_PEAK] >= c[ALT_LEVEL] or (restarted and c[ALT_RESTART] > 0.5)
    if s[HELD_FAULT] < 0.5 and peaked and int(s[PAST_COUNT]) - int(s[ANCHOR]) < PAST_SIZE:
        held = PAST + int(s[ANCHOR]) % PAST_SIZE
        _remember_alt(s, c, s[held], s[held + PAST_SIZE], False)
    s[RUN_PEAK] = 0.0


@njit(cache=True)
def _remember_alt(s, c, a, b, force):
    """Remember the calibration ``a``, ``b`` from before a change the filter may have absorbed,
    for ``c[ALT_LIFE]`` samples (longer than an offset lasts), so that the offset's end is taken
    for a return to it rather than a new fault (:func:`_returned`). A calibration already
    remembered is kept unless ``force`` (a declaration ended: the calibration it held is the one
    from before the offset). ``c[ALT_WAIT]`` samples later it is forgotten if ``a`` and ``b``
    have not moved ``c[ALT_SHIFT]`` away from it (:func:`_check_alt`): nothing was absorbed."""
    if s[ALT_LEFT] > 0.0 and not force:
        return
    s[ALT_A], s[ALT_B] = a, b
    s[ALT_LEFT] = c[ALT_LIFE]
    s[ALT_CHECK] = c[ALT_WAIT]


@njit(cache=True)
def _check_alt(s, c):
    """One sample of the remembered calibration's life (:func:`_remember_alt`): forgotten when
    it is over, or when ``a`` and ``b`` have not moved from it by ``c[ALT_SHIFT]`` (count, at the
    present turn rate) ``c[ALT_WAIT]`` samples after it was remembered. With none remembered,
    the oldest calibration of the ring of past ones is, if ``a`` and ``b`` have moved from it by
    ``c[ALT_MOVED]`` (count, at the present turn rate): an offset missed, being absorbed."""
    count = int(s[PAST_COUNT])
    if s[ALT_RUN] > 0.0:
        s[ALT_RUN] -= 1.0
    seen = s[ALT_RUN] > 0.0 or c[ALT_NEEDS_RUN] < 0.5  # the residual saw a change (a drift the filter follows unseen)
    if seen and count >= PAST_SIZE and (s[ALT_LEFT] <= 0.0 or c[ALT_LIFE] - s[ALT_LEFT] >= PAST_SIZE):
        # a and b moved fast, no fault declared: the filter may be absorbing an offset (the latest such move wins)
        old = PAST + (count - PAST_SIZE + 1) % PAST_SIZE  # remembered: the oldest, before the move's start
        recent = PAST + (count - int(c[ALT_SPAN])) % PAST_SIZE
        moved = (s[A] - s[recent]) * s[HELD_GPS] + s[B] - s[recent + PAST_SIZE]
        away = abs((s[A] - s[ALT_A]) * s[HELD_GPS] + s[B] - s[ALT_B])  # a move back to the one remembered keeps it
        before = abs((s[old] - s[ALT_A]) * s[HELD_GPS] + s[old + PAST_SIZE] - s[ALT_B])
        if abs(moved) >= c[ALT_MOVED] and (s[ALT_LEFT] <= 0.0 or away > before - 0.5 * abs(moved)):
            _remember_alt(s, c, s[old], s[old + PAST_SIZE], True)
            s[ALT_CHECK] = 0.0  # it has moved already
    if s[ALT_LEFT] <= 0.0:
        return
    s[ALT_LEFT] -= 1.0
    if s[ALT_CHECK] > 0.0:
        s[ALT_CHECK] -= 1.0
        moved = (s[A] - s[ALT_A]) * s[HELD_GPS] + s[B] - s[ALT_B]
        if s[ALT_CHECK] <= 0.0 and abs(moved) < c[ALT_SHIFT]:
            s[ALT_LEFT] = 0.0


@njit(cache=True)
def _returned(s, c, d, a, b):
    """Whether the change ``d`` (count, in the consistency residual) about to be declared, seen
    against the calibration ``a``, ``b``, brings the sensors back to the calibration remembered
    (:func:`_remember_alt`): an offset the filter absorbed earlier, ending. Against that
    calibration the residual would be ``d + delta``, ``delta`` the two calibrations' difference
    at the present turn rate; it is a return when that is less than ``c[ALT_FRACTION]`` of ``d``."""
    if s[ALT_LEFT] <= 0.0:
        return False
    delta = (a - s[ALT_A]) * s[HELD_GPS] + b - s[ALT_B]
    return abs(d + delta) < c[ALT_FRACTION] * abs(d)


@njit(cache=True)
def _plateau_return(s, c, d, a, b):
    """Whether the change ``d`` (count, in the consistency residual) about to be declared, seen
    against the calibration ``a``, ``b``, ends an offset the filter absorbed unseen: the slow
    ring of past calibrations (one per second) shows, at the present turn rate, a plateau at
    ``a``, ``b`` (within ``c[PLATEAU_FLAT]`` of ``|d|``) for at least ``c[PLATEAU_MIN]`` entries
    before the newest ``c[PLATEAU_SKIP]`` (the change itself), and within ``c[PLATEAU_MOVE]``
    entries before that plateau a calibration the change brings the sensors back to (against
    it the residual would be ``d`` minus their difference, less than ``c[PLATEAU_MATCH]`` of
    ``|d|``): the absorbed offset's start, a move of ``-d``. That calibration is left in
    ``ALT_A``, ``ALT_B`` (:func:`_take_back`). The cloud's ramps and the filter's catching up
    after them leave no plateau that long before the GPS fault that follows."""
    if c[PLATEAU_MIN] <= 0.0:
        return False
    count = int(s[SLOW_COUNT])
    n = count if count < SLOW_SIZE else SLOW_SIZE
    u = s[HELD_GPS]
    flat, match = min(c[PLATEAU_FLAT] * abs(d), c[PLATEAU_FLAT_MAX]), c[PLATEAU_MATCH] * abs(d)
    m = int(c[PLATEAU_SKIP])
    while m < n:  # back along the plateau, newest first
        slot = SLOW + (count - 1 - m) % SLOW_SIZE
        if not abs((s[slot] - a) * u + s[slot + SLOW_SIZE] - b) <= flat:  # nan too: not learnt then
            break
        m += 1
    if m - c[PLATEAU_SKIP] < c[PLATEAU_MIN]:
        return False
    last = m + int(c[PLATEAU_MOVE])
    while m < n and m < last:  # the move that made it: does it start from where d returns to?
        slot = SLOW + (count - 1 - m) % SLOW_SIZE
        if abs((s[slot] - a) * u + s[slot + SLOW_SIZE] - b - d) < match:
            s[ALT_A], s[ALT_B] = s[slot], s[slot + SLOW_SIZE]
            return True
        m += 1
    return False


@njit(cache=True)
def _take_back(s, c):
    """A return recognised (:func:`_returned`): the remembered calibration back, no fault."""
    s[A], s[B] = s[ALT_A], s[ALT_B]
    s[ALT_LEFT] = 0.0
    reopen(s, c)
    if c[RETURN_HOLD] > 0.5:  # an IR offset's end: the paired window still holds offset samples
        s[HOLD] = c[WINDOW_SPAN]


@njit(cache=True)
def remember_calibration(s, c):
    """Keep this sample's ``a``, ``b`` and their covariance in the ring of past calibrations,
    and once a second ``a`` and ``b`` in the slow ring (``nan`` while the variance of ``b`` is
    above ``c[PLATEAU_VAR]``: not learnt yet, so neither a plateau nor where a change returns to)."""
    count = int(s[PAST_COUNT])
    slot = PAST + count % PAST_SIZE
    s[slot] = s[A]
    s[slot + PAST_SIZE] = s[B]
    s[slot + 2 * PAST_SIZE] = s[PAA]
    s[slot + 3 * PAST_SIZE] = s[PAB]
    s[slot + 4 * PAST_SIZE] = s[PBB]
    s[PAST_COUNT] = count + 1
    if count % SLOW_EVERY == 0:  # the slow ring (:func:`_plateau_return`)
        slow = int(s[SLOW_COUNT])
        slot = SLOW + slow % SLOW_SIZE
        learnt = s[PBB] <= c[PLATEAU_VAR]
        s[slot] = s[A] if learnt else math.nan
        s[slot + SLOW_SIZE] = s[B] if learnt else math.nan
        s[SLOW_COUNT] = slow + 1


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
    if c[ALT_ENDED] > 0.5:  # a and b were held from before the offset: if it lasts on, the filter absorbs it now
        _remember_alt(s, c, s[A], s[B], True)
    s[flag] = 0.0
    s[CONS_OFFSET] = 0.0
    s[HELD_FAULT] = 0.0
    s[SETTLING] = 0.0
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
def detect(s, c, gps_seen, pair_seen, raw_seen):
    """Declare, attribute and end faults from this sample's innovations (see the module).

    Parameters
    ----------
    s, c : float arrays
        EKF state (updated in place) and configuration.
    gps_seen : bool
        A GPS innovation was computed at this sample (``s[NU_GPS]``, ``s[GATE_GPS]``).
    pair_seen : bool
        A paired IR innovation was computed (``s[NU_IR]``, ``s[GATE_IR]``).
    raw_seen : bool
        The consistency residual's IR was there (:func:`consistency`).
    """
    if s[IR_FAULT] > 0.5:
        s[IR_SUSPECT] = 0.0  # the IR is not fused: its samples may fill the window the end test watches
    if s[HELD_FAULT] > 0.5 and c[END_MODE] > 0.5:
        if gps_seen:
            _end_held(s, c, raw_seen)
        return
    if s[GPS_FAULT] > 0.5:
        if gps_seen:
            _end_gps(s, c)
        return
    if s[IR_FAULT] > 0.5:
        _end_ir(s, c, pair_seen)
        return
    _check_alt(s, c)
    if s[HOLD] > 0.0:
        s[HOLD] -= 1.0
        pair_seen = False
        raw_seen = False
    if not gps_seen:  # one sensor alone: a drift and a fault look alike, and nothing would replace it
        _remember(s, math.nan, math.nan, math.nan)
        return
    gps = cusum(s, CUSUM_GPS, s[NU_GPS], s[GATE_GPS], c[CUSUM_K], c[CUSUM_H]) if gps_seen else -1.0
    pair = cusum(s, CUSUM_PAIR, s[NU_IR], s[GATE_IR], c[CUSUM_K], c[CUSUM_H]) if pair_seen else -1.0
    now = cusum(s, CUSUM_NOW, s[NU_NOW], s[GATE_NOW], c[NOW_K], c[NOW_H])
    held = _held(s, c, raw_seen)
    ir = pair if pair > now else now
    if gps <= 0.0 and ir <= 0.0:
        sensor, size, onset = attribute(s, c, (held + 1.0) * c[CONS_H]) if held > 0.0 else (0, 0.0, 0)
        if sensor == 0:  # nothing, or a small offset whose sensor the residual does not tell yet
            if _quiet(s):
                s[A_SAFE], s[B_SAFE] = s[A], s[B]
            return
        ref = PAST + (int(s[PAST_COUNT]) - n_ring(s)) % PAST_SIZE  # the calibration the ring is seen against
        d, a, b = size * math.sqrt(s[GATE_CONS]), s[ref], s[ref + PAST_SIZE]
        if _returned(s, c, d, a, b) or _plateau_return(s, c, d, a, b):
            _take_back(s, c)  # the end of an offset absorbed earlier: its calibration back, no fault
        else:
            _declare_held(s, c, sensor, size, onset)
    elif c[ALT_INNOVATION] > 0.5 and (_returned(s, c, _innovation_step(s, gps, pair, now, ir), s[A_SAFE], s[B_SAFE])
                                      or _plateau_return(s, c, _innovation_step(s, gps, pair, now, ir), s[A_SAFE],
                                                         s[B_SAFE])):
        _take_back(s, c)
    else:
        _declare(s, c, gps, pair, now, ir)
    s[END_STAT] = 0.0
    s[END_PAIR] = -1.0  # not armed
    restart(s)


@njit(cache=True)
def _end_held(s, c, pair_seen):
    """The end test of a fault (``c[END_MODE]`` 1): the consistency residual, watched as before
    the fault (:func:`_held`), must step back, against the offset's sign, by at least half of
    it, with a significant signature (:func:`evidence`, either shape). An error of the held
    calibration that a turn exposes meanwhile is no end (the signature's fit holds it). An IR
    offset is watched once it has filled the paired window (``s[SETTLING]``)."""
    s[END_LLR] = 0.0
    if s[SETTLING] > 0.0:  # the offset is still entering the paired window: no baseline for its end yet
        s[SETTLING] -= 1.0
        s[RING_COUNT] = 0.0
        return
    _held(s, c, pair_seen)
    if not pair_seen:
        return
    offset = s[CONS_OFFSET]
    healthy = 0 if c[END_TURN] < 0.5 else (1 if s[GPS_FAULT] > 0.5 else 2)  # 1, 2: the sensor not faulty's
    larger, step, ramp, step_size, ramp_size, step_at, ramp_at = evidence(s, c, -1.0 if offset > 0.0 else 1.0,
                                                                            healthy)
    size, onset = (step_size, step_at) if step >= ramp else (ramp_size, ramp_at)
    if abs(size) * math.sqrt(s[GATE_CONS]) < 0.5 * abs(offset):
        return
    s[END_LLR] = larger
    if larger < c[END_SIGNIFICANCE]:
        return
    if s[IR_FAULT] > 0.5:  # the paired window may still hold faulty samples: not fused until it does not
        left = c[RAMP] - (n_ring(s) - onset)
        _ended(s, c, IR_FAULT)
        s[HOLD] = left if left > 0.0 else 0.0
    else:
        _ended(s, c, GPS_FAULT)


@njit(cache=True)
def _held(s, c, pair_seen):
    """The consistency CUSUM on this sample's residual (how far over its threshold, in
    thresholds; -1 when it is zero or there is no residual), the sample kept in the ring, and
    the residual's spread followed while its statistic is zero."""
    if not pair_seen:
        _remember(s, math.nan, math.nan, math.nan)
        return -1.0
    _remember(s, s[HELD_IR] - s[CONS_OFFSET], s[HELD_GPS], s[GATE_CONS])
    running = s[CUSUM_CONS + G_UP] > 0.0 or s[CUSUM_CONS + G_DOWN] > 0.0
    held = cusum(s, CUSUM_CONS, s[NU_CONS], s[GATE_CONS], c[CONS_K], c[CONS_H])
    if held > -1.0:
        s[ALT_RUN] = PAST_SIZE
    if running and held == -1.0:
        _run_over(s, c, False)
    if held == -1.0 and s[HELD_FAULT] < 0.5:  # its statistic is zero: no offset shows, the residual is noise and drift
        z = s[NU_CONS] / math.sqrt(s[GATE_CONS])
        s[HELD_SCALE] += c[SCALE_GAIN] * (z * z - s[HELD_SCALE])
    return held


@njit(cache=True)
def _innovation_step(s, gps, pair, now, ir):
    """The change (count, in the consistency residual) that the CUSUM of the GPS, the paired IR
    or the present IR (how far each is over its threshold) would declare (:func:`_declare`)."""
    if gps > ir:
        return -s[A_SAFE] * run_mean(s, CUSUM_GPS)
    return run_mean(s, CUSUM_PAIR) if pair > now else run_mean(s, CUSUM_NOW)


@njit(cache=True)
def _declare(s, c, gps, pair, now, ir):
    """A fault declared by the CUSUM of the GPS, the paired IR or the present IR (how far each
    is over its threshold): the furthest names the sensor, its run the offset. With
    ``c[END_MODE]`` its end is watched on the consistency residual too (:func:`_end_held`):
    the offset there, and for the present IR the wait until it has entered the paired window."""
    s[A], s[B] = s[A_SAFE], s[B_SAFE]  # what the faulty sensor pulled a and b by before the alarm, undone
    if gps > ir:
        s[GPS_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_GPS)
        s[CONS_OFFSET] = -s[A] * s[FAULT_SIZE]
    else:
        s[IR_FAULT] = 1.0
        s[FAULT_SIZE] = run_mean(s, CUSUM_PAIR) if pair > now else run_mean(s, CUSUM_NOW)
        s[CONS_OFFSET] = s[FAULT_SIZE]
        s[SETTLING] = c[WINDOW_SPAN] if now >= pair else c[RAMP]
    s[HELD_FAULT] = 1.0 if c[END_MODE] > 0.5 else 0.0


@njit(cache=True)
def _declare_held(s, c, sensor, size, onset):
    """A fault declared by the consistency CUSUM, on the ``sensor`` :func:`attribute` named
    (1 the GPS, 2 the IR), of normalised ``size``, fitted to start at ``onset`` in the ring: the
    offset in the units of that sensor's innovation end test (the GPS: rad/s, ``-d / a``; the IR:
    count) and in the residual's (count). ``a`` and ``b`` go back to the held calibration, from
    before the offset."""
    offset = size * math.sqrt(s[GATE_CONS])
    held = PAST + int(s[ANCHOR]) % PAST_SIZE
    s[A], s[B] = s[held], s[held + PAST_SIZE]  # the calibration from before the offset
    s[CONS_OFFSET] = offset
    s[HELD_FAULT] = 1.0 if c[END_MODE] > 0.5 else 0.0
    if sensor == 2:  # the end test waits until the IR's ramp is whole
        left = c[RAMP] - (n_ring(s) - onset)
        s[SETTLING] = left if left > 0.0 else 0.0
    if sensor == 1:
        s[GPS_FAULT] = 1.0
        s[FAULT_SIZE] = -offset / s[A]
    else:
        s[IR_FAULT] = 1.0
        s[FAULT_SIZE] = offset
