"""A magnetometer calibration from flights: hard and soft iron when the rotations allow, each
interference model fitted on training flights and scored on held-out ones, and the result as a
:class:`quadcosim.calibration.Calibration`."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from quadcosim.calibration.dynamic import MotorFieldModel
from quadcosim.calibration.file import Calibration
from quadcosim.calibration.flight import catalogue
from quadcosim.calibration.flight.evaluate import score
from quadcosim.calibration.flight.linear import earth_and_offset
from quadcosim.calibration.flight.models import NotIdentifiable
from quadcosim.calibration.static import CalibrationError, StaticCalibration, fit_static, sphere_coverage

MIN_COVERAGE = 0.5  # share of the 80 sphere cells the Earth field must visit in the body frame


def _fit_models(train, names) -> tuple[dict, dict]:
    fitted, refused = {}, {}
    known = catalogue.models()
    for name in names:
        model = known[name].build(fitted)
        reason = model.refusal(train)
        if reason is None:
            try:
                fitted[name] = model.fit(train)
            except (NotIdentifiable, CalibrationError) as error:
                reason = str(error)
        if reason is not None:
            refused[name] = reason
    return fitted, refused


def _unscorable(fitted: dict, test) -> dict:
    """The fitted models the ``test`` parts cannot score, with the reason: what a model reads that
    the test flights did not log (a current sensor, a battery voltage)."""
    reasons = {}
    for name, f in fitted.items():
        lacking = [p.source for p in test if name == "current" and p.current() is None]
        if lacking:
            reasons[name] = (f"fitted on the training flights, but the test flights have no current sensor to score "
                             f"it on ({', '.join(sorted(set(lacking)))}); test on flights that log the current")
            continue
        if not all(np.isfinite(f.predict(p)).all() for p in test):
            reasons[name] = ("fitted on the training flights, but its prediction on the test flights is not finite "
                             "(they lack what it reads: the battery voltage?); test on flights that log it")
    return reasons


def _static(train, best, offsets, soft_iron) -> tuple[StaticCalibration, dict]:
    """Hard and soft iron from the flights' rotations when they cover enough of the sphere, else the log's."""
    first = train[0]
    base = earth_and_offset(first.rotation, first.raw - (0 if best is None else best.predict(first)), first.earth)
    m_E = base.nuisance[0, :3]
    directions = np.einsum("tji,j->ti", first.rotation, m_E)
    coverage = sphere_coverage(directions)
    kept = StaticCalibration(A=soft_iron, b_s=offsets, field_norm=float(np.linalg.norm(m_E)), coverage=coverage)
    if coverage < MIN_COVERAGE:
        return kept, {"source": "log", "coverage": coverage,
                      "reason": f"the flight's rotations cover {coverage:.2f} of the sphere (< {MIN_COVERAGE}): "
                                "hard and soft iron cannot be fitted, the log's offsets are kept"}
    samples = np.concatenate([p.raw - (0 if best is None else best.predict(p)) for p in train])
    try:
        static = fit_static(samples, field_norm=float(np.linalg.norm(m_E)))
    except CalibrationError as error:
        return kept, {"source": "log", "coverage": coverage, "reason": f"the ellipsoid fit was refused: {error}"}
    return static, {"source": "flight", "coverage": coverage, "reason": "fitted on the flight's rotations"}


def model_offsets(fitted) -> np.ndarray:
    """The offsets (3,), T, fitted together with a motor model: its per-flight offsets averaged.

    Parameters
    ----------
    fitted : quadcosim.calibration.flight.models.Fitted
        A fitted model whose ``extra["nuisance"]`` holds each flight's Earth field and offsets (P, 6), T.

    Returns
    -------
    numpy.ndarray
        The offsets (3,), T, that go with the model's vectors.
    """
    return np.mean(fitted.extra["nuisance"][:, 3:], axis=0)


def paired_static(static: StaticCalibration, notes: dict, chosen: str | None, fitted: dict) -> StaticCalibration:
    """The hard and soft iron that go with the motor model ``chosen``.

    When the log's offsets are kept (``notes["source"] == "log"``) and a model is chosen, its own
    offsets replace them: the log's were set with the motors running, so they already hold the
    motors' mean field, which the model's vectors would remove a second time (a constant field in
    the body frame). Offsets fitted on the flight's rotations (with the interference removed) and
    a calibration without a model are returned unchanged.

    Parameters
    ----------
    static : quadcosim.calibration.static.StaticCalibration
        Hard iron ``b_s`` (3,), T, and soft iron ``A`` (3, 3) from :func:`_static`.
    notes : dict
        :func:`_static`'s notes (``source``: ``"log"`` or ``"flight"``).
    chosen : str or None
        The motor model the calibration carries (:func:`_field_model`).
    fitted : dict
        The fitted models by name.

    Returns
    -------
    quadcosim.calibration.static.StaticCalibration
        ``static``, its offsets (T) those fitted with ``chosen`` when the log's were kept.
    """
    if chosen is None or notes["source"] != "log":
        return static
    return replace(static, b_s=model_offsets(fitted[chosen]))


def _field_model(fitted: dict, motors: int, explained: dict | None = None) -> tuple[str | None, MotorFieldModel | None]:
    """The preferred identified model in the file's form (:attr:`catalogue.Model.to_file`): the first
    of the a-priori order that helps out of sample.

    Parameters
    ----------
    fitted : dict
        The fitted models by name.
    motors : int
        The number of motors of the file.
    explained : dict, optional
        Each model's share (1) of the held-out residual it explains; a model that explains none
        (``<= 0``: it does no better than no model, the file's alternative) is passed over.

    Returns
    -------
    name, model : str and quadcosim.calibration.dynamic.MotorFieldModel, or None and None
    """
    # the first the flights identify of those the file can carry (an a-priori order, richest
    # first, not a choice on the scores), provided it beats no model on the held-out part
    for name in catalogue.preferred("in_file"):
        if name in fitted and (explained is None or explained.get(name, 0.0) > 0.0):
            return name, catalogue.models()[name].to_file(fitted[name], motors)
    return None, None


def calibrate(train, test, names=None, attitude: str = "auto") -> tuple[dict, Calibration, dict]:
    """Fit on the ``train`` parts, score on the ``test`` parts (lists of FlightData of one compass);
    ``names`` the models tried (default every installed model,
    :func:`quadcosim.calibration.flight.catalogue.models`), ``attitude`` the attitude the parts were
    built with (recorded).

    Returns the metrics (JSON-ready), the :class:`quadcosim.calibration.Calibration` for the file and the
    fitted models by name (:class:`quadcosim.calibration.flight.models.Fitted`).
    """
    names = tuple(catalogue.models()) if names is None else names
    fitted, refused = _fit_models(train, names)
    for name, reason in _unscorable(fitted, test).items():  # fitted on the training flights, not testable
        refused[name] = reason
        del fitted[name]
    compass = train[0].log.compasses[train[0].compass]
    models = {}
    for name in names:
        if name in refused:
            models[name] = {"refused": refused[name]}
            continue
        f = fitted[name]
        on_test, on_train = score(f, test), score(f, train)
        models[name] = {"explained_test": on_test["explained"], "explained_train": on_train["explained"],
                        "coefficients": f.coefficients, "perturbation_at_hover_T": on_test["perturbation_at_hover_T"],
                        "heading_rms_change_deg": on_test["heading_rms_change_deg"],
                        "heading_error_rms_deg": on_test["heading_error_rms_deg"], "delay_s": f.delay,
                        "condition_number": f.condition}
    explained = {name: m["explained_test"] for name, m in models.items() if "explained_test" in m}
    chosen, field = _field_model(fitted, train[0].motors.commands.shape[1], explained)
    passed_over = {name: f"explains {100 * explained[name]:.1f} % of the held-out residual: no better than no model"
                   for name in catalogue.preferred("in_file")
                   if name in explained and name != chosen and explained[name] <= 0.0}
    # the ellipsoid is fitted on the field with the interference removed that explains most in training
    best = max(fitted, key=lambda name: models[name]["explained_train"], default=None)
    static, static_notes = _static(train, fitted.get(best), compass.offsets, compass.soft_iron)
    static_notes["interference_removed"] = best
    static = paired_static(static, static_notes, chosen, fitted)
    if chosen is not None and static_notes["source"] == "log":
        static_notes["offsets"] = f"those fitted with the {chosen} model (the log's hold the motors' mean field)"
    baseline = score(None, test)
    metrics = {"train": sorted({p.source for p in train}), "test": sorted({p.source for p in test}),
               "attitude": attitude,
               "baseline_rms_test_T": baseline["baseline_rms_T"],
               "heading_error_rms_without_deg": baseline["heading_error_rms_deg"]["without"],
               "static": {k: v for k, v in static_notes.items()}, "models": models, "calibration_model": chosen,
               "calibration_model_passed_over": passed_over}
    calibration = Calibration(train[0].motors.commands.shape[1], static, field,
                              fitted["dynamic"].extra["dynamics"] if "dynamic" in fitted and chosen == "metge"
                              else None, None,
                              {"source": "flight calibration", "train": metrics["train"], "model": chosen})
    return metrics, calibration, fitted
