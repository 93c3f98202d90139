"""Magnetometer calibration and compensation of the motor currents' field.

- :func:`fit_static`: soft and hard iron by ellipsoid fitting (:mod:`calibration.static`);
- :func:`fit_dynamic`, :func:`order_study`: the motor-field model of Metge et al.
  (:mod:`calibration.dynamic`);
- :func:`fit_motor_dynamics`: motor dynamics from the rig data (:mod:`calibration.identify`);
- :class:`Calibration`: all of it, saved to and loaded from JSON (:mod:`calibration.file`);
- :class:`MagCompensator` and :func:`compensate`: eq. 9 streaming and on arrays
  (:mod:`calibration.compensator`).
"""

from orchestrator import numba_cache

# before the modules below decorate their functions: numba picks a function's cache folder then
numba_cache.install()

from calibration.compensator import MagCompensator, compensate
from calibration.dynamic import MotorFieldModel, Sweep, fit_dynamic, order_study
from calibration.file import Calibration
from calibration.identify import MotorDynamics, fit_motor_dynamics
from calibration.static import Bounds, CalibrationError, StaticCalibration, fit_static

__all__ = ["Bounds", "Calibration", "CalibrationError", "MagCompensator", "MotorDynamics", "MotorFieldModel",
           "StaticCalibration", "Sweep", "compensate", "fit_dynamic", "fit_motor_dynamics", "fit_static",
           "order_study"]
