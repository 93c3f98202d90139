"""How often the infrared calibration's Kalman filter finds a fault, on the right sensor, and cries wolf.

Judged on fleets of flights it was never tuned on.

``python -m quadcosim.studies.ir_detection`` flies the ``ir-calibration`` flight (8000 samples at
20 Hz, drift on) in batch (:mod:`quadcosim.studies.ir_fleet`, the InfraredSensor's arithmetic on
arrays), one fault at a time at the slides' onsets and length (IR from 60 s, GPS from 280 s,
2000 samples), over a fleet of seeds per fault kind and size, and fault-free flights over
another; it prints for each case the rates with their 95 % intervals (Clopper-Pearson for a
proportion, Garwood's exact Poisson interval for false alarms per flight-hour):

- declared: a fault declared, on either sensor, while the offset lasts;
- on the right sensor: the first such declaration names the faulty sensor;
- the delay of that declaration (percentiles over the flights where it came);
- ended early: the fault's declaration ended while the offset still lasted;
- left standing: a fault still declared at the flight's end (the GPS offset ends 20 s before
  it, the IR's 240 s before);
- cleared: how long after the offset's end no fault was declared any more;
- other declarations: faults declared outside the offset and the 5 s after it;
- fault-free flights: faults declared, and per flight-hour.

The seeds: :data:`TUNING` are those the detector's settings were chosen on (and every design
was looked at on); :data:`FRESH` (per fault case) and :data:`FRESH_CLEAN` (fault-free) are
disjoint from them and were flown only to score the design once frozen.

``--ablation`` scores each design choice of :mod:`quadcosim.calibration.infrared.detection` by flying
fleets of tuning seeds (:data:`ABLATION_FAULTS`, :data:`ABLATION_CLEAN`: an ablation is looked
at) with it undone (:data:`ABLATIONS`), and the earlier design as a whole.
``--quick`` is the small fresh set CI re-checks (:data:`QUICK`). ``--figure DIR`` draws a GPS
offset missed from its start and its end (:func:`missed_figure`); ``--plateau`` undoes each part
of the test that takes such an end for a return (:func:`plateau_ablation`, tuning seeds).
"""

from __future__ import annotations

import argparse
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from quadcosim.calibration.infrared import EKFSettings, Estimator
from quadcosim.scenarios.ir_calibration import RATE, episodes, fault_windows

SAMPLES = 8000
#: seeds the settings were chosen on or a design looked at: the first fault-free 9999 and fault seeds 1-300, then
#: fleets flown to judge an earlier design and looked at before its last change (so tuning seeds now)
TUNING = ((1, 9999), (1_000_000, 1_000_999), (2_000_000, 2_008_999), (3_000_000, 3_000_039), (3_100_000, 3_100_199),
          (3_200_000, 3_200_199), (4_000_000, 4_000_199), (4_100_000, 4_100_049), (5_000_000, 5_000_010),
          (10_000_000, 10_000_999), (20_000_000, 20_004_499), (60_000_000, 60_000_999), (61_000_000, 61_004_499))
FRESH = (70_000_000, 70_000_999)  # per fault case: 1000 flights, flown once, after the design was frozen
FRESH_CLEAN = (71_000_000, 71_004_499)  # fault-free: 4500 flights, 500 flight-hours
QUICK = {"faults": (30_000_000, 30_000_039), "clean": (30_100_000, 30_100_199)}  # CI's fresh subset
CASES = (("ir", 100.0), ("gps", 0.1))  # the smallest offsets the detector is designed for
LARGER = (("ir", 200.0), ("ir", 400.0), ("ir", 1200.0), ("gps", 0.2), ("gps", 0.3), ("gps", 1.5))
BELOW = (("ir", 50.0), ("gps", 0.05))  # below the sizes the detector is designed for
UNITS = {"ir": "count", "gps": "rad/s"}
AFTER_S = 5.0  # s after an offset's end within which a declaration is "at its end"
CONFIDENCE = 0.95
EARLIER = {"cusum_h": 10.0, "now_k": 3.5, "freeze": False, "turn": "mean", "raw": False, "end": "innovation",
           "sd_drift": 0.0, "significance": 25.0}
#: each design choice undone alone (label -> settings), and the earlier design whole
ABLATIONS = {
    "designed": {},
    "held_not_frozen": {"freeze": False},
    "held_40_not_frozen": {"freeze": False, "held_lag": 40},
    "turn_mean": {"turn": "mean"},
    "turn_healthy": {"turn": "healthy"},
    "no_drift": {"sd_drift": 0.0},
    "no_drift_significance_25": {"sd_drift": 0.0, "significance": 25.0},
    "pair_not_raw": {"raw": False},
    "end_on_innovation": {"end": "innovation"},
    "innovation_cusums": {"cusum_h": 10.0},
    "present_ir_k_3_5": {"now_k": 3.5},
    "present_ir_off": {"now_h": math.inf},
    "decisive_100": {"decisive": 100.0},
    "alt_level_10": {"alt_level": 10.0},
    "alt_not_ended": {"alt_ended": False},
    "alt_not_innovation": {"alt_innovation": False},
    "alt_restart": {"alt_restart": True},
    "alt_moved_25": {"alt_moved": 25.0},
    "alt_moved_25_fraction_0_25": {"alt_moved": 25.0, "alt_fraction": 0.25},
    "plateau_off": {"plateau": 0},
    "plateau_300": {"plateau": 300},
    "plateau_1200": {"plateau": 1200},
    "plateau_match_0_25": {"plateau_match": 0.25},
    "plateau_flat_uncapped": {"plateau_flat_max": math.inf},
    "plateau_unsettled_kept": {"plateau_settled": math.inf},
    "return_hold_off": {"return_hold": False},
    "earlier_design": EARLIER,
}
ABLATION_CASES = (("ir", 100.0), ("gps", 0.1), ("ir", 50.0), ("ir", 1200.0))
ABLATION_FAULTS = (10_000_000, 10_000_999)  # per fault case of the ablation: tuning seeds, never the fresh ones
ABLATION_CLEAN = (2_000_000, 2_001_999)  # fault-free flights of the ablation: 2000 tuning ones


def kalman(flight: dict, settings: EKFSettings | None = None) -> dict:
    """The gated Kalman filter (default settings unless ``settings``) over ``flight``."""
    use = flight["gps_valid"] > 0.5
    return Estimator("kalman", settings or EKFSettings()).run(flight["ir"], flight["gps_turn_rate"], use)


def fly(seed: int, sensor: str = "none", size: float = 0.0) -> dict:
    """The ``ir-calibration`` flight of ``seed`` with one fault of ``size`` on ``sensor``
    (``"ir"``, count; ``"gps"``, rad/s; ``"none"``), in batch."""
    from quadcosim.studies.ir_fleet import fly as batch

    return batch(seed, SAMPLES, faults=sensor, ir_fault=size, gps_fault=size)


def outcome(estimate: dict, time: np.ndarray, sensor: str, size: float) -> dict:
    """What the filter declared on one flight (see the module): for a fault-free flight
    (``sensor`` ``"none"``) the ``declarations``; else ``declared``, ``right``, ``delay_s``,
    ``ended_early``, ``standing``, ``cleared_s`` (``inf`` when left standing), ``at_end`` and
    ``other`` declarations. ``estimate`` is the filter's output (:func:`kalman`), ``time`` its
    sample times (s), ``size`` the offset (count for the IR, rad/s for the GPS)."""
    runs = {name: episodes(estimate[f"{name}_fault"], time) for name in ("ir", "gps")}
    standing = any(estimate[f"{name}_fault"][-1] > 0.5 for name in runs)
    if sensor == "none":
        return {"declarations": sum(len(r) for r in runs.values()), "standing": standing}
    ((_, onset, end, _),) = fault_windows(sensor, size, size)
    inside = sorted((start, name) for name, r in runs.items() for start, _ in r if onset - 1e-9 <= start < end)
    right = [(start, stop) for start, stop in runs[sensor] if onset - 1e-9 <= start < end]
    stops = [stop for r in runs.values() for start, stop in r
             if start < end + AFTER_S and (stop is None or stop >= end)]
    return {"declared": bool(inside), "right": bool(inside) and inside[0][1] == sensor,
            "delay_s": right[0][0] - onset if right else math.nan,
            "ended_early": any(stop is not None and stop < end - 1e-9 for _, stop in right),
            "standing": standing,
            "cleared_s": 0.0 if not stops else (math.inf if None in stops else max(stops) - end),
            "at_end": sum(1 for r in runs.values() for start, _ in r if end - 1e-9 <= start < end + AFTER_S),
            "other": sum(1 for r in runs.values() for start, _ in r if not onset - 1e-9 <= start < end + AFTER_S)}


def _fly_seeds(job) -> list[dict]:
    sensor, size, seeds, overrides = job
    settings = EKFSettings(**overrides)
    rows = []
    for seed in seeds:
        flight = fly(seed, sensor, size)
        rows.append(outcome(kalman(flight, settings), flight["time"], sensor, size) | {"seed": seed})
    return rows


def fleet(sensor: str, size: float, seeds, overrides: dict | None = None, jobs: int = 1) -> list[dict]:
    """:func:`outcome` of every flight of ``seeds`` (one fault of ``size`` on ``sensor``, or
    ``"none"``), the filter's settings changed by ``overrides``; over ``jobs`` processes."""
    seeds = list(seeds)
    work = [(sensor, size, seeds[i::jobs], dict(overrides or {})) for i in range(jobs)]
    if jobs == 1:
        return _fly_seeds(work[0])
    with ProcessPoolExecutor(jobs) as pool:
        rows = [row for part in pool.map(_fly_seeds, work) for row in part]
    return sorted(rows, key=lambda row: row["seed"])


def proportion(k: int, n: int) -> dict:
    """``k`` of ``n`` as a rate with its Clopper-Pearson 95 % interval."""
    from scipy.stats import binomtest

    if n == 0:
        return {"k": 0, "n": 0, "rate": math.nan, "low": 0.0, "high": 1.0}
    interval = binomtest(k, n).proportion_ci(CONFIDENCE, method="exact")
    return {"k": int(k), "n": int(n), "rate": k / n, "low": float(interval.low), "high": float(interval.high)}


def per_hour(k: int, hours: float) -> dict:
    """``k`` events in ``hours`` as a rate per hour with Garwood's exact 95 % Poisson interval."""
    from scipy.stats import chi2

    tail = 0.5 * (1.0 - CONFIDENCE)
    low = 0.0 if k == 0 else chi2.ppf(tail, 2 * k) / 2.0
    high = chi2.ppf(1.0 - tail, 2 * k + 2) / 2.0
    return {"k": int(k), "hours": hours, "rate": k / hours, "low": low / hours, "high": high / hours}


def summary(rows: list[dict], sensor: str) -> dict:
    """The rates of a fleet's ``rows`` (:func:`fleet`) with their 95 % intervals; ``sensor`` is
    the faulty one (``"ir"``, ``"gps"``) or ``"none"`` for fault-free flights."""
    n = len(rows)
    hours = n * SAMPLES / RATE / 3600.0
    if sensor == "none":
        declared = sum(r["declarations"] for r in rows)
        return {"flights": n, "hours": hours, "false_alarms": per_hour(declared, hours),
                "flights_with_one": [r["seed"] for r in rows if r["declarations"]],
                "standing": proportion(sum(r["standing"] for r in rows), n)}
    delays = np.array([r["delay_s"] for r in rows if r["right"]])
    cleared = np.array([r["cleared_s"] for r in rows if r["declared"]])
    return {"flights": n, "hours": hours,
            "declared": proportion(sum(r["declared"] for r in rows), n),
            "right": proportion(sum(r["right"] for r in rows), n),
            "ended_early": proportion(sum(r["ended_early"] for r in rows), n),
            "standing": proportion(sum(r["standing"] for r in rows), n),
            "delay_s": {f"p{q}": float(np.percentile(delays, q)) if len(delays) else math.nan for q in (50, 90, 99)},
            "cleared_s": {f"p{q}": float(np.percentile(cleared, q)) if len(cleared) else math.nan for q in (50, 99)},
            "cleared_max_s": float(cleared.max()) if len(cleared) else math.nan,
            "at_end": sum(r["at_end"] for r in rows), "other": sum(r["other"] for r in rows),
            "missed": [r["seed"] for r in rows if not r["right"]],
            "standing_seeds": [r["seed"] for r in rows if r["standing"]]}


def study(cases=CASES, fresh=FRESH, clean=FRESH_CLEAN, overrides: dict | None = None, jobs: int = 1,
          echo: bool = True) -> dict:
    """The detection table: :func:`summary` of each fault case over the seeds ``fresh``
    (first, last) and of the fault-free flights over ``clean``, the filter's settings changed by
    ``overrides``, for each ``(sensor, size)`` of ``cases``; the fleets flown on ``jobs``
    processes, each line printed as it comes when ``echo``."""
    out = {"cases": {}}
    for sensor, size in cases:
        out["cases"][f"{sensor}_{size:g}"] = s = summary(fleet(sensor, size, range(fresh[0], fresh[1] + 1),
                                                               overrides, jobs), sensor)
        if echo:
            print(case_line(sensor, size, s), flush=True)
    out["clean"] = c = summary(fleet("none", 0.0, range(clean[0], clean[1] + 1), overrides, jobs), "none")
    if echo:
        print(clean_line(c, clean), flush=True)
    return out


def _rate(p: dict) -> str:
    return f"{p['k']}/{p['n']} = {100 * p['rate']:.2f} % [{100 * p['low']:.2f}, {100 * p['high']:.2f}]"


def case_line(sensor: str, size: float, s: dict) -> str:
    """One case of the table, as printed: the summary ``s`` of the offset ``size`` on ``sensor``."""
    d, c = s["delay_s"], s["cleared_s"]
    return (f"{sensor} +{size:g} {UNITS[sensor]}: declared {_rate(s['declared'])}; on the right sensor "
            f"{_rate(s['right'])}; delay p50 {d['p50']:.2f} p90 {d['p90']:.2f} p99 {d['p99']:.2f} s; ended early "
            f"{_rate(s['ended_early'])}; left standing {_rate(s['standing'])}; cleared after its end p50 "
            f"{c['p50']:.2f} p99 {c['p99']:.2f} s; declared at its end {s['at_end']}; other declarations "
            f"{s['other']}")


def clean_line(c: dict, seeds) -> str:
    """The fault-free flights' summary ``c`` over the seeds ``seeds`` (first, last), as printed."""
    fa = c["false_alarms"]
    return (f"fault-free, seeds {seeds[0]} to {seeds[1]}: {c['flights']} flights, {c['hours']:.1f} flight-hours, "
            f"{fa['k']} faults declared = {fa['rate']:.4f} per flight-hour [{fa['low']:.4f}, {fa['high']:.4f}]"
            f" = one per {_hours_per(fa['rate'])} flight-hours"
            + (f" (seeds {c['flights_with_one']})" if fa["k"] else "")
            + f"; left standing at the flight's end {c['standing']['k']}")


def _hours_per(rate: float) -> str:
    return "inf" if rate == 0 else f"{1.0 / rate:.0f}"


def ablation(variants=ABLATIONS, cases=ABLATION_CASES, fresh=ABLATION_FAULTS, clean=ABLATION_CLEAN, jobs: int = 1,
             echo: bool = True) -> dict:
    """Each design choice undone alone (:data:`ABLATIONS`), on the fleets of ``cases`` over the
    seeds ``fresh`` (tuning seeds by default: an ablation is looked at) and the fault-free
    flights of ``clean``: label -> :func:`study`. ``variants`` maps a label to the settings it
    overrides; ``jobs`` and ``echo`` as for :func:`study`."""
    out = {}
    for label, overrides in variants.items():
        if echo:
            print(f"[{label}] {overrides or 'the design as shipped'}", flush=True)
        out[label] = study(cases, fresh, clean, overrides, jobs, echo)
    return out


def main(argv=None) -> int:
    """``python -m quadcosim.studies.ir_detection [--fresh A:B] [--clean A:B] [--ablation] [--quick] [--plateau]
    [--figure DIR]
    [--jobs N] [--out FILE]``.

    Parameters
    ----------
    argv : list of str, optional
        The arguments (the process's if None).
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fresh", help=f"seeds of each fault case, FIRST:LAST (default {FRESH[0]}:{FRESH[1]}; "
                                        f"with --ablation, tuning seeds {ABLATION_FAULTS[0]}:{ABLATION_FAULTS[1]})")
    parser.add_argument("--clean", help=f"seeds of the fault-free flights, FIRST:LAST (default {FRESH_CLEAN[0]}:"
                                        f"{FRESH_CLEAN[1]}; with --ablation {ABLATION_CLEAN[0]}:{ABLATION_CLEAN[1]})")
    parser.add_argument("--ablation", action="store_true", help="each design choice undone (on tuning seeds)")
    parser.add_argument("--quick", action="store_true", help="the small fresh set CI re-checks")
    parser.add_argument("--larger", action="store_true", help="also the larger offsets and those below the design")
    parser.add_argument("--plateau", action="store_true", help="the plateau test's parts undone (tuning seeds)")
    parser.add_argument("--figure", metavar="DIR", help="draw missed_offset.png (a missed GPS offset's end) into DIR")
    parser.add_argument("--jobs", type=int, default=1, help="processes (default 1)")
    parser.add_argument("--out", help="write the results to this JSON file")
    args = parser.parse_args(argv)
    faults, free = (ABLATION_FAULTS, ABLATION_CLEAN) if args.ablation else (FRESH, FRESH_CLEAN)
    try:
        fresh = tuple(int(x) for x in args.fresh.split(":")) if args.fresh else faults
        clean = tuple(int(x) for x in args.clean.split(":")) if args.clean else free
        if len(fresh) != 2 or len(clean) != 2:
            raise ValueError
    except ValueError:
        parser.error("write the seeds as FIRST:LAST, e.g. 1000000:1000999")
    if args.jobs < 1:
        parser.error(f"--jobs {args.jobs}: give at least one process")
    if args.figure:
        print(f"figure: {missed_figure(args.figure)}")
        return 0
    if args.plateau:
        result = plateau_ablation(jobs=args.jobs)
        for label, cases in result.items():
            for case, s in cases.items():
                print(f"[{label}] {case}: on the right sensor {_rate(s['right'])}; left standing "
                      f"{_rate(s['standing'])}", flush=True)
    elif args.quick:
        result = quick(echo=True)
    elif args.ablation:
        last = min(clean[1], clean[0] + ABLATION_CLEAN[1] - ABLATION_CLEAN[0])
        result = ablation(fresh=fresh, clean=(clean[0], last), jobs=args.jobs)
    else:
        tuning = ", ".join(f"{a}-{b}" for a, b in TUNING)
        print(f"tuning seeds {tuning}; fresh seeds {fresh[0]} to {fresh[1]} per fault case, "
              f"{clean[0]} to {clean[1]} fault-free", flush=True)
        result = study(CASES + (LARGER + BELOW if args.larger else ()), fresh=fresh, clean=clean, jobs=args.jobs)
    if args.out:
        from quadcosim.infra.files import write_json

        write_json(args.out, result)
    return 0


def quick(echo: bool = False) -> dict:
    """The small fresh set CI re-checks (:data:`QUICK`): IR +100 counts and GPS +0.1 rad/s over
    40 seeds each, and 200 fault-free flights; printed as they come when ``echo``."""
    return study((("ir", 100.0), ("gps", 0.1)), QUICK["faults"], QUICK["clean"], echo=echo)


#: the plateau test's parts undone alone (label -> settings), each on the cases it bears on
PLATEAU_ABLATION = {
    "designed": ({}, (("gps", 0.1), ("ir", 100.0), ("gps", 0.3))),
    "plateau_off": ({"plateau": 0}, (("gps", 0.1),)),
    "return_hold_off": ({"return_hold": False}, (("ir", 100.0),)),
    "flat_uncapped": ({"plateau_flat_max": math.inf}, (("gps", 0.3),)),
    "unsettled_kept": ({"plateau_flat_max": math.inf, "plateau_settled": math.inf}, (("ir", 100.0), ("gps", 0.3))),
    "match_0_25": ({"plateau_match": 0.25}, (("gps", 0.1),)),
}
PLATEAU_SEEDS = ((10_000_000, 10_000_999), (60_000_000, 60_000_999))  # tuning: the ablation is looked at


def plateau_ablation(variants=PLATEAU_ABLATION, seeds=PLATEAU_SEEDS, jobs: int = 1) -> dict:
    """The plateau test's parts undone alone, on the tuning fleets ``seeds`` ((first, last)
    each) pooled: label -> case -> :func:`summary`. ``variants`` maps a label to the settings it
    overrides and the ``(sensor, size)`` cases it is flown on; ``jobs`` processes. A return test
    only ever withdraws a declaration, so fault-free flights, which declare none, cannot move."""
    out = {}
    for label, (overrides, cases) in variants.items():
        out[label] = {}
        for sensor, size in cases:
            rows = [row for first, last in seeds
                    for row in fleet(sensor, size, range(first, last + 1), overrides, jobs)]
            out[label][f"{sensor}_{size:g}"] = summary(rows, sensor)
    return out


def missed_figure(out, seed: int = 60_000_178, size: float = 0.1):
    """``missed_offset.png``: a GPS offset of ``size`` (rad/s) missed from its start on the flight
    of ``seed`` (tuning), with the plateau test and without (``plateau=0``): the filter's ``b``
    against the true one (count), and the GPS fault it declares; returns its path. ``out`` is
    the folder."""
    import matplotlib.pyplot as plt
    from quadcosim.scenarios.plant import save_figure

    flight = fly(seed, "gps", size)
    time = flight["time"]
    ((_, onset, end, _),) = fault_windows("gps", size, size)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 5), sharex=True, height_ratios=(3, 1))
    for label, overrides, style in (("plateau test (the design)", {}, "-"), ("plateau=0", {"plateau": 0}, "--")):
        estimate = kalman(flight, EKFSettings(**overrides))
        top.plot(time, estimate["b"] - flight["b"], style, lw=1, label=f"filter's b - true b, {label}")
        bottom.plot(time, estimate["gps_fault"], style, lw=1, label=label)
    for ax in (top, bottom):
        ax.axvspan(onset, end, color="tab:red", alpha=0.1, label="GPS offset" if ax is top else None)
        ax.grid(alpha=0.3)
    top.axhline(-EKFSettings().a0 * size, color="k", lw=0.6, ls=":", label="the offset in counts, -a0 x offset")
    top.set_ylabel("count")
    top.set_ylim(-40, 80)
    top.legend(fontsize=7, loc="upper left")
    bottom.set_ylabel("GPS fault declared")
    bottom.set_xlabel("time (s)")
    bottom.legend(fontsize=7, loc="upper left")
    top.set_title(f"GPS +{size:g} rad/s from {onset:g} s missed from its start (seed {seed}): the filter absorbs it; "
                  "its end is a return, not a new fault", fontsize=8)
    return save_figure(fig, Path(out), "missed_offset.png")


def one_fault(sensor: str, size: float, seed: int = 1, settings: EKFSettings | None = None) -> dict:
    """The declaration of one fault of ``size`` on ``sensor`` in the flight of ``seed``
    (:func:`outcome`, and the ``turn_rate_error_std_deg_s`` after 30 s), under the filter's
    ``settings`` (:class:`EKFSettings`, its defaults when None)."""
    flight = fly(seed, sensor, size)
    estimate = kalman(flight, settings)
    settled = flight["time"] >= 30.0
    return outcome(estimate, flight["time"], sensor, size) | {
        "turn_rate_error_std_deg_s": float(np.degrees(estimate["turn_rate"] - flight["r"])[settled].std())}


__all__ = ["ABLATIONS", "CASES", "FRESH", "FRESH_CLEAN", "QUICK", "TUNING", "ablation", "fleet", "one_fault",
           "missed_figure", "outcome", "per_hour", "plateau_ablation", "proportion", "quick", "study", "summary"]

if __name__ == "__main__":  # the same as quadcosim study ir-detection
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study ir-detection").run, main)
