"""Findings of the gain study: the linear filter's predicted error variance against simulation.

One ``quadcosim run gain-study`` (a 10 200 s recorded hover stream, then 16 estimate-fed
closed loops of 120 s on Dask): about 4 minutes idle, 10 loaded. Nothing here is quick.
"""

from __future__ import annotations

from findings import finding

RUN = "quadcosim run gain-study"
PERCENT = 100.0
CHOSEN_GAINS = (0.05, 0.58, 0.79, 2.0, 5.0)  # 1/s: the gains the README quotes, the nearest of the grid


def _nearest(gains: list[float], k: float) -> int:
    return min(range(len(gains)), key=lambda i: abs(gains[i] - k))


def compute(quick: bool = False) -> list[dict]:
    """The GT mode's agreement and optimum, the closed loop's parting from the prediction;
    ``quick``: none (the run takes minutes)."""
    if quick:
        return []
    from quadcosim import (
        scenarios,
        studies,  # noqa: F401  (registers gain-study)
    )

    m = scenarios.run("gain-study", {})[1]
    gains, difference = m["gains"], m["closed_loop_relative_difference"]
    error = m["closed_loop_relative_standard_error"]
    up_to_optimum = [d for g, d in zip(gains, difference, strict=True) if g <= m["predicted_optimal_gain"]]
    found = [finding("gain_study.gt.max_difference_pct", PERCENT * m["max_abs_relative_difference"], "%", RUN, 0.05, 1),
             finding("gain_study.gt.max_standard_error_pct", PERCENT * m["max_relative_standard_error"], "%", RUN,
                     0.05, 1),
             finding("gain_study.gt.optimal_gain_predicted", m["predicted_optimal_gain"], "1/s", RUN, 0.005, 2),
             finding("gain_study.gt.optimal_gain_simulated", m["simulated_optimal_gain"], "1/s", RUN, 0.005, 2),
             finding("gain_study.closed.low_min_pct", PERCENT * min(up_to_optimum), "%", RUN, 0.5, 0),
             finding("gain_study.closed.low_max_pct", PERCENT * max(up_to_optimum), "%", RUN, 0.5, 0)]
    for k in CHOSEN_GAINS:
        i = _nearest(gains, k)
        label = f"gain_study.closed.k{k:g}".replace(".", "_").replace("gain_study_closed_", "gain_study.closed.")
        found += [finding(f"{label}.gain", gains[i], "1/s", RUN, 0.005, 2),
                  finding(f"{label}.difference_pct", PERCENT * difference[i], "%", RUN, 0.5, 0),
                  finding(f"{label}.standard_error_pct", PERCENT * error[i], "%", RUN, 0.05, 1)]
    return found
