"""Trim and small-signal predictions of the drag model: what the closed loop should show.

The plant's drag (Quadrotor FMU) on the airspeed ``v_a = R^T (v - wind)``, body frame:
``F = -k_d (sum_n |omega_n|) (v_a,x, v_a,y, 0) - D v_a`` (rotor H-force and optional linear
drag; the parasitic drag is off by default and left out here). Rotor thrust ``T = k_f sum
omega_n^2`` along ``-z_B``. In trim all rotors turn at one speed, so ``sum |omega_n| =
2 sqrt(T / k_f)``.

- :func:`wind_hover_tilt`: the tilt at which a vehicle holding its position in a steady
  horizontal wind balances drag against thrust.
- :func:`drag_time_constant`: linearised about a trim of thrust ``T``, the horizontal body
  velocity obeys ``m du/dt = -m g theta - mu u`` with ``mu = k_d sum|omega_n| + D``, and the
  accelerometer reads ``f_x = -mu u / m``: the accelerometer's tilt ``f_x / g`` follows the
  true tilt as a first-order lag of time constant ``m / mu`` (Martin and Salaün, "The true
  role of accelerometer feedback in quadrotor control", ICRA 2010).
- In steady flight (``dv/dt = 0``) the accelerometer reads ``-g R^T e3`` whatever the drag:
  its tilt is the true tilt. Without drag a tilted vehicle never reaches a steady velocity.
"""

from __future__ import annotations

import math

from quadcosim.fmus import vehicle

THRUST_ITERATIONS = 50  # fixed-point iterations of the vertical balance (they converge: drag << weight)
LARGEST_TRIM_TILT = math.radians(60.0)  # rad, upper end of the search for the tilt into the wind


def _rotor_sum(thrust: float, thrust_coeff: float) -> float:
    """``sum |omega_n|`` (rad/s) of four equal rotors giving ``thrust`` (N)."""
    return 2.0 * math.sqrt(thrust / thrust_coeff)


def drag_time_constant(thrust: float | None = None, mass: float = vehicle.MASS,
                       thrust_coeff: float = vehicle.THRUST_COEFF, rotor_drag: float = vehicle.ROTOR_DRAG_COEFF,
                       linear_drag: float = vehicle.LINEAR_DRAG) -> float:
    """Time constant (s) of the accelerometer's tilt after a tilt step, ``m / mu``.

    Parameters
    ----------
    thrust : float, optional
        Total rotor thrust of the trim (N); default ``m g`` (hover).
    mass : float
        Vehicle mass (kg).
    thrust_coeff : float
        ``k_f`` (N s^2/rad^2).
    rotor_drag : float
        ``k_d`` (kg/rad): rotor H-force per rad/s of rotor speed per m/s of airspeed.
    linear_drag : float
        ``D`` (N s/m), isotropic linear drag.
    """
    thrust = mass * vehicle.GRAVITY if thrust is None else thrust
    mu = rotor_drag * _rotor_sum(thrust, thrust_coeff) + linear_drag
    if not mu > 0:
        raise ValueError("without drag (k_d = D = 0) the accelerometer never sees the tilt: no time constant")
    return mass / mu


def wind_hover_tilt(wind_speed: float, mass: float = vehicle.MASS, thrust_coeff: float = vehicle.THRUST_COEFF,
                    rotor_drag: float = vehicle.ROTOR_DRAG_COEFF, linear_drag: float = vehicle.LINEAR_DRAG,
                    g: float = vehicle.GRAVITY) -> tuple[float, float]:
    """Tilt (rad, into the wind) and thrust (N) of a vehicle holding still in a horizontal wind.

    Tilted by ``theta`` about the horizontal axis across the wind, the airspeed in {B} is
    ``(-w cos theta, 0, -w sin theta)``; force balance in {I}, along and across gravity::

        T sin theta = k_d S w cos^2 theta + D w
        T cos theta = m g - k_d S w cos theta sin theta,     S = 2 sqrt(T / k_f)

    solved for ``theta`` (the linear drag acts along the airspeed and adds ``D w`` to the first
    line only).

    Parameters
    ----------
    wind_speed : float
        Horizontal wind speed (m/s).
    mass, thrust_coeff, rotor_drag, linear_drag, g
        Vehicle mass (kg), ``k_f`` (N s^2/rad^2), ``k_d`` (kg/rad), ``D`` (N s/m), gravity (m/s^2).

    Returns
    -------
    tilt : float
        rad, the thrust leaning into the wind.
    thrust : float
        N.
    """
    w = float(wind_speed)

    def thrust_of(theta):  # from the vertical balance, by fixed point (it converges: drag << weight)
        t = mass * g
        for _ in range(THRUST_ITERATIONS):
            t = (mass * g - rotor_drag * _rotor_sum(t, thrust_coeff) * w * math.cos(theta) * math.sin(theta)) \
                / math.cos(theta)
        return t

    def horizontal(theta):
        t = thrust_of(theta)
        return t * math.sin(theta) - rotor_drag * _rotor_sum(t, thrust_coeff) * w * math.cos(theta) ** 2 \
            - linear_drag * w

    if w == 0.0:
        return 0.0, mass * g
    tilt = brent_root(horizontal, 0.0, LARGEST_TRIM_TILT, xtol=1e-14)
    return tilt, thrust_of(tilt)


#: Relative tolerance of :func:`brent_root`, 4 machine epsilons (``scipy.optimize.brentq``'s default).
BRENT_RTOL = 4 * 2.220446049250313e-16
BRENT_ITERATIONS = 100  # most iterations of :func:`brent_root` (``brentq``'s default)


def brent_root(f, a: float, b: float, xtol: float = 2e-12, rtol: float = BRENT_RTOL,
               iterations: int = BRENT_ITERATIONS) -> float:
    """A root of ``f`` bracketed by ``a`` and ``b``: Brent's method, step for step as
    ``scipy.optimize.brentq`` takes it, so the same bits (a test holds the two equal).

    Every ``quasi`` flight trims its cruise at start-up; importing ``scipy.optimize`` for
    this one root cost more CPU than a 2 s run simulates.

    Parameters
    ----------
    f : callable
        ``f(x) -> float``, of opposite signs at ``a`` and ``b``.
    a, b : float
        The bracket (the unit of ``x``).
    xtol, rtol : float
        Absolute (the unit of ``x``) and relative (1) tolerance on the root.
    iterations : int
        Most iterations.

    Returns
    -------
    float
        The root.

    Raises
    ------
    ValueError
        ``f(a)`` and ``f(b)`` of one sign, or no convergence within ``iterations``.
    """
    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = float(f(xpre)), float(f(xcur))
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    for _ in range(iterations):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):  # the best estimate is the one of least |f|
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):  # a good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
        fcur = float(f(xcur))
    raise ValueError(f"no root found within {iterations} iterations")
