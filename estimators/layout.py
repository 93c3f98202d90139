"""The layouts of the compiled estimators' vectors, each declared once.

Every layout (inputs, configuration, state, outputs, gains, scratch, error sums) is a tuple of
``(name, size)`` pairs; the compiled code (:mod:`quadcosim.estimators.core` and the filters'
own modules) reads slots by the constants derived here from those names, never by bare
positions. ``benchmarks/c/batch_explicit.c`` numbers its slots as these layouts do.
"""

from __future__ import annotations


def _offsets(layout):
    """{name: (start, stop)} of consecutive slots declared as (name, size) pairs."""
    slots, start = {}, 0
    for name, size in layout:
        slots[name] = (start, start + size)
        start += size
    return slots, start


# the configuration's codes: the quaternion update (exponential map, Euler step), the passive filter's R_y
EXP, EULER = 0, 1
REEL, TRIAD = 0, 1

INPUT_LAYOUT = (("acc", 3), ("gyro", 3), ("mag", 3), ("R_reel", 9))
INPUT_SLOTS, INPUT_SIZE = _offsets(INPUT_LAYOUT)
ACC, GYRO, MAG, R_Y = (INPUT_SLOTS[n][0] for n in ("acc", "gyro", "mag", "R_reel"))

CONFIG_LAYOUT = (("gravity", 3), ("earth_field", 3), ("discretisation", 1), ("ry", 1))
CONFIG_SLOTS, CONFIG_SIZE = _offsets(CONFIG_LAYOUT)
GRAVITY, FIELD, DISCRETE, RY = (CONFIG_SLOTS[n][0] for n in ("gravity", "earth_field", "discretisation", "ry"))

# "pending" is 1 until the first sample has set the attitude from TRIAD (initial="triad");
# "started" is 0 until the first sample has set the low-pass filters (rest detector, specific force);
# "acc_filter", "mag_filter": the two delay vectors of the low-passes of specific force and field,
# body coordinates; "field_reference" and "field_candidate": (norm, dip) of the accepted field
# and of the candidate one, "candidate_time" how long the candidate has held (s); "rejection_time" how
# long the magnetometer has been rejected, less twice the time it has been accepted since (s)
STATE_LAYOUT = (("q", 4), ("b", 3), ("theta", 3), ("gyro_lowpass", 3), ("acc_lowpass", 3), ("rest_time", 1),
                ("pending", 1), ("started", 1), ("acc_filter", 6), ("mag_filter", 6), ("field_reference", 2),
                ("field_candidate", 2), ("candidate_time", 1), ("rejection_time", 1))
STATE_SLOTS, STATE_SIZE = _offsets(STATE_LAYOUT)
Q, B, THETA, GYRO_LP, ACC_LP, REST_TIME, PENDING, STARTED, ACC_FILTER, MAG_FILTER = (STATE_SLOTS[n][0] for n in (
    "q", "b", "theta", "gyro_lowpass", "acc_lowpass", "rest_time", "pending", "started", "acc_filter", "mag_filter"))
FIELD_REF, FIELD_CANDIDATE, CANDIDATE_TIME, REJECTION_TIME = (STATE_SLOTS[n][0] for n in (
    "field_reference", "field_candidate", "candidate_time", "rejection_time"))

# weights: accelerometer weight, magnetometer weight (0..1), at rest (0 or 1)
OUTPUT_LAYOUT = (("q", 4), ("theta", 3), ("b", 3), ("omega", 3), ("weights", 3))
OUTPUT_SLOTS, OUTPUT_SIZE = _offsets(OUTPUT_LAYOUT)
OUT_Q, OUT_THETA, OUT_B, OUT_OMEGA, OUT_WEIGHTS = (OUTPUT_SLOTS[n][0] for n in ("q", "theta", "b", "omega", "weights"))

# Gains and correction settings, one vector per gain set: the gains are the filters' own (their modules say
# their units and meanings), the settings :mod:`quadcosim.estimators.corrections`'.
GAIN_NAMES = ("k1", "k2", "k3", "kP", "kI", "heading_only", "acc_tolerance", "mag_norm_tolerance",
              "mag_dip_tolerance", "rest_gyro", "rest_acc", "rest_time", "rest_gain",
              "acc_lowpass", "mag_lowpass", "mag_reference_time", "bias_clip", "heading_level", "rest_deviation",
              "mag_new_min_gyro", "mag_rejection_time", "correct_at_sample",
              "mag_new_time", "mag_first_time", "heading_angle", "mag_scale_time")
GAIN_SLOTS = {name: i for i, name in enumerate(GAIN_NAMES)}
GAIN_SIZE = len(GAIN_NAMES)
K1, K2, K3, KP, KI = (GAIN_SLOTS[n] for n in ("k1", "k2", "k3", "kP", "kI"))
HEADING_ONLY, ACC_TOL, MAG_NORM_TOL, MAG_DIP_TOL = (GAIN_SLOTS[n] for n in (
    "heading_only", "acc_tolerance", "mag_norm_tolerance", "mag_dip_tolerance"))
REST_GYRO, REST_ACC, REST_MIN_TIME, REST_GAIN = (GAIN_SLOTS[n] for n in ("rest_gyro", "rest_acc", "rest_time",
                                                                          "rest_gain"))
ACC_LOWPASS, MAG_LOWPASS, MAG_REF_TIME, BIAS_CLIP = (GAIN_SLOTS[n] for n in ("acc_lowpass", "mag_lowpass",
                                                                             "mag_reference_time", "bias_clip"))
HEADING_LEVEL, REST_DEVIATION, MAG_NEW_MIN_GYRO, MAG_REJECTION_TIME, CORRECT_AT_SAMPLE = (GAIN_SLOTS[n] for n in (
    "heading_level", "rest_deviation", "mag_new_min_gyro", "mag_rejection_time", "correct_at_sample"))
MAG_NEW_TIME, MAG_FIRST_TIME, HEADING_ANGLE, MAG_SCALE_TIME = (GAIN_SLOTS[n] for n in (
    "mag_new_time", "mag_first_time", "heading_angle", "mag_scale_time"))

REST_LOWPASS_TAU = 0.5  # s, time constant of the low-pass filters of the rest detector
REJECTION_SLOWDOWN = 0.5  # magnetometer weight once rejected for longer than mag_rejection_time (VQF's factor 2)
REJECTION_RECOVERY = 2.0  # the rejection time runs back this many times faster while the field is accepted (VQF's)
SMALL_ANGLE = 1e-12  # rad: a smaller rotation in one step is integrated to first order (sin x = x)
WORK_LAYOUT = (("R", 9), ("omega", 3), ("R_y", 9), ("v_up", 3), ("v_field", 3), ("scratch", 3), ("acc", 3),
               ("mag", 3))
WORK_SLOTS, WORK_SIZE = _offsets(WORK_LAYOUT)
W_R, W_OMEGA, W_RY, W_UP, W_FIELD, W_SCRATCH, W_ACC, W_MAG = (WORK_SLOTS[n][0] for n in (
    "R", "omega", "R_y", "v_up", "v_field", "scratch", "acc", "mag"))
# error sums of the in-loop reduction, per gain set
ERROR_LAYOUT = (("total2", 1), ("inclination2", 1), ("heading2", 1), ("heading_sin", 1), ("heading_cos", 1),
                ("count", 1))
ERROR_SLOTS, ERROR_SIZE = _offsets(ERROR_LAYOUT)
E_TOTAL, E_INCL, E_HEAD, E_SIN, E_COS, E_COUNT = range(ERROR_SIZE)
