"""Mixer of the quad-X: body thrust and torques to rotor speeds, rotor speeds to ESC commands.

Motor numbering, arm directions and spins come from :mod:`quadcosim.fmus.airframe`; the ESC command
that holds a rotor speed is the motors' steady-state map :func:`quadcosim.fmus.vehicle.steady_command`,
compiled here for the control law (one formula for the plant's defaults and the controller).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from quadcosim.fmus import vehicle
from quadcosim.fmus.airframe import MOTORS

#: ESC command (1) holding rotor speed ``omega`` (rad/s) at battery voltage ``u_batt`` (V),
#: for winding resistance (ohm), back-EMF constant (V s/rad) and rotor drag-torque
#: coefficient (N m s^2): :func:`quadcosim.fmus.vehicle.steady_command`, compiled.
esc_command = njit(cache=True)(vehicle.steady_command)


def allocation_matrix(arm: float = vehicle.ARM, thrust_coeff: float = vehicle.THRUST_COEFF,
                      drag_torque_coeff: float = vehicle.DRAG_TORQUE_COEFF) -> np.ndarray:
    """Allocation matrix ``M`` with ``[T, tau_x, tau_y, tau_z] = M [T_1, ..., T_4]``.

    Parameters
    ----------
    arm : float
        Distance from the centre to a rotor axis (m).
    thrust_coeff : float
        ``k_f`` (N s^2/rad^2): rotor thrust ``T_n = k_f omega_n^2``.
    drag_torque_coeff : float
        ``k_m`` (N m s^2/rad^2): rotor reaction torque ``k_m omega_n^2``.

    Returns
    -------
    (4, 4) ndarray
        Rows: total thrust (N, along -z_B), torques about x_B, y_B, z_B (N m) per unit rotor
        thrust (N), body frame FRD; columns: motors in :data:`quadcosim.fmus.airframe.MOTORS` order.
    """
    rows = [[1.0] * len(MOTORS),
            [-arm * m.direction[1] for m in MOTORS],
            [arm * m.direction[0] for m in MOTORS],
            [drag_torque_coeff / thrust_coeff * m.spin for m in MOTORS]]
    return np.array(rows)
