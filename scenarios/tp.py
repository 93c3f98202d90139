"""``tp``: the lab's closed loop: Setpoint -> Controller -> MotorMagnetics -> Quadrotor -> IMU -> Quaternion_estim.

One case of the lab's matrix (Bao and Yuan, lab report, 2024) per run: estimator x flight profile x feedback (the
controller fed by the ground truth, "gt", or by the estimate) x noise x gyro bias, with or
without the field of the motor currents at the magnetometer (the lab had none).
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
from quadcosim.calibration import MagCompensator
from quadcosim.estimators import QuaternionEstim, kinds, parse_corrections
from quadcosim.estimators.quaternions import euler_to_quaternion
from quadcosim.flight import FLIGHTS, SETPOINT, Controller, initial_state, profile_at
from quadcosim.flight.controller import SETPOINT_UNITS
from quadcosim.flight.profile_file import FileProfile, is_profile_file
from quadcosim.flight.profiles import STEP_AXES, STEP_TIME, step_sizes
from quadcosim.fmus import vehicle
from quadcosim.orchestrator import System, Table
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.ablation import GravityOnly
from quadcosim.scenarios.compensation import COMPENSATIONS, add_compensator
from quadcosim.scenarios.divergence import Bounds
from quadcosim.scenarios.figures import (
    angle_curve,
    fault_text,
    faults_of,
    floor_span,
    label_axes,
    shade_faults,
    title_lines,
    wrapped_curve,
)
from quadcosim.scenarios.plant import PLANT_BLOCKS, add_plant, imu_parameters, save_figure

BENCH_SUPPLY = 1000.0  # 1, capacity multiplier of option bench_supply

OPTIONS = {
    "estimator": Option("linear", "attitude estimator, or module:Class (a block of your own: estimators/contract.py)",
                        choices=kinds.streaming(), classes=True),
    "flight": Option("quasi", "flight profile (flight/profiles.py), or a setpoint profile in a CSV file "
                              "(flight/profile_file.py)", choices=FLIGHTS, files=".csv"),
    "tilt_deg": Option(5.0, "pitch setpoint of flight=tilt (deg)", applies="flight=tilt"),
    "step_axis": Option("pitch", "axes of flight=step", choices=tuple(STEP_AXES), applies="flight=step"),
    "step_deg": Option(5.0, "attitude step of flight=step (deg)", applies="flight=step"),
    "step_time": Option(STEP_TIME, "time of the step of flight=step (s)", minimum=0.0, applies="flight=step"),
    "feedback": Option("gt", "controller fed by the ground truth or the estimate", choices=("gt", "estimate")),
    "noise": Option(False, "IMU white noise"),
    "bias": Option(False, "gyro bias (0.02, -0.01, 0.015) rad/s, or IMU.gyro_bias=x,y,z"),
    "rotor_drag": Option(True, "rotor drag (H-force) on the airspeed, the Quadrotor's k_d; off: k_d = 0"),
    "wind_n": Option(0.0, "steady wind towards the north (m/s)"),
    "wind_e": Option(0.0, "steady wind towards the east (m/s)"),
    "accelerometer": Option("measured", "IMU fed the true specific force, or gravity alone (an ablation)",
                            choices=("measured", "gravity")),
    "bench_supply": Option(False, "battery capacity x1000, for hovers longer than the battery's ten minutes"),
    "magnetic": Option(False, "field of the motor currents at the magnetometer"),
    "ry": Option("reel", "passive filter: R_y from the IMU's R_reel or TRIAD", choices=("reel", "triad"),
                 applies="estimator=passive"),
    "discretisation": Option("exp", "quaternion update", choices=("exp", "euler")),
    "k": Option(0.05, "linear filter gain, all three axes (1/s)", minimum=0.0, applies="estimator=linear"),
    "k1": Option(0.2, "explicit filter: accelerometer weight (1; Mahony's Kp = kP k1)", minimum=0.0,
                 applies="estimator=explicit"),
    "k2": Option(0.2, "explicit filter: magnetometer weight (1)", minimum=0.0, applies="estimator=explicit"),
    "kP": Option(1.0, "explicit and passive: proportional gain (1/s)", minimum=0.0,
                 applies="estimator=explicit,passive"),
    "kI": Option("lab", "bias gain (1/s^2); lab: the lab's value, 0 (explicit), 1 (passive)", minimum=0.0,
                 applies="estimator=explicit,passive", marker="lab"),
    "corrections": Option("off", "explicit/passive: disturbance-aware corrections, on, off or names (a,b)",
                          applies="estimator=explicit,passive"),
    "duration": Option(20.0, "simulated time (s)", minimum=0.01),
    "settle": Option(2.0, "time excluded from the error metrics (s)", minimum=0.0),
    "dt": Option(1e-3, "macro step (s)", minimum=1e-5),
    "imu_rate": Option(1000.0, "IMU and estimator rate (Hz)", minimum=1.0),
    "seed": Option(1, "IMU noise seed", applies="noise=true"),
    "compensation": Option("none", "field of the motor currents compensated (scenarios/compensation.py)",
                           choices=COMPENSATIONS),
    "calibration": Option("", "calibration file (JSON) for the compensation; empty: made on the clamped rig"),
}


def estimator_gains(o: dict) -> dict:
    """The estimator's gains from the options: ``k`` for the three axes of the linear filter
    (1/s); ``k1``, ``k2`` (weights of gravity and field), ``kP`` (1/s) and ``kI`` (1/s^2) for the
    explicit filter; ``kP`` and ``kI`` for the passive one; none for ``vqf`` and ``madgwick``
    (their packages' defaults) and for a user's block (``module:Class``, its gains its own).
    ``kI = "lab"`` takes the lab's value.

    Parameters
    ----------
    o : dict
        Parsed options.

    Returns
    -------
    dict
        Gain name -> value, as :class:`quadcosim.estimators.QuaternionEstim` takes them.
    """
    kind = o["estimator"]
    if kind == "linear":
        return {"k1": o["k"], "k2": o["k"], "k3": o["k"]}
    member = kinds.get(kind)
    if member is None or not member.lab:
        return {}  # the packages' defaults; a user's block holds its own
    lab = member.lab_gains()
    ki = lab["kI"] if o["kI"] == "lab" else o["kI"]
    if kind == "explicit":
        return {"k1": o["k1"], "k2": o["k2"], "kP": o["kP"], "kI": ki}
    return {"k1": lab["k1"], "k2": lab["k2"], "kP": o["kP"], "kI": ki}


def resolve(o: dict) -> dict:
    """The options as used: ``kI = "lab"`` replaced by the bias gain the estimator uses (1/s^2);
    kept as the word for an estimator without one (linear, vqf, madgwick), as any option that
    acts on nothing keeps its value."""
    kind = o["estimator"]
    return o | ({"kI": estimator_gains(o)["kI"]} if kind in kinds.with_bias() else {})


#: Signals tp's result files leave out by default (recorded all the same; ``--record all``
#: writes them; ``metrics.json`` lists them): each follows from signals kept. Quadrotor.R and
#: IMU.R_reel are the rotation matrix of Quadrotor.q; each motor's field b_dN sums to
#: MotorMagnetics.b_d; domega_r is the derivative of omega_r; the supply currents i_s are the
#: commands times i. A 20 s run then writes < 10 MB.
UNRECORDED = ["Quadrotor.R", "IMU.R_reel", "MotorMagnetics.b_d1", "MotorMagnetics.b_d2", "MotorMagnetics.b_d3",
              "MotorMagnetics.b_d4", "MotorMagnetics.domega_r", "MotorMagnetics.i_s"]

#: Tolerance of ``bias_convergence_s``: every axis of the bias estimate within it of the true bias.
BIAS_TOLERANCE = 1e-3  # rad/s

#: ``steady_error_deg`` and ``steady_tracking_error_deg`` average the last quarter of the run.
STEADY_SHARE = 0.25


def build(o: dict, estimator=None) -> System:
    """The lab's closed loop: setpoint profile, controller, motors and battery, rigid body, IMU
    (at ``imu_rate``, a divisor of the macro step rate) and the attitude estimator, the
    controller fed by the truth or by the estimate (``feedback``), with the optional
    compensation of the motors' field.

    Parameters
    ----------
    o : dict
        Parsed options (``quadcosim list`` shows them with their units).
    estimator : quadcosim.orchestrator.Block or class, optional
        An estimator of the user's in the place of ``Quaternion_estim`` (see
        :mod:`quadcosim.estimators.contract`; :meth:`quadcosim.scenarios.Scenario.prepare` names it in the options,
        ``module:Class``). ``o["estimator"] = "module:Class"`` does the same from the options.

    Returns
    -------
    quadcosim.orchestrator.System
        The system, ready to run for ``duration`` seconds.

    Raises
    ------
    ValueError
        ``imu_rate`` not a divisor of ``1 / dt``, or a user's
        estimator that cannot be loaded or breaks the contract.
    """
    period = round(1.0 / (o["imu_rate"] * o["dt"]))
    if period < 1 or abs(period * o["dt"] * o["imu_rate"] - 1.0) > 1e-9:
        raise ValueError(f"imu_rate = {o['imu_rate']} Hz must divide the macro step rate {1 / o['dt']:g} Hz")
    system = System(dt=o["dt"])
    if is_profile_file(o["flight"]):
        setpoint = FileProfile(o["flight"], SETPOINT)
    else:
        setpoint = partial(profile_at, o["flight"], tilt=np.radians(o["tilt_deg"]), step_axis=o["step_axis"],
                           step=np.radians(o["step_deg"]), step_time=o["step_time"])  # evaluated as the run goes
    system.add(Table("Setpoint", SETPOINT, setpoint, units=SETPOINT_UNITS))
    if o["accelerometer"] == "gravity":
        system.add(GravityOnly())
    start = initial_state(o["flight"])  # the estimator starts from the vehicle's initial attitude
    add_plant(system, quadrotor=start | ({} if o["rotor_drag"] else {"k_d": 0.0}), wind=(o["wind_n"], o["wind_e"], 0.0),
              motors={"omega0": vehicle.hover_rotor_speed()}
              | ({"capacity": BENCH_SUPPLY * vehicle.BATTERY_CAPACITY} if o["bench_supply"] else {}),
              imu=imu_parameters(o["noise"], o["bias"], o["seed"], sample_rate=o["imu_rate"]),
              magnetic=o["magnetic"], imu_period=period,
              specific_force="GravityOnly.f" if o["accelerometer"] == "gravity" else "Quadrotor.f")
    if o["accelerometer"] == "gravity":
        system.connect("Quadrotor.q", "GravityOnly.q")
    q0 = euler_to_quaternion(0.0, start.get("theta2_0", 0.0), 0.0)
    registered = kinds.get(o["estimator"])
    if estimator is not None or registered is None or registered.block:  # a block of its own
        from quadcosim.estimators import contract

        spec = estimator if estimator is not None else registered.block if registered else o["estimator"]
        estimator = system.add(contract.adopt(spec, period,
                                              q0=q0, available=system.blocks["IMU"].outputs))
    else:
        estimator = system.add(QuaternionEstim(o["estimator"], estimator_gains(o), period=period,
                                               discretisation=o["discretisation"], ry=o["ry"],
                                               corrections=parse_corrections(o["corrections"]), q0=q0))
    for name in estimator.inputs:
        if not (o["compensation"] != "none" and name.startswith("magneto")):  # else from MagCompensator
            system.connect(f"IMU.{name}", f"Quaternion_estim.{name}")
    system.add(Controller())
    for name in SETPOINT:
        system.connect(f"Setpoint.{name}", f"Controller.{name}")
    if o["feedback"] == "gt":
        system.connect("Quadrotor.q", "Controller.q")
        system.connect("Quadrotor.omega", "Controller.omega")
    else:
        system.connect("Quaternion_estim.q_est", "Controller.q")
        system.connect("Quaternion_estim.omega_est", "Controller.omega")
    system.connect("Quadrotor.p", "Controller.p")
    system.connect("Quadrotor.v", "Controller.v")
    system.connect("MotorMagnetics.u_batt", "Controller.u_batt")
    system.connect("Controller.c", "MotorMagnetics.c")
    add_compensator(system, o["compensation"], o["calibration"], o)
    return system


def wrapped(angle: np.ndarray) -> np.ndarray:
    """``angle`` (rad) wrapped to [-pi, pi)."""
    return (angle + np.pi) % (2 * np.pi) - np.pi


def errors(result) -> tuple[np.ndarray, np.ndarray]:
    """Estimation and tracking errors (rad), columns roll, pitch, yaw, of the recorded run
    ``result``. Tracking compares the attitude with the controller's setpoint (the position
    hold's roll and pitch when holding)."""
    estimation = np.column_stack([euler_error(result, "Quaternion_estim.theta_est", k) for k in range(3)])
    tracking = np.column_stack([euler_error(result, _SETPOINTS[k], k) for k in range(3)])
    return estimation, tracking


_SETPOINTS = ("Controller.theta_d1", "Controller.theta_d2", "Setpoint.theta_d3")


def euler_error(result, signal: str, k: int) -> np.ndarray:
    """``signal`` (or its component ``k + 1``) minus the true Euler angle ``k``, wrapped to
    [-pi, pi) (rad): one new column, computed in place.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A tp run (or a window of one).
    signal : str
        ``"Quaternion_estim.theta_est"`` (the component ``k + 1`` is taken) or a setpoint
        signal of the controller (``"Controller.theta_d1"``).
    k : int
        Euler angle: 0 roll, 1 pitch, 2 yaw.

    Returns
    -------
    numpy.ndarray
        The error (rad), one per sample.
    """
    name = signal if signal.startswith(("Controller", "Setpoint")) else f"{signal}{k + 1}"
    difference = np.subtract(result[name], result[f"Quadrotor.theta{k + 1}"])
    difference += np.pi
    np.mod(difference, 2 * np.pi, out=difference)
    difference -= np.pi
    return difference


def report(result, o, out) -> dict:
    """Figures and metrics of one run. Statistics are taken column by column and the figures
    drawn from envelopes, so that the report adds little to the memory of the record.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The recorded run.
    o : dict
        Parsed options.
    out : pathlib.Path or None
        Folder of the figures; None writes none.

    Returns
    -------
    dict
        Estimation and tracking errors (deg; roll, pitch, yaw) after ``settle_s``, the final
        gyro bias error (rad/s) and its convergence time (s) when the bias is estimated, the
        real-time factor, and the figures written.
    """
    settle = min(o["settle"], 0.5 * o["duration"])  # a short run keeps its second half
    metrics = {"settle_s": settle, **_error_statistics(result, settle), **steady_errors(result),
               "bias_error_final": None, "figures": _figures(result, o, out) + _tilt_figures(result, o, out),
               "units": {"bias_error_final": "rad/s", "real_time_factor": "1"}}
    if o["estimator"] != "linear" and estimator_gains(o).get("kI", 0) > 0:
        metrics |= _bias_statistics(result)
    metrics |= _predictions(result, o)
    metrics |= _flight_findings(result, o)
    metrics["attitude_span_deg"] = [math.degrees(float(_span(result, f"Quadrotor.theta{k}"))) for k in (1, 2, 3)]
    loop = result.meta.get("loop_seconds")
    if loop:
        metrics["real_time_factor"] = o["duration"] / loop
    return metrics


def _bias_error(window, axis: str) -> np.ndarray:
    """The gyro bias estimate's error on one axis (rad/s)."""
    return window[f"Quaternion_estim.b_est_{axis}"] - window[f"IMU.gyro_bias_{axis}"]


def _bias_statistics(result) -> dict:
    """The final gyro bias error (rad/s) and its convergence time (s, :func:`bias_convergence_time`),
    window by window (:meth:`quadcosim.orchestrator.Result.windows`)."""
    last, offset, window = -1, 0, None  # index of the last sample outside the tolerance, over every axis
    for window in result.windows():
        found = bias_convergence_time(np.arange(len(window)), (_bias_error(window, a) for a in "xyz"),
                                      BIAS_TOLERANCE)  # the first index inside, in this window
        if found is None:
            last = offset + len(window) - 1
        elif found > 0:
            last = offset + int(found) - 1
        offset += len(window)
    final = [float(_bias_error(window, a)[-1]) for a in "xyz"]
    converged = None if last == len(result) - 1 else float(result.time[last + 1])
    return {"bias_error_final": final, "bias_convergence_s": converged,
            "bias_convergence_tolerance_rad_s": BIAS_TOLERANCE}


def _predictions(result, o) -> dict:
    """What the linearised analyses (:mod:`quadcosim.estimators.analysis`) predict for this run's gyro bias:
    the passive filter's bias-convergence time (s), the explicit filter's steady error without
    bias estimate (deg, roll, pitch, yaw); nothing without a bias or for the other filters."""
    if not o["bias"] or o["estimator"] not in kinds.with_bias():
        return {}
    from quadcosim.estimators import analysis

    gains, bias = estimator_gains(o), next(result.windows())["IMU.gyro_bias"][0]  # the first sample
    if o["estimator"] == "passive" and gains["kI"] > 0:
        return {"bias_convergence_predicted_s": analysis.passive_bias_convergence_time(
            gains["kP"], gains["kI"], float(np.abs(bias).max()), BIAS_TOLERANCE)}
    if o["estimator"] == "explicit" and gains["kI"] == 0:
        predicted = analysis.explicit_bias_steady_error(gains["k1"], gains["k2"], gains["kP"], bias)
        return {"steady_error_predicted_deg": np.degrees(predicted).tolist()}
    return {}


def _flight_findings(result, o) -> dict:
    """What the flight shows of the drag model: the tilt step's lag and speed (``flight=tilt``),
    the tilt into a steady wind and the position held (a wind on a position-holding flight); an
    attitude step's metrics (``flight=step`` and ``flight=tilt``, :func:`quadcosim.flight.measured.step_response`)."""
    from quadcosim.flight import measured

    found = {}
    if o["flight"] == "tilt":
        found |= measured.tilt_step(result, math.radians(o["tilt_deg"]), o["rotor_drag"])
    steps = step_sizes(o["flight"], o["step_axis"], math.radians(o["step_deg"]), math.radians(o["tilt_deg"]))
    if steps is not None:  # rise, settling, overshoot, steady error of the attitude step
        found |= measured.step_response(result, steps, o["step_time"] if o["flight"] == "step" else STEP_TIME)
    wind = math.hypot(o["wind_n"], o["wind_e"])
    if wind > 0 and o["flight"] == "hover":
        found |= measured.wind_hold(result, wind)
    return found


def _span(result, name: str) -> float:
    """``numpy.ptp`` of a signal, its largest minus its smallest value, window by window."""
    lowest, highest = np.inf, -np.inf
    for window in result.windows():
        values = window[name]
        lowest, highest = min(lowest, values.min()), max(highest, values.max())
    return highest - lowest


def steady_errors(result) -> dict:
    """Mean estimation and tracking errors over the last :data:`STEADY_SHARE` of the run: the
    steady error a filter without bias estimate keeps.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A tp run's record.

    Returns
    -------
    dict
        ``steady_error_deg`` and ``steady_tracking_error_deg`` (deg; roll, pitch, yaw, wrapped
        to +-180), ``steady_window_s`` (its first and last time, s).
    """
    start = result.time[0] + (1 - STEADY_SHARE) * (result.time[-1] - result.time[0])
    sums, count = np.zeros(6), 0
    for window in result.windows():  # sums of the errors after `start`, window by window
        late = slice(np.searchsorted(window.time, start), None)
        for k in range(3):
            sums[k] += euler_error(window, "Quaternion_estim.theta_est", k)[late].sum()
            sums[3 + k] += euler_error(window, _SETPOINTS[k], k)[late].sum()
        count += len(window.time[late])
    means = [math.degrees(float(total / count)) for total in sums]
    first = result.time[np.searchsorted(result.time, start)]
    return {"steady_error_deg": means[:3], "steady_tracking_error_deg": means[3:],
            "steady_window_s": [float(first), float(result.time[-1])]}


def _error_statistics(result, settle: float) -> dict:
    """RMS and largest estimation error, RMS tracking error (deg; roll, pitch, yaw) after
    ``settle`` seconds, one error column at a time."""
    squares, peaks, count = np.zeros(6), np.full(3, -np.inf), 0
    for window in result.windows():
        after = slice(np.searchsorted(window.time, settle), None)
        if not len(window.time[after]):
            continue
        for k in range(3):
            error = euler_error(window, "Quaternion_estim.theta_est", k)[after]
            squares[k] += np.dot(error, error)
            peaks[k] = max(peaks[k], error.max(), -error.min())
            del error
            error = euler_error(window, _SETPOINTS[k], k)[after]
            squares[3 + k] += np.dot(error, error)
            del error
        count += len(window.time[after])
    rms = [math.degrees(math.sqrt(total / count)) for total in squares]
    return {"rms_error_deg": rms[:3], "max_error_deg": [math.degrees(p) for p in peaks],
            "tracking_rms_deg": rms[3:]}


#: What the components of a metric list are, for tables and figures (``rms_error_deg[0]`` is roll).
COMPONENTS = {name: ("roll", "pitch", "yaw") for name in ("rms_error_deg", "max_error_deg", "tracking_rms_deg",
                                                          "steady_error_deg", "steady_tracking_error_deg")}
COMPONENTS["bias_error_final"] = ("x", "y", "z")

FLIGHT_NAMES = {"quasi": "quasi-stationary flight", "nonstationary": "non-stationary flight", "hover": "hover",
                "tilt": "tilt"}
FEEDBACK_NAMES = {"gt": "controller fed by the ground truth", "estimate": "controller fed by the estimate"}
# options the title states in words; any other option off its default is listed as key=value
_TITLED = {"estimator", "flight", "tilt_deg", "feedback", "noise", "bias", "magnetic", "compensation", "k", "k1",
           "k2", "kP", "kI", "corrections", "duration", "settle", "seed", "calibration", "ry", "discretisation"}


def estimator_text(o: dict, name: str | None = None) -> str:
    """The estimator and the gains it runs with, as a figure title states them.

    Parameters
    ----------
    o : dict
        tp's options.
    name : str, optional
        A user's estimator, named as given (its gains are its own and not stated).

    Returns
    -------
    str
        ``"explicit filter (k1 = 0.2, k2 = 0.2, kP = 1 1/s, kI = 0.1 1/s^2)"``.
    """
    if name or kinds.get(o["estimator"]) is None or kinds.get(o["estimator"]).block:  # a block of its own
        return f"estimator {name or o['estimator']}"
    kind = o["estimator"]
    gains = estimator_gains(o)
    if kind == "linear":
        text = f"k = {gains['k1']:g} 1/s"
    elif kind in kinds.with_bias():
        parts = [f"k1 = {gains['k1']:g}", f"k2 = {gains['k2']:g}"] if kind == "explicit" else []
        parts += [f"kP = {gains['kP']:g} 1/s", f"kI = {gains['kI']:g} 1/s\u00b2"]
        text = ", ".join(parts)
        if o["corrections"] != "off":
            text += f", corrections {o['corrections']}"
        if kind == "passive" and o["ry"] != "reel":
            text += f", R_y by {o['ry'].upper()}"
    else:
        text = "the package's default gains"
    if o["discretisation"] != "exp":
        text += f", {o['discretisation']} update"
    return f"{kind} filter ({text})"


def describe(o: dict, estimator: str | None = None) -> list[str]:
    """The run in words, one line each: estimator and gains; flight and feedback; sensors and
    the other options off their defaults.

    Parameters
    ----------
    o : dict
        tp's options.
    estimator : str, optional
        A user's estimator, by name.

    Returns
    -------
    list of str
    """
    flight = FLIGHT_NAMES.get(o["flight"], f"setpoints from {o['flight']}")
    flight += f" {o['tilt_deg']:g} deg" if o["flight"] == "tilt" else ""
    sensors = [f"IMU noise {'on' if o['noise'] else 'off'}",
               ("gyro bias on" if any(k.startswith(("IMU.gyro_bias", "IMU.b_g")) for k in o)  # its value in others
                else "gyro bias (0.02, -0.01, 0.015) rad/s") if o["bias"] else "no gyro bias",
               "motor-current field " + ("on" if o["magnetic"] else "off")]
    if o["compensation"] != "none":
        sensors.append(f"{o['compensation']} compensation")
    defaults = {key: option.default for key, option in OPTIONS.items()}
    others = [f"{key}={o[key]}" for key in OPTIONS if key not in _TITLED and o[key] != defaults[key]]
    others += [f"{key}={o[key]}" for key in o if "." in key]  # block parameters set by name
    return [f"tp: {estimator_text(o, estimator)}", f"{flight}, {FEEDBACK_NAMES[o['feedback']]}",
            ", ".join(sensors) + ("; " + ", ".join(others) if others else "")]


def figure_title(result, o: dict) -> str:
    """Title of tp's figures: :func:`describe`'s lines and the faults.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The run (its ``meta`` may name a user's estimator, and names the faults).
    o : dict
        tp's options.

    Returns
    -------
    str
        Several lines.
    """
    units = result.meta.get("units", {})
    connections = result.meta.get("connections", {})
    faults = faults_of(result)
    return title_lines(*describe(o, result.meta.get("estimator")),
                       fault_text(faults, {f["target"]: units.get(connections.get(f["target"], ""), "")
                                           for f in faults}))


# Smallest span of the y axes (deg, rad/s): a still vehicle's axis shows a flat line, not
# rounding noise stretched over the figure.
ANGLE_SPAN_DEG, ERROR_SPAN_DEG, BIAS_SPAN = 1.0, 0.05, 2e-3


def _figures(result, o, out) -> list[str]:
    """Roll and pitch, yaw, and (when estimated) the gyro bias: truth and estimate, then the
    estimate's error, fault windows shaded; the files written (none, and nothing drawn, without
    a folder ``out``)."""
    if out is None:
        return []
    import matplotlib.pyplot as plt

    t = result.time
    title = figure_title(result, o)
    faults = faults_of(result)

    def curve(ax, of, style="-", scale=1.0, **options):  # of: a window of the record -> the values drawn
        times, values = result.envelope(of)
        return ax.plot(times, values * scale, style, **options)[0]

    def finish(fig, axes, spans, name):
        shade_faults(axes, faults)
        for ax, span in zip(axes, spans, strict=True):
            floor_span(ax, span)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0.0)  # off the curves
        axes[-1].set_xlabel("time (s)")
        axes[-1].set_xlim(t[0], t[-1])
        fig.suptitle(title, fontsize=9)
        label_axes(axes)
        return save_figure(fig, out, name)

    figures = []
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True, height_ratios=(1, 1, 0.8))
    for k, name in enumerate(("roll", "pitch")):
        curve(axes[k], lambda w, k=k: w[f"Quadrotor.theta{k + 1}"], scale=180 / np.pi, label=f"{name}, truth")
        curve(axes[k], lambda w, k=k: w[f"Quaternion_estim.theta_est{k + 1}"], "--", scale=180 / np.pi,
              label=f"{name}, estimate")
        axes[k].set_ylabel(f"{name} (deg)")
        curve(axes[2], lambda w, k=k: euler_error(w, "Quaternion_estim.theta_est", k), scale=180 / np.pi,
              label=f"{name} error", lw=0.9)
    axes[2].axhline(0.0, color="k", lw=0.5)
    axes[2].set_ylabel("estimate - truth (deg)")
    figures.append(finish(fig, axes, (ANGLE_SPAN_DEG, ANGLE_SPAN_DEG, ERROR_SPAN_DEG), "roll_pitch.png"))

    fig, axes = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True, height_ratios=(1, 0.8))
    axes[0].plot(*_angle_curve(result, "Quadrotor.theta3"), label="yaw, truth")
    axes[0].plot(*_angle_curve(result, "Quaternion_estim.theta_est3"), "--", label="yaw, estimate")
    axes[0].set_ylabel("yaw (deg)")
    curve(axes[1], lambda w: euler_error(w, "Quaternion_estim.theta_est", 2), scale=180 / np.pi, label="yaw error",
          lw=0.9)
    axes[1].axhline(0.0, color="k", lw=0.5)
    axes[1].set_ylabel("estimate - truth (deg)")
    figures.append(finish(fig, axes, (ANGLE_SPAN_DEG, ERROR_SPAN_DEG), "yaw.png"))

    # the bias figure only for an estimator that estimates one (the linear filter does not)
    if any(np.any(w[f"Quaternion_estim.b_est_{axis}"]) for w in result.windows() for axis in "xyz"):
        figures.append(finish(*_bias_axes(plt, curve), (BIAS_SPAN, BIAS_SPAN), "bias.png"))
    return [f for f in figures if f]


def _angle_curve(result, name: str):
    """:func:`quadcosim.scenarios.figures.angle_curve` of signal ``name`` (rad); a streamed record is
    unwrapped window by window, each window continuing from the last sample of the one before."""
    windows = result.windows()
    first = next(windows)
    if next(windows, None) is None:  # a record in memory: one window
        return angle_curve(result.time, np.degrees(result[name]))
    carried = {}  # the last raw sample and the offset unwrapping added to it

    def unwrapped(window):
        raw = window[name]
        if not carried:
            turned = np.unwrap(raw)
        else:
            turned = np.unwrap(np.concatenate([[carried["raw"]], raw]))[1:] + carried["offset"]
        carried["raw"], carried["offset"] = raw[-1], turned[-1] - raw[-1]
        return np.degrees(turned)

    del first
    return wrapped_curve(*result.envelope(unwrapped))


def _bias_axes(plt, curve):
    """The gyro bias figure's two axes drawn with ``curve``: estimate and truth, then the error."""
    fig, axes = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True, height_ratios=(1, 0.8))
    for axis in "xyz":
        line = curve(axes[0], lambda w, a=axis: w[f"Quaternion_estim.b_est_{a}"], label=f"b_{axis}, estimate")
        curve(axes[0], lambda w, a=axis: w[f"IMU.gyro_bias_{a}"], ":", color=line.get_color(), label=f"b_{axis}, truth")
        curve(axes[1], lambda w, a=axis: _bias_error(w, a), color=line.get_color(), label=f"b_{axis} error", lw=0.9)
    axes[0].set_ylabel("gyro bias (rad/s)")
    axes[1].axhline(0.0, color="k", lw=0.5)
    axes[1].set_ylabel("estimate - truth (rad/s)")
    return fig, axes


def _tilt_figures(result, o, out) -> list[str]:
    """The tilt finding's figure for ``flight=tilt`` (what the accelerometer reads, the speed)."""
    if o["flight"] != "tilt":
        return []
    from quadcosim.scenarios.tilt_figure import tilt_figure

    written = save_figure(tilt_figure(result, o, figure_title(result, o)), out, "tilt.png")
    return [written] if written else []


def bias_convergence_time(t, error, tolerance) -> float | None:
    """First time (s) after which every component of ``error`` stays within ``tolerance``.

    ``error`` is an (n, m) array, or an iterable of m length-n arrays (taken one at a time)."""
    columns = error.T if isinstance(error, np.ndarray) else error
    last = -1  # index of the last sample outside the tolerance, over every component
    for column in columns:
        outside = np.abs(column) > tolerance
        if outside.any():
            last = max(last, len(outside) - 1 - int(np.argmax(outside[::-1])))
    if last == len(t) - 1:
        return None
    return float(t[last + 1])


def diagram_title(o: dict) -> str:
    """Title of tp's wiring diagram: the estimator and what feeds the controller.

    Parameters
    ----------
    o : dict
        tp's options.

    Returns
    -------
    str
    """
    return title_lines(*describe(o))


# a flight that strays this far, for a second, diverged (scenarios/divergence.py): 20 s flights of every
# profile, estimate-fed by each filter with noise and bias, reach 27 deg of tilt error, 0.73 m of altitude
# error and 15 m/s (the linear filter's non-stationary flight); a 20 deg tilt step is tracked within it
DIVERGENCE = Bounds(tilt_error_deg=60.0, altitude_error_m=10.0, speed_m_s=60.0, held_s=1.0)

# IMU parameters the options set: --set IMU.seed=... would contradict the option seed
DERIVED = {"IMU.noise_enabled": "noise", "IMU.bias_enabled": "bias", "IMU.seed": "seed", "IMU.sample_rate": "imu_rate"}
# every block tp may hold (GravityOnly, MagCompensator: by their options; Quaternion_estim: another block
# class when the estimator is one, whose parameters are checked once it is built)
BLOCKS = {"Setpoint": Table, "GravityOnly": GravityOnly, **PLANT_BLOCKS, "Quaternion_estim": QuaternionEstim,
          "Controller": Controller, "MagCompensator": MagCompensator}
SCENARIO = Scenario("tp", __doc__.split(": ", 1)[1].splitlines()[0], OPTIONS, build, report,
                    extra={"diagram": True, "title": diagram_title, "derived": DERIVED, "unrecorded": UNRECORDED,
                           "blocks": BLOCKS,
                           "components": COMPONENTS, "divergence": DIVERGENCE},
                    resolve=resolve)
