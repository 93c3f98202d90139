"""The speed and sweep-cost findings are read from the benchmarks' figures as the pages state them:
a C loop that parts from the orchestrator, or a study with a failed member, stops the group
rather than leaving "equal to the last bit" or a cost on the page; absolute timings carry a
twofold tolerance, ratios a tighter one."""

import pytest

from findings import speed, sweep_cost

BENCH = {"open_loop_over_c": 1.03, "open_loop_over_c_spread": [0.92, 1.05], "closed_loop_over_c": 1.18,
         "closed_loop_over_c_spread": [1.1, 1.2], "fmu_step_over_equations": 1.06,
         "fmu_step_over_equations_spread": [1.06, 1.08], "batch_over_c": 1.03, "batch_over_c_euler": 0.94,
         "closed_loop_us_per_step": 4.1, "closed_loop_c_us_per_step": 3.6, "rtf_closed_loop": 244.0,
         "rtf_closed_loop_c": 281.0, "fmu_steps_us": 1.77, "equations_steps_us": 1.64,
         "batch_updates_per_s": 5.8e6, "batch_c_updates_per_s": 5.9e6, "parallel_batch_updates_per_s": 2.5e6,
         "ahrs_samples_per_s": 1.0e4, "batch_over_ahrs": 580.0, "open_loop_identical": True,
         "closed_loop_identical": True, "batch_identical_to_c": True, "fmu_steps_identical": True}


def test_speed_findings_take_the_benchmark_figures_with_honest_tolerances():
    found = {f["name"]: f for f in speed.bench_findings(BENCH)}
    assert found["speed.bench.closed_loop_over_c"]["value"] == 1.18
    assert found["speed.bench.batch_updates_per_s_million"]["value"] == pytest.approx(5.8)
    timing, ratio = found["speed.bench.closed_loop_us_per_step"], found["speed.bench.closed_loop_over_c"]
    assert timing["tolerance"] == timing["value"] and ratio["tolerance"] < 0.25 * ratio["value"]


@pytest.mark.parametrize("flag", ["closed_loop_identical", "batch_identical_to_c"])
def test_a_c_reference_that_parts_from_the_orchestrator_stops_the_speed_group(flag):
    with pytest.raises(RuntimeError, match=flag):
        speed.bench_findings(BENCH | {flag: False})


def test_a_study_with_a_failed_member_gives_no_findings():
    with pytest.raises(RuntimeError, match="3 members failed"):
        sweep_cost.study_findings({"failed": 3})
