"""The infrared estimators' settings: the Kalman filter's and its detector's
(:class:`EKFSettings`), the slides' regression's (:class:`RegressionSettings`) and the recursive
least squares' (:class:`RLSSettings`), each checked when made and packed into the configuration
vector the compiled steps read.

Units: turn rate rad/s, IR in counts, ``a`` in counts per rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from quadcosim.calibration.infrared.layout import (
    A_SAFE,
    ALT_ENDED,
    ALT_FRACTION,
    ALT_INNOVATION,
    ALT_LEVEL,
    ALT_LIFE,
    ALT_MOVED,
    ALT_NEEDS_RUN,
    ALT_RESTART,
    ALT_SHIFT,
    ALT_SPAN,
    ALT_WAIT,
    ANCHOR,
    B_SAFE,
    COMPLETE,
    CONS_H,
    CONS_K,
    CUSUM_H,
    CUSUM_K,
    DECISIVE,
    EKF_CONFIG_SIZE,
    EKF_SIZE,
    END_H,
    END_MODE,
    END_SIGNIFICANCE,
    END_TURN,
    FIT_A,
    FIT_B,
    FREEZE,
    GAMMA2,
    HELD_LAG,
    HELD_SCALE,
    LAG,
    MARGIN,
    NOW_H,
    NOW_K,
    PA0,
    PAA,
    PAB,
    PAR,
    PAST,
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
    QA,
    QB,
    QR,
    RAW_SEEN,
    REG_SIZE,
    RETURN_HOLD,
    RG,
    RI,
    RI1,
    RING_SIZE,
    SCALE_GAIN,
    SD_A_HELD,
    SD_DRIFT,
    SIGNIFICANCE,
    SIZE_GAIN,
    SLOW_EVERY,
    SLOW_SIZE,
    TURN_MODE,
    A,
    B,
)


def _check_positive(name: str, value: float, unit: str, fix: str):
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} = {value!r} {unit} must be positive and finite; {fix}")


TURNS = ("mean", "healthy", "smoothed")  # the turn rates the attribution may take (EKFSettings.turn), in c[TURN_MODE]


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
        GPS turn-rate noise (rad/s). At the default 0.04 rad/s the filter trusts the GPS turn
        rate less than the window-mean IR (``sd_ir / |a0|`` = 0.0125 rad/s).
    sd_ir : float
        Noise of the window-mean IR (count), inflated for the overlap of successive windows.
    sd_ir_sample : float
        Noise of one IR sample (count), for the check of the present IR.
    sd_lag : float
        How much the turn rate may change over the GPS lag (rad/s), for the check of the
        present IR against the paired turn rate; it lets a fault of the IR be declared before
        it reaches the paired window, 1 s later.
    gate : float
        Innovation gate gamma in standard deviations; 0 turns gating and fault detection off.
    cusum_k, cusum_h : float
        Allowance and threshold (standard deviations) of the CUSUMs on the GPS and the paired
        IR innovations (:mod:`quadcosim.calibration.infrared.detection`); ``cusum_h = inf`` (the default)
        turns them off: the consistency residual sees the same offsets without the lag of the
        filter's turn rate, which made them declare faults in hard turn reversals (fault-free
        flights of seeds 1 to 2000: three; the earlier design's ``cusum_h = 10``).
    now_k, now_h : float
        The same for the present IR, whose variance includes the turn's change over the lag: it
        declares a large IR offset a second before it reaches the pairs. The allowance of 6
        standard deviations lies above what the hardest turn reversals of the fault-free
        flights of seeds 1 to 2000 give (the earlier design's 3.5 declared two faults there).
    held_k, held_h : float
        Allowance and threshold (standard deviations) of the two-sided CUSUM on the GPS-IR
        consistency residual against the held calibration
        (:func:`quadcosim.calibration.infrared.detection.consistency`), which finds the offsets the filter
        absorbs into ``b`` and ``a`` before its own innovations show them. The allowance is
        half the smallest offset it is meant for (a GPS +0.1 rad/s, 40 counts, 2.3 standard
        deviations); its alarm is only examined (:func:`~quadcosim.calibration.infrared.attribution.attribute`).
    held_lag : int
        How old the held calibration is (samples) while the CUSUM is at zero.
    freeze : bool
        Once the CUSUM runs, hold the calibration it started against until it falls back to
        zero (or the run outlasts the ring of past calibrations), rather than one ``held_lag``
        samples old, which absorbs a small offset within a second.
    margin : float
        Log-likelihood by which one sensor's signature in the consistency residual (the GPS:
        a step; the IR: a ramp over the GPS window) must beat the other's before a fault is
        declared on it, the residual scaled by its own spread: ``log 100``.
    significance : float
        Log-likelihood (the residual scaled by its own spread) that an offset starting inside
        the attribution ring must reach beyond an error of the calibration and a drift
        (``delta_b + delta_a u + beta t``) before a fault is declared. Set on the tuning seeds:
        on the fault-free flights of seeds 1 to 9000 the largest was 10.3; in the first 5 s of
        a GPS +0.1 rad/s offset on seeds 1 to 300 the smallest 25.0
        (``python -m quadcosim.studies.ir_detectability --calibrate``).
    sd_a_held : float
        Prior standard deviation of the held calibration's error of ``a`` (count per rad/s)
        in that test: the largest error of the filter's ``a`` 10 samples old on the fault-free
        flights of seeds 101 to 200 was 50.6.
    turn : {"smoothed", "mean", "healthy"}
        The turn rate ``u`` of that error: the GPS's averaged over the GPS window (its noise,
        which the residual holds, mostly out of it), the mean of the GPS's and the IR's (the
        earlier design: in straight flight the error of ``a`` then explains the GPS noise and a
        GPS offset with it), or for each hypothesis the sensor it holds healthy.
    sd_drift : float
        Prior standard deviation of the drift rate ``beta`` in that test (count per sample; 0:
        no drift in the fit). 0.2 (4 counts/s at 20 Hz, against the cloud's 7.3 at most):
        without it the cloud's change of ``b`` passes for an IR offset's ramp (fault-free
        flights of seeds 1 to 3000: largest log-likelihood 37.8, against 9.1 with it).
    raw : bool
        The consistency residual takes the mean over the GPS window of every IR sample,
        including those the present-IR gate keeps out of the filter's pairs (a large IR offset
        would otherwise leave it blind).
    end : {"consistency", "innovation"}
        How a fault ends: the consistency residual stepping back by half the offset or more
        (:func:`~quadcosim.calibration.infrared.detection._end_held`), or the faulty sensor's innovation
        consistent again (the earlier design; a turn exposing the held calibration's error of
        ``a`` ended GPS faults early).
    decisive : float
        Consistency statistic (standard deviations) from which the better signature is declared
        whatever its fit (``inf``: never; under a frozen calibration the cloud's drift drives the
        statistic as high as a fault).
    alt_level, alt_life : float, int
        Attribution log-likelihood from which a CUSUM run that declared nothing leaves the
        calibration from before it remembered for ``alt_life`` samples, so that a later change
        back to it is taken for the end of an offset the filter absorbed, not for a fault
        (``inf``: never; it takes real faults for returns too).
    alt_ended : bool
        When a fault's declaration ends, remember the calibration it held (from before the
        offset) for ``alt_life`` samples: if the offset lasts on, the filter absorbs it, and its
        end is then taken for a return to that calibration, not for a new fault that would never
        clear.
    alt_restart : bool
        Remember the calibration a consistency run was held against when the run outlasts the
        ring of past calibrations (off: the cloud's ramps leave calibrations that real faults
        then return to).
    alt_moved, alt_span : float, int
        Remember the calibration of 10 s before when ``a`` and ``b`` move by ``alt_moved``
        counts (at the present turn rate) within ``alt_span`` samples, the consistency CUSUM
        having run (``alt_needs_run``): a missed offset being absorbed (``inf``, the default:
        never; the filter's catching up after the cloud takes real faults for returns).
    alt_shift, alt_wait : float, int
        A remembered calibration is forgotten ``alt_wait`` samples later if ``a`` and ``b`` have
        not moved ``alt_shift`` counts from it (at the present turn rate): nothing was absorbed.
    alt_innovation : bool
        Test the faults the innovations' CUSUMs declare for such a return too (else only those
        of the consistency residual).
    alt_fraction : float
        A change is a return when, against the remembered calibration, the residual after it is
        less than this fraction of the change.
    plateau, plateau_skip, plateau_move : int
        The end of an offset missed from its start, which no declaration ever held a calibration
        for: a change about to be declared is taken for a return when the calibrations of the
        last 160 s (one a second) show, at the present turn rate, a plateau at the present one
        for at least ``plateau`` samples (0: never), the newest ``plateau_skip`` samples left
        out (the change itself), and, within ``plateau_move`` samples before it, the
        calibration the change brings the sensors back to (:func:`~quadcosim.calibration.infrared.
        detection._plateau_return`). The cloud and the filter's catching up after it leave no
        plateau that long before the GPS fault that follows.
    plateau_flat, plateau_flat_max : float
        How far the plateau's calibrations may stray from the present one (count, at the present
        turn rate): this fraction of the change, at most ``plateau_flat_max`` counts (a large
        change would take the cloud's full cover for a plateau).
    plateau_match : float
        How far (a fraction of the change) the calibration before the move may be from the one
        the change returns to.
    plateau_settled : float
        A calibration whose variance of ``b`` exceeds this fraction of the initial one
        (``sd_b0^2``) is no plateau nor a return's end (the filter's first seconds).
    return_hold : bool
        After a return, leave the paired IR unwatched for the GPS window's span: after an IR
        offset's end the window still holds offset samples, which would be declared anew.
    scale_gain : float
        Weight per sample of the running mean square of the normalised consistency residual
        while its CUSUM is zero (1 / samples): the spread the attribution scales by.
    end_h : float
        Threshold of the log-likelihood ratio that ends a fault.
    end_significance : float
        Log-likelihood the step back of the consistency residual must reach before a fault
        ends (``end="consistency"``), as ``significance`` for its start.
    complete : int
        Samples of the offset's shape the attribution ring must hold past its onset before a
        fault is declared (0: as soon as the signatures part).
    end_healthy : bool
        Fit the end's turn-rate term with the sensor not at fault (the ``"healthy"`` reading of
        ``turn``) rather than the smoothed GPS turn rate.
    size_gain : float
        Weight per sample of the running estimate of a declared fault's offset (1 / samples).
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
    cusum_k: float = 2.0
    cusum_h: float = math.inf
    now_k: float = 6.0
    now_h: float = 25.0
    held_k: float = 1.15
    held_h: float = 10.0
    held_lag: int = 10
    freeze: bool = True
    margin: float = 4.6
    significance: float = 15.0
    sd_a_held: float = 50.0
    turn: str = "smoothed"
    sd_drift: float = 0.2
    raw: bool = True
    end: str = "consistency"
    end_significance: float = 15.0
    complete: int = 0
    end_healthy: bool = False
    decisive: float = math.inf
    alt_level: float = math.inf
    alt_life: int = 4000
    alt_ended: bool = True
    alt_restart: bool = False
    alt_shift: float = 15.0
    alt_wait: int = 200
    alt_innovation: bool = True
    alt_moved: float = math.inf
    alt_needs_run: bool = True
    alt_span: int = 40
    alt_fraction: float = 0.5
    plateau: int = 600
    plateau_skip: int = 200
    plateau_move: int = 300
    plateau_flat: float = 0.5
    plateau_match: float = 0.5
    plateau_settled: float = 0.1
    plateau_flat_max: float = 20.0
    return_hold: bool = True
    scale_gain: float = 0.01
    end_h: float = 10.0
    size_gain: float = 0.05
    form: str = "sequential"

    def __post_init__(self):
        for name in ("sd_a0", "sd_b0", "sd_r0", "q_a", "q_b", "q_r", "sd_gps", "sd_ir", "sd_ir_sample", "sd_lag"):
            _check_positive(name, getattr(self, name), "", "a covariance must be positive definite")
        if not (math.isfinite(self.a0) and self.a0 != 0.0 and math.isfinite(self.b0)):
            raise ValueError(f"a0 = {self.a0!r}, b0 = {self.b0!r}: a0 must be finite and non-zero, b0 finite")
        if not (self.gate == 0.0 or (math.isfinite(self.gate) and self.gate > 0.0)):
            raise ValueError(f"gate = {self.gate!r} standard deviations must be positive, or 0 for no gating")
        for name in ("cusum_k", "cusum_h", "now_k", "now_h", "held_k", "held_h", "margin", "significance", "sd_a_held",
                     "scale_gain", "end_h", "size_gain", "decisive", "alt_level", "alt_life", "end_significance"):
            value = getattr(self, name)
            if not value > 0.0 or math.isnan(value):
                raise ValueError(f"{name} = {value!r} must be positive (inf where it turns a detector off); "
                                 "the detector needs a positive allowance and threshold")
        for name in ("alt_shift", "alt_moved", "alt_fraction", "plateau_flat", "plateau_flat_max", "plateau_match",
                     "plateau_settled"):
            if not getattr(self, name) >= 0.0:
                raise ValueError(f"{name} = {getattr(self, name)!r} must be >= 0 (inf: never)")
        span = self.plateau + self.plateau_skip + self.plateau_move
        if span > SLOW_EVERY * SLOW_SIZE:
            raise ValueError(f"plateau + plateau_skip + plateau_move = {span} samples: the slow ring of past "
                             f"calibrations holds {SLOW_EVERY * SLOW_SIZE}")
        for name, top in (("alt_wait", math.inf), ("alt_span", PAST_SIZE - 1), ("plateau", math.inf),
                          ("plateau_skip", math.inf), ("plateau_move", math.inf)):
            value = getattr(self, name)
            if int(value) != value or not 0 <= value <= top:
                raise ValueError(f"{name} = {value!r} must be a whole number of samples in [0, {top}]")
        if int(self.held_lag) != self.held_lag or not 1 <= self.held_lag < PAST_SIZE - RING_SIZE:
            raise ValueError(f"held_lag = {self.held_lag!r} must be a whole number of samples in "
                             f"[1, {PAST_SIZE - RING_SIZE})")
        if not (self.sd_drift >= 0.0 and math.isfinite(self.sd_drift)):
            raise ValueError(f"sd_drift = {self.sd_drift!r} count per sample must be finite and >= 0 (0: no drift)")
        if self.turn not in TURNS:
            raise ValueError(f"turn = {self.turn!r} must be one of {', '.join(TURNS)}")
        if self.end not in ("consistency", "innovation"):
            raise ValueError(f"end = {self.end!r} must be 'consistency' or 'innovation'")
        if self.form not in ("sequential", "joint"):
            raise ValueError(f"form = {self.form!r} must be 'sequential' or 'joint'")
        if self.form == "joint" and self.gate:
            raise ValueError("the joint form is the slides' filter and is not gated: set gate=0 or form='sequential'")

    def config(self) -> np.ndarray:
        """The configuration vector of the step functions (variances per sample, gate, rules)."""
        c = np.zeros(EKF_CONFIG_SIZE)
        c[[QA, QB, QR, RG, RI]] = np.square([self.q_a, self.q_b, self.q_r, self.sd_gps, self.sd_ir])
        c[GAMMA2] = self.gate**2
        c[CUSUM_K], c[CUSUM_H], c[NOW_K], c[NOW_H] = self.cusum_k, self.cusum_h, self.now_k, self.now_h
        c[END_H], c[SIZE_GAIN] = self.end_h, self.size_gain
        c[CONS_K], c[CONS_H], c[MARGIN], c[HELD_LAG] = self.held_k, self.held_h, self.margin, self.held_lag
        c[SCALE_GAIN], c[SIGNIFICANCE], c[SD_A_HELD] = self.scale_gain, self.significance, self.sd_a_held
        c[FREEZE], c[DECISIVE], c[TURN_MODE] = float(self.freeze), self.decisive, TURNS.index(self.turn)
        c[END_MODE], c[RAW_SEEN] = float(self.end == "consistency"), float(self.raw)
        c[ALT_LEVEL], c[ALT_LIFE], c[SD_DRIFT] = self.alt_level, self.alt_life, self.sd_drift
        c[END_SIGNIFICANCE], c[COMPLETE] = self.end_significance, self.complete
        c[END_TURN] = float(self.end_healthy)
        c[ALT_ENDED], c[ALT_RESTART], c[ALT_INNOVATION] = self.alt_ended, self.alt_restart, self.alt_innovation
        c[ALT_SHIFT], c[ALT_WAIT], c[ALT_MOVED] = self.alt_shift, self.alt_wait, self.alt_moved
        c[ALT_NEEDS_RUN], c[ALT_FRACTION], c[ALT_SPAN] = self.alt_needs_run, self.alt_fraction, self.alt_span
        c[PLATEAU_SKIP], c[PLATEAU_MIN] = self.plateau_skip // SLOW_EVERY, self.plateau // SLOW_EVERY
        c[PLATEAU_MOVE], c[PLATEAU_FLAT], c[PLATEAU_MATCH] = (self.plateau_move // SLOW_EVERY, self.plateau_flat,
                                                              self.plateau_match)
        c[PLATEAU_VAR] = self.plateau_settled * self.sd_b0**2
        c[PLATEAU_FLAT_MAX], c[RETURN_HOLD] = self.plateau_flat_max, self.return_hold
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
        s[A_SAFE], s[B_SAFE] = self.a0, self.b0
        s[HELD_SCALE] = 1.0  # the filter's noise model, until the residuals say otherwise
        s[ANCHOR] = -float(self.held_lag)
        P = np.diag(np.square([self.sd_a0, self.sd_b0, self.sd_r0])) if covariance is None else covariance
        P = np.asarray(P, dtype=float)
        if P.shape != (3, 3) or not np.isfinite(P).all() or not np.allclose(P, P.T):
            raise ValueError(f"initial covariance must be a finite symmetric 3x3 matrix, not {P!r}")
        if np.linalg.eigvalsh(P).min() <= 0.0:
            raise ValueError(f"initial covariance is not positive definite (eigenvalues {np.linalg.eigvalsh(P)}); "
                             "give positive variances")
        s[[PAA, PAB, PAR, PBB, PBR, PRR]] = P[0, 0], P[0, 1], P[0, 2], P[1, 1], P[1, 2], P[2, 2]
        for j, value in enumerate((self.a0, self.b0, P[0, 0], P[0, 1], P[1, 1])):  # the held calibrations
            s[PAST + j * PAST_SIZE:PAST + (j + 1) * PAST_SIZE] = value
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
