"""Findings of the in-flight infrared calibration: the estimators' errors, the fault detection, the cost.

``quadcosim run ir-calibration`` in five cases, ``python -m quadcosim.studies.ir_detection --quick``
(IR +100 counts and GPS +0.1 rad/s over 40 fresh flights each, 200 fresh fault-free flights:
the quick subset CI re-checks), ``python -m quadcosim.studies.ir_detectability --explain`` and
``--ramps`` (the small faults in the filter's innovations, ramped faults), ``python -m
quadcosim.studies.ir_detection --plateau`` (the return test's ablation, tuning seeds), ``python -m
quadcosim.studies.ir_slides`` (the slides' comparison over fresh flights) and ``quadcosim bench
infrared`` (the operation count; its timings are not findings).
"""

from __future__ import annotations

import math

import numpy as np

from findings import command, finding

RUN = "quadcosim run ir-calibration"
DETECTION = "python -m quadcosim.studies.ir_detection"
DETECTABILITY = "python -m quadcosim.studies.ir_detectability"
BENCH = "quadcosim bench infrared"
SLIDES = "python -m quadcosim.studies.ir_slides"
UNIT = {"ir": "count", "gps": "rad/s"}
CASES = {"drift": {}, "no_drift": {"drift": False}, "no_gps_resetting": {"gps_resetting": False},
         "faults": {"faults": "both"}, "faults_ungated": {"faults": "both", "gating": False}}
METHODS = {"kalman": "Kalman", "regression": "regression", "rls": "RLS"}


def _command(settings: dict) -> str:
    return command(RUN, settings)


def errors() -> list[dict]:
    """The flight's statistics, the turn-rate error of each estimator in each case, the slides'
    faults declared and ended."""
    from quadcosim import scenarios

    found = []
    for case, settings in CASES.items():
        m, command = scenarios.run("ir-calibration", settings)[1], _command(settings)
        for method in METHODS:
            for span, key in (("whole", "turn_rate_error_deg_s"), ("after_30_s", "turn_rate_error_after_30_s_deg_s")):
                std = m[key][method]["std"]
                digits = 2 if std < 10 else (1 if std < 100 else 0)
                found.append(finding(f"infrared.{case}.{method}.{span}_deg_s", std, "deg/s", command,
                                     0.5 * 10.0 ** -digits, digits))
        if case == "drift":
            flight = m["flight"]
            found += [finding("infrared.flight.turn_rate_mean_rad_s", flight["turn_rate_mean"], "rad/s", command,
                              5e-4, 3),
                      finding("infrared.flight.turn_rate_std_rad_s", flight["turn_rate_std"], "rad/s", command,
                              5e-4, 3),
                      finding("infrared.flight.ir_mean", flight["ir_mean"], "count", command, 0.5, 0),
                      finding("infrared.flight.ir_std", flight["ir_std"], "count", command, 0.5, 0)]
        if case == "faults":
            for fault in m["faults"]:
                sensor = fault["sensor"]
                found += [finding(f"infrared.slides.{sensor}.declared_after_s", fault["declared_s"] - fault["onset_s"],
                                  "s", command, 0.005, 2),
                          finding(f"infrared.slides.{sensor}.ended_after_s", fault["cleared_s"] - fault["end_s"],
                                  "s", command, 0.005, 2)]
    return found


def _case(label: str, s: dict, command: str) -> list[dict]:
    """The findings of one fault case of :func:`quadcosim.studies.ir_detection.summary`."""
    found = [finding(f"{label}.flights", s["flights"], "1", command, 0.0, 0)]
    for key in ("right", "ended_early", "standing"):
        p = s[key]
        found += [finding(f"{label}.{key}", p["k"], "1", command, 1.0, 0),
                  finding(f"{label}.{key}_pct", 100 * p["rate"], "%", command, 100.0 / p["n"], 2),
                  finding(f"{label}.{key}_low_pct", 100 * p["low"], "%", command, 100.0 / p["n"], 2),
                  finding(f"{label}.{key}_high_pct", 100 * p["high"], "%", command, 100.0 / p["n"], 2)]
    found += [finding(f"{label}.delay_{q}_s", s["delay_s"][q], "s", command, 0.05, 2)
              for q in ("p50", "p90", "p99") if math.isfinite(s["delay_s"][q])]
    found += [finding(f"{label}.at_end", s["at_end"], "1", command, 1.0, 0),
              finding(f"{label}.other", s["other"], "1", command, 1.0, 0)]
    return found


def _clean(label: str, c: dict, command: str) -> list[dict]:
    """The findings of the fault-free fleet of :func:`quadcosim.studies.ir_detection.summary`."""
    fa = c["false_alarms"]
    return [finding(f"{label}.flights", c["flights"], "1", command, 0.0, 0),
            finding(f"{label}.hours", c["hours"], "h", command, 0.05, 1),
            finding(f"{label}.false_alarms", fa["k"], "1", command, 1.0, 0),
            finding(f"{label}.per_hour_high", fa["high"], "1/h", command, 0.0005, 4),
            finding(f"{label}.standing", c["standing"]["k"], "1", command, 1.0, 0)]


def detection_quick() -> list[dict]:
    """CI's re-check: IR +100 counts and GPS +0.1 rad/s over the 40 fresh flights each of
    :data:`quadcosim.studies.ir_detection.QUICK`, and its 200 fault-free flights."""
    from quadcosim.studies import ir_detection

    result, command = ir_detection.quick(), f"{DETECTION} --quick"
    found = []
    for case, s in result["cases"].items():
        found += _case(f"infrared.quick.{case.replace('.', '_')}", s, command)
    return found + _clean("infrared.quick.fault_free", result["clean"], command)


def detection_fresh() -> list[dict]:
    """The judgement of the frozen design: IR +100 counts and GPS +0.1 rad/s over the 1000 fresh
    flights each of :data:`quadcosim.studies.ir_detection.FRESH`, and the 4500 fault-free flights (500
    flight-hours) of :data:`quadcosim.studies.ir_detection.FRESH_CLEAN` (about two minutes on one core)."""
    from quadcosim.studies import ir_detection

    result, command = ir_detection.study(echo=False), DETECTION
    found = []
    for case, s in result["cases"].items():
        found += _case(f"infrared.fresh.{case.replace('.', '_')}", s, command)
    return found + _clean("infrared.fresh.fault_free", result["clean"], command)


def plateau() -> list[dict]:
    """The test that takes the end of an offset missed from its start for a return, each part
    undone alone, on the tuning fleets of :data:`quadcosim.studies.ir_detection.PLATEAU_SEEDS` pooled."""
    from quadcosim.studies import ir_detection

    command, found = f"{DETECTION} --plateau", []
    for label, cases in ir_detection.plateau_ablation().items():
        for case, s in cases.items():
            name = f"infrared.plateau.{label}.{case.replace('.', '_')}"
            found += [finding(f"{name}.flights", s["flights"], "1", command, 0.0, 0),
                      finding(f"{name}.right", s["right"]["k"], "1", command, 1.0, 0),
                      finding(f"{name}.standing", s["standing"]["k"], "1", command, 1.0, 0)]
    return found


def detectability() -> list[dict]:
    """Why the small faults escape the CUSUMs on the filter's own innovations (seed 1), and how
    slow a fault may come before it passes for drift (seed 1)."""
    from quadcosim.studies import ir_detectability

    e = ir_detectability.explain()
    free = e["fault_free"]
    found = [finding(f"infrared.detectability.fault_free.{name}_std", free[name], "1", f"{DETECTABILITY} --explain",
                     0.005, 2) for name in ("gps", "pair")]
    found.append(finding("infrared.detectability.fault_free.b_rate_max", free["b_rate_max"], "count/s",
                         f"{DETECTABILITY} --explain", 0.05, 1))
    for sensor, size in ir_detectability.FAULTS:
        row, label = e[f"{sensor}_{size:g}"], f"infrared.detectability.{sensor}_{size:g}".replace("0.", "0_")
        found += [finding(f"{label}.{name}", row[name], "1", f"{DETECTABILITY} --explain", 0.005, 2)
                  for name in ("gps", "pair")]
        found += [finding(f"{label}.b_shift", row["b_shift"], "count", f"{DETECTABILITY} --explain", 0.05, 1),
                  finding(f"{label}.a_shift", row["a_shift"], "count s/rad", f"{DETECTABILITY} --explain", 0.05, 1)]
    for sensor, size in ir_detectability.RAMPED:
        for ramp_s in ir_detectability.RAMPS_S:
            r = ir_detectability.ramped(sensor, size, ramp_s)
            if r["declared_after_s"] is not None:  # one never declared gives no finding (the page says so)
                found.append(finding(f"infrared.ramps.{sensor}_{ramp_s:g}s.declared_after_s", r["declared_after_s"],
                                     "s", f"{DETECTABILITY} --ramps", 0.005, 2))
    return found


def limits() -> list[dict]:
    """The detectability limit: the residual's noise, the predicted smallest offset found in
    99 % of flights, and per size the measured share declared on the right sensor and the delay
    within which 99 % were (fresh seeds of :data:`quadcosim.studies.ir_detectability.MEASURED`)."""
    from quadcosim.studies import ir_detectability

    result, command = ir_detectability.limits(jobs=2), f"{DETECTABILITY} --jobs 2"
    f = result["figures"]
    found = [finding("infrared.limit.sigma_count", f["sigma"], "count", command, 0.05, 2)]
    for sensor in ("ir", "gps"):
        p = result["predicted"][sensor]
        best = int(np.argmin(p["size"]))
        found += [finding(f"infrared.limit.{sensor}.predicted_size", p["size"][best], UNIT[sensor], command,
                          0.5 if sensor == "ir" else 0.0005, 1 if sensor == "ir" else 4),
                  finding(f"infrared.limit.{sensor}.predicted_within_s", p["time_s"][best], "s", command, 0.05, 2)]
        for key, v in result["measured"][sensor].items():
            label = f"infrared.limit.{sensor}.{key.replace('.', '_')}"
            found.append(finding(f"{label}.declared_right_pct", 100 * v["declared_right"], "%", command, 1.0, 1))
            if math.isfinite(v["t99_s"]):
                found.append(finding(f"{label}.t99_s", v["t99_s"], "s", command, 0.05, 2))
    return found


def comparison() -> list[dict]:
    """The slides' Kalman/regression comparison in their terms (bank angle, degrees) and in turn
    rate, with its ablation, as the mean over the fresh flights of :data:`quadcosim.studies.ir_slides.SEEDS`."""
    from quadcosim.studies import ir_slides

    found = []
    for label, entry in ir_slides.table().items():
        for unit, r in entry.items():
            for name, value in r.items():
                found.append(finding(f"infrared.comparison.{label}.{unit}.{name}", value,
                                     "1" if name.startswith("ratio") else unit.split("_", 1)[1].replace("_", "/"),
                                     SLIDES, 0.005, 2))
    return found


def cost() -> list[dict]:
    """Operations per iteration on the fault-free flight (the convention of calibration/infrared/cost.py)."""
    from quadcosim.benchmarks.infrared import measure

    figures = measure(repeats=1)
    return [finding("infrared.cost.gated_mean", figures["kalman"]["operations_mean"], "1", BENCH, 0.05, 1),
            finding("infrared.cost.gated_max", figures["kalman"]["operations_max"], "1", BENCH, 0.0, 0),
            finding("infrared.cost.ungated_mean", figures["kalman_ungated"]["operations_mean"], "1", BENCH, 0.05, 1),
            finding("infrared.cost.joint_mean", figures["kalman_joint"]["operations_mean"], "1", BENCH, 0.05, 1)]


def compute(quick: bool = False) -> list[dict]:
    """Every infrared finding; ``quick``: the small fresh fleets CI re-checks (:func:`detection_quick`)."""
    if quick:
        return detection_quick()
    return (errors() + detection_quick() + detection_fresh() + plateau() + detectability() + limits() + comparison()
            + cost())
