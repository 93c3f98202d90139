"""The benchmark's C reference loops (``benchmarks/c/loops.c``) make the same FMI calls and the
same explicit filter and controller as the orchestrator: their trajectories are equal to the
last bit, which is what lets ``quadcosim bench`` compare their speeds."""

import pytest

from benchmarks import master


@pytest.mark.parametrize("scenario, settings", [("open-loop", {}), ("tp", master.CLOSED_LOOP),
                                                ("tp", {"estimator": "explicit", "flight": "tilt", "kI": 0.05})])
def test_the_c_reference_loops_give_the_orchestrators_trajectories(scenario, settings):
    figures = master.compare(scenario, settings, seconds=0.5, repeats=1)
    assert figures["identical"]
    assert figures["us_per_step"] > 0 and figures["c_us_per_step"] > 0


def test_the_c_reference_refuses_a_filter_it_does_not_implement():
    import scenarios

    definition = scenarios.get("tp")
    system = definition.build(definition.parse({"estimator": "explicit", "corrections": "on"}))
    with pytest.raises(ValueError, match="explicit filter without corrections"):
        master.ReferenceLoop(system, 0.1)
