"""The ``dynamic`` model on a flight: the commands through identified motor dynamics.

:func:`quadcosim.calibration.fit_motor_dynamics` fits the back-EMF dynamics and one field gain per motor
along the directions of the ``metge`` fit, to the field left once the Earth field and the offset
are removed; :func:`quadcosim.calibration.compensate` evaluates it. Motor time constants are tens of
milliseconds, so both the magnetometer and the motor outputs must be logged faster than
:data:`quadcosim.calibration.flight.models.DYNAMIC_MIN_RATE_HZ`; slower logs refuse the model.
"""

from __future__ import annotations

import numpy as np
from quadcosim.calibration.compensator import compensate
from quadcosim.calibration.file import Calibration
from quadcosim.calibration.flight.catalogue import Model
from quadcosim.calibration.flight.models import DYNAMIC_MIN_RATE_HZ, Fitted
from quadcosim.calibration.identify import fit_motor_dynamics

GRID_HZ = 200.0  # the dynamics are integrated on this uniform grid


def _grid(data) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    time = np.arange(data.time[0], data.time[-1], 1.0 / GRID_HZ)
    m = data.motors
    commands = np.column_stack([np.interp(time, m.time, m.commands[:, n]) for n in range(m.commands.shape[1])])
    return time, commands, np.interp(time, data.battery.time, data.battery.voltage)


def _rate(time) -> float:
    return (len(time) - 1) / (time[-1] - time[0]) if len(time) > 1 else 0.0


class DynamicModel:
    """Motor dynamics and field gains identified on a flight, along the ``metge`` directions."""

    name = "dynamic"

    def __init__(self, metge: Fitted | None):
        self.metge = metge

    def refusal(self, parts) -> str | None:
        """Why the training ``parts`` (FlightData) cannot identify the model, or None."""
        mag = min(_rate(p.time) for p in parts)
        motors = min(_rate(p.motors.time) for p in parts)
        if min(mag, motors) < DYNAMIC_MIN_RATE_HZ:
            return (f"the log is too slow to see motor dynamics: magnetometer at {mag:.1f} Hz and motor outputs at "
                    f"{motors:.1f} Hz, both must exceed {DYNAMIC_MIN_RATE_HZ:g} Hz (log them faster)")
        if self.metge is None:
            return "it takes the field directions of the metge model, which was refused"
        if any(p.battery is None for p in parts):
            return "no battery voltage in the log to drive the motor model"
        return None

    def fit(self, parts) -> Fitted:
        """Fit on the training ``parts``; the Earth field and offset are those of the ``metge`` fit."""
        nuisance = self.metge.extra["nuisance"]
        v = self.metge.extra["field"].v
        records = []
        for p, (m_E, b) in zip(parts, ((n[:3], n[3:]) for n in nuisance), strict=True):
            left = p.raw - np.einsum("tij,i->tj", p.rotation, m_E) - b
            time, commands, voltage = _grid(p)
            field = np.column_stack([np.interp(time, p.time, left[:, k]) for k in range(3)])
            records.append((time - time[0], field, commands, voltage))
        dynamics = fit_motor_dynamics(records, np.zeros(3), v)
        calibration = Calibration(len(v), field=self.metge.extra["field"], dynamics=dynamics)

        def predict(data):
            time, commands, voltage = _grid(data)
            b_d = -compensate(calibration, time, np.zeros((len(time), 3)), commands, voltage, "dynamic")
            return np.column_stack([np.interp(data.time, time, b_d[:, k]) for k in range(3)])

        return Fitted("dynamic", 0.0, {"rate_1_s": dynamics.rate, "drag_1_V_s": dynamics.drag,
                                       "limit_V": dynamics.limit if np.isfinite(dynamics.limit) else None,
                                       "exponent": dynamics.exponent, "freewheel": dynamics.freewheel,
                                       "gain_T_per_V": np.asarray(dynamics.gain).tolist()},
                      predict, extra={"dynamics": dynamics})


#: The dynamic model, registered by its line in quadcosim.interference (pyproject.toml); it starts from metge.
DYNAMIC = Model("dynamic", lambda fitted: DynamicModel(fitted.get("metge")), preference=4, order=5)
