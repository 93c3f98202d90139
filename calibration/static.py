"""Static magnetometer calibration: soft iron ``A`` and hard iron ``b_s`` by ellipsoid fitting.

Sensor model (Metge et al., "Compensation dynamique des perturbations magnétiques pour
l'estimation d'attitude d'un micro-drone", eq. 1, motors off so ``b_d = 0``)::

    m_bar = A m + b_s + noise,    |m| = constant (the Earth field)

so the measurements lie on the ellipsoid ``|A^-1 (m_bar - b_s)| = |m|``.

Convention for what an ellipsoid cannot determine
--------------------------------------------------
The ellipsoid fixes ``A A^T`` and ``b_s`` only: ``A`` and ``A R`` (any rotation ``R``) fit the
same samples. :func:`fit_static` returns the **symmetric positive-definite** ``A`` (the polar
factor: the correction that rotates the samples least; a rotation between sensor and body
axes is an alignment question no sweep of ``|m|`` can answer). Its scale is set by
``field_norm`` (the norm of the corrected field, in the samples' unit) when given; otherwise
``det A = 1``, so the corrected field keeps the ellipsoid's mean radius.

Refusals follow ArduPilot's ``CompassCalibrator::fit_acceptable`` (AP_Compass library): field
radius between 150 and 950 mGauss, each hard-iron offset below ``COMPASS_OFFS_MAX`` (1800
mGauss by default), soft-iron diagonal within 0.2 to 5 and off-diagonal below 1 in magnitude
(for the unit-determinant correction matrix, as ArduPilot's radius carries the scale), and the
RMS residual below ``COMPASS_CAL_FIT`` (16 mGauss by default). The sphere coverage figure
counts the 80 cells of a near-uniform grid (ArduPilot's completion mask uses the 80 triangles
of a geodesic grid).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from quadcosim.infra.errors import UsageError


class CalibrationError(UsageError, ValueError):
    """Data or a file that cannot give a calibration; the message names the defect and the fix."""


@dataclass(frozen=True)
class Bounds:
    """Sanity bounds of a static fit, in the samples' unit (tesla by default).

    Parameters
    ----------
    radius : (float, float) or None
        Accepted field norm (ArduPilot: 150 to 950 mGauss = 15 to 95 uT).
    offset_max : float or None
        Largest accepted hard-iron component (ArduPilot ``COMPASS_OFFS_MAX``: 1800 mGauss).
    rms_max : float or None
        Largest accepted RMS residual of ``|m|`` (ArduPilot ``COMPASS_CAL_FIT``: 16 mGauss).
    diagonal : (float, float)
        Accepted diagonal of the unit-determinant correction ``A^-1`` (1).
    off_diagonal : float
        Largest accepted off-diagonal magnitude of the same matrix (1).
    """

    radius: tuple[float, float] | None = (15e-6, 95e-6)
    offset_max: float | None = 180e-6
    rms_max: float | None = 1.6e-6
    diagonal: tuple[float, float] = (0.2, 5.0)
    off_diagonal: float = 1.0

    def scaled(self, factor: float) -> Bounds:
        """The same bounds in another unit: ``factor`` is that unit per tesla (1e6 for uT)."""
        return replace(self,
                       radius=None if self.radius is None else (self.radius[0] * factor, self.radius[1] * factor),
                       offset_max=None if self.offset_max is None else self.offset_max * factor,
                       rms_max=None if self.rms_max is None else self.rms_max * factor)


TESLA = Bounds()
MIN_SAMPLES = 50
PLANAR_RATIO = 0.02  # smallest over largest spread of the samples below which a sweep is planar
COVERAGE_CELLS = 80
# A recorded sweep must spread off its plane by more than its noise, by this many standard
# errors: a sweep about one axis does not, whatever the noise (its samples' spread off the plane
# is their noise); an ellipsoid as flat as ArduPilot's bounds allow, turned every way, does.
OFF_PLANE_ERRORS = 5.0
ORDERED_CORRELATION = 0.1  # lag-1 correlation above which samples are taken as a recorded sequence
AXIS_COSINE = 0.9  # a direction this close to a sensor axis is named as that axis


@dataclass(frozen=True)
class StaticCalibration:
    """Result of :func:`fit_static`: ``m_bar = A m + b_s``.

    Attributes
    ----------
    A : (3, 3) array
        Soft-iron matrix, symmetric positive definite (1, or unit of samples per unit of field).
    b_s : (3,) array
        Hard-iron bias, sensor frame, in the samples' unit.
    field_norm : float
        Norm of the corrected field ``|A^-1 (m_bar - b_s)|`` the fit aims at.
    spread : float
        Relative spread of the corrected norm: std / mean (1).
    rms : float
        RMS residual of the corrected norm against ``field_norm`` (samples' unit).
    coverage : float
        Fraction of the 80 sphere cells the corrected directions visit (1).
    samples : int
        Number of samples fitted.
    """

    A: np.ndarray
    b_s: np.ndarray
    field_norm: float
    spread: float = 0.0
    rms: float = 0.0
    coverage: float = 0.0
    samples: int = 0

    def correct(self, samples) -> np.ndarray:
        """Corrected field ``A^-1 (m_bar - b_s)`` of ``(N, 3)`` (or ``(3,)``) samples, same unit."""
        x = np.asarray(samples, dtype=float)
        return np.linalg.solve(self.A, (x - self.b_s).T).T

    def quality(self) -> dict:
        """Quality figures: ``spread`` (1), ``rms`` (samples' unit), ``coverage`` (1), ``samples``,
        ``field_norm`` (samples' unit)."""
        return {"spread": self.spread, "rms": self.rms, "coverage": self.coverage, "samples": self.samples,
                "field_norm": self.field_norm}


def _check_samples(samples, min_samples: int) -> np.ndarray:
    x = np.asarray(samples, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3:
        raise CalibrationError(f"samples must be an (N, 3) array of magnetometer readings, not shape {x.shape}")
    bad = ~np.isfinite(x).all(axis=1)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise CalibrationError(f"{int(bad.sum())} sample(s) hold NaN or Inf (first at row {first}); "
                               "drop them before fitting")
    if len(x) < min_samples:
        raise CalibrationError(f"too few samples: {len(x)} < {min_samples}; record a longer sweep "
                               "(turn the sensor through all orientations)")
    _, spread, axes = np.linalg.svd(x - x.mean(axis=0), full_matrices=False)
    if not spread[0] > 0:
        raise CalibrationError(f"the {len(x)} samples are all equal ({x[0].tolist()}): the sensor did not turn, or "
                               "reads a constant (zeros: is it connected?); record a sweep through all orientations")
    missing = _axis_name(axes[2])
    if spread[2] < PLANAR_RATIO * spread[0]:
        raise CalibrationError(
            f"planar or single-axis sweep: the samples span a plane (smallest/largest spread "
            f"{spread[2] / spread[0]:.3f} < {PLANAR_RATIO}), which cannot determine an ellipsoid; they hardly "
            f"move along the sensor's {missing}: turn the sensor about the other axes too (roll and pitch it as "
            "well as yaw)")
    if not _leaves_the_plane(x - x.mean(axis=0), spread / np.sqrt(len(x)), axes):
        raise CalibrationError(
            f"planar or single-axis sweep: off the plane of the sweep the samples spread no more than their noise; "
            f"they never move along the sensor's {missing}, whatever the noise: the sweep turned the sensor about "
            "one axis; turn it about the others too (roll and pitch it as well as yaw)")
    return x


def _leaves_the_plane(centred: np.ndarray, spread: np.ndarray, axes: np.ndarray) -> bool:
    """Whether the samples spread along their weakest principal axis by more than their noise.

    The noise along that axis is half the variance of the differences of successive samples,
    when they follow each other (a recorded sweep: successive positions correlated); its spread
    beyond the noise must exceed :data:`OFF_PLANE_ERRORS` standard errors of the variances'
    difference (``sqrt(2 / N)`` of the noise variance). Samples in no order pass (the relative
    test of :data:`PLANAR_RATIO` is theirs)."""
    first = centred @ axes[0]
    if not np.corrcoef(first[:-1], first[1:])[0, 1] > ORDERED_CORRELATION:
        return True
    noise = np.var(np.diff(centred @ axes[2])) / 2.0
    return bool(spread[2] ** 2 - noise > OFF_PLANE_ERRORS * noise * np.sqrt(2.0 / len(centred)))


def _axis_name(direction: np.ndarray) -> str:
    """A direction of the sensor frame in words: ``"z axis"``, or ``"axis (0.12, 0.70, 0.70)"``."""
    k = int(np.argmax(np.abs(direction)))
    if abs(direction[k]) > AXIS_COSINE:
        return f"{'xyz'[k]} axis"
    return "axis ({:.2f}, {:.2f}, {:.2f})".format(*(direction * np.sign(direction[k])))


def _algebraic(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear least-squares quadric ``x^T M x + 2 n^T x = 1``; returns the centre and the
    matrix ``Q`` of ``(x - c)^T Q (x - c) = 1``."""
    X, Y, Z = x.T
    design = np.column_stack([X * X, Y * Y, Z * Z, 2 * Y * Z, 2 * X * Z, 2 * X * Y, 2 * X, 2 * Y, 2 * Z])
    p, *_ = np.linalg.lstsq(design, np.ones(len(x)), rcond=None)
    M = np.array([[p[0], p[5], p[4]], [p[5], p[1], p[3]], [p[4], p[3], p[2]]])
    n = p[6:9]
    try:
        centre = -np.linalg.solve(M, n)
    except np.linalg.LinAlgError:
        raise CalibrationError("the samples do not lie on an ellipsoid (singular quadric); "
                               "check the sweep covers all orientations with the motors off") from None
    k = 1.0 + centre @ M @ centre
    Q = M / k
    if not (np.linalg.eigvalsh(Q) > 0).all():
        raise CalibrationError("the samples do not lie on an ellipsoid (the fitted quadric is not positive "
                               "definite); check the sweep covers all orientations with the motors off")
    return centre, Q


def _sym(p: np.ndarray) -> np.ndarray:
    return np.array([[p[0], p[3], p[4]], [p[3], p[1], p[5]], [p[4], p[5], p[2]]])


def _sqrtm_spd(Q: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh(Q)
    return (V * np.sqrt(w)) @ V.T


def sphere_coverage(directions: np.ndarray, cells: int = COVERAGE_CELLS) -> float:
    """Fraction of ``cells`` near-uniform cells (Fibonacci centres) that ``directions`` visit."""
    k = np.arange(cells) + 0.5
    z = 1.0 - 2.0 * k / cells
    phi = np.pi * (1.0 + 5.0**0.5) * k
    r = np.sqrt(1.0 - z * z)
    centres = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    unit = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    hit = np.unique(np.argmax(unit @ centres.T, axis=1))
    return len(hit) / cells


def fit_static(samples, field_norm: float | None = None, bounds: Bounds | None = TESLA,
               min_samples: int = MIN_SAMPLES) -> StaticCalibration:
    """Fit soft iron ``A`` and hard iron ``b_s`` to a rotation sweep, motors off.

    An algebraic ellipsoid fit gives the start; ``scipy.optimize.least_squares`` refines the
    nine parameters (symmetric correction and centre) on the geometric residual
    ``|S (m_bar - b_s)| - 1``.

    Parameters
    ----------
    samples : (N, 3) array
        Magnetometer readings in the sensor frame, any consistent unit (tesla for the default
        ``bounds``).
    field_norm : float, optional
        Norm of the true field in the samples' unit; sets the scale of ``A``. Default:
        ``det A = 1``.
    bounds : Bounds or None
        Sanity bounds (ArduPilot's, in tesla); ``TESLA.scaled(1e6)`` for microtesla, ``None``
        to accept any fit.
    min_samples : int
        Fewest samples accepted.

    Returns
    -------
    StaticCalibration

    Raises
    ------
    CalibrationError
        Too few samples, non-finite values, a planar or single-axis sweep, no ellipsoid, or a
        fit outside ``bounds``.
    """
    x = _check_samples(samples, min_samples)
    mean = x.mean(axis=0)
    scale = np.sqrt(((x - mean) ** 2).sum(axis=1).mean())
    y = (x - mean) / scale  # conditioning: unit-size cloud around the origin
    centre, Q = _algebraic(y)
    S = _sqrtm_spd(Q)
    start = np.r_[S[0, 0], S[1, 1], S[2, 2], S[0, 1], S[0, 2], S[1, 2], centre]

    def residual(p):
        return np.linalg.norm((y - p[6:]) @ _sym(p[:6]), axis=1) - 1.0

    from scipy.optimize import least_squares  # imported where used: start-up

    fit = least_squares(residual, start, method="lm", x_scale="jac")
    S = _sym(fit.x[:6])
    if not (np.linalg.eigvalsh(S) > 0).all():
        raise CalibrationError("the refined fit is not positive definite; the sweep does not determine "
                               "an ellipsoid (cover all orientations)")
    S = S / scale  # correction in sample units: |S (x - b)| = 1
    b_s = mean + scale * fit.x[6:]
    unit_shape = np.linalg.inv(S)  # A up to scale
    radius = np.linalg.det(unit_shape) ** (1.0 / 3.0)  # equal-volume sphere radius (samples' unit)
    norm = radius if field_norm is None else float(field_norm)
    if not (np.isfinite(norm) and norm > 0):
        raise CalibrationError(f"field_norm = {field_norm!r} must be a positive number in the samples' unit")
    A = unit_shape / norm
    corrected = (x - b_s) @ np.linalg.inv(A).T
    magnitude = np.linalg.norm(corrected, axis=1)
    rms_radius = float(np.sqrt(np.mean((np.linalg.norm((x - b_s) @ S.T, axis=1) * radius - radius) ** 2)))
    result = StaticCalibration(A=A, b_s=b_s, field_norm=norm, spread=float(magnitude.std() / magnitude.mean()),
                               rms=float(np.sqrt(np.mean((magnitude - norm) ** 2))),
                               coverage=sphere_coverage(corrected), samples=len(x))
    if bounds is not None:
        _check_bounds(radius, b_s, radius * S, rms_radius, bounds)
    return result


def _check_bounds(radius: float, b_s: np.ndarray, correction: np.ndarray, rms: float, bounds: Bounds):
    """ArduPilot's acceptance test, on the radius, the offsets, the unit-determinant
    correction matrix and the RMS residual (all in the samples' unit)."""
    diagonal = np.diag(correction)
    low, high = bounds.diagonal
    if not ((diagonal > low) & (diagonal < high)).all():
        raise CalibrationError(f"soft-iron diagonal {np.round(diagonal, 3).tolist()} is outside ({low}, {high}); "
                               "the sweep is too distorted or incomplete to trust: repeat it away from iron")
    off = np.abs(correction[np.triu_indices(3, 1)])
    if (off >= bounds.off_diagonal).any():
        raise CalibrationError(f"soft-iron off-diagonal {np.round(off, 3).tolist()} reaches {bounds.off_diagonal}; "
                               "repeat the sweep away from iron")
    if bounds.radius is not None and not bounds.radius[0] < radius < bounds.radius[1]:
        raise CalibrationError(f"fitted field radius {radius:.4g} is outside ({bounds.radius[0]:.4g}, "
                               f"{bounds.radius[1]:.4g}); the samples are not an Earth field in this unit (pass "
                               "bounds=TESLA.scaled(factor) for another unit) or a magnet is near the sensor")
    if bounds.offset_max is not None and np.abs(b_s).max() >= bounds.offset_max:
        raise CalibrationError(f"hard-iron offset {np.abs(b_s).max():.4g} exceeds {bounds.offset_max:.4g}; "
                               "move the sensor away from magnetised parts or raise bounds.offset_max")
    if bounds.rms_max is not None and rms > bounds.rms_max:
        raise CalibrationError(f"RMS residual {rms:.4g} exceeds {bounds.rms_max:.4g}: the samples are not one "
                               "ellipsoid (motors on, a moving magnet, or a varying field during the sweep)")
