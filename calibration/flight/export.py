"""What a flight calibration exports, scored as the autopilot will apply it.

:func:`score_parameters` is the one judge of a parameter set: any ArduPilot or PX4 parameters
(this project's export, the log's own, a file another tool wrote), loaded on top of the log's
parameters and applied to the raw field exactly as the log's firmware applies them
(each autopilot's ``apply``, :mod:`quadcosim.flightlogs.autopilots`), on the held-out parts. It
returns the heading error against the log's attitude and the share of the field residual the
parameters' motor compensation explains. The heading's constant offset (declination, mounting) is
estimated for each parameter set on parts it does not score and removed frozen: a hard iron that
turns the heading by a near-constant angle on a scored part that barely turns is then seen.

:func:`choose` builds the export group by group (offsets, motor compensation, soft iron) from
the fits on the training parts and keeps each group only when it beats what the log already
holds on the choice parts; the log's values stay for the others, and the notes say which. The
export is then scored on parts that neither the fit nor the choice has seen.
A compass whose offsets are all zero (never calibrated) gets offsets from the flight, with the
Earth field model, or is refused: zeros are never fitted; like any other compass, :func:`judge`
writes the log's values back when the fitted file scores worse on the score part.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from quadcosim.calibration.flight.autopilot import autopilot_of
from quadcosim.calibration.flight.evaluate import heading_offset, tilt_compensated_heading, wrap
from quadcosim.calibration.flight.linear import earth_and_offset, fit_linear
from quadcosim.calibration.static import CalibrationError

MAX_CONDITION = 1e3  # column-normalised design: above it the parameters cannot be told apart


def _inputs(part) -> dict:
    """The firmware's inputs at the compass's samples, without delay: current (A), the
    autopilot's throttle (0..1), motor commands (0..1) and battery voltage (V)."""
    throttle = part.autopilot_throttle()
    return {"current": part.current(), "throttle": part.throttle() if throttle is None else throttle,
            "commands": part.commands(), "voltage": part.voltage()}


def apply_parameters(part, params: dict, rule=None) -> np.ndarray:
    """The body-frame field (T, 3) (T) the log's firmware reports from ``part``'s raw field with
    ``params`` loaded on top of the log's own parameters; ``rule`` overrides ArduPilot's version rules."""
    return autopilot_of(part).apply(part, {**part.log.params, **params}, _inputs(part), rule)


def _heading_error(part, corrected: np.ndarray) -> np.ndarray:
    """The tilt-compensated heading of ``corrected`` (T, 3), the field the firmware reports, against
    ``part``'s heading, wrapped, nothing removed (rad)."""
    return wrap(tilt_compensated_heading(corrected, part.euler) - part.euler[:, 2])


def score_parameters(parts, params: dict, rule=None, *, offset_from) -> dict:
    """Score a parameter set on the held-out ``parts`` (FlightData of one compass), applied as
    each part's firmware applies it (``rule``: an ArduPilot :class:`Rules` overriding the log's).

    Parameters
    ----------
    parts : list of FlightData
        The scored parts.
    params : dict
        Parameter name: value, in the autopilot's units; names it lacks keep the log's values.
    offset_from : list of FlightData
        Parts of the same compass that are not scored (the fit or choice parts): the heading offset
        (the declination and any mounting offset) of ``params`` is estimated there and removed,
        frozen, from the scored parts. Estimated on the scored parts themselves it would hide a
        constant heading error (a hard iron on a flight that barely turns) from the score.

    Returns
    -------
    dict
        ``heading_rms_deg``: RMS of the tilt-compensated heading of the corrected field against the
        log's heading, ``heading_offset_deg`` removed (deg); ``explained``: the share of the residual
        left by the Earth field and offset alone (fitted again) on the field the same parameters give
        with their motor compensation switched off that is gone with it on: what the motor
        compensation explains (1). The baseline carries the parameters' own offsets and soft iron,
        so a soft iron that only matches the compass's scale to the field model's magnitude is not
        counted as explained interference.
    """
    offset = heading_offset(np.concatenate([_heading_error(p, apply_parameters(p, params, rule)) for p in offset_from]),
                            0.0)
    errors, base_cost, cost = [], 0.0, 0.0
    for p in parts:
        corrected = apply_parameters(p, params, rule)
        errors.append(wrap(_heading_error(p, corrected) - offset))
        attitude = p.rotation @ np.asarray(p.log.compasses[p.compass].rotation).T  # body to NED
        uncompensated = apply_parameters(p, {**params, **autopilot_of(p).motor_off}, rule)  # the explained share's base
        base_cost += earth_and_offset(attitude, uncompensated, p.earth).cost
        cost += earth_and_offset(attitude, corrected, p.earth).cost
    return {"heading_rms_deg": float(np.degrees(np.sqrt(np.mean(np.concatenate(errors) ** 2)))),
            "heading_offset_deg": float(np.degrees(offset)),
            "explained": 1.0 - cost / base_cost if base_cost > 0 else 0.0}


def score_file(path, parts, rule=None, *, offset_from) -> dict:
    """:func:`score_parameters` of the parameter file at ``path`` (ArduPilot ``.parm`` or a PX4
    ``.params`` of QGroundControl) on ``parts``, its heading offset estimated on ``offset_from``,
    applied under ``rule`` (None: the log's), with its name and parameter count."""
    from quadcosim.calibration.flight.autopilot import read_parameters

    params = read_parameters(path, autopilot_of(parts[0]))
    _check_scored(path, parts, params, rule)
    scored = score_parameters(parts, params, rule, offset_from=offset_from)
    return {"file": str(path), "parameters": len(params)} | scored


#: How many times the log's raw field a calibrated field may be before the parameters are absurd.
MAX_FIELD_RATIO = 10.0


def _check_scored(path, parts, params: dict, rule) -> None:
    """Refuse a parameter file that would be scored as something it is not: one none of whose
    parameters acts on the compass scored (it would score as the log), or one whose values make
    the firmware's field absurd (``COMPASS_MOT2_X,3e38`` once scored a share of -8e78 %)."""
    fields = [apply_parameters(p, params, rule) for p in parts]
    if all(np.array_equal(f, apply_parameters(p, {}, rule)) for f, p in zip(fields, parts, strict=True)):
        raise ValueError(f"{path}: none of its {len(params)} parameters ({', '.join(list(params)[:4])}"
                         f"{', ...' if len(params) > 4 else ''}) acts on the compass scored (compass "
                         f"{parts[0].compass}): it would score as the log's own; give the file for this compass "
                         "(--compass) and this autopilot")
    size = float(np.median(np.concatenate([np.linalg.norm(f, axis=1) for f in fields])))
    raw = float(np.median(np.concatenate([np.linalg.norm(p.raw, axis=1) for p in parts])))
    if not size <= MAX_FIELD_RATIO * raw:
        largest = max(params, key=lambda k: abs(params[k]))
        raise ValueError(f"{path}: with its parameters the firmware would report a field of {size * 1e6:.3g} uT, "
                         f"more than {MAX_FIELD_RATIO:g} times the log's raw {raw * 1e6:.3g} uT: no calibration gives "
                         f"that (its largest value: {largest} = {params[largest]:g}); fix the file")


@dataclass
class Candidate:
    """A fitted piece of the export: the hard iron ``offset`` (3,) (T, raw frame), the soft-iron
    inverse ``correction`` (3, 3), the motor ``model`` (or None), its vectors ``K`` (T per unit) and
    ``notes`` (text)."""

    offset: np.ndarray
    correction: np.ndarray
    model: str | None = None
    K: np.ndarray | None = None
    notes: dict = field(default_factory=dict)


def _motor_regressors(part, model: str) -> np.ndarray | None:
    """(T, J) regressors of the firmware's motor compensation ``model``, without delay (the
    autopilot's ``motor_inputs``)."""
    return autopilot_of(part).motor_inputs(model, _inputs(part))


def motor_models(part, rule=None) -> tuple[str, ...]:
    """The motor compensations ``part``'s firmware has for its compass (the autopilot's
    ``motor_models``, :class:`quadcosim.flightlogs.autopilots.Autopilot`): ``current`` and ``throttle``,
    and ``motors`` (``COMPASS_PMOT``) on ArduPilot 4.0 and later's first compass (``rule`` overriding
    the log's version)."""
    return autopilot_of(part).motor_models(part, rule)


def fit_motor(train, model: str | None):
    """Offsets (3,) and the motor ``model``'s vectors (J, 3) fitted together on ``train`` (no
    delay: the firmware applies none), with the Earth field model where known; None when the
    log lacks the model's input or its design cannot be told apart."""
    regressors = []
    for p in train:
        r = np.zeros((len(p.time), 0)) if model is None else _motor_regressors(p, model)
        if r is None:
            return None
        regressors.append(r)
    fit = fit_linear([(p.rotation, p.raw, r, p.earth) for p, r in zip(train, regressors, strict=True)])
    if model is not None and fit.condition > MAX_CONDITION:
        return None
    offsets = np.mean(fit.nuisance[:, 3:], axis=0)
    return offsets, fit.K, fit


def offsets_identifiable(train) -> tuple[bool, str]:
    """Whether the training flights identify all three offsets, and why (the Earth field model, or
    the condition number of the free field's design)."""
    if all(p.earth is not None for p in train):
        return True, "all three offsets against the Earth field model"
    condition = fit_linear([(p.rotation, p.raw, np.zeros((len(p.time), 0))) for p in train]).condition
    if condition > MAX_CONDITION:
        return False, (f"without the Earth field model (no GPS fix) the flight's rotations cannot tell the z offset "
                       f"from the field's vertical component (condition number {condition:.3g} > {MAX_CONDITION:g})")
    return True, f"the flight's rotations identify them with a free Earth field (condition number {condition:.3g})"


def fit_soft_iron(train, model, K) -> tuple[np.ndarray, np.ndarray] | str:
    """Symmetric soft iron ``A`` and offsets ``b`` in ``raw - K x = A R^T m_E + b``, against the
    Earth field model, fitted on the ``train`` parts; the reason (str) when the model is absent or the
    rotations cannot identify it."""
    if any(p.earth is None for p in train):
        return "soft iron needs the Earth field model (a GPS fix) on flights like these"
    pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
    rows, targets = [], []
    for p in train:
        left = p.raw if model is None else p.raw - _motor_regressors(p, model) @ np.atleast_2d(K)
        e = np.einsum("tji,j->ti", p.rotation, p.earth)  # R^T m_E
        T = len(p.time)
        D = np.zeros((T, 3, len(pairs) + 3))
        for c, (i, j) in enumerate(pairs):
            D[:, i, c] += e[:, j]
            if i != j:
                D[:, j, c] += e[:, i]
        D[:, :, len(pairs):] = np.eye(3)
        rows.append(D.reshape(3 * T, -1))
        targets.append(left.ravel())
    D, y = np.concatenate(rows), np.concatenate(targets)
    scale = np.linalg.norm(D, axis=0)
    singular = np.linalg.svd(D / scale, compute_uv=False)
    condition = float(singular[0] / max(singular[-1], 1e-300))
    if condition > MAX_CONDITION:
        return (f"the flight's rotations cannot identify the soft iron (condition number {condition:.3g} > "
                f"{MAX_CONDITION:g}: it turns mostly about the vertical)")
    x = np.linalg.lstsq(D, y, rcond=None)[0]
    A = np.zeros((3, 3))
    for c, (i, j) in enumerate(pairs):
        A[i, j] = A[j, i] = x[c]
    return A, x[len(pairs):]


def parameters_of(part, candidate: Candidate, rule=None) -> dict:
    """``candidate`` as the parameters of ``part``'s firmware (compass's own slot; ``rule`` overriding
    ArduPilot's version)."""
    return autopilot_of(part).parameters(part, candidate, rule)


def log_parameters(part, names) -> dict:
    """The values of ``names`` in ``part``'s log (those it holds; the others keep the firmware's defaults)."""
    return {n: part.log.params[n] for n in names if n in part.log.params}


def _motor_keys(part, params: dict) -> dict:
    """The motor-compensation entries of ``params`` for ``part``'s firmware (the autopilot's
    ``is_motor_key``: ArduPilot's ``COMPASS_*MOT*``, PX4's ``CAL_MAG*COMP*``)."""
    is_motor_key = autopilot_of(part).is_motor_key
    return {k: v for k, v in params.items() if is_motor_key(k)}


def _motor_trials(train, rule, trial, held, log_soft, models=None) -> dict:
    """Each motor compensation the firmware has, fitted on ``train`` with the offsets (or with
    ``held``, the offsets kept, when the flights cannot identify them) and scored by ``trial``; the
    reason when it cannot be fitted.

    The compensation goes out with the offsets fitted with it and no others: offsets fitted
    without it hold the motors' mean field, which it would add a second time, and the log's (or
    any others) with the fitted vectors are a pair no fit produced. A choice part flown at one
    throttle cannot tell such pairs apart (only ``offsets + K x`` at that throttle shows), so
    they are not offered to it."""
    trials = {}
    for model in motor_models(train[0], rule):
        if models is not None and model not in models:
            continue
        fitted = fit_motor(train, model)
        if fitted is None:
            trials[model] = {"refused": "its input is not logged or its design cannot be told apart"}
            continue
        K = fitted[1] if model == "motors" else fitted[1][0]
        candidate = Candidate(fitted[0] if held is None else held, log_soft, model, K)
        params, found = trial(candidate)
        trials[model] = found | {"candidate": candidate, "params": params}
    return trials


def _soft_iron_trial(first, soft, chosen, rule, trial, log_motor) -> tuple[dict, dict]:
    """The fitted soft iron ``soft`` (A, b) with the ``chosen`` motor compensation (or the log's),
    as parameters and their score."""
    A, b = soft
    candidate = Candidate(b, np.linalg.inv(A), chosen.model if chosen else None, chosen.K if chosen else None)
    scale = autopilot_of(first).scale_reset(first, rule)  # the fitted soft iron carries the scale
    return trial(candidate, (log_motor if chosen is None else {}) | scale)


def _zero_offsets(source: str, why: str) -> CalibrationError:
    """The refusal of a compass whose offsets are all zero: never exported with zeros."""
    return CalibrationError(f"{source}: its offsets are all zero (never calibrated), {why}; no parameter file is "
                            "written rather than one with zero offsets")


def _setup_notes(part) -> dict:
    """The notes of how the compass is set up: ``orientation``, the rotation the export's frame depends
    on (the offsets and motor vectors are in the frame the firmware rotates the compass into before
    correcting it, ``AP_Compass_Backend::rotate_field``), and ``use``, what the export carries to
    enable a compass the log's firmware does not use (:class:`quadcosim.flightlogs.autopilots.Autopilot`'s
    ``enabling``); each left out when it does not apply (an orientation ``NONE``: nothing rotated)."""
    notes = {}
    orientation = part.log.compasses[part.compass].setup.get("orientation", "")
    if orientation and "(NONE)" not in orientation:  # a compass not rotated needs no warning
        notes["orientation"] = (f"{orientation}: the file's offsets and motor vectors are in the frame it rotates the "
                                "compass into, right only with that orientation")
    enabler = autopilot_of(part).enabling
    enabling = enabler(part) if enabler is not None else {}
    if enabling:
        named = ", ".join(f"{k} = {v}" for k, v in enabling.items())
        notes["use"] = (f"the log's firmware does not use this compass: the file carries what enabling it needs "
                        f"({named}); load it only to fly on this compass")
    return notes


def choose(train, choice, rule=None, models=None) -> tuple[dict, dict]:
    """The parameters to export for the compass of ``train``/``choice`` and the notes saying what was
    exported and kept: offsets, then motor compensation, then soft iron, each fitted on ``train``
    and kept only when it lowers the heading error on the ``choice`` parts (its heading offset
    estimated on ``train``) (the motor compensation
    also needs a positive explained share there). The export's score belongs on parts neither has
    seen. ``rule`` overrides ArduPilot's version rules; ``models`` (names of the models an
    autopilot can carry, :mod:`quadcosim.calibration.flight.catalogue`) restricts the motor compensations
    tried (default: all the firmware has).

    Raises
    ------
    CalibrationError
        The compass has zero offsets (never calibrated) and the flights cannot give them.
    """
    first = train[0]
    compass = first.log.compasses[first.compass]
    zero = not np.any(compass.offsets)
    log_soft = np.linalg.inv(compass.soft_iron)  # the log's correction matrix
    identifiable, why = offsets_identifiable(train)
    notes = {"offsets": why} | _setup_notes(first)
    if zero and not identifiable:
        raise _zero_offsets(first.source, f"and {why}: calibrate it with the field model (log a GPS fix) or with a "
                                          "rotation sweep")
    names = list(parameters_of(first, Candidate(np.zeros(3), np.eye(3)), rule))
    flown = log_parameters(first, names)
    best, best_score = dict(flown), score_parameters(choice, flown, rule, offset_from=train)
    kept = {"offsets": "log", "motor": "log", "soft_iron": "log"}
    offsets = np.asarray(compass.offsets, dtype=float)
    log_motor = _motor_keys(first, flown)

    def trial(candidate: Candidate, motor: dict | None = None) -> tuple[dict, dict]:
        params = parameters_of(first, candidate, rule) | (motor or {})
        return params, score_parameters(choice, params, rule, offset_from=train)

    if identifiable:  # offsets, with the log's soft iron and motor compensation
        fitted_offsets = fit_motor(train, None)[0]
        params, found = trial(Candidate(fitted_offsets, log_soft), log_motor)
        if found["heading_rms_deg"] < best_score["heading_rms_deg"] or zero:
            best, best_score, kept["offsets"], offsets = params, found, "fitted", fitted_offsets
    if zero and kept["offsets"] != "fitted":
        raise _zero_offsets(first.source, "and the fitted ones do not beat them on the choice part")
    trials = _motor_trials(train, rule, trial, offsets if not identifiable else None, log_soft, models)
    notes["motor_models"] = {m: {k: v for k, v in t.items() if k not in ("candidate", "params")}
                             for m, t in trials.items()}
    scored = {m: t for m, t in trials.items() if "refused" not in t}
    chosen, notes["motor"] = None, "no motor compensation could be fitted: the log's kept"
    if scored:
        model = min(scored, key=lambda m: scored[m]["heading_rms_deg"])
        t = scored[model]
        if t["explained"] <= 0:
            notes["motor"] = (f"{model} explains {100 * t['explained']:.1f} % of the choice part's residual, less than "
                              "nothing: flagged and not exported; the log's motor compensation kept")
        elif t["heading_rms_deg"] < best_score["heading_rms_deg"]:
            best, best_score, kept["motor"] = t["params"], {k: t[k] for k in ("heading_rms_deg", "explained")}, model
            chosen = t["candidate"]
            kept["offsets"] = "log" if np.allclose(chosen.offset, compass.offsets) else "fitted"
            notes["motor"] = f"{model}: exported"
        else:
            notes["motor"] = (f"{model}: {t['heading_rms_deg']:.2f} deg on the choice part, not below "
                              f"{best_score['heading_rms_deg']:.2f} deg: the log's motor compensation kept")
    soft = fit_soft_iron(train, chosen.model if chosen else None, chosen.K if chosen else None)
    if isinstance(soft, str):
        notes["soft_iron"] = f"{soft}: the log's kept"
    else:
        params, found = _soft_iron_trial(first, soft, chosen, rule, trial, log_motor)
        if found["heading_rms_deg"] < best_score["heading_rms_deg"]:
            best, best_score, kept["soft_iron"], kept["offsets"] = params, found, "fitted", "fitted"
            notes["soft_iron"] = "fitted against the Earth field model: exported"
        else:
            notes["soft_iron"] = (f"fitted: {found['heading_rms_deg']:.2f} deg on the choice part, not below "
                                  f"{best_score['heading_rms_deg']:.2f} deg: the log's kept")
    return best, {"kept": kept, "notes": notes, "model": kept["motor"] if kept["motor"] != "log" else None}


def judge(part, params: dict, exported: dict, flown_params: dict, flown: dict) -> tuple[dict, dict, str | None]:
    """The parameters to write for ``part``'s compass, their score on the score part and the reason
    when the log's are kept: the export ``params`` (scored ``exported``, :func:`score_parameters`)
    goes out only when it beats ``flown_params``, the log's values of the same names (scored
    ``flown``), on the score part; otherwise the log's values go out, unchanged, and the reason says
    why (the choice part preferred what the score part does not). No compass is exempt: each
    score removes the heading offset the fit and choice parts show, so a compass never calibrated
    (offsets all zero) is scored with the heading error its hard iron leaves, not with it hidden."""
    if exported["heading_rms_deg"] <= flown["heading_rms_deg"]:
        return params, exported, None
    compass = part.log.compasses[part.compass]
    uncalibrated = "" if np.any(compass.offsets) else (" (all zero: the firmware still does not accept this compass "
                                                        "as calibrated)")
    return dict(flown_params), flown, (f"the export scores {exported['heading_rms_deg']:.2f} deg on the score part "
                                       f"against {flown['heading_rms_deg']:.2f} deg as flown: the choice part "
                                       "preferred it, the score part does not; the log's values are kept (the file "
                                       f"holds them unchanged){uncalibrated}")
