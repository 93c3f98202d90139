"""Dynamic calibration of the field of the motor currents (Metge et al., eqs. 2 to 8).

Metge, Mégret, Giremus, Berthoumieu, Mazel, "Compensation dynamique des perturbations
magnétiques pour l'estimation d'attitude d'un micro-drone" (GRETSI 2013) model the field of
motor ``n`` at the magnetometer as a fixed direction times an amplitude that is a
bi-polynomial of the module's state ``lambda_n = (c_n, u_n)`` (command, battery voltage)::

    b_d = sum_n f(c_n, u_n; theta_n) v_n,     f = sum_{j=0..J} sum_{i=1..I} a_ij u^j c^i    (eqs. 3, 4)

Calibration, drone clamped: ``m0`` with the motors off, then each motor alone at K states:

- eq. 5: ``b_n,k = m_bar(lambda_n,k) - m0``;
- eq. 6: ``v_n = sum_k b_n,k / |sum_k b_n,k|`` (the sum weights the strong, reliable points);
- eq. 7: ``f_n,k = |b_n,k|``;
- eq. 8: ``theta_n`` by linear least squares on the basis ``u^j c^i``.

``theta_n`` is ordered as in the paper: ``[a_10, a_11, ..., a_1J, a_20, ..., a_IJ]`` (``i``
outer, ``j`` inner). Everything here works on raw readings, before the static correction,
as eq. 9 subtracts ``b_d`` before applying ``A^-1``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from quadcosim.calibration.static import CalibrationError


def basis(c, u, orders: tuple[int, int]) -> np.ndarray:
    """Columns ``u^j c^i`` (``i = 1..I`` outer, ``j = 0..J`` inner) of eq. 4, shape ``(..., I (J + 1))``,
    for commands ``c`` (1) and voltages ``u`` (V) of one shape; ``orders`` is ``(I, J)``."""
    I, J = orders
    c = np.asarray(c, dtype=float)[..., None]
    u = np.asarray(u, dtype=float)[..., None]
    i = np.repeat(np.arange(1, I + 1), J + 1)
    j = np.tile(np.arange(J + 1), I)
    return c**i * u**j


@dataclass(frozen=True)
class Sweep:
    """One motor's calibration measurements: ``K`` readings with that motor alone running.

    Attributes
    ----------
    field : (K, 3) array
        Raw magnetometer readings, sensor frame (T).
    command : (K,) array
        The motor's ESC command (1).
    voltage : (K,) array
        Battery voltage (V).
    """

    field: np.ndarray
    command: np.ndarray
    voltage: np.ndarray


@dataclass(frozen=True)
class MotorFieldModel:
    """The paper's perturbation model: directions ``v`` (N, 3) and amplitudes ``theta`` (N, I (J + 1)).

    ``field(c, u)`` evaluates eq. 3 for commands ``c`` of shape ``(..., N)`` (1) and voltages
    ``u`` of shape ``(...)`` (V); returns ``(..., 3)`` (T). ``orders`` ``(I, J)``: powers of the
    command and of the voltage (eq. 4).
    """

    v: np.ndarray
    theta: np.ndarray
    orders: tuple[int, int] = (4, 1)

    def __post_init__(self):
        I, J = self.orders
        if self.v.ndim != 2 or self.v.shape[1] != 3:
            raise CalibrationError(f"directions v must have shape (motors, 3), not {self.v.shape}")
        if self.theta.shape != (len(self.v), I * (J + 1)):
            raise CalibrationError(f"theta must have shape ({len(self.v)}, {I * (J + 1)}) for orders I = {I}, "
                                   f"J = {J}, not {self.theta.shape}")

    @property
    def motors(self) -> int:
        """Number of motors N."""
        return len(self.v)

    def amplitude(self, c, u) -> np.ndarray:
        """Amplitudes ``f(c_n, u)`` (T), shape ``(..., N)``."""
        c = np.asarray(c, dtype=float)
        u = np.asarray(u, dtype=float)[..., None]
        return np.einsum("...nk,nk->...n", basis(c, np.broadcast_to(u, c.shape), self.orders), self.theta)

    def field(self, c, u) -> np.ndarray:
        """Eq. 3: ``sum_n f(c_n, u) v_n`` (T, sensor frame), shape ``(..., 3)``, for commands
        ``c`` (1) of shape ``(..., N)`` and voltages ``u`` (V) of shape ``(...)``."""
        return self.amplitude(c, u) @ self.v


def fit_dynamic(reference, sweeps, orders: tuple[int, int] = (4, 1)) -> MotorFieldModel:
    """Eqs. 5 to 8: directions and amplitude polynomials of each motor's field.

    Parameters
    ----------
    reference : (3,) array
        ``m0``, the raw reading with all motors off, drone clamped (T).
    sweeps : sequence of Sweep
        One per motor, in motor order.
    orders : (int, int)
        ``(I, J)``: highest power of the command (>= 1) and of the voltage (>= 0).
    """
    I, J = (int(orders[0]), int(orders[1]))
    if I < 1 or J < 0:
        raise CalibrationError(f"orders (I, J) = {orders} must have I >= 1 and J >= 0")
    m0 = np.asarray(reference, dtype=float)
    if m0.shape != (3,) or not np.isfinite(m0).all():
        raise CalibrationError(f"reference m0 must be 3 finite values, not {m0!r}")
    v, theta = [], []
    for n, sweep in enumerate(sweeps, start=1):
        field = np.asarray(sweep.field, dtype=float)
        c = np.asarray(sweep.command, dtype=float)
        u = np.asarray(sweep.voltage, dtype=float)
        if field.ndim != 2 or field.shape[1] != 3 or c.shape != (len(field),) or u.shape != (len(field),):
            raise CalibrationError(f"motor {n}: field (K, 3), command (K,) and voltage (K,) must agree; got "
                                   f"{field.shape}, {c.shape}, {u.shape}")
        if not (np.isfinite(field).all() and np.isfinite(c).all() and np.isfinite(u).all()):
            raise CalibrationError(f"motor {n}: the sweep holds NaN or Inf")
        columns = I * (J + 1)
        if len(field) < columns:
            raise CalibrationError(f"motor {n}: {len(field)} points cannot fit {columns} coefficients (I = {I}, "
                                   f"J = {J}); sweep more points or lower the orders")
        b = field - m0  # eq. 5
        total = b.sum(axis=0)
        if not np.linalg.norm(total) > 0:
            raise CalibrationError(f"motor {n}: the sweep shows no perturbation; was the motor running?")
        v_n = total / np.linalg.norm(total)  # eq. 6
        f = np.linalg.norm(b, axis=1)  # eq. 7
        design = basis(c, u, (I, J))
        scale = np.abs(design).max(axis=0)
        scale[scale == 0] = 1.0
        coefficients, *_ = np.linalg.lstsq(design / scale, f, rcond=None)  # eq. 8
        v.append(v_n)
        theta.append(coefficients / scale)
    if not v:
        raise CalibrationError("no sweep given: one per motor is needed")
    return MotorFieldModel(np.array(v), np.array(theta), (I, J))


def amplitude_residual(model: MotorFieldModel, reference, sweeps) -> float:
    """RMS of ``|b_n,k| - f(c, u)`` over every motor's points (T): the eq. 8 residual on
    any set, which is the cross-validation score of :func:`order_study`.

    Parameters
    ----------
    model : MotorFieldModel
        The fitted model.
    reference : (3,) array
        Field with the motors off (T, sensor frame), subtracted from every point.
    sweeps : sequence
        One sweep per motor, with ``field`` (k, 3) (T), ``command`` (k,) (1) and ``voltage`` (k,) (V).
    """
    m0 = np.asarray(reference, dtype=float)
    squares = []
    for n, sweep in enumerate(sweeps):
        measured = np.linalg.norm(np.asarray(sweep.field) - m0, axis=1)
        predicted = basis(sweep.command, sweep.voltage, model.orders) @ model.theta[n]
        squares.append((measured - predicted) ** 2)
    return float(np.sqrt(np.concatenate(squares).mean()))


def order_study(sets, I_range=range(1, 7), J_range=range(0, 3)) -> dict:
    """Orders ``(I, J)`` chosen by cross-validation between calibration sets.

    Each set (``(reference, sweeps)``) is fitted in turn and scored on the others; the score
    is the mean held-out amplitude RMS (T). Returns the score table and the best orders (the
    smallest model within 2 % of the lowest score: extra coefficients must earn their place).
    ``I_range`` and ``J_range`` are the command and voltage orders tried.
    """
    if len(sets) < 2:
        raise CalibrationError("cross-validation needs at least two calibration sets")
    scores = {}
    for I in I_range:
        for J in J_range:
            held_out = []
            for k, (reference, sweeps) in enumerate(sets):
                model = fit_dynamic(reference, sweeps, (I, J))
                held_out += [amplitude_residual(model, r, s) for m, (r, s) in enumerate(sets) if m != k]
            scores[(I, J)] = float(np.mean(held_out))
    lowest = min(scores.values())
    best = min((k for k, s in scores.items() if s <= 1.02 * lowest), key=lambda k: (k[0] * (k[1] + 1), k))
    return {"scores": scores, "best": best}
