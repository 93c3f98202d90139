"""Flight: the controller, the mixer and the flight profiles of the closed loop.

- :mod:`quadcosim.flight.controller`: ``Controller``, attitude, altitude and position-hold
  control law (a block like the others);
- :mod:`quadcosim.flight.mixer`: thrust and torques to rotor speeds (quad-X allocation) and
  rotor speeds to ESC commands (the motors' steady-state map of :mod:`quadcosim.fmus.vehicle`);
- :mod:`quadcosim.flight.profiles`: the setpoint tables of the lab's flight profiles.
"""

from quadcosim.infra import numba_cache

# before the modules below decorate their functions: numba picks a function's cache folder then
numba_cache.install()

from quadcosim.flight.controller import GAINS, SETPOINT, Controller
from quadcosim.flight.mixer import allocation_matrix, esc_command
from quadcosim.flight.profiles import FLIGHTS, initial_state, profile, profile_at

__all__ = ["FLIGHTS", "GAINS", "SETPOINT", "Controller", "allocation_matrix", "esc_command", "initial_state", "profile",
           "profile_at"]
