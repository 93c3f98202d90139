"""Motor dynamics identified from the clamped-rig data, for a compensation that knows them.

Metge et al. name the weakness of eq. 9: during fast command changes the command no longer
matches the motor's state. A brushless motor behind its ESC is, in the DC-motor approximation
with a quasi-static current (electrical time constant far below the mechanical one), a
back-EMF ``e = k_e omega`` that obeys::

    de/dt = rate w - drag e |e|,    rate = k_e^2 / (J_r R),  drag = k_m / (J_r k_e)

with the winding voltage ``w = c u - e`` and current ``w / R``. The field of a supply cable follows the ESC's input
current ``c (c u - e) / R`` (``exponent = 1``), that of a motor lead the motor current
(``exponent = 0``); an ESC that free-wheels passes no negative current (``w >= 0``), and a
current limit clips it (``|w| <= limit``), in the dynamics as in the field.
:func:`fit_motor_dynamics` fits ``rate``, ``drag``, the limit and one gain per motor to the
magnetometer record of the calibration sweeps (readings minus ``m0`` against the directions
``v_n`` of eq. 6), for each structural choice (exponent, free-wheeling), and keeps the best.
Only what a real rig records is used: commands, battery voltage, magnetometer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from quadcosim.calibration.compensator import _compensate
from quadcosim.calibration.static import CalibrationError


@dataclass(frozen=True)
class MotorDynamics:
    """Identified motor dynamics and field gains (see the module docstring).

    Attributes
    ----------
    rate : float
        1/s.
    drag : float
        1/(V s).
    limit : float
        Largest winding voltage ``c u - e`` passed (V), the current limit times R.
    exponent : int
        1: field of the ESC input current; 0: of the motor current.
    freewheel : bool
        True: no negative current.
    gain : (N,) array
        Field amplitude per volt of winding voltage (T/V), per motor.
    rms : float
        RMS residual of the fit (T).
    """

    rate: float
    drag: float
    limit: float
    exponent: int
    freewheel: bool
    gain: np.ndarray
    rms: float = float("nan")

    def vector(self) -> np.ndarray:
        """``rate, drag, limit, exponent, freewheel, gain[N]`` as the compensator's dynamics vector."""
        return np.r_[self.rate, self.drag, self.limit, float(self.exponent), float(self.freewheel),
                     np.asarray(self.gain, dtype=float)]


def _predicted(params, time, c, u, v, exponent, freewheel, sample_rate):
    n = len(v)
    dynamics = np.r_[np.exp(np.clip(params[:3], -30.0, 30.0)), exponent, freewheel, params[3:3 + n]]
    out = np.empty((len(time), 3))
    zero = np.zeros(n)
    # Compensating a zero reading with A = I, b_s = 0 returns -b_d: the prediction, negated.
    _compensate(time, np.zeros((len(time), 3)), c, u, np.eye(3), np.zeros(3), v, zero[:, None], 1, 0,
                dynamics, 2, sample_rate, out)
    return -out


def fit_motor_dynamics(records, reference, v, sample_rate: float = 0.0, progress=None) -> MotorDynamics:
    """Fit the motor dynamics and field gains to rig records.

    Parameters
    ----------
    records : sequence of (time, magneto, commands, voltage)
        Time series (s, T (T, 3), 1 (T, N), V) recorded on the clamped rig, each starting
        with the motors at rest; the calibration sweeps themselves.
    reference : (3,) array or sequence of them
        ``m0`` of each record (T).
    v : (N, 3) array
        Directions of eq. 6.
    sample_rate : float
        Magnetometer rate (Hz); only its sample instants are fitted. 0: every row.
    progress : callable, optional
        Called with a line of text before each of the least-squares fits (a few seconds each).
    """
    v = np.asarray(v, dtype=float)
    references = np.broadcast_to(np.asarray(reference, dtype=float), (len(records), 3))
    data = []
    for (time, mag, c, u), m0 in zip(records, references, strict=True):
        time = np.asarray(time, dtype=float)
        rows = (np.ones(len(time), bool) if sample_rate <= 0
                else np.abs(time * sample_rate - np.round(time * sample_rate)) < 1e-6)
        data.append((time, np.ascontiguousarray(c, dtype=float), np.ascontiguousarray(u, dtype=float),
                     (np.asarray(mag) - m0)[rows], rows))
    u_mean = float(np.mean(np.concatenate([d[2] for d in data])))
    scale = float(np.sqrt(np.mean(np.concatenate([d[3] for d in data]) ** 2)))
    if not scale > 0:
        raise CalibrationError("the records show no perturbation; were the motors running?")

    def residual(params, exponent, freewheel):
        parts = [(_predicted(params, t, c, u, v, exponent, freewheel, sample_rate)[rows] - b) / scale
                 for t, c, u, b, rows in data]
        return np.concatenate(parts).ravel()

    # physical bounds: mechanical time constants of 2 ms to 1 s, a drag and a limit within
    # six decades, gains of either sign
    lower = np.r_[np.log(1.0), np.log(1e-4), np.log(1e-3 * u_mean), np.full(len(v), -np.inf)]
    upper = np.r_[np.log(500.0), np.log(1e2), np.log(1e3 * u_mean), np.full(len(v), np.inf)]

    def fit(exponent, freewheel, rate0, limit0, evaluations=300):
        # start: back-EMF at 85 % of the drive at full command, gains matched on the first record
        start = np.r_[np.log(rate0), np.log(rate0 * 0.15 / (0.85**2 * u_mean)), np.log(limit0), np.zeros(len(v))]
        unit = _predicted(np.r_[start[:3], np.ones(len(v))], *data[0][:3], v, exponent, freewheel,
                          sample_rate)[data[0][4]]
        start[3:] = np.linalg.norm(data[0][3], axis=1).mean() / max(np.linalg.norm(unit, axis=1).mean(), 1e-30)
        from scipy.optimize import least_squares  # imported where used: start-up

        if progress is not None:
            progress(f"identifying the motors' dynamics: a fit from a {1e3 / rate0:.0f} ms time constant "
                     f"(exponent {exponent}, {'free-wheeling' if freewheel else 'regenerative'} ESCs)")
        result = least_squares(residual, np.clip(start, lower, upper), args=(exponent, freewheel), x_scale="jac",
                               max_nfev=evaluations, bounds=(lower, upper), ftol=1e-6, xtol=1e-6)
        return float(np.sqrt(np.mean(result.fun**2))) * scale, result.x, exponent, freewheel

    # The structure from a 25 ms mechanical time constant and a limit at 15 % of the voltage, then
    # other starts against local minima (a limit never reached, slower and faster motors).
    # The structures are told apart by short fits.
    best = min((fit(e, f, 40.0, 0.15 * u_mean, 40) for e in (1, 0) for f in (1.0, 0.0)),
               key=lambda r: r[0])
    for rate0, limit0 in ((40.0, 0.15 * u_mean), (40.0, u_mean), (10.0, 0.15 * u_mean), (150.0, 0.15 * u_mean)):
        best = min(best, fit(best[2], best[3], rate0, limit0), key=lambda r: r[0])
    cost, x, exponent, freewheel = best
    limit = float(np.exp(x[2]))
    if limit > 10 * u_mean:  # never reached in the records: no limit seen
        limit = np.inf
    return MotorDynamics(rate=float(np.exp(x[0])), drag=float(np.exp(x[1])), limit=limit,
                         exponent=int(exponent), freewheel=bool(freewheel), gain=np.array(x[3:]), rms=cost)
