"""How small an offset the infrared calibration's fault detector can find, and how fast: computed, and measured.

The detector (:mod:`quadcosim.calibration.infrared.detection`) declares a fault when a generalised
likelihood ratio on the GPS-IR consistency residual of the last ``RING_SIZE`` samples, against
the calibration from before them, reaches ``significance``, beside a constant error of that
calibration and a drift of it (its rate with the prior ``sd_drift``); it looks only when a
CUSUM on the residual has passed its threshold. Three things set the smallest offset it finds:

- the residual's noise ``sigma`` (counts per sample; mostly the GPS heading noise times ``a``);
- the drift: a step must stand out of a straight line through the ring (the drift's fit takes
  the rest), and the longer the offset has lasted the more of the ring it covers;
- the reference's age: the calibration is from before the ring, so an offset is seen against
  it only while its onset lies in the ring (``RING_SIZE`` samples); later the filter has
  absorbed it into that calibration.

:func:`predicted` computes, for an offset that entered the residual ``t`` s ago, the expected
log-likelihood ratio at its true onset, ``d^2 E(t) / (2 sigma^2)``, with ``E`` the energy of
its signature (a step for the GPS; a ramp over the GPS window, a second late, for the IR)
left after the fit of the constant and the drift; it is found in 99 % of flights when ``d
sqrt(E) / sigma`` exceeds ``sqrt(2 significance)`` by the normal's 99 % quantile. The CUSUM adds
a floor: its increments ``d / s - k`` (``s`` the filter's model deviation of the residual,
``k`` the allowance) must reach its threshold. :func:`measured` flies fleets of fresh seeds
with offsets from below to above that limit and gives the delay within which 99 % of them were
declared on the right sensor. ``python -m quadcosim.studies.ir_detectability`` prints both and draws
``detectability.png``.

``--explain`` shows, on one flight, why the filter's own innovations miss small offsets (it
absorbs them into ``b`` and ``a`` within seconds); ``--ramps`` flies offsets that come in over 2
to 60 s; ``--calibrate`` prints what the detector's thresholds were set on (tuning seeds).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from quadcosim.calibration.infrared import EKFSettings
from quadcosim.calibration.infrared.layout import RING_SIZE
from quadcosim.scenarios.ir_calibration import FAULT_SAMPLES, GPS_FAULT, IR_FAULT, RATE, episodes
from quadcosim.studies.ir_detection import TUNING, fleet, fly, kalman

SAMPLES = 8000
SETTLED_S = 30.0  # s: the spreads are taken after the filter has converged
ABSORBED_S = 3.0  # s after the fault reaches the filter: how much of it b and a hold then
BIN = 10  # samples: half a second, the averaging of the fault's signature
SIGNATURE_S = 6.0  # s after the fault reaches the filter, searched for its largest mean
FAULTS = (("ir", 100.0), ("gps", 0.2))
RAMPED = (("ir", 400.0), ("gps", 0.3))  # count, rad/s
RAMPS_S = (2.0, 5.0, 10.0, 20.0, 60.0)  # s over which they come in
Z99 = 2.3263478740408408  # the standard normal's 99 % quantile
SIZES = {"ir": (20.0, 30.0, 40.0, 50.0, 70.0, 100.0, 150.0), "gps": (0.03, 0.04, 0.05, 0.06, 0.08, 0.1, 0.15)}
MEASURED = (40_000_000, 40_000_099)  # fresh seeds of the measured limit: 100 flights per size
SPREAD_SEEDS = (40_100_000, 40_100_049)  # fresh fault-free flights the residual's spread is measured on
LATE_S = 1.0  # s: an IR offset reaches the paired window the GPS delay later
T_GRID = np.round(np.arange(0.05, 5.01, 0.05), 2)  # s after the onset


def _quiet(settings: EKFSettings | None = None) -> EKFSettings:
    """Settings that watch but never declare (the thresholds out of reach)."""
    base = settings or EKFSettings()
    from dataclasses import replace

    return replace(base, significance=math.inf, now_h=math.inf, cusum_h=math.inf)


def spread(seeds=range(SPREAD_SEEDS[0], SPREAD_SEEDS[1] + 1)) -> dict:
    """The consistency residual on fault-free flights, after 30 s, while its CUSUM is at zero
    (against the calibration ``held_lag`` samples old): ``sigma`` its standard deviation
    (count), ``model`` the filter's model deviation of it (count, the median), ``a`` the median
    gain (count per rad/s) over the GPS fault's window, over the fault-free flights of ``seeds``."""
    residuals, models, gains = [], [], []
    for seed in seeds:
        flight = fly(seed)
        e = kalman(flight, _quiet())
        held = (e["S_held"] > 0) & (flight["time"] >= SETTLED_S) & (np.maximum(e["held_up"], e["held_down"]) == 0)
        residuals.append(e["nu_held"][held])
        models.append(np.sqrt(e["S_held"][held]))
        window = (flight["time"] >= GPS_FAULT[0]) & (flight["time"] < GPS_FAULT[0] + FAULT_SAMPLES / RATE)
        gains.append(flight["a"][window])
    return {"sigma": float(np.std(np.concatenate(residuals))), "model": float(np.median(np.concatenate(models))),
            "a": float(np.median(np.concatenate(gains)))}


def energy(sensor: str, t: float, settings: EKFSettings | None = None, sigma: float = 1.0) -> float:
    """``E(t)``: the energy (in samples) of a unit offset's signature in the ring ``t`` s after
    its onset, left after the fit of a constant and a drift (the drift's rate with the prior
    ``sd_drift``, against the noise ``sigma``, count). The GPS's is a step; the IR's a ramp over
    the GPS window, reaching the residual :data:`LATE_S` later. Zero once the onset has left the
    ring (the reference has absorbed it). ``sensor`` is ``"ir"`` or ``"gps"``; ``settings`` the
    filter's (:class:`EKFSettings`, its defaults when None)."""
    settings = settings or EKFSettings()
    window = int(RATE * 1.0)
    inside = t - (LATE_S if sensor == "ir" else 0.0)
    n_post = int(round(inside * RATE))
    if n_post <= 0 or n_post >= RING_SIZE:
        return 0.0
    m = np.arange(RING_SIZE)
    onset = RING_SIZE - n_post
    ramp = 1 if sensor == "gps" else window
    f = np.clip((m - onset + 1) / ramp, 0.0, 1.0)
    X = np.column_stack([np.ones(RING_SIZE), m - 0.5 * (RING_SIZE - 1)])
    ridge = np.diag([0.0, (sigma / settings.sd_drift) ** 2 if settings.sd_drift > 0 else 1e12])
    fitted = X @ np.linalg.solve(X.T @ X + ridge, X.T @ f)
    return float(f @ (f - fitted))


def predicted(sensor: str, times=T_GRID, figures: dict | None = None, settings: EKFSettings | None = None) -> dict:
    """The smallest offset found in 99 % of flights within each time of ``times`` (s after the
    onset): in the residual's counts, and in the sensor's units (the GPS's divided by ``|a|``).

    Parameters
    ----------
    sensor : {"ir", "gps"}
        The faulty sensor.
    times : sequence of float
        Seconds after the onset.
    figures : dict, optional
        :func:`spread` (measured if omitted).
    settings : EKFSettings, optional
        The detector's (default settings).

    Returns
    -------
    dict
        ``time_s``, ``glr`` (the limit of the likelihood ratio alone, count), ``cusum`` (the
        CUSUM's floor, count), ``count`` (the larger), ``size`` (in the sensor's units; ``inf``
        where nothing is found in time).
    """
    settings = settings or EKFSettings()
    figures = figures or spread()
    sigma, model = figures["sigma"], figures["model"]
    reach = math.sqrt(2.0 * settings.significance) + Z99
    glr, floor = [], []
    for t in times:
        e = energy(sensor, t, settings, sigma)
        glr.append(sigma * reach / math.sqrt(e) if e > 0 else math.inf)
        # the CUSUM passes its threshold after held_h / (d / model - k) samples of the offset in the residual
        inside = (t - (LATE_S if sensor == "ir" else 0.0)) * RATE
        floor.append(model * (settings.held_k + settings.held_h / inside) if inside > 0 else math.inf)
    count = np.maximum(glr, floor)
    scale = 1.0 if sensor == "ir" else abs(figures["a"])
    return {"time_s": [float(t) for t in times], "glr": [float(v) for v in glr], "cusum": [float(v) for v in floor],
            "count": [float(v) for v in count], "size": [float(v / scale) for v in count]}


def measured(sensor: str, sizes=None, seeds=range(MEASURED[0], MEASURED[1] + 1), jobs: int = 1) -> dict:
    """Per offset size: the fraction of flights where it was declared on the right sensor, and
    the delay within which 99 % of the flights had it so (``inf`` where fewer than 99 % did).

    Parameters
    ----------
    sensor : {"ir", "gps"}
        The faulty sensor.
    sizes : sequence of float, optional
        Offsets (count; rad/s), :data:`SIZES` by default.
    seeds : iterable of int
        Flights per size (fresh: :data:`MEASURED`).
    jobs : int
        Processes.
    """
    out = {}
    for size in sizes or SIZES[sensor]:
        rows = fleet(sensor, size, seeds, jobs=jobs)
        delays = np.array([r["delay_s"] if r["right"] else math.inf for r in rows])
        found = float(np.mean(np.isfinite(delays)))
        t99 = float(np.sort(delays)[math.ceil(0.99 * len(delays)) - 1])
        out[f"{size:g}"] = {"size": size, "flights": len(rows), "declared_right": found, "t99_s": t99,
                            "within": [float(np.mean(delays <= t)) for t in T_GRID]}
    return out


def figure(out, prediction: dict, measurement: dict, figures: dict):
    """``detectability.png``: per sensor, the predicted smallest offset found in 99 % of flights
    within ``T`` s (likelihood ratio, CUSUM floor) against the measured delays by which 99 % of
    the fleets of each size were found; returns its path. ``out`` is the folder, ``prediction``
    and ``measurement`` the per-sensor tables of :func:`limits` (``predicted``, ``measured``),
    ``figures`` the residual's figures of :func:`spread`."""
    import matplotlib.pyplot as plt
    from quadcosim.scenarios.plant import save_figure

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    for ax, sensor, unit in ((axes[0], "ir", "count"), (axes[1], "gps", "rad/s")):
        p, m = prediction[sensor], measurement[sensor]
        scale = 1.0 if sensor == "ir" else abs(figures["a"])
        t = np.array(p["time_s"])
        ax.plot(t, np.array(p["glr"]) / scale, ":", color="tab:blue", lw=1, label="likelihood ratio alone")
        ax.plot(t, np.array(p["cusum"]) / scale, ":", color="tab:orange", lw=1, label="CUSUM trigger alone")
        ax.plot(t, p["size"], "-", color="k", lw=1.5, label="predicted: the larger")
        reached = [(v["t99_s"], v["size"]) for v in m.values() if math.isfinite(v["t99_s"])]
        missed = [v for v in m.values() if not math.isfinite(v["t99_s"])]
        if reached:
            ax.plot(*zip(*reached, strict=True), "o", color="tab:red", label="measured: 99 % declared by then")
        for v in missed:
            ax.plot([t[-1]], [v["size"]], ">", color="tab:red", alpha=0.6)
            ax.annotate(f"{100 * v['declared_right']:.0f} % in all", (t[-1], v["size"]), textcoords="offset points",
                        xytext=(-8, 4), ha="right", fontsize=7, color="tab:red")
        ax.set_yscale("log")
        sizes = [v["size"] for v in m.values()]
        ax.set_ylim(0.7 * min(sizes), 1.5 * max(sizes))
        ax.set_xlim(0, t[-1] + 0.1)
        ax.set_xlabel("time after the offset's onset, T (s)")
        ax.set_ylabel(f"{sensor.upper()} offset ({unit})")
        ax.set_title(f"{sensor.upper()}: smallest offset declared on the right sensor in 99 % of flights within T",
                     fontsize=8)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Infrared fault detection, detectability: residual noise {figures['sigma']:.1f} counts per "
                 f"sample, ring {RING_SIZE} samples, drift prior {EKFSettings().sd_drift:g} count/sample; measured "
                 f"on {next(iter(measurement['ir'].values()))['flights']} fresh flights per size "
                 "(> at the right: never 99 %)", fontsize=8)
    return save_figure(fig, Path(out), "detectability.png")


def limits(jobs: int = 1) -> dict:
    """The predicted and measured limits of both sensors, and the residual's figures; the fleets
    flown on ``jobs`` processes."""
    figures = spread()
    return {"figures": figures, "predicted": {s: predicted(s, figures=figures) for s in ("ir", "gps")},
            "measured": {s: measured(s, jobs=jobs) for s in ("ir", "gps")}}


def explain(seed: int = 1) -> dict:
    """Why the filter's own innovations miss small offsets, on one flight, from the difference
    with the same flight without the fault (same noise), flown with ``seed``.

    Returns
    -------
    dict
        ``fault_free``: the spread of the normalised GPS and paired-IR innovations after 30 s, the
        largest drift rate of the true ``b`` (count/s); per fault (``ir_100``, ``gps_0.2``): its
        largest half-second mean on each normalised innovation, and the shift of ``b`` (count)
        and ``a`` (count per rad/s) 3 s after it reached the filter.
    """
    innovations = {"gps": ("nu_gps", "S_gps"), "pair": ("nu_ir", "S_ir")}
    clean_flight = fly(seed)
    clean = kalman(clean_flight, _quiet())
    settled = clean_flight["time"] >= SETTLED_S
    z_clean = {name: _normalised(clean, *keys) for name, keys in innovations.items()}
    out = {"fault_free": {name: float(np.nanstd(z[settled])) for name, z in z_clean.items()}}
    out["fault_free"]["b_rate_max"] = float(np.abs(np.diff(clean_flight["b"])).max() * RATE)
    for sensor, size in FAULTS:
        estimate = kalman(fly(seed, sensor, size), _quiet())
        onset = IR_FAULT[0] if sensor == "ir" else GPS_FAULT[0]
        reached = int(round(onset * RATE)) + (int(RATE) if sensor == "ir" else 0)  # the IR: a GPS delay later
        span = slice(reached, reached + int(SIGNATURE_S * RATE))
        row = {}
        for name, keys in innovations.items():
            signature = (_normalised(estimate, *keys) - z_clean[name])[span]
            row[name] = float(max(np.nanmean(signature[i:i + BIN]) for i in range(0, len(signature), BIN)))
        later = reached + int(ABSORBED_S * RATE)
        row["b_shift"] = float(estimate["b"][later] - clean["b"][later])
        row["a_shift"] = float(estimate["a"][later] - clean["a"][later])
        out[f"{sensor}_{size:g}"] = row
    return out


def _normalised(estimate: dict, nu: str, S: str) -> np.ndarray:
    computed = estimate[S] > 0.0
    return np.where(computed, estimate[nu] / np.sqrt(np.where(computed, estimate[S], 1.0)), np.nan)


def ramped(sensor: str, size: float, ramp_s: float, seed: int = 1) -> dict:
    """A fault that comes in linearly over ``ramp_s`` from the slides' onset, stays for the
    slides' 2000 samples, then goes at once: an offset of ``size`` (count for the IR, rad/s for
    the GPS) on ``sensor`` (``"ir"`` or ``"gps"``), on the flight of ``seed``.

    Returns
    -------
    dict
        ``declared_after_s`` (s after the onset, None if not declared while it lasted) and
        ``attributed`` (the sensor declared then); ``end_declared`` (a fault declared when it
        went, the filter having absorbed it) and ``end_cleared`` (that declaration ended before
        the flight's end).
    """
    flight = fly(seed)
    onset = IR_FAULT[0] if sensor == "ir" else GPS_FAULT[0]
    end = onset + FAULT_SAMPLES / RATE
    t = flight["time"]
    shape = np.clip((t - onset) / ramp_s, 0.0, 1.0) * (t < end - 1e-9)
    flight["ir" if sensor == "ir" else "gps_turn_rate"] += size * shape
    estimate = kalman(flight)
    out = {"declared_after_s": None, "attributed": None, "end_declared": False, "end_cleared": False}
    for name in ("ir", "gps"):
        for start, stop in episodes(estimate[f"{name}_fault"], t):
            if onset <= start < end and (out["declared_after_s"] is None or start - onset < out["declared_after_s"]):
                out["declared_after_s"], out["attributed"] = start - onset, name
            elif start >= end:
                out["end_declared"], out["end_cleared"] = True, stop is not None
    return out


def calibrate(clean=(1, 9000), faults=(1, 300)) -> dict:
    """What the detector's significance was set on, on tuning seeds only: the largest
    likelihood ratio its attribution saw on the fault-free flights of ``clean``, and the
    smallest largest one in the first 5 s of a GPS +0.1 rad/s and an IR +100 counts offset on
    the flights of ``faults`` (the detector watching, never declaring)."""
    assert clean[1] <= TUNING[0][1] and faults[1] <= TUNING[0][1], "calibrate on tuning seeds only"
    watching = EKFSettings(significance=math.inf)
    null = max((float(kalman(fly(seed), watching)["run_peak"].max()), seed) for seed in range(clean[0], clean[1] + 1))
    out = {"fault_free_max": null[0], "fault_free_max_seed": null[1], "flights": clean[1] - clean[0] + 1}
    for sensor, size in (("gps", 0.1), ("ir", 100.0)):
        onset = int(round((IR_FAULT[0] if sensor == "ir" else GPS_FAULT[0]) * RATE))
        peaks = [(float(kalman(fly(seed, sensor, size), watching)["run_peak"][onset:onset + 100].max()), seed)
                 for seed in range(faults[0], faults[1] + 1)]
        out[f"{sensor}_{size:g}_min"], out[f"{sensor}_{size:g}_min_seed"] = min(peaks)
    return out


def main(argv=None) -> int:
    """``python -m quadcosim.studies.ir_detectability [--explain | --ramps | --calibrate] [--out DIR] [--jobs N]``.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's if None).
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--explain", action="store_true", help="why the filter's own innovations miss small offsets")
    parser.add_argument("--ramps", action="store_true", help="offsets ramped in over 2 to 60 s")
    parser.add_argument("--calibrate", action="store_true",
                        help="what the significance was set on (tuning seeds; several minutes)")
    parser.add_argument("--out", default="results/ir-detectability", help="folder of detectability.png")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    args = parser.parse_args(argv)
    if args.explain:
        e = explain()
        free = e["fault_free"]
        print(f"fault-free, seed 1, after {SETTLED_S:g} s: normalised innovation std GPS {free['gps']:.2f}, paired IR "
              f"{free['pair']:.2f}; true b drifts at most {free['b_rate_max']:.1f} count/s")
        for sensor, size in FAULTS:
            row = e[f"{sensor}_{size:g}"]
            print(f"{sensor} +{size:g}: largest half-second mean in normalised units: GPS innovation "
                  f"{row['gps']:.2f}, paired IR {row['pair']:.2f}; {ABSORBED_S:g} s after it reached the filter b has "
                  f"moved {row['b_shift']:+.1f} counts and a {row['a_shift']:+.1f} count per rad/s")
        return 0
    if args.ramps:
        for sensor, size in RAMPED:
            for ramp_s in RAMPS_S:
                r = ramped(sensor, size, ramp_s)
                declared = ("not declared while it lasted" if r["declared_after_s"] is None else
                            f"declared after {r['declared_after_s']:.2f} s on {r['attributed']}")
                gone = ("its end declared as a fault, " + ("ended" if r["end_cleared"] else "never ended")
                        if r["end_declared"] else "nothing declared at its end")
                print(f"{sensor} +{size:g} in over {ramp_s:g} s: {declared}; {gone}")
        return 0
    if args.calibrate:
        c = calibrate()
        print(f"tuning seeds: largest attribution log-likelihood on the fault-free flights of seeds 1 to "
              f"{c['flights']}: {c['fault_free_max']:.1f} (seed {c['fault_free_max_seed']}); smallest largest in "
              f"the first 5 s of a GPS +0.1 rad/s offset: {c['gps_0.1_min']:.1f} (seed {c['gps_0.1_min_seed']}), "
              f"of an IR +100 counts offset: {c['ir_100_min']:.1f} (seed {c['ir_100_min_seed']})")
        return 0
    result = limits(args.jobs)
    f = result["figures"]
    print(f"consistency residual on {SPREAD_SEEDS[1] - SPREAD_SEEDS[0] + 1} fresh fault-free flights: noise "
          f"{f['sigma']:.2f} counts per sample (the filter's model {f['model']:.1f}); |a| {abs(f['a']):.0f} count per "
          "rad/s in the GPS fault's window")
    for sensor, unit in (("ir", "counts"), ("gps", "rad/s")):
        p = result["predicted"][sensor]
        best = min(p["size"])
        at = p["time_s"][int(np.argmin(p["size"]))]
        print(f"{sensor}: predicted smallest offset found in 99 % of flights {best:.3g} {unit} (within {at:.2f} s); "
              + "; ".join(f"within {t:g} s {p['size'][int(np.argmin(np.abs(np.array(p['time_s']) - t)))]:.3g}"
                          for t in (1.0, 2.0, 3.0)))
        for v in result["measured"][sensor].values():
            t99 = "never in 99 %" if not math.isfinite(v["t99_s"]) else f"99 % within {v['t99_s']:.2f} s"
            print(f"  measured {sensor} +{v['size']:g} {unit}: declared on the right sensor in "
                  f"{100 * v['declared_right']:.1f} % of {v['flights']} flights, {t99}")
    path = figure(args.out, result["predicted"], result["measured"], f)
    print(f"figure: {path}")
    return 0


if __name__ == "__main__":  # the same as quadcosim study ir-detectability
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study ir-detectability").run, main)
