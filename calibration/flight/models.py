"""The interference models a flight can identify, each fitted with ``scipy.optimize.least_squares``
and each refused, with the reason, when the flight cannot identify it.

- ``current``: ``b_d = K i``, one vector per ampere (ArduPilot's ``COMPASS_MOTCT = 2``);
- ``throttle``: ``b_d = K t`` with ``t`` the autopilot's throttle (``CTUN.ThO``, PX4's thrust: the
  signal ``COMPASS_MOTCT = 1`` and ``CAL_MAG_COMP_TYP = 1`` multiply), or the mean motor command
  when the log has none;
- ``motors``: ``b_d = sum_n K_n c_n``, one vector per motor command;
- ``metge``: Metge et al.'s ``b_d = sum_n f(c_n, u; theta_n) v_n`` (eqs. 3, 4), the bi-polynomial
  of command and battery voltage evaluated by :class:`quadcosim.calibration.MotorFieldModel`;
- ``dynamic``: the commands through identified motor dynamics (:func:`quadcosim.calibration.fit_motor_dynamics`,
  evaluated by :func:`quadcosim.calibration.compensate`).

Each linear model is fitted for every delay of :data:`DELAYS` (its regressors read at ``t - d``)
and keeps the delay of least training residual, as PX4's offline compensation scripts search a
time shift; ``metge`` takes the delay of ``motors``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from quadcosim.calibration.dynamic import MotorFieldModel
from quadcosim.calibration.flight.catalogue import Model
from quadcosim.calibration.flight.linear import NUISANCE, fit_linear

from quadcosim.infra.errors import RunError

DELAYS = np.round(np.arange(0.0, 0.301, 0.02), 3)  # s
MIN_CURRENT_SPREAD_A = 1.0  # standard deviation of the current needed to identify the current model
MIN_COMMAND_SPREAD = 0.02  # standard deviation of a command (or the throttle) needed to identify a model
MAX_CONDITION = 1e3  # column-normalised design: above it, coefficients cannot be told apart
# (I, J) tried in turn, the richest first: the first the training flights identify is kept
METGE_ORDERS = ((2, 1), (2, 0))
METGE_EVALUATIONS = 2000  # residual evaluations, finite differences included
DYNAMIC_MIN_RATE_HZ = 50.0  # motor time constants of tens of ms need both records faster than this


class NotIdentifiable(RunError):
    """A model the flight cannot identify; the message is the reason."""


@dataclass
class Fitted:
    """A fitted interference model: ``name``, ``delay`` (s), ``coefficients`` (SI, JSON-ready),
    ``predict`` (FlightData -> (T, 3) field, T), ``condition`` (the design's condition number) and
    ``extra`` (the fit's arrays: ``K``, ``nuisance``, ``field``, ``dynamics``, as the model has them)."""

    name: str
    delay: float
    coefficients: dict
    predict: object
    condition: float = float("nan")
    extra: dict = field(default_factory=dict)


def _spread(parts, values) -> float:
    return float(np.std(np.concatenate([values(p) for p in parts])))


class LinearModel:
    """A model linear in its regressors; ``name`` is ``current``, ``throttle`` or ``motors``."""

    def __init__(self, name: str):
        self.name = name

    def regressors(self, data, delay: float) -> np.ndarray:
        """(T, J) regressors of ``data`` (a FlightData) read at ``t - delay`` (s)."""
        if self.name == "current":
            return data.current(delay)[:, None]
        if self.name == "throttle":
            autopilot = data.autopilot_throttle(delay)
            return (data.throttle(delay) if autopilot is None else autopilot)[:, None]
        return data.commands(delay)

    def refusal(self, parts) -> str | None:
        """Why the training ``parts`` cannot identify the model, or None."""
        if self.name == "current":
            if any(p.current() is None for p in parts):
                why = "no battery logged" if parts[0].battery is None else parts[0].battery.current_sensor
                return f"no current sensor in the log ({why})"
            spread = _spread(parts, lambda p: p.current())
            if spread < MIN_CURRENT_SPREAD_A:
                return f"the current varies too little ({spread:.2f} A standard deviation < {MIN_CURRENT_SPREAD_A} A)"
            return None
        spread = _spread(parts, lambda p: self.regressors(p, 0.0)[:, 0]) if self.name == "throttle" else \
            min(_spread(parts, lambda p, n=n: p.commands()[:, n]) for n in range(parts[0].motors.commands.shape[1]))
        if spread < MIN_COMMAND_SPREAD:
            what = "throttle" if self.name == "throttle" else "least varied motor command"
            return (f"too little throttle variation to identify anything: the {what} has a standard deviation "
                    f"of {spread:.3f} < {MIN_COMMAND_SPREAD}; fly with climbs and descents")
        return None

    def fit(self, parts) -> Fitted:
        """Fit on the training ``parts`` (FlightData), the delay searched over :data:`DELAYS`."""
        best = None
        for delay in DELAYS:
            fit = fit_linear([(p.rotation, p.raw, self.regressors(p, delay), p.earth) for p in parts])
            if best is None or fit.cost < best[1].cost:
                best = (float(delay), fit)
        delay, fit = best
        if fit.condition > MAX_CONDITION:
            raise NotIdentifiable(f"its regressors cannot be told from one another or from the Earth field and offset "
                          f"(condition number {fit.condition:.3g} > {MAX_CONDITION:g})")
        K = fit.K.copy()
        names = {"current": "K_T_per_A", "throttle": "K_T_per_throttle", "motors": "K_T_per_command"}
        coefficients = {names[self.name]: K.tolist() if self.name == "motors" else K[0].tolist()}
        return Fitted(self.name, delay, coefficients, lambda data: self.regressors(data, delay) @ K, fit.condition,
                      {"K": K, "nuisance": fit.nuisance})


def _unit(angles: np.ndarray) -> np.ndarray:
    azimuth, elevation = angles[:, 0], angles[:, 1]
    return np.column_stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                            np.sin(elevation)])


class MetgeModel:
    """Eqs. 3 and 4 of Metge et al. fitted on a flight, with the richest orders of
    :data:`METGE_ORDERS` the training flights identify; ``motors`` is the fitted ``motors`` model
    it starts from (None when refused)."""

    name = "metge"

    def __init__(self, motors: Fitted | None):
        self.motors = motors

    def refusal(self, parts) -> str | None:
        """Why the training ``parts`` cannot identify the model, or None."""
        if self.motors is None:
            return "the per-motor model it starts from was refused"
        return None

    def fit(self, parts) -> Fitted:
        """Fit directions and amplitude polynomials with the Earth field and offset of each of the
        training ``parts`` (FlightData), trying the orders of :data:`METGE_ORDERS` in turn."""
        reasons = []
        for orders in METGE_ORDERS:
            try:
                fitted = self._fit(parts, orders)
            except NotIdentifiable as error:
                reasons.append(f"orders (I, J) = {orders}: {error}")
                continue
            if reasons:
                fitted.coefficients["richer_orders_refused"] = reasons
            return fitted
        raise NotIdentifiable("; ".join(reasons))

    def _fit(self, parts, orders) -> Fitted:
        from scipy.optimize import least_squares

        if orders[1] > 0 and any(p.battery is None for p in parts):
            raise NotIdentifiable("no battery voltage in the log for the voltage terms")
        delay = self.motors.delay
        K = self.motors.extra["K"]
        N, (I, J) = len(K), orders
        width = I * (J + 1)
        inputs = [(p.commands(delay), p.voltage(delay)) for p in parts]
        angles0 = np.column_stack([np.arctan2(K[:, 1], K[:, 0]), np.arcsin(K[:, 2] / np.linalg.norm(K, axis=1))])
        theta0 = np.zeros((N, width))
        theta0[:, 0] = np.linalg.norm(K, axis=1)
        x0 = np.r_[self.motors.extra["nuisance"].ravel(), angles0.ravel(), theta0.ravel()]
        P = len(parts)
        scale = np.r_[np.full(NUISANCE * P, 1e-5), np.ones(2 * N), np.full(N * width, 1e-6)]

        def model(x):
            return MotorFieldModel(_unit(x[NUISANCE * P:NUISANCE * P + 2 * N].reshape(N, 2)),
                                   x[NUISANCE * P + 2 * N:].reshape(N, width), orders)

        def residual(x):
            field_model = model(x)
            out = []
            for k, (p, (c, u)) in enumerate(zip(parts, inputs, strict=True)):
                m_E, b = x[NUISANCE * k:NUISANCE * k + 3], x[NUISANCE * k + 3:NUISANCE * (k + 1)]
                predicted = np.einsum("tij,i->tj", p.rotation, m_E) + b + field_model.field(c, u)
                out.append((predicted - p.raw).ravel())
            return np.concatenate(out)

        fit = least_squares(residual, x0, x_scale=scale, method="lm", max_nfev=METGE_EVALUATIONS)
        columns = fit.jac / np.maximum(np.linalg.norm(fit.jac, axis=0), 1e-300)
        singular = np.linalg.svd(columns, compute_uv=False)
        condition = float(singular[0] / max(singular[-1], 1e-300))
        if condition > MAX_CONDITION:
            raise NotIdentifiable(f"its per-motor directions and polynomial coefficients cannot be told apart on these "
                          f"flights (condition number {condition:.3g} > {MAX_CONDITION:g})")
        found = model(fit.x)
        return Fitted("metge", delay, {"orders": {"I": I, "J": J}, "v": found.v.tolist(),
                                       "theta": found.theta.tolist()},
                      lambda data: found.field(data.commands(delay), data.voltage(delay)), condition,
                      {"field": found, "nuisance": fit.x[:NUISANCE * P].reshape(P, NUISANCE)})


def _vectors_field(vectors) -> MotorFieldModel:
    """Field vectors per motor (motors, 3) (T per unit command) as the file's model (eqs. 3, 4 of
    Metge et al.): unit directions and magnitudes, the field linear in each command."""
    norms = np.linalg.norm(vectors, axis=1)
    safe = np.where(norms > 0, norms, 1.0)
    directions = np.where(norms[:, None] > 0, vectors / safe[:, None], np.array([1.0, 0.0, 0.0]))
    return MotorFieldModel(directions, norms[:, None], (1, 0))


def _motors_field(fitted, motors: int) -> MotorFieldModel:
    return _vectors_field(fitted.extra["K"])


def _throttle_field(fitted, motors: int) -> MotorFieldModel:
    return _vectors_field(np.repeat(fitted.extra["K"] / motors, motors, axis=0))  # throttle = mean command


def _metge_field(fitted, motors: int) -> MotorFieldModel:
    return fitted.extra["field"]


# The models of this file, each registered by its line in quadcosim.interference (pyproject.toml).
CURRENT = Model("current", lambda fitted: LinearModel("current"), preference=1, autopilot=True, order=1)
THROTTLE = Model("throttle", lambda fitted: LinearModel("throttle"), preference=3, to_file=_throttle_field,
                 autopilot=True, order=2)
MOTORS = Model("motors", lambda fitted: LinearModel("motors"), preference=2, to_file=_motors_field, autopilot=True,
               order=3)
METGE = Model("metge", lambda fitted: MetgeModel(fitted.get("motors")), preference=0, to_file=_metge_field, order=4)
