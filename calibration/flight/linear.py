"""The linear core of a flight calibration: the Earth field and the offset of each flight, and
shared interference coefficients, fitted together by ``scipy.optimize.least_squares``.

For the samples ``k`` of flight ``p``::

    m_raw,k = R_k^T m_E,p + b_p + sum_j x_kj K_j + noise

``R_k`` the body-to-NED rotation, ``m_E,p`` the Earth field (NED, T) and ``b_p`` the offset (body,
T) of that flight, ``x_kj`` the interference regressors (current, throttle, commands) and
``K_j`` their field vectors (T per unit), shared by all flights. When the Earth field is known
(the World Magnetic Model at the log's position, :mod:`quadcosim.calibration.flight.earth`), ``m_E,p`` is
that field and only the offset is fitted with the coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NUISANCE = 6  # Earth field (3) and offset (3) per flight


@dataclass(frozen=True)
class LinearFit:
    """Result of :func:`fit_linear`: ``nuisance`` (P, 6) the Earth field (NED, T) and offset
    (body, T) per flight, ``K`` (J, 3) the regressors' field vectors (T per unit), ``residual``
    (list of (T_p, 3) arrays, T), ``condition`` the condition number of the column-normalised
    design (1)."""

    nuisance: np.ndarray
    K: np.ndarray
    residual: list
    condition: float

    @property
    def cost(self) -> float:
        """Sum of squared residuals over every flight (T^2)."""
        return float(sum((r**2).sum() for r in self.residual))


def _blocks(rotation: np.ndarray, regressors: np.ndarray, known: bool) -> tuple[np.ndarray, np.ndarray]:
    """Design of one flight: the Earth-field and offset columns (3T, 6), or the offset's alone (3T, 3)
    when the field is ``known``, and the regressor columns (3T, 3J)."""
    T = len(rotation)
    nuisance = np.zeros((T, 3, NUISANCE))
    nuisance[:, :, :3] = np.transpose(rotation, (0, 2, 1))  # R^T
    nuisance[:, :, 3:] = np.eye(3)
    if known:
        nuisance = nuisance[:, :, 3:]
    shared = np.einsum("tj,ab->tajb", regressors, np.eye(3)).reshape(T, 3, -1)
    return nuisance.reshape(3 * T, -1), shared.reshape(3 * T, -1)


def fit_linear(parts) -> LinearFit:
    """Fit the Earth field and offset of each flight and the shared field vectors.

    Parameters
    ----------
    parts : sequence of (rotation, raw, regressors) or (rotation, raw, regressors, earth)
        Per flight: body-to-NED rotations (T, 3, 3), raw field (T, 3) (T), regressors (T, J)
        (J may be 0), and the known Earth field (3,) (NED, T) or None to fit it.
    """
    from scipy.optimize import least_squares  # imported where used: start-up

    designs, targets, earths = [], [], []
    J = np.asarray(parts[0][2]).shape[1]
    for part in parts:
        rotation, raw, regressors = (np.asarray(a, dtype=float) for a in part[:3])
        earth = None if len(part) < 4 or part[3] is None else np.asarray(part[3], dtype=float)
        nuisance, shared = _blocks(rotation, regressors.reshape(len(raw), J), earth is not None)
        designs.append((nuisance, shared))
        target = raw if earth is None else raw - np.einsum("tji,j->ti", rotation, earth)
        targets.append(target.ravel())
        earths.append(earth)
    P = len(parts)
    widths = [d[0].shape[1] for d in designs]
    first = np.concatenate([[0], np.cumsum(widths)])
    rows = sum(len(t) for t in targets)
    D = np.zeros((rows, first[-1] + 3 * J))
    start = 0
    for p, (nuisance, shared) in enumerate(designs):
        D[start:start + len(nuisance), first[p]:first[p + 1]] = nuisance
        D[start:start + len(nuisance), first[-1]:] = shared
        start += len(nuisance)
    y = np.concatenate(targets)
    scale = np.linalg.norm(D, axis=0)
    scale[scale == 0] = 1.0
    Ds = D / scale
    singular = np.linalg.svd(Ds, compute_uv=False)
    fit = least_squares(lambda x: Ds @ x - y, np.zeros(D.shape[1]), jac=lambda x: Ds, method="lm")
    x = fit.x / scale
    residual, start = [], 0
    for nuisance, _ in designs:
        residual.append((D[start:start + len(nuisance)] @ x - y[start:start + len(nuisance)]).reshape(-1, 3))
        start += len(nuisance)
    nuisance = np.zeros((P, NUISANCE))
    for p, earth in enumerate(earths):
        found = x[first[p]:first[p + 1]]
        nuisance[p] = found if earth is None else np.r_[earth, found]
    return LinearFit(nuisance, x[first[-1]:].reshape(J, 3), residual, float(singular[0] / max(singular[-1], 1e-300)))


def earth_and_offset(rotation, raw, earth=None) -> LinearFit:
    """The Earth field and offset alone on one flight (``rotation`` (T, 3, 3), ``raw`` (T, 3) T), the
    offset alone when the Earth field ``earth`` (3,) (NED, T) is known: the baseline every
    interference model is scored against."""
    raw = np.asarray(raw)
    return fit_linear([(rotation, raw, np.zeros((len(raw), 0)), earth)])
