"""Findings of the magnetometer calibration on the clamped rig (Metge et al.) and of its robustness.

Three ``metge`` runs (default options; ``noise=off``; one battery state per set) and the
robustness study (:mod:`scenarios.metge_robustness`). About 10 minutes; nothing here is quick.
"""

from __future__ import annotations

from scenarios.findings import finding

RUN = "quadcosim run metge"
NOISELESS = f"{RUN} --set noise=off"
ONE_STATE = f"{RUN} --set soc1=0.95 soc2=0.8"
ROBUSTNESS = "python -m scenarios.metge --robustness --out results/robustness"
DEG = 0.005  # deg, tolerance of a re-run (the runs are seeded: a re-run differs by round-off)


def _run(settings: dict) -> dict:
    import scenarios

    return scenarios.run("metge", settings)[1]


def default() -> list[dict]:
    """Table 1, the free set's thirds, the dynamics-aware compensation, the order study."""
    m = _run({})
    t, found = m["table1_deg"], []
    for column in ("set1", "set2", "free"):
        found.append(finding(f"metge.none.{column}_deg", t["none"][column], "deg", RUN, DEG, 1))
    for row in ("calibration1", "calibration2"):
        found.append(finding(f"metge.{row}.free_deg", t[row]["free"], "deg", RUN, DEG, 1))
    low, high = m["sets_calibrated_range_deg"]
    found += [finding("metge.sets_calibrated_min_deg", low, "deg", RUN, DEG, 2),
              finding("metge.sets_calibrated_max_deg", high, "deg", RUN, DEG, 2),
              finding("metge.improvement_min", m["improvement_range"][0], "1", RUN, 0.05, 0),
              finding("metge.improvement_max", m["improvement_range"][1], "1", RUN, 0.05, 0),
              finding("metge.free_eq9_slow_deg", m["free_eq9_slow_fast_deg"]["slow"], "deg", RUN, DEG, 1),
              finding("metge.free_eq9_fast_deg", m["free_eq9_slow_fast_deg"]["fast"], "deg", RUN, DEG, 1),
              finding("metge.free_dynamic_calibration1_deg", m["free_set_dynamic_deg"], "deg", RUN, DEG, 2),
              finding("metge.free_dynamic_calibration2_deg", m["free_set_dynamic_calibration2_deg"], "deg", RUN,
                      DEG, 2),
              finding("metge.free_dynamic_fast_deg", m["free_dynamic_slow_fast_deg"]["fast"], "deg", RUN, DEG, 2),
              finding("metge.dynamic_gain_free", m["dynamic_gain_free"], "1", RUN, 0.05, 1),
              finding("metge.order_study_3_1_over_4_1", m["order_study_3_1_over_4_1"], "1", RUN, 0.005, 2),
              finding("metge.order_study_best_j0_over_4_1", m["order_study_best_j0_over_4_1"], "1", RUN, 0.05, 1)]
    return found


def noiseless_and_one_state() -> list[dict]:
    """Without the magnetometer's noise; with one battery state per calibration set."""
    m = _run({"noise": False})
    low, high = m["sets_calibrated_range_deg"]
    one = _run({"soc1": "0.95", "soc2": "0.8"})
    return [finding("metge.noiseless.sets_calibrated_min_deg", low, "deg", NOISELESS, 5e-4, 3),
            finding("metge.noiseless.sets_calibrated_max_deg", high, "deg", NOISELESS, 5e-4, 3),
            finding("metge.noiseless.free_dynamic_calibration1_deg", m["free_set_dynamic_deg"], "deg", NOISELESS,
                    DEG, 2),
            finding("metge.noiseless.free_dynamic_calibration2_deg", m["free_set_dynamic_calibration2_deg"], "deg",
                    NOISELESS, DEG, 2),
            finding("metge.one_state.calibration1_on_set2_deg", one["table1_deg"]["calibration1"]["set2"], "deg",
                    ONE_STATE, 0.05, 0)]


def robustness() -> list[dict]:
    """The compensation on plants the identified family does not contain."""
    from scenarios.metge_robustness import study

    found = []
    for case, row in study().items():
        found += [finding(f"metge.robustness.{case}.free_dynamic_deg", row["free_dynamic_deg"], "deg", ROBUSTNESS,
                          DEG, 2),
                  finding(f"metge.robustness.{case}.fast_third_deg", row["free_dynamic_fast_deg"], "deg", ROBUSTNESS,
                          DEG, 2),
                  finding(f"metge.robustness.{case}.free_eq9_deg", row["free_eq9_deg"], "deg", ROBUSTNESS, DEG, 1)]
    return found


def compute(quick: bool = False) -> list[dict]:
    """Every metge finding; ``quick``: none (each run takes minutes)."""
    if quick:
        return []
    return default() + noiseless_and_one_state() + robustness()
