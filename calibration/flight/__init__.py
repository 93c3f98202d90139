"""Magnetometer calibration from real flights (logs read by :mod:`flightlogs`).

For one compass, the raw field (before the autopilot's own corrections) is explained as the
Earth field rotated into the body frame, an offset, and the field of the motor currents::

    m_raw(t) = R(t)^T m_E + b + b_d(t)

- :mod:`quadcosim.calibration.flight.data`: the compass aligned with the attitude that removes the Earth
  field, the log's own or one whose heading is integrated from the gyro (the default: the log's
  heading is steered by the compass being calibrated, so its interference leaks into it);
- :mod:`quadcosim.calibration.flight.linear`: the Earth field and offset of each flight with the shared
  coefficients, by least squares;
- :mod:`quadcosim.calibration.flight.catalogue`: the interference models, registered in the
  entry-point group ``quadcosim.interference``: :mod:`quadcosim.calibration.flight.models`' ``current``,
  ``throttle``, ``motors`` and ``metge`` and :mod:`quadcosim.calibration.flight.dynamic`'s, each refused
  with its reason when the flight cannot identify it;
- :mod:`quadcosim.calibration.flight.evaluate`: out-of-sample scores;
- :mod:`quadcosim.calibration.flight.calibrate`: all of it, and the :class:`quadcosim.calibration.Calibration`;
- :mod:`quadcosim.calibration.flight.export`: the parameters of the log's autopilot, scored as its
  firmware applies them (each autopilot's arithmetic and parameter writer are its own, in
  :mod:`quadcosim.flightlogs.autopilots`).
"""

from quadcosim.calibration.flight.calibrate import calibrate
from quadcosim.calibration.flight.data import ATTITUDES, FlightData, flight_data

__all__ = ["ATTITUDES", "FlightData", "calibrate", "flight_data"]
