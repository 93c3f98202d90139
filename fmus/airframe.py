"""Motor numbering and spin directions of the quad-X airframe: the one place that says them.

Body frame {B} is Forward-Right-Down. Seen from above (looking down +z_B)::

        front (x)
     3 (CW)   1 (CCW)
         \\   /
          \\ /
          / \\
         /   \\
     2 (CCW)  4 (CW)      right (y) ->

This is PX4's quad-X numbering. A rotor spinning counter-clockwise seen from above has its
angular velocity along -z_B; the drag reaction on the body is then along +z_B, a positive
(nose-right) yaw torque. Hence ``spin = +1`` for CCW rotors and the yaw torque is
``tau_z = k_m * sum(spin_n * omega_n^2)``.

The C models include ``airframe.h``, generated from this table by :mod:`quadcosim.fmus.build`; the
mixer reads :data:`MOTORS`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Motor:
    number: int
    position: str
    angle_deg: float  # angle of the arm from +x_B towards +y_B, degrees
    spin: int  # +1 counter-clockwise seen from above, -1 clockwise

    @property
    def direction(self) -> tuple[float, float]:
        """Unit vector (x, y) of the arm in {B}."""
        a = math.radians(self.angle_deg)
        return math.cos(a), math.sin(a)


MOTORS = (
    Motor(1, "front-right", 45.0, +1),
    Motor(2, "rear-left", -135.0, +1),
    Motor(3, "front-left", -45.0, -1),
    Motor(4, "rear-right", 135.0, -1),
)


def c_header() -> str:
    """``airframe.h``: the arm directions and spins as C arrays."""
    cos = ", ".join(repr(m.direction[0]) for m in MOTORS)
    sin = ", ".join(repr(m.direction[1]) for m in MOTORS)
    spin = ", ".join(f"{m.spin:.1f}" for m in MOTORS)
    return (
        "/* Generated from fmus/airframe.py by quadcosim.fmus.build: do not edit. */\n"
        "#ifndef AIRFRAME_H\n#define AIRFRAME_H\n\n"
        f"#define N_MOTORS {len(MOTORS)}\n"
        "/* Unit arm direction in the body frame and spin (+1 CCW seen from above). */\n"
        f"static const double ARM_X[N_MOTORS] = {{{cos}}};\n"
        f"static const double ARM_Y[N_MOTORS] = {{{sin}}};\n"
        f"static const double SPIN[N_MOTORS] = {{{spin}}};\n\n"
        "#endif\n"
    )
