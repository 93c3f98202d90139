"""Findings of the magnetometer calibration on the clamped rig (Metge et al.) and of its robustness.

Four ``metge`` runs (default options; ``noise=off``; one battery state per set; the paper's
free-set regime), the robustness study (:mod:`quadcosim.studies.metge_robustness`) and the free set's
ablation (:mod:`quadcosim.studies.metge_free`). About 20 minutes; the quick subset is the free set's
uncompensated error of the default and the paper's regime over the ablation's seeds (no
calibration needed) and the bounds (seconds).
"""

from __future__ import annotations

from findings import finding

RUN = "quadcosim run metge"
NOISELESS = f"{RUN} --set noise=off"
ONE_STATE = f"{RUN} --set soc1=0.95 soc2=0.8"
ROBUSTNESS = "python -m quadcosim.studies.metge --robustness --out results/robustness"
PAPER_REGIME = f"{RUN} --set regime=paper"
FREE_SET = "python -m quadcosim.studies.metge --free-set --out results/free-set"
#: The ablation's cases whose uncompensated free set the quick subset re-measures.
QUICK_CASES = ("default", "paper")
DEG = 0.005  # deg, tolerance of a re-run (the runs are seeded: a re-run differs by round-off)


def _run(settings: dict) -> dict:
    from quadcosim import scenarios

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
    from quadcosim.studies.metge_robustness import study

    found = []
    for case, row in study().items():
        found += [finding(f"metge.robustness.{case}.free_dynamic_deg", row["free_dynamic_deg"], "deg", ROBUSTNESS,
                          DEG, 2),
                  finding(f"metge.robustness.{case}.fast_third_deg", row["free_dynamic_fast_deg"], "deg", ROBUSTNESS,
                          DEG, 2),
                  finding(f"metge.robustness.{case}.free_eq9_deg", row["free_eq9_deg"], "deg", ROBUSTNESS, DEG, 1)]
    return found


def paper_regime() -> list[dict]:
    """Table 1 re-measured in the paper's free-set regime (``regime=paper``)."""
    m = _run({"regime": "paper"})
    t, found = m["table1_deg"], []
    for row in ("none", "calibration1", "calibration2"):
        for column in ("set1", "set2", "free"):
            digits = 2 if row != "none" and column != "free" else 1
            found.append(finding(f"metge.paper.{row}.{column}_deg", t[row][column], "deg", PAPER_REGIME, DEG, digits))
    return found + [
        finding("metge.paper.free_dynamic_calibration1_deg", m["free_set_dynamic_deg"], "deg", PAPER_REGIME, DEG, 2),
        finding("metge.paper.free_dynamic_calibration2_deg", m["free_set_dynamic_calibration2_deg"], "deg",
                PAPER_REGIME, DEG, 2),
        finding("metge.paper.eq9_gain_free", t["none"]["free"] / t["calibration1"]["free"], "1", PAPER_REGIME, 0.05,
                0)]


CASE_FIELDS = ("none", "none_min", "none_max", "quasi_static", "eq9", "dynamic")  # a case's findings (deg)


def _case(name: str, row: dict, fields=CASE_FIELDS) -> list[dict]:
    digits = {"dynamic": 2}
    return [finding(f"metge.free.{name}.{k}_deg", row[f"{k}_deg"], "deg", FREE_SET, DEG, digits.get(k, 1))
            for k in fields if f"{k}_deg" in row]


def _bounds() -> list[dict]:
    from quadcosim.studies import metge_free

    return [finding("metge.free.bound_steady_deg", metge_free.largest_turn_deg(), "deg", FREE_SET, DEG, 1),
            finding("metge.free.bound_current_limit_deg", metge_free.largest_turn_deg(limit_current=True), "deg",
                    FREE_SET, DEG, 1),
            finding("metge.free.paper_removed_min_deg", metge_free.paper_removed_min_deg(), "deg", FREE_SET, 1e-9, 1)]


def free_set(quick: bool = False) -> list[dict]:
    """The free set's ablation: every case, the heading and the flight, the bounds; ``quick``:
    the uncompensated free set of :data:`QUICK_CASES` and the bounds."""
    from quadcosim.studies import metge_free

    if quick:
        found = []
        for name in QUICK_CASES:
            errors = metge_free.uncompensated_free_deg(metge_free.cases()[name][1])
            found += _case(name, {"none_deg": float(sum(errors) / len(errors)), "none_min_deg": min(errors),
                                  "none_max_deg": max(errors)})
        return found + _bounds()
    study, found = metge_free.study(), []
    for name, row in study["cases"].items():
        found += _case(name, row)
    # the sets, uncompensated: many cases share a plant (and its value), so their range and the default's
    sets = [row["sets_deg"] for row in study["cases"].values()]
    found += [finding("metge.free.sets_min_deg", min(sets), "deg", FREE_SET, DEG, 2),
              finding("metge.free.sets_max_deg", max(sets), "deg", FREE_SET, DEG, 2),
              finding("metge.free.default.sets_deg", study["cases"]["default"]["sets_deg"], "deg", FREE_SET, DEG, 2)]
    for name in ("default", "common_up", "paper_east"):
        row = study["cases"][name]
        found += [finding(f"metge.free.{name}.sets_heading_deg", row["sets_heading_deg"], "deg", FREE_SET, DEG, 1),
                  finding(f"metge.free.{name}.heading_deg", row["heading_deg"], "deg", FREE_SET, DEG, 1)]
    for name in ("default", "paper"):
        found.append(finding(f"metge.free.{name}.removed_deg", study["cases"][name]["removed_deg"], "deg", FREE_SET,
                             DEG, 1))
    found += [finding(f"metge.free.flying.{k}", v, "deg", FREE_SET, DEG, 1) for k, v in study["flying"].items()]
    return found + _bounds()


def compute(quick: bool = False) -> list[dict]:
    """Every metge finding; ``quick``: the free set's quick subset (:func:`free_set`)."""
    if quick:
        return free_set(quick=True)
    return default() + noiseless_and_one_state() + robustness() + paper_regime() + free_set()
