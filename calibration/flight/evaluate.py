"""Scores of a fitted interference model on a part of a flight it was not fitted on.

The residual left by the Earth field and the offset alone is the baseline. On the scored part,
the model's prediction (fitted elsewhere) is subtracted and only the Earth field and the offset
are fitted again; ``explained`` is the share of the baseline's squared residual this removes.
"""

from __future__ import annotations

import numpy as np
from quadcosim.calibration.flight.linear import earth_and_offset

AIRBORNE_THROTTLE = 0.2  # collective throttle above which the vehicle is taken to fly


def wrap(angle):
    """``angle`` (rad) wrapped to [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def tilt_compensated_heading(field: np.ndarray, euler: np.ndarray) -> np.ndarray:
    """Magnetic heading (rad) of body-frame ``field`` (T, 3) levelled by the roll and pitch of
    ``euler`` (T, 3) (rad): the angle of the field's horizontal part from the body's x axis."""
    roll, pitch = euler[:, 0], euler[:, 1]
    x, y, z = field.T
    north = x * np.cos(pitch) + (y * np.sin(roll) + z * np.cos(roll)) * np.sin(pitch)
    east = y * np.cos(roll) - z * np.sin(roll)
    return np.arctan2(-east, north)


def heading_offset(heading: np.ndarray, reference: np.ndarray) -> float:
    """Circular mean (rad) of ``heading - reference``: the declination and any mounting offset, as
    estimated on the samples given (give them the parts a score does not score)."""
    return float(np.angle(np.mean(np.exp(1j * wrap(np.asarray(heading) - reference)))))


def heading_error(heading: np.ndarray, reference: np.ndarray, offset: float | None = None) -> np.ndarray:
    """``heading - reference`` (rad) wrapped, ``offset`` (rad, :func:`heading_offset` estimated
    elsewhere and frozen) removed; None removes the samples' own circular mean (an analysis that
    refits the offset on the part it scores)."""
    error = wrap(heading - reference)
    if offset is None:
        offset = heading_offset(heading, reference)
    return wrap(error - offset)


def score(fitted, parts) -> dict:
    """``explained`` share, costs (T^2), heading figures (deg) of the model ``fitted`` (a
    :class:`quadcosim.calibration.flight.models.Fitted`, or None for the baseline alone) on ``parts`` (FlightData)."""
    base_cost = model_cost = 0.0
    change, before, after, perturbation = [], [], [], []
    for p in parts:
        base = earth_and_offset(p.rotation, p.raw, p.earth)
        predicted = np.zeros_like(p.raw) if fitted is None else fitted.predict(p)
        fit = earth_and_offset(p.rotation, p.raw - predicted, p.earth)
        base_cost += base.cost
        model_cost += fit.cost
        without = tilt_compensated_heading(p.body(p.raw - base.nuisance[0, 3:]), p.euler)
        with_model = tilt_compensated_heading(p.body(p.raw - predicted - fit.nuisance[0, 3:]), p.euler)
        change.append(wrap(with_model - without))
        before.append(heading_error(without, p.euler[:, 2]))
        after.append(heading_error(with_model, p.euler[:, 2]))
        flying = p.throttle() > AIRBORNE_THROTTLE
        perturbation.append(np.linalg.norm(predicted[flying], axis=1))

    def rms(values):
        return float(np.degrees(np.sqrt(np.mean(np.concatenate(values) ** 2))))

    flying = np.concatenate(perturbation)
    return {"explained": 1.0 - model_cost / base_cost if base_cost > 0 else 0.0,
            "baseline_rms_T": float(np.sqrt(base_cost / sum(3 * len(p.time) for p in parts))),
            "heading_rms_change_deg": rms(change),
            "heading_error_rms_deg": {"without": rms(before), "with": rms(after)},
            "perturbation_at_hover_T": float(np.median(flying)) if len(flying) else float("nan")}
