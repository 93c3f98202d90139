"""Layouts of the estimators' state and configuration vectors: one index per quantity.

The step functions (:mod:`quadcosim.calibration.infrared.filters`, :mod:`quadcosim.calibration.infrared.detection`)
work on flat float arrays so that numba compiles them and the batch path and the streaming
block share them; these constants name the entries.
"""

# EKF state vector s: estimate, covariance (upper triangle), faults, last innovations, detectors.
A, B, R = 0, 1, 2
PAA, PAB, PAR, PBB, PBR, PRR = 3, 4, 5, 6, 7, 8
GPS_FAULT, IR_FAULT, FAULT_SIZE, END_STAT = 9, 10, 11, 12
END_PAIR = 42  # the end test on the paired IR (END_STAT: on the present IR, or the GPS)
A_SAFE, B_SAFE = 43, 44  # a and b when no detector last saw anything: restored when a fault is declared
HOLD = 45  # samples left before the paired IR is watched again after an IR fault (its window still holds it)
NU_GPS, GATE_GPS, NU_IR, GATE_IR, RATE, STATUS = 13, 14, 15, 16, 17, 18
GPS_USED, IR_USED, IR_SUSPECT, NU_NOW, GATE_NOW = 19, 20, 21, 22, 23
# one two-sided CUSUM per innovation: the GPS, the paired IR, the present IR
CUSUM_GPS, CUSUM_PAIR, CUSUM_NOW = 24, 30, 36
# inside a CUSUM: statistic, sum of the raw innovations and count of its run, upwards then downwards
G_UP, SUM_UP, N_UP, G_DOWN, SUM_DOWN, N_DOWN = range(6)
CUSUM_SIZE = 6
# the GPS-IR consistency residual against the held calibration, its variance, its CUSUM, the
# running mean square of its normalised values while no offset shows, the GPS turn rate and the
# paired IR it was taken from, the index (in the ring of past calibrations) of the calibration it
# is held against while its CUSUM runs (ANCHOR; -1 when none is frozen), the ring of the samples
# since the last restart that attributes a fault (paired IR, then GPS turn rate, then the
# residual's variance), and the ring of the past calibrations (a, b, then their covariance PAA,
# PAB, PBB; one per sample)
NU_CONS, GATE_CONS, CUSUM_CONS, RING_COUNT, HELD_SCALE, HELD_GPS, HELD_IR = 46, 47, 48, 54, 55, 56, 57
ANCHOR = 58
CONS_OFFSET, HELD_FAULT = 59, 60  # a declared fault's offset in the residual (count); 1: it was declared on it
RAW_PAIR = 61  # the mean IR over the GPS window, suspect samples included (count)
SETTLING = 62  # samples before the end test of a fault watches the residual: its onset is still coming in
# a calibration from before a change the residual showed but no fault was declared on (a and b), the samples it
# is kept for, and the largest attribution log-likelihood of the CUSUM's present run
ALT_A, ALT_B, ALT_LEFT, RUN_PEAK = 63, 64, 65, 66
END_LLR = 67  # the end test's log-likelihood at this sample, of a step back at least half the offset
ALT_CHECK = 68  # samples left before the remembered calibration is kept only if a and b have moved away from it
ALT_RUN = 69  # samples left for which the consistency CUSUM ran lately (a ring's span after its last run)
RING = 70
RING_SIZE = 60  # samples: 3 s at 20 Hz, the onset of the fault and the GPS window's ramp
PAST_COUNT = RING + 3 * RING_SIZE
PAST = PAST_COUNT + 1
PAST_SIZE = 200  # samples: the calibrations a frozen run may be held against (10 s at 20 Hz)
PAST_FIELDS = 5
# the slow ring of past calibrations: a and b once every SLOW_EVERY samples, for longer than an offset lasts, so that
# the end of an offset the filter absorbed unseen is told from a new fault by the plateau it leaves behind
SLOW_COUNT = PAST + PAST_FIELDS * PAST_SIZE
SLOW = SLOW_COUNT + 1
SLOW_EVERY = 20  # samples: 1 s at 20 Hz
SLOW_SIZE = 160  # entries: 160 s, longer than an offset (100 s) and the move that absorbed it
EKF_SIZE = SLOW + 2 * SLOW_SIZE
# EKF configuration c: process noise variances per sample, measurement variances, gate, detectors.
# WINDOW_SPAN: delay + window of the GPS pairing (samples), set by the estimator.
QA, QB, QR, RG, RI, GAMMA2, LAG, RI1, PA0, PB0 = range(10)
CUSUM_K, CUSUM_H, NOW_K, NOW_H, END_H, SIZE_GAIN, WINDOW_SPAN = range(10, 17)
# the consistency detector: allowance and threshold, attribution margin (log-likelihood), GPS window (samples),
# lag of the held calibration (samples), weight of its spread, significance, prior deviation of a's error,
# whether the held calibration is frozen while the CUSUM runs, the CUSUM statistic from which the better
# shape is declared whatever the fit, which turn rate the attribution takes (0: the mean of the two
# sensors'; 1: each hypothesis the healthy sensor's; 2: the GPS's averaged over its window), whether a
# fault ends by the residual stepping back (1) or by the faulty sensor's innovation (0), whether the residual
# takes the window's mean of every IR sample, suspect or not (1), or only the pair the filter fuses (0), the
# attribution log-likelihood above which a run that declared nothing leaves its calibration remembered,
# and for how many samples, the prior deviation of the residual's drift in the fit (count per sample), and the
# log-likelihood of a step back that ends a fault, and how many samples the better signature's onset must lie
# in the past before a fault is declared on it
CONS_K, CONS_H, MARGIN, RAMP, HELD_LAG, SCALE_GAIN, SIGNIFICANCE, SD_A_HELD = range(17, 25)
FREEZE, DECISIVE, TURN_MODE, END_MODE, RAW_SEEN, ALT_LEVEL, ALT_LIFE, SD_DRIFT = range(25, 33)
# and whether the end test takes the turn rate of the sensor held healthy (1) or the attribution's (0)
END_SIGNIFICANCE, COMPLETE, END_TURN = 33, 34, 35
# what leaves a calibration remembered for the end of an absorbed offset (ALT_LEVEL above): a fault's declaration
# ending (1) and a consistency run outlasting the ring of past calibrations (1); how far a and b must have moved
# from it (count, at the present turn rate) ALT_WAIT samples later for it to be kept; whether a fault the
# innovations' CUSUMs declare is tested for such a return too (1); how far (count, at the present turn rate) a and b
# must move within the ring of past calibrations, no fault declared, for the oldest there to be remembered; whether
# that needs the consistency CUSUM to have run meanwhile (1); the fraction of a change its return may miss by
# and the span (samples) within which a and b must move that far (a cloud's drift is slower, an absorbed offset fast)
ALT_ENDED, ALT_RESTART, ALT_SHIFT, ALT_WAIT, ALT_INNOVATION, ALT_MOVED, ALT_NEEDS_RUN, ALT_FRACTION = range(36, 44)
ALT_SPAN = 44
# the end of an offset absorbed unseen (the slow ring above): the entries (s) newest that the plateau skips (the
# change itself), the plateau's least length and the longest move before it (entries), and the fractions of the
# change by which the plateau may stray from the present calibration and the calibration before the move may miss
# the one the change returns to (0 length: off), and the variance of b (count^2) above which a calibration, not
# yet learnt, enters the slow ring as none; the most (count) the plateau may stray by whatever the change, and
# whether the paired IR is left unwatched for the GPS window's span after a return (1: it may still hold the offset)
PLATEAU_SKIP, PLATEAU_MIN, PLATEAU_MOVE, PLATEAU_FLAT, PLATEAU_MATCH, PLATEAU_VAR = range(45, 51)
PLATEAU_FLAT_MAX, RETURN_HOLD = 51, 52
EKF_CONFIG_SIZE = 53
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
