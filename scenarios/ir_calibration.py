"""``ir-calibration``: in-flight calibration of the infrared horizon sensor against the GPS.

After "Calibration d'un récepteur Infra-Rouge pour Micro Drone" (Paparazzi project, 2004). A
fixed-wing flies a scripted bank profile (turns and straight legs whose turn rate has the
slides' mean 0.037 and standard deviation 0.24 rad/s); the InfraredSensor FMU gives the IR
reading, whose ``a`` and ``b`` drift, and the GPS turn rate, 1 s late. Three estimators run
side by side as streaming blocks: the Kalman filter (gated or not), the slides' regression and
Paparazzi's forgetting RLS. Faults as in the slides: IR +1200 for 2000 samples from 60 s,
GPS turn rate +1.5 rad/s for 2000 samples from 280 s; the drift's cloud (170 to 270 s) lies
between them.

Figures: ``calibration.png`` (a, b and the turn rate against their truth), ``innovations.png``
(the Kalman innovations and their gates), ``errors.png`` (turn-rate error histograms).
"""

from __future__ import annotations

import math

import numpy as np
from quadcosim.calibration.infrared import METHODS, EKFSettings, Estimator, InfraredCalibration
from quadcosim.fmus.build import table
from quadcosim.orchestrator import Block, FMUBlock, System, Table, portable
from quadcosim.orchestrator.fmu import FMUInstance
from quadcosim.scenarios import Option, Scenario
from quadcosim.scenarios.divergence import Bounds
from quadcosim.scenarios.figures import fault_text, faults_of, title_lines
from quadcosim.scenarios.plant import save_figure

RATE = 20.0  # Hz, the sensor's
IR_FAULT = (60.0, 1200.0)  # onset (s), offset (count): 2000 samples
GPS_FAULT = (280.0, 1.5)  # onset (s), offset (rad/s): 2000 samples
FAULT_SAMPLES = 2000
TURN_RATE_MEAN, TURN_RATE_STD = 0.037, 0.24  # rad/s, the slides' real flight

OPTIONS = {
    "duration": Option(400.0, "simulated time (s): 8000 samples at 20 Hz", minimum=5.0),
    "drift": Option(True, "a and b drift with time of day, temperature and cloud"),
    "faults": Option("none", "sensor faults of the slides", choices=("none", "ir", "gps", "both")),
    "ir_fault": Option(IR_FAULT[1], "offset of the IR fault (count; the slides': 1200)"),
    "gps_fault": Option(GPS_FAULT[1], "offset of the GPS fault (rad/s; the slides': 1.5)"),
    "gps_resetting": Option(True, "GPS fused all flight (the slides' 'with GPS resetting'); off: only until "
                                  "calibration_s (their 'real case')"),
    "calibration_s": Option(60.0, "end of the GPS calibration phase when gps_resetting is off (s)", minimum=0.0),
    "gating": Option(True, "innovation gating and fault declaration in the Kalman filter"),
    "noise": Option(True, "sensor noise"),
    "seed": Option(1, "seed of the sensor noise and of the bank profile"),
}


def bank_profile(samples: int, seed: int = 1, airspeed: float | None = None, gravity: float | None = None,
                 rate: float = RATE) -> np.ndarray:
    """Bank angles (rad) of a flight of turns and straight legs, one per sample.

    Legs of 2 to 8 s, 20 % of them straight, joined by 1.5 s roll transitions (a small
    aircraft navigating between waypoints and circling over targets); the turn rate
    ``g tan(phi) / V`` is then scaled to the slides' mean 0.037 and standard deviation 0.24 rad/s.
    ``samples`` at ``rate`` (Hz), drawn with ``seed``; ``airspeed`` V (m/s) and ``gravity`` g
    (m/s^2) default to the FMU's.
    """
    parameters = {v.name: v.start for v in table("InfraredSensor").of("parameter")}
    airspeed = airspeed or parameters["airspeed"]
    gravity = gravity or parameters["gravity"]
    rng = np.random.default_rng(seed)
    r = np.empty(samples)
    ramp = int(1.5 * rate)
    blend = portable.sin(0.5 * np.pi * np.arange(1, ramp + 1) / ramp) ** 2
    k, previous = 0, 0.0
    while k < samples:
        length = max(int(rng.uniform(2.0, 8.0) * rate), ramp)
        target = rng.normal() if rng.random() < 0.8 else 0.0
        leg = np.full(length, target)
        leg[:ramp] = previous + (target - previous) * blend
        r[k:k + length] = leg[:samples - k]
        k, previous = k + length, target
    r = TURN_RATE_MEAN + TURN_RATE_STD * (r - r.mean()) / r.std()
    return portable.arctan(r * airspeed / gravity)  # the same bits on every CPU


def fault_windows(faults: str, ir_fault: float = IR_FAULT[1], gps_fault: float = GPS_FAULT[1]
                  ) -> list[tuple[str, float, float, float]]:
    """The injected faults: (sensor, onset s, end s, offset).

    Parameters
    ----------
    faults : {"none", "ir", "gps", "both"}
        Which sensors fail, at the slides' onsets, for 2000 samples.
    ir_fault : float
        Offset of the IR (count); the slides' 1200 by default.
    gps_fault : float
        Offset of the GPS turn rate (rad/s); the slides' 1.5 by default.
    """
    windows = []
    if faults in ("ir", "both"):
        windows.append(("ir", IR_FAULT[0], IR_FAULT[0] + FAULT_SAMPLES / RATE, float(ir_fault)))
    if faults in ("gps", "both"):
        windows.append(("gps", GPS_FAULT[0], GPS_FAULT[0] + FAULT_SAMPLES / RATE, float(gps_fault)))
    return windows


def sensor_parameters(seed: int, drift: bool, noise: bool) -> dict:
    """InfraredSensor parameters for a noise ``seed``, drift on or off, noise on or off."""
    return {"seed": seed, "drift_enabled": drift, "noise_enabled": noise}


def simulate_flight(samples: int = 8000, seed: int = 1, drift: bool = True, noise: bool = True,
                    faults: str = "none", parameters: dict | None = None, ir_fault: float = IR_FAULT[1],
                    gps_fault: float = GPS_FAULT[1]) -> dict[str, np.ndarray]:
    """The InfraredSensor FMU over a flight of :func:`bank_profile`, on arrays, without the master.

    Returns arrays of ``samples`` values at 20 Hz: ``time`` (s), the truth ``r`` (rad/s), ``a``,
    ``b``, and the sensors as the estimators see them, faults added: ``ir`` (count),
    ``gps_turn_rate`` (rad/s), ``gps_valid``. ``parameters`` overrides the FMU's (for instance
    ``{"cloud_start": 100.0}`` to put the cloud inside the IR fault). ``seed`` draws the bank
    profile and the noise; ``drift`` (of a and b), ``noise`` and ``faults`` (``none``, ``ir``,
    ``gps``, ``both``) switch the slides' effects; ``ir_fault`` (count) and ``gps_fault``
    (rad/s) are the faults' offsets.
    """
    phi = bank_profile(samples, seed)
    names = ["r", "a", "b", "ir", "gps_turn_rate", "gps_valid"]
    fmu = FMUInstance("InfraredSensor", sensor_parameters(seed, drift, noise) | dict(parameters or {}))
    values = np.empty((samples, len(names)))
    try:
        for k in range(samples):
            fmu.set(["phi"], [phi[k]])
            values[k] = fmu.get(names)
            fmu.step(k / RATE, 1.0 / RATE)
    finally:
        fmu.close()
    flight = {name: values[:, j] for j, name in enumerate(names)}
    flight["time"] = np.arange(samples) / RATE
    for sensor, start, stop, offset in fault_windows(faults, ir_fault, gps_fault):
        window = (flight["time"] >= start - 1e-9) & (flight["time"] < stop - 1e-9)
        flight["ir" if sensor == "ir" else "gps_turn_rate"][window] += offset
    return flight


def estimate(flight: dict, gating: bool = True, gps_until: float = math.inf) -> dict[str, dict]:
    """The three estimators over a ``flight`` from :func:`simulate_flight` (the batch path); the
    Kalman filter's innovation ``gating`` on or off; the GPS used only before ``gps_until`` (s)."""
    use = (flight["gps_valid"] > 0.5) & (flight["time"] < gps_until)
    settings = {"kalman": EKFSettings(gate=5.0 if gating else 0.0)}
    return {m: Estimator(m, settings.get(m)).run(flight["ir"], flight["gps_turn_rate"], use) for m in METHODS}


def summarize(time, truth: dict, estimates: dict, windows) -> dict:
    """Metrics of a run: turn-rate errors, faults declared and false alarms, recovery of a and b.

    ``truth`` holds ``r``, ``a``, ``b``; ``estimates`` maps each method to its ``turn_rate``,
    ``a``, ``b`` (and, for the Kalman filter, ``ir_fault`` and ``gps_fault``), at the instants
    ``time`` (s); ``windows`` are the injected faults ``(sensor, start, stop, offset)``.
    """
    valid = time >= 2.0  # the GPS window is filled
    metrics = {"turn_rate_error_deg_s": {}}
    for m, e in estimates.items():
        error = np.degrees(e["turn_rate"] - truth["r"])[valid]
        metrics["turn_rate_error_deg_s"][m] = {"mean": float(error.mean()), "std": float(error.std())}
        settled = np.degrees(e["turn_rate"] - truth["r"])[time >= 30.0]
        if len(settled):  # a run shorter than 30 s has no settled part to score
            metrics.setdefault("turn_rate_error_after_30_s_deg_s", {})[m] = {"mean": float(settled.mean()),
                                                                             "std": float(settled.std())}
    kalman = estimates["kalman"]
    flags = {"ir": kalman["ir_fault"], "gps": kalman["gps_fault"]}
    metrics["faults"], metrics["false_alarms"] = fault_report(windows, flags, time)
    recovery = []
    a, b = truth["a"], truth["b"]
    close = (np.abs(kalman["a"] - a) <= 0.05 * np.abs(a)) & (np.abs(kalman["b"] - b) <= 0.05 * np.abs(b))
    for sensor, _onset, end, _ in windows:
        after = (time >= end) & (time <= end + 10.0)
        if not after.any():  # the flight ended before the fault did: no recovery to measure
            recovery.append({"sensor": sensor, "back_within_5_percent_s": None,
                             "a_error_percent_at_end_plus_10_s": None, "b_error_percent_at_end_plus_10_s": None})
            continue
        # back within 5 % and staying there until 10 s after the end
        inside = close[after]
        bad = np.flatnonzero(~inside)
        back = 0.0 if not len(bad) else (float(time[after][bad[-1] + 1] - end) if bad[-1] + 1 < len(inside) else None)
        recovery.append({"sensor": sensor, "back_within_5_percent_s": back,
                         "a_error_percent_at_end_plus_10_s": float(100 * (kalman["a"][after][-1] / a[after][-1] - 1)),
                         "b_error_percent_at_end_plus_10_s": float(100 * (kalman["b"][after][-1] / b[after][-1] - 1))})
    metrics["recovery"] = recovery
    return metrics


class SensorFaults(Block):
    """Adds the slides' offsets to the IR and the GPS turn rate over their fault windows; ``name``:
    the block's; ``windows``: ``(sensor, start, stop, offset)`` with sensor ``ir`` (count) or
    ``gps`` (rad/s), times in s."""

    inputs = ("ir", "gps_turn_rate")
    outputs = ("ir", "gps_turn_rate")

    def __init__(self, name: str, windows):
        super().__init__(name)
        self.windows = [(0 if sensor == "ir" else 1, start, stop, offset) for sensor, start, stop, offset in windows]

    def step(self, t, u, y):
        y[:] = u
        for channel, start, stop, offset in self.windows:
            if start - 1e-9 <= t < stop - 1e-9:
                y[channel] += offset


def build(o: dict) -> System:
    """Bank profile -> InfraredSensor -> faults -> the three estimators, all at 20 Hz.

    Parameters
    ----------
    o : dict
        The scenario's options (see ``OPTIONS``).
    """
    samples = int(round(o["duration"] * RATE))
    for sensor, start, stop, _ in fault_windows(o["faults"], o["ir_fault"], o["gps_fault"]):
        if start >= o["duration"]:
            raise ValueError(f"faults={o['faults']}: the {sensor.upper()} fault starts at {start:g} s (the slides' "
                             f"onset), after this run's {o['duration']:g} s; run at least duration={stop:g} to see "
                             "it whole, or choose faults=none")
    system = System(dt=1.0 / RATE)
    # the profile of samples rows (the last is held), the same as simulate_flight flies
    system.add(Table("Bank", ["phi"], bank_profile(samples, o["seed"])[:, None], units={"phi": "rad"}))
    system.add(FMUBlock("InfraredSensor", parameters=sensor_parameters(o["seed"], o["drift"], o["noise"])))
    system.add(SensorFaults("Faults", fault_windows(o["faults"], o["ir_fault"], o["gps_fault"])))
    system.connect("Bank.phi", "InfraredSensor.phi")
    system.connect("InfraredSensor.ir", "Faults.ir")
    system.connect("InfraredSensor.gps_turn_rate", "Faults.gps_turn_rate")
    gps_until = math.inf if o["gps_resetting"] else o["calibration_s"]
    settings = {"kalman": EKFSettings(gate=5.0 if o["gating"] else 0.0)}
    for method in METHODS:
        name = method.capitalize()
        system.add(InfraredCalibration(name, Estimator(method, settings.get(method)), gps_until=gps_until))
        system.connect("Faults.ir", f"{name}.ir")
        system.connect("Faults.gps_turn_rate", f"{name}.gps_turn_rate")
        system.connect("InfraredSensor.gps_valid", f"{name}.gps_valid")
    return system


def episodes(flag: np.ndarray, time: np.ndarray) -> list[tuple[float, float | None]]:
    """(declared, cleared) times of each run of a 0/1 flag; ``None`` when still declared."""
    on = np.asarray(flag) > 0.5
    edges = np.diff(on.astype(int), prepend=0, append=0)
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(float(time[s]), float(time[e]) if e < len(time) else None) for s, e in zip(starts, stops, strict=True)]


def fault_report(windows, kalman_flags: dict[str, np.ndarray], time: np.ndarray) -> tuple[list[dict], int]:
    """Match the fault episodes declared by the Kalman filter (``kalman_flags``: sensor -> flag per
    instant of ``time``, s) with the injected faults ``windows``; the rest are false alarms. Each
    fault: its onset and end, when it was declared and cleared, and (when declared) how long after
    its onset it was declared and after its end cleared (s; None while still declared)."""
    declared = {sensor: episodes(flag, time) for sensor, flag in kalman_flags.items()}
    faults, matched = [], set()
    for sensor, onset, end, _ in windows:
        entry = {"sensor": sensor, "onset_s": onset, "end_s": end, "declared_s": None, "cleared_s": None}
        for i, (start, stop) in enumerate(declared[sensor]):
            if onset - 1e-9 <= start < end:
                entry |= {"declared_s": start, "cleared_s": stop, "declared_after_s": start - onset,
                          "ended_after_s": None if stop is None else stop - end}
                matched.add((sensor, i))
                break
        faults.append(entry)
    false_alarms = sum(1 for sensor, runs in declared.items() for i in range(len(runs)) if (sensor, i) not in matched)
    return faults, false_alarms


def _shade(ax, windows):
    for sensor, start, stop, _ in windows:
        ax.axvspan(start, stop, color="tab:red" if sensor == "ir" else "tab:purple", alpha=0.12,
                   label=f"{sensor.upper()} fault")


_STYLES = {"kalman": "tab:blue", "regression": "tab:orange", "rls": "tab:green"}


def report(result, o, out) -> dict:
    """Metrics (:func:`summarize`, and the flight's statistics) and the three figures.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The run.
    o : dict
        The scenario's options.
    out : pathlib.Path or None
        Folder of the figures; none are written when ``None``.
    """
    t = result.time
    windows = fault_windows(o["faults"], o["ir_fault"], o["gps_fault"])
    truth = {"r": result["InfraredSensor.r"], "a": result["InfraredSensor.a"], "b": result["InfraredSensor.b"]}
    estimates = {m: {k: result[f"{m.capitalize()}.{k}"] for k in ("turn_rate", "a", "b")} for m in METHODS}
    estimates["kalman"] |= {k: result[f"Kalman.{k}"] for k in ("ir_fault", "gps_fault")}
    metrics = summarize(t, truth, estimates, windows)
    ir, r = result["InfraredSensor.ir"], truth["r"]
    slope, intercept = np.polyfit(r, ir, 1)
    metrics["flight"] = {"ir_mean": float(ir.mean()), "ir_std": float(ir.std()), "turn_rate_mean": float(r.mean()),
                         "turn_rate_std": float(r.std()), "ir_fit": {"a": float(slope), "b": float(intercept)}}
    title = run_title(result, o)
    figures = [_calibration_figure(result, o, truth, windows, out, title),
               _innovations_figure(result, o, windows, out, title),
               _errors_figure(t, truth, estimates, metrics["turn_rate_error_deg_s"], out, title)]
    metrics["figures"] = [f for f in figures if f]
    return metrics


def run_title(result, o: dict) -> str:
    """Title of the scenario's figures: the sensor model, the faults, the filter's settings.

    Parameters
    ----------
    result : quadcosim.orchestrator.Result
        The run (its injected faults, if any, are named too).
    o : dict
        The scenario's options.

    Returns
    -------
    str
        Two lines or more.
    """
    gps = "GPS fused all flight" if o["gps_resetting"] else f"GPS fused until {o['calibration_s']:g} s"
    faults = {"none": "no sensor fault", "ir": "IR fault", "gps": "GPS fault", "both": "IR and GPS faults"}
    return title_lines(f"ir-calibration: {o['duration']:g} s of banked flight, a and b drift "
                       f"{'on' if o['drift'] else 'off'}, sensor noise {'on' if o['noise'] else 'off'}",
                       f"{faults[o['faults']]}, innovation gating {'on' if o['gating'] else 'off'}, {gps}",
                       fault_text(faults_of(result)))


def _calibration_figure(result, o, truth, windows, out, title):
    """a, b and the turn rate against time, with their truth."""
    if out is None:  # nothing would keep it
        return None
    import matplotlib.pyplot as plt

    t, a, b, truth_r = result.time, truth["a"], truth["b"], truth["r"]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for m in METHODS:
        axes[0].plot(t, result[f"{m.capitalize()}.a"], color=_STYLES[m], lw=1, label=m)
        axes[1].plot(t, result[f"{m.capitalize()}.b"], color=_STYLES[m], lw=1, label=m)
    axes[0].plot(t, a, "k--", lw=1, label="truth")
    axes[1].plot(t, b, "k--", lw=1, label="truth")
    axes[2].plot(t, np.degrees(result["Faults.gps_turn_rate"]), color="0.6", lw=0.6, label="GPS (late)")
    axes[2].plot(t, np.degrees(result["Kalman.turn_rate"]), color=_STYLES["kalman"], lw=0.8,
                 label="Kalman (IR - b) / a")
    axes[2].plot(t, np.degrees(truth_r), "k--", lw=0.8, label="truth")
    axes[0].set_ylabel("a (count per rad/s)")
    axes[1].set_ylabel("b (count)")
    axes[2].set_ylabel("turn rate (deg/s)")
    axes[2].set_xlabel("time (s)")
    span = np.ptp(a), np.ptp(b)
    axes[0].set_ylim(a.min() - max(0.5 * span[0], 40), a.max() + max(0.5 * span[0], 40))
    axes[1].set_ylim(b.min() - max(0.5 * span[1], 40), b.max() + max(0.5 * span[1], 40))
    axes[2].set_ylim(np.degrees(truth_r.min()) - 20, np.degrees(truth_r.max()) + 20)
    for ax in axes:
        _shade(ax, windows)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8, ncol=3)
    axes[2].legend(loc="upper right", fontsize=8, ncol=3)
    axes[0].set_title("a and b: the three estimators against the truth (axes centred on the truth)", fontsize=8)
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, out, "calibration.png")


def _innovations_figure(result, o, windows, out, title):
    """The Kalman filter's innovations with their gates: GPS, paired IR, present IR."""
    if out is None:  # nothing would keep it
        return None
    import matplotlib.pyplot as plt

    t = result.time
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    gamma = EKFSettings().gate if o["gating"] else 0.0
    panels = ((axes[0], "gps", "GPS turn rate (deg/s)", 180 / np.pi),
              (axes[1], "ir", "paired IR (count)", 1.0),
              (axes[2], "ir_now", "present IR (count)", 1.0))
    for ax, key, unit, scale in panels:
        S = result[f"Kalman.S_{key}"]
        computed = S > 0.0
        nu = np.where(computed, result[f"Kalman.nu_{key}"] * scale, np.nan)
        ax.plot(t, nu, lw=0.6, label="innovation")
        if not computed.any():  # no sample of this kind was fused (GPS fused for less than a pairing)
            ax.text(0.5, 0.5, "none computed in this run", transform=ax.transAxes, ha="center", va="center")
        elif gamma:
            gate = np.where(computed, gamma * np.sqrt(np.where(computed, S, 1.0)) * scale, np.nan)
            ax.plot(t, gate, "r", lw=0.8, label=f"gate ±{gamma:g} sqrt(S)")
            ax.plot(t, -gate, "r", lw=0.8)
            # the gates, and the innovations of a fault
            top = 1.1 * max(3 * np.nanmedian(gate), np.nanpercentile(np.abs(nu), 99.9))
            ax.set_ylim(-top, top)
        ax.set_ylabel(unit)
        _shade(ax, windows)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, ncol=4)
    axes[0].set_title("Kalman innovations: GPS and paired IR (fused when inside the gate), present IR (checked)",
                      fontsize=8)
    axes[2].set_xlabel("time (s)")
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, out, "innovations.png")


def _errors_figure(t, truth, estimates, stats, out, title):
    """Histograms of the turn-rate error of each method."""
    if out is None:  # nothing would keep it
        return None
    import matplotlib.pyplot as plt

    valid = t >= 2.0
    errors = {m: np.degrees(estimates[m]["turn_rate"] - truth["r"])[valid] for m in METHODS}
    fig, ax = plt.subplots(figsize=(8, 4.5))
    limit = max(5.0, float(np.percentile(np.abs(np.concatenate(list(errors.values()))), 99.5)))
    bins = np.linspace(-limit, limit, 121)
    for m in METHODS:
        ax.hist(np.clip(errors[m], -limit, limit), bins=bins, histtype="step", color=_STYLES[m], lw=1.2,
                label=f"{m}: mean {stats[m]['mean']:.2f}, std {stats[m]['std']:.2f} deg/s")
    ax.set_xlabel(f"turn-rate error, estimate - truth (deg/s); beyond ±{limit:.0f} counted in the end bins")
    ax.set_ylabel("samples")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax.set_title("turn-rate error of each estimator, after the first 2 s", fontsize=8)
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, out, "errors.png")


# the aircraft's true turn rate g tan(phi) / V (InfraredSensor.r): at most 1.03 rad/s over the default 400 s
# (0.78 and 0.72 with seeds 2 and 3, banks up to 52 deg at 12 m/s). 2.5 rad/s is a 72 deg bank at 12 m/s
# (3.2 g), beyond a small aircraft's envelope; held 0.5 s (a roll transition lasts 1.5 s)
DIVERGENCE = Bounds(tilt_error_deg=None, altitude_error_m=None, speed_m_s=None, held_s=0.5, turn_rate_rad_s=2.5)
SCENARIO = Scenario(
    name="ir-calibration",
    description="In-flight calibration of an infrared horizon sensor against the GPS turn rate: Kalman filter "
                "with fault detection, the slides' regression, Paparazzi's RLS",
    options=OPTIONS,
    build=build,
    report=report,
    extra={"divergence": DIVERGENCE,
           "blocks": {"Bank": Table, "InfraredSensor": "InfraredSensor", "Faults": SensorFaults,
                      **{m.capitalize(): InfraredCalibration for m in METHODS}}},
)
