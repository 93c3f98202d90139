"""Findings of the in-flight infrared calibration: the estimators' errors, the fault detection, the cost.

``quadcosim run ir-calibration`` in five cases, ``python -m scenarios.ir_detection`` (a fault of
each size, then fault-free flights of seeds 1 to 100, and of seeds 201 to 300),
``python -m scenarios.ir_detectability`` (the small faults in the filter's innovations, and what
the consistency detector was set on) and ``quadcosim bench infrared`` (the operation count; its
timings are not findings). The quick subset: the two faults the
acceptance names (IR +400 counts, GPS +0.3 rad/s).
"""

from __future__ import annotations

from scenarios.findings import command, finding

RUN = "quadcosim run ir-calibration"
DETECTION = "python -m scenarios.ir_detection"
FRESH = (201, 300)  # fault-free flights no setting was chosen on, nor any design looked at
DETECTABILITY = "python -m scenarios.ir_detectability"
BENCH = "quadcosim bench infrared"
CASES = {"drift": {}, "no_drift": {"drift": False}, "no_gps_resetting": {"gps_resetting": False},
         "faults": {"faults": "both"}, "faults_ungated": {"faults": "both", "gating": False}}
METHODS = {"kalman": "Kalman", "regression": "regression", "rls": "RLS"}


def _command(settings: dict) -> str:
    return command(RUN, settings)


def errors() -> list[dict]:
    """The flight's statistics, the turn-rate error of each estimator in each case, the slides'
    faults declared and ended."""
    import scenarios

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


def detection(sizes=None) -> list[dict]:
    """Declaration delay and end of one fault of each size (``sizes``: ``(sensor, size)`` pairs,
    default every size of :mod:`scenarios.ir_detection`); a fault never declared gives no finding
    (the README says "never")."""
    from scenarios import ir_detection

    sizes = sizes or [("ir", s) for s in ir_detection.IR_SIZES] + [("gps", s) for s in ir_detection.GPS_SIZES]
    found = []
    for sensor, size in sizes:
        row = ir_detection.one_fault(sensor, size)
        label = f"infrared.detection.{sensor}_{size:g}".replace(".", "_").replace("infrared_detection_",
                                                                                "infrared.detection.")
        if row["declared_after_s"] is not None and row["attributed"] == sensor:
            found += [finding(f"{label}.declared_after_s", row["declared_after_s"], "s", DETECTION, 0.005, 2),
                      finding(f"{label}.ended_after_s", row["ended_after_s"], "s", DETECTION, 0.005, 2)]
        found.append(finding(f"{label}.other_declarations", row["false_alarms"], "1", DETECTION, 0.0, 0))
    return found


def fault_free() -> list[dict]:
    """Faults declared over the fault-free flights of seeds 1 to 100, and of seeds 201 to 300."""
    from scenarios import ir_detection

    clean = ir_detection.false_alarms()
    fresh = ir_detection.false_alarms(range(FRESH[0], FRESH[1] + 1))
    fresh_command = f"{DETECTION} --seeds {FRESH[0]}:{FRESH[1]}"
    return [finding("infrared.fault_free.flights", clean["flights"], "1", DETECTION, 0.0, 0),
            finding("infrared.fault_free.false_alarms", clean["false_alarms"], "1", DETECTION, 0.0, 0),
            finding("infrared.fault_free.fresh_flights", fresh["flights"], "1", fresh_command, 0.0, 0),
            finding("infrared.fault_free.fresh_false_alarms", fresh["false_alarms"], "1", fresh_command, 0.0, 0)]


def detectability() -> list[dict]:
    """Why the small faults escaped the CUSUMs on the filter's innovations (seed 1), how slow a
    fault may come before it passes for drift, and what the consistency detector was set on
    (seeds 101 to 200)."""
    from scenarios import ir_detectability

    e = ir_detectability.explain()
    free = e["fault_free"]
    found = [finding(f"infrared.detectability.fault_free.{name}_std", free[name], "1", DETECTABILITY, 0.005, 2)
             for name in ("gps", "pair", "held")]
    found += [finding("infrared.detectability.fault_free.held_std_count", free["held_count"], "count",
                      DETECTABILITY, 0.05, 1),
              finding("infrared.detectability.fault_free.b_rate_max", free["b_rate_max"], "count/s", DETECTABILITY,
                      0.05, 1)]
    for sensor, size in ir_detectability.FAULTS:
        row, label = e[f"{sensor}_{size:g}"], f"infrared.detectability.{sensor}_{size:g}".replace("0.", "0_")
        found += [finding(f"{label}.{name}", row[name], "1", DETECTABILITY, 0.005, 2)
                  for name in ("gps", "pair", "held")]
        found += [finding(f"{label}.b_shift", row["b_shift"], "count", DETECTABILITY, 0.05, 1),
                  finding(f"{label}.a_shift", row["a_shift"], "count s/rad", DETECTABILITY, 0.05, 1),
                  finding(f"{label}.held_count", row["held_count"], "count", DETECTABILITY, 0.05, 1)]
    for sensor, size in ir_detectability.RAMPED:
        for ramp_s in ir_detectability.RAMPS_S:
            r = ir_detectability.ramped(sensor, size, ramp_s)
            if r["declared_after_s"] is not None:  # one never declared gives no finding (the page says so)
                found.append(finding(f"infrared.ramps.{sensor}_{ramp_s:g}s.declared_after_s", r["declared_after_s"],
                                     "s", f"{DETECTABILITY} --ramps", 0.005, 2))
    trained, command = ir_detectability.calibrate(), f"{DETECTABILITY} --calibrate"
    return found + [finding("infrared.training.statistic_max", trained["statistic_max"], "1", command, 0.005, 2),
                    finding("infrared.training.a_error_max", trained["a_error_max"], "count s/rad", command, 0.05, 1),
                    finding("infrared.training.significance_max", trained["significance_max"], "1", command, 0.05, 1)]


def cost() -> list[dict]:
    """Operations per iteration on the fault-free flight (the convention of calibration/infrared/cost.py)."""
    from benchmarks.infrared import measure

    figures = measure(repeats=1)
    return [finding("infrared.cost.gated_mean", figures["kalman"]["operations_mean"], "1", BENCH, 0.05, 1),
            finding("infrared.cost.gated_max", figures["kalman"]["operations_max"], "1", BENCH, 0.0, 0),
            finding("infrared.cost.ungated_mean", figures["kalman_ungated"]["operations_mean"], "1", BENCH, 0.05, 1),
            finding("infrared.cost.joint_mean", figures["kalman_joint"]["operations_mean"], "1", BENCH, 0.05, 1)]


def compute(quick: bool = False) -> list[dict]:
    """Every infrared finding; ``quick``: the declarations of IR +400 and GPS +0.3 (two flights)."""
    if quick:
        return detection([("ir", 400.0), ("gps", 0.3)])
    return errors() + detection() + fault_free() + detectability() + cost()
