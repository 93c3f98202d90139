"""Physical assertions on a recorded run, for tests: each checks one property in physical units.

Every helper takes an :class:`quadcosim.orchestrator.Result` (a run of :func:`quadcosim.scenarios.run` or of the
``run_scenario`` fixture), returns the figure it checked, and on failure raises
:class:`AssertionError` saying what failed, where and by how much: the worst sample's time (s),
its value and the bound, and the seed of the run, so that the failure can be run again.

- :func:`assert_attitude_error`: the estimate against the true attitude, per Euler angle;
- :func:`assert_tracking`: a signal following its setpoint (a signal or a constant);
- :func:`step_response` and :func:`assert_step`: settling time and overshoot of a step;
- :func:`assert_bias_converges`: the gyro bias estimate reaching the true bias and staying;
- :func:`assert_bounds`: a signal within its bounds;
- :func:`assert_runs_close`: two runs agreeing signal by signal within a tolerance.

The errors they compute are those of the scenarios' metrics (:func:`quadcosim.scenarios.tp.euler_error`,
:func:`quadcosim.scenarios.tp.bias_convergence_time`), so that a test and a ``metrics.json`` measure the
same thing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

AXES = ("roll", "pitch", "yaw")

#: Default tolerance of :func:`assert_bias_converges` (rad/s): that of tp's ``bias_convergence_s``.
BIAS_TOLERANCE = 1e-3


def seed_text(result) -> str:
    """The seed of the run that made ``result``, as a failure message states it.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result

    Returns
    -------
    str
        ``"seed 1234 (test node tests/test_x.py::test_y)"`` from the ``run_scenario`` fixture,
        else the scenario's ``seed`` option, else ``"no seed recorded"``.
    """
    test = result.meta.get("test") or {}
    if "seed" in test:
        return f"seed {test['seed']} (test {test.get('node', '?')})"
    options = result.meta.get("scenario", {}).get("options", {})
    return f"seed {options['seed']} (option seed)" if "seed" in options else "no seed recorded"


def _number(name: str, value, magnitude: bool = True) -> float:
    """``value`` as a bound: a real number, not NaN (no comparison with NaN fails, so a NaN
    bound would pass anything), and not negative when it bounds a magnitude."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}={value!r} must be a number (a {type(value).__name__} was given); write "
                        f"{name}=0.5, in the unit of the quantity bounded")
    value = float(value)
    if math.isnan(value):
        raise ValueError(f"{name}=nan is not a bound: no comparison with NaN fails, so it would pass anything; "
                         "give a number")
    if magnitude and value < 0:
        raise ValueError(f"{name}={value:g} is negative: it bounds a magnitude, which no sample can keep below "
                         "zero; give a bound >= 0")
    return value


def _axes(axes) -> list[str]:
    """The Euler axes asked for, checked: a name or names among :data:`AXES`."""
    axes = [axes] if isinstance(axes, str) else list(axes)
    unknown = [a for a in axes if a not in AXES]
    if unknown or not axes:
        raise ValueError(f"axes={tuple(axes)!r}: {', '.join(map(repr, unknown)) or 'none given'}; give axes among "
                         f"{', '.join(map(repr, AXES))} (lower case)")
    return axes


def _no_nan(name: str, values: np.ndarray, mask: np.ndarray, result) -> None:
    """Fail on the first NaN among the samples checked: a NaN compares false with any bound."""
    bad = np.flatnonzero(mask & np.isnan(values.reshape(len(mask), -1)).any(axis=1))
    if len(bad):
        _fail(f"{name} is NaN at t = {result.time[bad[0]]:.4f} s ({len(bad)} of {int(mask.sum())} samples checked): "
              "a NaN is no value within any bound", result)


def _fail(what: str, result) -> None:
    raise AssertionError(f"{what}; {seed_text(result)}")


def _after(result, after_s: float) -> np.ndarray:
    """Mask of the samples at or after ``after_s`` seconds; refuses an empty window."""
    mask = np.asarray(result.time) >= after_s
    if not mask.any():
        raise ValueError(f"after_s = {after_s:g} s leaves no sample: the run ends at {result.time[-1]:g} s")
    return mask


def _values(result, signal) -> tuple[str, np.ndarray]:
    """(name, values) of ``signal``: a recorded name, or ``(name, array)`` of one value per sample."""
    if isinstance(signal, str):
        return signal, np.asarray(result[signal], dtype=float)
    name, values = signal
    values = np.asarray(values, dtype=float)
    if len(values) != len(result):
        raise ValueError(f"{name}: {len(values)} values for {len(result)} samples")
    return name, values


def _unit(result, signal: str) -> str:
    unit = result.units.get(signal, "") if isinstance(signal, str) else ""
    return f" {unit}" if unit else ""


def _worst(excess: np.ndarray, mask: np.ndarray) -> int:
    """Index of the largest ``excess`` among the samples of ``mask``."""
    masked = np.where(mask, excess, -np.inf)
    return int(np.argmax(masked))


def attitude_errors_deg(result) -> np.ndarray:
    """Estimation error of every sample (deg; columns roll, pitch, yaw, wrapped to +-180): the
    estimate ``Quaternion_estim.theta_est`` minus the truth ``Quadrotor.theta``, as tp's metrics
    compute it (:func:`quadcosim.scenarios.tp.euler_error`).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A run of the lab's closed loop (or any run recording those two signals).

    Returns
    -------
    numpy.ndarray, shape (len(result), 3)
    """
    from quadcosim.scenarios.tp import euler_error

    return np.degrees(np.column_stack([euler_error(result, "Quaternion_estim.theta_est", k) for k in range(3)]))


def assert_attitude_error(result, below_deg: float, after_s: float = 0.0, axes=AXES) -> float:
    """Check that the attitude estimate stays within ``below_deg`` of the truth after ``after_s``.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A run recording ``Quaternion_estim.theta_est`` and ``Quadrotor.theta`` (rad).
    below_deg : float
        Bound on the absolute Euler angle error of every sample (deg).
    after_s : float
        Samples before this time (s) are not checked: the filter's convergence.
    axes : sequence of str
        Among ``"roll"``, ``"pitch"``, ``"yaw"``.

    Returns
    -------
    float
        The largest absolute error checked (deg).

    Raises
    ------
    AssertionError
        A sample beyond the bound; the message gives the axis, time, error, bound and seed.
    """
    below_deg = _number("below_deg", below_deg)
    axes = _axes(axes)
    columns = [AXES.index(axis) for axis in axes]
    errors = np.abs(attitude_errors_deg(result)[:, columns])
    mask = _after(result, after_s)
    _no_nan("the attitude error", errors, mask, result)
    worst_per_axis = np.where(mask[:, None], errors, -np.inf).max(axis=0)
    k = int(np.argmax(worst_per_axis))
    i = _worst(errors[:, k], mask)
    if errors[i, k] > below_deg:
        _fail(f"attitude error: {axes[k]} estimate off the truth by {errors[i, k]:.4g} deg at t = "
              f"{result.time[i]:.4f} s, above the bound {below_deg:g} deg (checked from {after_s:g} s)", result)
    return float(errors[i, k])


def assert_tracking(result, signal, setpoint, within: float, after_s: float = 0.0, angle: bool = False) -> float:
    """Check that ``signal`` stays within ``within`` of ``setpoint`` after ``after_s``.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
    signal : str or (str, array_like)
        A recorded signal (``"Quadrotor.theta2"``), or a name and one value per sample.
    setpoint : str, float or (str, array_like)
        A recorded signal (``"Controller.theta_d2"``), a constant, or a name and values; in
        ``signal``'s unit.
    within : float
        Bound on ``|signal - setpoint|`` at every sample checked, in ``signal``'s unit.
    after_s : float
        Samples before this time (s) are not checked.
    angle : bool
        The difference is an angle (rad), wrapped to [-pi, pi) before it is compared.

    Returns
    -------
    float
        The largest absolute difference checked.

    Raises
    ------
    AssertionError
        A sample off the setpoint by more than ``within``; the message gives its time, the
        signal's value, the setpoint's, the difference, the bound and the seed.
    """
    within = _number("within", within)
    name, values = _values(result, signal)
    if isinstance(setpoint, (int, float)):
        target_name, target = f"{setpoint:g}", np.full(len(result), float(setpoint))
    else:
        target_name, target = _values(result, setpoint)
    difference = values - target
    if angle:
        from quadcosim.scenarios.tp import wrapped

        difference = wrapped(difference)
    mask = _after(result, after_s)
    _no_nan(f"{name} - {target_name}", difference, mask, result)
    i = _worst(np.abs(difference), mask)
    unit = _unit(result, signal)
    if abs(difference[i]) > within:
        _fail(f"tracking: {name} = {values[i]:.6g}{unit} at t = {result.time[i]:.4f} s against the setpoint "
              f"{target_name} = {target[i]:.6g}{unit}: off by {difference[i]:.4g}{unit}, beyond the bound "
              f"{within:g}{unit} (checked from {after_s:g} s)", result)
    return float(abs(difference[i]))


@dataclass
class StepResponse:
    """Settling time and overshoot of a step, measured by :func:`step_response`.

    Attributes
    ----------
    settling_time_s : float
        Time from the step until the signal enters the band around the final value for good
        (s); ``inf`` if it never does.
    overshoot_percent : float
        Peak beyond the final value, in percent of the step's size.
    peak_time_s, peak_value : float
        Time (s, from the run's start) and value of the peak.
    last_outside_time_s, last_outside_value : float or None
        The last sample outside the band (time from the run's start, s; value); None if the
        signal is inside at the step already.
    initial, final, band : float
        Value at the step, final value, half-width of the settling band (fraction of the step).
    """

    settling_time_s: float
    overshoot_percent: float
    peak_time_s: float
    peak_value: float
    last_outside_time_s: float | None
    last_outside_value: float | None
    initial: float
    final: float
    band: float


def step_response(result, signal, step_s: float, final: float | None = None, band: float = 0.02) -> StepResponse:
    """Settling time and overshoot of ``signal`` after a step at ``step_s``, by python-control's
    :func:`control.step_info` on the samples from the step on, taken relative to the value at
    the step.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
    signal : str or (str, array_like)
        A recorded signal, or a name and one value per sample.
    step_s : float
        Time of the step (s).
    final : float, optional
        The value the step goes to (the setpoint), in the signal's unit; default: the last sample.
    band : float
        Settling band, a fraction of the step's size (0.02: within 2 %).

    Returns
    -------
    StepResponse
    """
    from quadcosim.flight.measured import step_figures

    name, values = _values(result, signal)
    start = int(np.searchsorted(result.time, step_s))
    if start >= len(result) - 1:
        raise ValueError(f"{name}: the step at {step_s:g} s leaves fewer than two samples (the run ends at "
                         f"{result.time[-1]:g} s)")
    t, y = np.asarray(result.time[start:]) - result.time[start], values[start:] - values[start]
    target = float(values[-1] if final is None else final)
    size = target - values[start]
    if size == 0:
        raise ValueError(f"{name}: the step from {values[start]:g} to {target:g} has no size")
    _, settling, overshoot = step_figures(t, y, size, band)
    outside = np.nonzero(np.abs(y - size) > band * abs(size))[0]
    last = int(outside[-1]) if len(outside) else None
    settled = np.inf if settling is None else settling
    peak = start + int(np.argmax(np.sign(size) * y))
    return StepResponse(settled, overshoot, float(result.time[peak]), float(values[peak]),
                        None if last is None else float(result.time[start + last]),
                        None if last is None else float(values[start + last]), float(values[start]), target, band)


def assert_step(result, signal, step_s: float, final: float | None = None, settles_within_s: float | None = None,
                overshoot_below_percent: float | None = None, band: float = 0.02) -> StepResponse:
    """Check the settling time and the overshoot of a step (:func:`step_response`).

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
    signal : str or (str, array_like)
        A recorded signal, or a name and one value per sample.
    step_s : float
        Time of the step (s).
    final : float, optional
        The value the step goes to, in the signal's unit; default: the last sample.
    settles_within_s : float, optional
        Bound on the settling time, from the step (s).
    overshoot_below_percent : float, optional
        Bound on the overshoot (percent of the step).
    band : float
        Settling band, a fraction of the step (0.02: 2 %).

    Returns
    -------
    StepResponse

    Raises
    ------
    AssertionError
        Too slow (the message gives the last sample outside the band: its time, value and the
        band) or too much overshoot (the peak's time and value, the bound), and the seed.
    """
    settles_within_s = None if settles_within_s is None else _number("settles_within_s", settles_within_s)
    if overshoot_below_percent is not None:
        overshoot_below_percent = _number("overshoot_below_percent", overshoot_below_percent)
    name = signal if isinstance(signal, str) else signal[0]
    unit = _unit(result, signal)
    step = step_response(result, signal, step_s, final, band)
    if math.isnan(step.overshoot_percent):
        _fail(f"step of {name} at {step_s:g} s: the overshoot is NaN (the signal holds NaN)", result)
    half = band * abs(step.final - step.initial)
    low, high = step.final - half, step.final + half
    if settles_within_s is not None and not step.settling_time_s <= settles_within_s:
        _fail(f"step of {name} at {step_s:g} s: settles in {step.settling_time_s:.4g} s, beyond the bound "
              f"{settles_within_s:g} s; the last sample outside the {100 * band:g} % band "
              f"[{low:.6g}, {high:.6g}]{unit} is {step.last_outside_value:.6g}{unit} at t = "
              f"{step.last_outside_time_s:.4f} s", result)
    if overshoot_below_percent is not None and not step.overshoot_percent <= overshoot_below_percent:
        _fail(f"step of {name} at {step_s:g} s from {step.initial:.6g} to {step.final:.6g}{unit}: overshoot "
              f"{step.overshoot_percent:.4g} %, above the bound {overshoot_below_percent:g} %; peak "
              f"{step.peak_value:.6g}{unit} at t = {step.peak_time_s:.4f} s", result)
    return step


def assert_bias_converges(result, within_s: float | None = None, tolerance: float = BIAS_TOLERANCE,
                          estimate: str = "Quaternion_estim.b_est", truth: str = "IMU.gyro_bias") -> float:
    """Check that the gyro bias estimate reaches the true bias and stays within ``tolerance``.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        A run recording the bias estimate and the true bias (rad/s, body frame).
    within_s : float, optional
        Bound on the convergence time (s); None checks only that it converges before the end.
    tolerance : float
        Every axis within this of the truth from the convergence time on (rad/s).
    estimate, truth : str
        The recorded vectors compared.

    Returns
    -------
    float
        The convergence time (s, :func:`quadcosim.scenarios.tp.bias_convergence_time`).

    Raises
    ------
    AssertionError
        No convergence, or too late; the message gives the last sample outside the tolerance
        (time, axis, error), the bound and the seed.
    """
    from quadcosim.scenarios.tp import bias_convergence_time

    tolerance = _number("tolerance", tolerance)
    within_s = None if within_s is None else _number("within_s", within_s)
    estimated = np.asarray(result[estimate], dtype=float)
    if len(estimated) and np.isfinite(estimated).all() and (np.ptp(estimated, axis=0) == 0).all():
        raise ValueError(f"{estimate} holds {estimated[0].tolist()} at every sample: this filter estimates no gyro "
                         "bias, so its convergence cannot be checked; run a filter that estimates one (tp's "
                         "estimator=passive or explicit with kI > 0)")
    error = estimated - np.asarray(result[truth], dtype=float)
    _no_nan(f"{estimate} - {truth}", error, np.ones(len(error), bool), result)
    converged = bias_convergence_time(result.time, error, tolerance)
    if converged is None or (within_s is not None and converged > within_s):
        outside = np.nonzero((np.abs(error) > tolerance).any(axis=1))[0][-1]
        axis = int(np.argmax(np.abs(error[outside])))
        when = "never converges before the run's end" if converged is None else f"converges at {converged:.4f} s"
        _fail(f"bias: {estimate} {when}, bound {within_s if within_s is not None else 'the run'} s; the last sample "
              f"outside +-{tolerance:g} rad/s of {truth} is at t = {result.time[outside]:.4f} s, axis "
              f"{'xyz'[axis]} off by {error[outside, axis]:.4g} rad/s", result)
    return converged


def assert_bounds(result, signal, lower: float | None = None, upper: float | None = None,
                  after_s: float = 0.0) -> tuple[float, float]:
    """Check that every sample of ``signal`` (every component of a vector) lies in [lower, upper].

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
    signal : str or (str, array_like)
        A recorded signal or vector (``"Quadrotor.p"``), or a name and values (one row per sample).
    lower, upper : float, optional
        Bounds in the signal's unit; None: unbounded on that side.
    after_s : float
        Samples before this time (s) are not checked.

    Returns
    -------
    (float, float)
        The smallest and largest value checked.

    Raises
    ------
    AssertionError
        A sample out of bounds; the message gives the component, its time, value, the bound and
        the seed.
    """
    lower = None if lower is None else _number("lower", lower, magnitude=False)
    upper = None if upper is None else _number("upper", upper, magnitude=False)
    if lower is not None and upper is not None and lower > upper:
        raise ValueError(f"lower={lower:g} is above upper={upper:g}: no value lies between them")
    name, values = _values(result, signal)
    table = values.reshape(len(result), -1)
    mask = _after(result, after_s)
    _no_nan(name, table, mask, result)
    checked = table[mask]
    components = result.columns(name) if isinstance(signal, str) else [name]
    if len(components) != table.shape[1]:
        components = [f"{name}[{j}]" for j in range(table.shape[1])]
    unit = _unit(result, components[0] if isinstance(signal, str) else signal)
    for bound, sign, word in ((upper, 1.0, "above the upper"), (lower, -1.0, "below the lower")):
        if bound is None:
            continue
        excess = np.where(mask[:, None], sign * (table - bound), -np.inf)
        i, j = np.unravel_index(int(np.argmax(excess)), excess.shape)
        if excess[i, j] > 0:
            _fail(f"bounds: {components[j]} = {table[i, j]:.6g}{unit} at t = {result.time[i]:.4f} s, {word} bound "
                  f"{bound:g}{unit} (checked from {after_s:g} s)", result)
    return float(checked.min()), float(checked.max())


def assert_runs_close(result, other, signals=None, atol: float = 0.0, rtol: float = 0.0,
                      equal_nan: bool = False) -> float:
    """Check that two runs agree: ``|a - b| <= atol + rtol |b|`` at every sample of every signal.

    Parameters
    ----------
    result, other : quadcosim.orchestrator.Result
        The runs, on the same time samples.
    signals : sequence of str, optional
        Signals or vectors compared; default: every signal both recorded.
    atol : float
        Absolute tolerance, in each signal's unit (0 with ``rtol = 0``: identical bit for bit).
    rtol : float
        Relative tolerance, of ``other``'s value.
    equal_nan : bool
        NaN in both at the same sample counts as agreement.

    Returns
    -------
    float
        The largest ``|a - b|`` found.

    Raises
    ------
    AssertionError
        Different sample times, or a sample beyond the tolerance; the message gives the signal,
        time, both values, the bound and the seeds of both runs.
    """
    atol, rtol = _number("atol", atol), _number("rtol", rtol)
    if len(result) != len(other) or not np.array_equal(result.time, other.time):
        _fail(f"runs: different time samples ({len(result)} and {len(other)} samples, ending at "
              f"{result.time[-1]:g} and {other.time[-1]:g} s)", result)
    names = [n for n in result.names if n in set(other.names)] if signals is None else \
        [m for s in signals for m in result.columns(s)]
    if not names:
        raise ValueError("the two runs record no signal in common")
    largest, worst = 0.0, None
    for name in names:
        a, b = np.asarray(result[name], dtype=float), np.asarray(other[name], dtype=float)
        difference = np.abs(a - b)
        if equal_nan:
            difference[np.isnan(a) & np.isnan(b)] = 0.0
        difference[np.isnan(difference)] = np.inf  # NaN in one run only
        excess = difference - (atol + rtol * np.abs(b))
        i = int(np.argmax(excess))
        largest = max(largest, float(difference[i]))
        if excess[i] > 0 and (worst is None or excess[i] > worst[0]):
            worst = (excess[i], name, i, a[i], b[i], atol + rtol * abs(b[i]))
    if worst is not None:
        _, name, i, a, b, bound = worst
        unit = _unit(result, name)
        _fail(f"runs differ: {name} = {a:.17g} against {b:.17g}{unit} at t = {result.time[i]:.4f} s, "
              f"|difference| {abs(a - b):.4g}{unit} beyond the bound {bound:.4g}{unit}; other run's "
              f"{seed_text(other)}", result)
    return largest


__all__ = ["AXES", "BIAS_TOLERANCE", "StepResponse", "assert_attitude_error", "assert_bias_converges",
           "assert_bounds", "assert_runs_close", "assert_step", "assert_tracking", "attitude_errors_deg",
           "seed_text", "step_response"]
