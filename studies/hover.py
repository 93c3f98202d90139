"""The default vehicle at hover, simulated: trim, motor time constant, and what follows from them.

``python -m quadcosim.studies.hover`` prints the figures the documentation states about the default
vehicle (``fmus/vehicle.py``):

- the MotorMagnetics FMU driven at the hover command (:func:`quadcosim.fmus.vehicle.hover_command`) for
  :data:`SETTLE_S`: the rotor speed and the motor current it settles at;
- the command-to-speed time constant: the time the rotor speed takes to cover 63.2 % of its
  response to a small command step (:data:`STEP`) from that hover, stepped at :data:`FINE_STEP_S`;
- the yaw actuator's spin-up reaction over the rate drag torque, ``J_r / (2 k_m omega tau)``: the
  rotors' reaction to their own acceleration ``J_r dω/dt`` against the change of ``k_m ω²``
  during the first time constant;
- the drag model's predictions (:mod:`quadcosim.flight.trim`): the velocity time constant of
  rotor drag at hover and the pitch of the ``quasi`` cruise.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from quadcosim.fmus import vehicle

SETTLE_S = 1.0  # s at the hover command before the rotor speed and current are read
STEP = 0.02  # 1, height of the command step whose response gives the time constant
STEP_RESPONSE_S = 0.5  # s of response recorded after the step (about 18 time constants)
FINE_STEP_S = 1e-4  # s, communication step of the step response
COARSE_STEP_S = 1e-3  # s, communication step while settling
RISE_FRACTION = 1.0 - math.exp(-1.0)  # share of the step's response reached after one time constant


def _step(fmu, seconds: float, h: float) -> np.ndarray:
    """Step ``fmu`` for ``seconds`` by ``h`` (s); (n, 2) rotor speed of motor 1 (rad/s) and its current (A)."""
    steps = int(round(seconds / h))
    values = np.empty((steps, 2))
    for k in range(steps):
        fmu.step(fmu.time, h)
        values[k] = fmu.get(["omega_r1", "i1"])
    return values


def figures() -> dict:
    """The hover figures of the default vehicle.

    Returns
    -------
    dict
        ``command`` (1), ``omega_rad_s`` (rad/s) and ``current_a`` (A, per motor) at hover,
        ``motor_time_constant_ms`` (ms), ``yaw_spin_up_ratio`` (1), ``drag_time_constant_s`` (s)
        and the ``quasi`` cruise's ``cruise_speed_m_s`` (m/s) and ``cruise_pitch_deg`` (deg, nose
        down positive).
    """
    from quadcosim.flight import profiles, trim
    from quadcosim.orchestrator.fmu import FMUInstance

    command = vehicle.hover_command()
    fmu = FMUInstance("MotorMagnetics")
    try:
        fmu.set(["c1", "c2", "c3", "c4"], [command] * vehicle.MOTOR_COUNT)
        omega, current = _step(fmu, SETTLE_S, COARSE_STEP_S)[-1]
        fmu.set(["c1", "c2", "c3", "c4"], [command + STEP] * vehicle.MOTOR_COUNT)
        speed = _step(fmu, STEP_RESPONSE_S, FINE_STEP_S)[:, 0]
    finally:
        fmu.close()
    risen = speed - omega >= RISE_FRACTION * (speed[-1] - omega)
    tau = (int(np.argmax(risen)) + 1) * FINE_STEP_S
    ratio = vehicle.ROTOR_INERTIA / (2.0 * vehicle.DRAG_TORQUE_COEFF * omega * tau)
    return {"command": command, "omega_rad_s": float(omega), "current_a": float(current),
            "motor_time_constant_ms": tau * 1e3, "yaw_spin_up_ratio": ratio,
            "drag_time_constant_s": trim.drag_time_constant(),
            "cruise_speed_m_s": profiles.CRUISE_SPEED, "cruise_pitch_deg": -math.degrees(profiles.cruise_pitch())}


def main(argv=None) -> int:
    """Print :func:`figures`.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (none are taken; ``--help`` describes the module).

    Returns
    -------
    int
        Exit status, 0.
    """
    argparse.ArgumentParser(prog="python -m quadcosim.studies.hover",
                            description=__doc__.splitlines()[0]).parse_args(argv)
    f = figures()
    print(f"hover: ESC command {f['command']:.3f}, rotor speed {f['omega_rad_s']:.2f} rad/s, "
          f"current {f['current_a']:.3f} A per motor")
    print(f"command-to-speed time constant: {f['motor_time_constant_ms']:.1f} ms "
          f"(63.2 % of the response to a {STEP:g} command step)")
    print(f"yaw: spin-up reaction over the rate drag torque, J_r / (2 k_m omega tau) = {f['yaw_spin_up_ratio']:.2f}")
    print(f"rotor drag: velocity time constant at hover m / (4 k_d omega) = {f['drag_time_constant_s']:.3f} s")
    print(f"quasi cruise at {f['cruise_speed_m_s']:g} m/s: pitched {f['cruise_pitch_deg']:.3f} deg nose down")
    return 0


if __name__ == "__main__":  # the same as quadcosim study hover
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study hover").run, main)
