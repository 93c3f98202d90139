"""Leave one dataset out: each fold's search reads only the datasets it was given, and chooses what
their scores alone choose; the recordings a search uses are spread over a dataset."""

import numpy as np
import pytest
from quadcosim.benchmarks import tuning

# three 'datasets' whose ratio to VQF is a bowl in log2 of the inclination time constant, least at 2, 8 and 32 s
MINIMA = {"one": 1.0, "two": 3.0, "three": 5.0}


class _Bowls:
    """A stand-in for quadcosim.benchmarks.tuning.Scorer that records which datasets each call reads."""

    def __init__(self):
        self.recordings = dict.fromkeys(MINIMA)
        self.read = set()

    def ratios(self, kind, gains, names=None):
        names = list(self.recordings) if names is None else list(names)
        self.read |= set(names)
        a = np.log2(gains["tau_inclination"])
        found = {n: 1 + 0.1 * (a - MINIMA[n]) ** 2 + 0.01 * np.log2(gains["tau_heading"] / 8) ** 2 for n in names}
        self.last = {n: {"total_rmse_deg": r} for n, r in found.items()}
        return found


def test_a_fold_never_reads_the_dataset_it_holds_out():
    scorer = _Bowls()
    start = {"tau_inclination": 1.0, "tau_heading": 8.0}
    for held in MINIMA:
        scorer.read = set()
        tuning.search(tuning.Fold(scorer, [n for n in MINIMA if n != held]), "explicit", start, log=lambda t: None)
        assert held not in scorer.read and len(scorer.read) == 2


def test_leave_one_out_chooses_each_fold_on_the_others_alone():
    folds = tuning.leave_one_out(_Bowls(), "explicit", {"tau_inclination": 1.0, "tau_heading": 8.0},
                                 log=lambda t: None)
    # the score (worst + mean) / 2 of two bowls 0.1 (a - m)^2: least between their minima, nearer the worst one
    chosen = {held: np.log2(f["values"]["tau_inclination"]) for held, f in folds.items()}
    print(chosen)
    assert chosen == {"one": 4.0, "two": 3.0, "three": 2.0}
    assert all(f["searched_on"] == [n for n in MINIMA if n != held] for held, f in folds.items())
    assert all(f["values"]["tau_heading"] == 8.0 for f in folds.values())  # the minimum every fold shares


def test_the_search_takes_recordings_spread_over_a_dataset():
    recordings = [(f"r{k:02d}", None) for k in range(30)]
    picked = [label for label, _ in tuning.spread(recordings, 4)]
    assert picked == ["r00", "r10", "r19", "r29"]
    assert tuning.spread(recordings, None) == recordings and tuning.spread(recordings[:3], 12) == recordings[:3]


def test_swaps_put_each_differing_parameter_of_a_fold_at_the_defaults_value_and_back(tmp_path, monkeypatch):
    import json

    fold = {"tau_heading": 10.0, "tau_bias": 800.0, "mag_reference_time": 320.0}
    chosen = {"tau_heading": 10.0, "tau_bias": 100.0, "mag_reference_time": 20.0}
    record = tmp_path / "tuning_explicit.json"
    record.write_text(json.dumps({"chosen": chosen, "folds": {"held": {"values": fold}}}))
    monkeypatch.setattr(tuning, "record_path", lambda kind: record)
    monkeypatch.setattr(tuning.datasets, "load", lambda folder, name: [("r1", 1.0), ("r2", 3.0)])

    def errors(kind, data, gains):  # a total RMSE that adds each parameter's share: 2 deg for VQF
        if gains is None:
            return {"total_rmse_deg": np.array([2.0 * data])}
        return {"total_rmse_deg": data * (1.0 + gains["tau_bias"] / 100.0 + gains["mag_reference_time"] / 10.0)}

    monkeypatch.setattr(tuning, "errors", errors)
    found = tuning.swaps(tmp_path, "held")
    assert set(found["swapped"]) == {"tau_bias", "mag_reference_time"}  # tau_heading does not differ
    assert found["fold"] == (1 + 8 + 32) / 2 and found["defaults"] == (1 + 1 + 2) / 2
    assert found["swapped"]["tau_bias"] == {"into_fold": (1 + 1 + 32) / 2, "into_defaults": (1 + 8 + 2) / 2}
    assert found["swapped"]["mag_reference_time"] == {"into_fold": (1 + 8 + 2) / 2, "into_defaults": (1 + 1 + 32) / 2}


def test_a_recording_gets_the_same_gyro_bias_of_the_given_norm_in_every_search():
    data = {"gyro": np.zeros((50, 3)), "acc": np.ones((50, 3))}
    first = tuning.with_gyro_bias("iphones", "r1", data, 1.0)
    bias = first["gyro"][0]
    assert np.degrees(np.linalg.norm(bias)) == pytest.approx(1.0, rel=1e-12)
    assert np.all(first["gyro"] == bias) and first["acc"] is data["acc"] and not data["gyro"].any()
    assert np.array_equal(tuning.with_gyro_bias("iphones", "r1", data, 1.0)["gyro"], first["gyro"])
    others = [tuning.with_gyro_bias(d, r, data, 1.0)["gyro"][0] for d, r in (("iphones", "r2"), ("broad", "r1"))]
    assert all(np.linalg.norm(o - bias) > 1e-3 for o in others)  # drawn per recording


def test_a_fold_scores_its_datasets_as_recorded_and_biased_and_never_the_held_out_one(monkeypatch):
    monkeypatch.setattr(tuning.datasets, "load", lambda folder, name: [(f"{name}-r", {"gyro": np.zeros((10, 3))})])

    def errors(kind, data, gains):  # an error (deg) of 1 plus the gyro's bias in deg/s, VQF's half of it
        bias = np.degrees(np.linalg.norm(data["gyro"][0]))
        count = len(gains["tau_inclination"]) if kind == "explicit" else 1
        return {"total_rmse_deg": np.full(count, 1.0 + (bias if kind == "explicit" else bias / 2))}

    monkeypatch.setattr(tuning, "errors", errors)
    scorer = tuning.Scorer("data", names=("one", "two", "three"), gyro_bias_deg=2.0)
    assert list(scorer.scored) == ["one", "one+bias", "two", "two+bias", "three", "three+bias"]
    found = tuning.Fold(scorer, ["one", "two"]).ratios("explicit", {"tau_inclination": np.array([1.0, 2.0])})
    assert set(found) == {"one", "one+bias", "two", "two+bias"}
    assert np.allclose(found["one"], 1.0) and np.allclose(found["two+bias"], 3.0 / 2.0)
    plain = tuning.Scorer("data", names=("one",), gyro_bias_deg=0.0)
    assert list(plain.scored) == ["one"]
