"""The tilt finding as a figure (``quadcosim run tp --set flight=tilt``): after a pitch step the
accelerometer's tilt follows the true tilt as a first-order lag of the drag time constant
``m / (k_d sum|omega_n|)`` (Martin and Salaün 2010) while the speed settles where rotor drag
balances the tilted thrust; without rotor drag it reads level and the speed never settles."""

from __future__ import annotations

import numpy as np
from quadcosim.flight import profiles, trim


def accelerometer_tilt_deg(acc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch (deg) of the specific force an accelerometer measures, as a static
    inclinometer reads them: ``atan2(-a_y, -a_z)`` and ``atan2(a_x, hypot(a_y, a_z))``.

    Parameters
    ----------
    acc : (n, 3) ndarray
        Specific force in {B} (m/s^2).

    Returns
    -------
    roll, pitch : (n,) ndarray
        deg.
    """
    return (np.degrees(np.arctan2(-acc[:, 1], -acc[:, 2])),
            np.degrees(np.arctan2(acc[:, 0], np.hypot(acc[:, 1], acc[:, 2]))))


def tilt_figure(result, o: dict, title: str):
    """Pitch, true and as the accelerometer reads it, with the predicted first-order lag, above
    the speed; returns the figure (the caller saves it).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A tp run with ``flight=tilt``.
    o : dict
        tp's options (``tilt_deg``, ``rotor_drag``).
    title : str
        The figure's title (the run in words).
    """
    import matplotlib.pyplot as plt
    from quadcosim.orchestrator.result import envelope

    t = result.time
    _, acc_pitch = accelerometer_tilt_deg(result["IMU.acc"])
    speed = np.linalg.norm(result["Quadrotor.v"], axis=1)
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True, height_ratios=(1, 0.8))
    axes[0].plot(*envelope(t, np.degrees(result["Quadrotor.theta2"])), label="pitch, truth")
    axes[0].plot(*envelope(t, acc_pitch), label="pitch read by the accelerometer")
    if o["rotor_drag"]:
        tau = trim.drag_time_constant(thrust=float(result["Quadrotor.thrust"][-1]))
        after = t >= profiles.STEP_TIME
        lag = o["tilt_deg"] * (1.0 - np.exp(-(t[after] - profiles.STEP_TIME) / tau))
        axes[0].plot(*envelope(t[after], lag), "k:", label=f"first-order lag, tau = m / (k_d sum|w|) = {tau:.2f} s")
    axes[0].set_ylabel("pitch (deg)")
    axes[1].plot(*envelope(t, speed), color="C2", label=f"speed ({speed[-1]:.2f} m/s at {t[-1]:g} s)")
    axes[1].set_ylabel("speed (m/s)")
    axes[1].set_xlabel("time (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0.0)
    axes[1].set_xlim(t[0], t[-1])
    fig.suptitle(title, fontsize=9)
    return fig
