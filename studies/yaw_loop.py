"""How fast the yaw loop may be at a given control rate: measured on ``tp`` runs.

The controller's yaw loop is a PD of natural frequency ``w`` (rad/s) and damping 0.8
(``kp_yaw = w^2``, ``kd_yaw = 1.6 w``). The whole loop (controller, IMU, estimator) runs at
the macro step rate: ``dt = 1 / rate``, ``imu_rate = rate``. :func:`yaw_loop` flies one
case and measures:

- ``ringing_nm``: the RMS of the yaw torque asked for above :data:`RING_BAND_HZ` over the
  last :data:`TAIL_S` seconds (N m); a stable loop leaves rounding error there in hover and
  its manoeuvres' harmonics in flight, an unstable one an oscillation (:data:`QUIET_NM`);
- ``ring_hz``: the frequency of that oscillation (the largest peak above the band's edge);
- the range of the ESC commands and of the motor currents after :data:`SETTLE_S` seconds:
  a free-wheeling ESC cannot reverse its motor's current, so an oscillation that asks for
  braking finds the current at zero, a bound the commands do not show.

The ablation case ``100hz_24_hover_no_reaction`` removes the rotors' reaction to their own
acceleration (``J_r domega/dt``) from the rigid body: what makes the yaw actuator's first
tens of milliseconds stronger than ``k_m omega^2`` says, and the 100 Hz loop unstable.

``python -m quadcosim.studies.yaw_loop`` prints the cases of :func:`study`.
"""

from __future__ import annotations

import numpy as np

DAMPING = 0.8  # 1, of the yaw loop (the controller's default)
RING_BAND_HZ = 5.0  # Hz, lower edge of the band the ringing is measured in (the profiles' motions are below 1 Hz)
TAIL_S = 4.0  # s, end of the run the ringing is measured on
SETTLE_S = 2.0  # s, start of the run left out of the ranges (the profiles' ease-in)
DURATION_S = 20.0  # s, simulated time of each case
# N m, ringing below which the loop counts as quiet: a quiet loop leaves rounding error in hover
# (1e-17 N m) and its manoeuvres' harmonics in non-stationary flight (1e-4 N m), a ringing one 2e-2 N m
QUIET_NM = 1e-3
#: Natural frequencies (rad/s) scanned at 100 Hz for the largest quiet one, and for the first
#: whose commands reach a bound in non-stationary flight.
SCAN_100HZ = tuple(np.arange(8.0, 12.01, 0.5))
SCAN_BOUND_100HZ = tuple(np.arange(20.0, 26.01, 1.0))


def yaw_loop(rate: float, natural_frequency: float, flight: str = "hover", settings: dict | None = None) -> dict:
    """One ``tp`` flight with the whole loop at ``rate`` (Hz) and the yaw loop at
    ``natural_frequency`` (rad/s); ``settings``: other ``tp`` options or block parameters
    (``{"MotorMagnetics.regenerative": True}``).

    Returns
    -------
    dict
        ``ringing_nm``, ``ring_hz``, ``command_min``, ``command_max`` (1), ``current_min_a``,
        ``current_max_a`` (A), ``oscillating`` (ringing above :data:`QUIET_NM`).
    """
    from quadcosim import scenarios

    w = float(natural_frequency)
    options = {"flight": flight, "duration": DURATION_S, "dt": 1.0 / rate, "imu_rate": rate,
               "Controller.kp_yaw": w * w, "Controller.kd_yaw": 2.0 * DAMPING * w} | dict(settings or {})
    result, _ = scenarios.run("tp", options, record=["Controller.c", "Controller.tau_z", "MotorMagnetics.i"])
    t, tau = result.time, result["Controller.tau_z"]
    tail = tau[t >= t[-1] - TAIL_S]
    spectrum = np.fft.rfft(tail - tail.mean())
    frequency = np.fft.rfftfreq(len(tail), 1.0 / rate)
    band = frequency > RING_BAND_HZ
    # Parseval: the band's share of the tail's variance
    ringing = float(np.sqrt(2.0 * np.sum(np.abs(spectrum[band]) ** 2)) / len(tail))
    settled = t >= SETTLE_S
    c, i = result["Controller.c"][settled], result["MotorMagnetics.i"][settled]
    return {"ringing_nm": ringing, "ring_hz": float(frequency[band][np.argmax(np.abs(spectrum[band]))]),
            "command_min": float(c.min()), "command_max": float(c.max()), "current_min_a": float(i.min()),
            "current_max_a": float(i.max()), "oscillating": ringing > QUIET_NM}


def largest_quiet(rate: float = 100.0, scan=SCAN_100HZ) -> float:
    """The largest natural frequency (rad/s) of ``scan`` whose yaw loop at ``rate`` (Hz) stays
    quiet in a 20 s hover, every smaller one quiet too."""
    quiet = None
    for w in scan:
        if yaw_loop(rate, w)["oscillating"]:
            break
        quiet = float(w)
    if quiet is None:
        raise ValueError(f"every yaw loop of {scan} rings at {rate} Hz")
    return quiet


def first_at_bound(rate: float = 100.0, scan=SCAN_BOUND_100HZ) -> float:
    """The smallest natural frequency (rad/s) of ``scan`` whose ESC commands reach 0 or 1 in
    non-stationary flight with the loop at ``rate`` (Hz)."""
    for w in scan:
        case = yaw_loop(rate, w, "nonstationary")
        if case["command_min"] <= 0.0 or case["command_max"] >= 1.0:
            return float(w)
    raise ValueError(f"no yaw loop of {scan} reaches a command bound at {rate} Hz")


#: The cases :func:`study` flies: (name, rate Hz, natural frequency rad/s, flight, settings).
CASES = (("100hz_8_hover", 100.0, 8.0, "hover", {}),
         ("100hz_12_hover", 100.0, 12.0, "hover", {}),
         ("100hz_8_nonstationary", 100.0, 8.0, "nonstationary", {}),
         ("100hz_12_nonstationary", 100.0, 12.0, "nonstationary", {}),
         ("1khz_12_nonstationary", 1000.0, 12.0, "nonstationary", {}),
         ("1khz_32_hover", 1000.0, 32.0, "hover", {}),
         ("100hz_12_hover_regenerative", 100.0, 12.0, "hover", {"MotorMagnetics.regenerative": True}),
         # ablation: the rigid body without the rotors' reaction to their own acceleration (J_r domega/dt)
         ("100hz_24_hover_no_reaction", 100.0, 24.0, "hover", {"Quadrotor.J_r": 0.0}))


def study() -> dict:
    """Every case of :data:`CASES`, the largest quiet loop at 100 Hz and the first that reaches
    a command bound there; printed as they come.

    Returns
    -------
    dict
        ``cases`` (name -> :func:`yaw_loop`), ``largest_quiet_100hz``, ``first_at_bound_100hz`` (rad/s).
    """
    cases = {}
    for name, rate, w, flight, settings in CASES:
        case = cases[name] = yaw_loop(rate, w, flight, settings)
        print(f"{name:28s} ringing {case['ringing_nm']:.1e} N m at {case['ring_hz']:.1f} Hz; commands "
              f"{case['command_min']:.3f} to {case['command_max']:.3f}; motor currents {case['current_min_a']:.2f} to "
              f"{case['current_max_a']:.2f} A", flush=True)
    quiet, bound = largest_quiet(), first_at_bound()
    print(f"at 100 Hz: quiet up to {quiet:.1f} rad/s in hover; commands at a bound in non-stationary flight from "
          f"{bound:.1f} rad/s", flush=True)
    return {"cases": cases, "largest_quiet_100hz": quiet, "first_at_bound_100hz": bound}


def main(argv=None) -> int:
    """``quadcosim study yaw-loop`` (``python -m quadcosim.studies.yaw_loop``): :func:`study`,
    printed as it goes; it takes no options.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (default ``sys.argv[1:]``): none but ``--help``.
    """
    import argparse

    argparse.ArgumentParser(prog="quadcosim study yaw-loop", description=__doc__.splitlines()[0]).parse_args(argv)
    study()
    return 0


if __name__ == "__main__":  # the same as quadcosim study yaw-loop
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study yaw-loop").run, main)
