"""Magnetometer calibration and compensation of the motor currents' field.

- :func:`fit_static`: soft and hard iron by ellipsoid fitting (:mod:`quadcosim.calibration.static`);
- :func:`fit_dynamic`, :func:`order_study`: the motor-field model of Metge et al.
  (:mod:`quadcosim.calibration.dynamic`);
- :func:`fit_motor_dynamics`: motor dynamics from the rig data (:mod:`quadcosim.calibration.identify`);
- :class:`Calibration`: all of it, saved to and loaded from JSON (:mod:`quadcosim.calibration.file`);
- :class:`MagCompensator` and :func:`compensate`: eq. 9 streaming and on arrays
  (:mod:`quadcosim.calibration.compensator`).
"""

from quadcosim.infra import numba_cache

# before the modules below decorate their functions: numba picks a function's cache folder then
numba_cache.install()

from quadcosim.calibration.compensator import MagCompensator, compensate
from quadcosim.calibration.dynamic import MotorFieldModel, Sweep, fit_dynamic, order_study
from quadcosim.calibration.file import Calibration
from quadcosim.calibration.identify import MotorDynamics, fit_motor_dynamics
from quadcosim.calibration.static import Bounds, CalibrationError, StaticCalibration, fit_static

__all__ = ["Bounds", "Calibration", "CalibrationError", "MagCompensator", "MotorDynamics", "MotorFieldModel",
           "StaticCalibration", "Sweep", "compensate", "fit_dynamic", "fit_motor_dynamics", "fit_static",
           "order_study"]
