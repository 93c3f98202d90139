"""Every recorded signal of six short runs, and the lab's filters alone on inputs with the same
bits everywhere, against their references, within a tolerance set from the spread measured
across CPU kernels (see tests/trajectory_runs.py): another machine passes, a change of physics or
numerics fails. Bit-exact digests on one machine are `make digests`."""

import numpy as np
import pytest
from quadcosim.orchestrator import pool
from trajectory_runs import FILTERS, RUNS, compare, floor, kept, key, load_references, record

REFERENCES, TOLERANCES = load_references()


@pytest.mark.parametrize("label", [*RUNS, *FILTERS])
def test_every_recorded_signal_matches_its_reference(label):
    problems = compare(label, record(label), REFERENCES, TOLERANCES)
    assert not problems, f"{label}: {len(problems)} signals off their references:\n" + "\n".join(problems[:10])


def test_runs_on_reused_fmu_instances_match_their_references():
    previous = pool.reuse(True)
    try:
        for label in ("ir-calibration", "tp-passive-triad-magnetic", "tp-explicit-noise-bias-nonstationary-estimate"):
            problems = compare(label, record(label), REFERENCES, TOLERANCES)
            assert not problems, f"{label} on reused instances: " + "; ".join(problems[:5])
    finally:
        pool.reuse(previous)


def test_a_gain_changed_by_one_part_in_a_million_fails_the_references():
    """The tolerances are tight enough to see a genuine change: the lab's linear filter gain k
    times 1 + 1e-6 moves the estimate beyond them."""
    name, options = RUNS["tp-linear"]
    from quadcosim import scenarios

    result, _ = scenarios.run(name, dict(options) | {"k": 0.05 * (1 + 1e-6)})
    signals = {s: np.asarray(result[s]) for s in result.names} | {"time": np.asarray(result.time)}
    problems = compare("tp-linear", signals, REFERENCES, TOLERANCES)
    moved = [p.split(":")[0] for p in problems]
    assert "Quaternion_estim.theta_est1" in moved, problems


def test_the_tolerances_sit_near_the_measured_spread():
    """Each tolerance is ten times the spread measured across kernels (at least four ulp of the
    signal in a co-simulation run; none for a filter alone): never a blanket bound."""
    import json

    from trajectory_runs import TOLERANCES as PATH

    stored = json.loads(PATH.read_text())
    for name, tolerance in stored["tolerances"].items():
        assert tolerance == pytest.approx(10 * max(stored["spread"][name], floor(name, REFERENCES[name])),
                                          rel=1e-12, abs=0.0), name
    assert key("tp-linear", "time") in REFERENCES and len(kept(np.arange(10_000))) == 100
