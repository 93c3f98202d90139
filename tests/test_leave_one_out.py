"""Leave one dataset out: each fold's search reads only the datasets it was given, and chooses what
their scores alone choose; the recordings a search uses are spread over a dataset."""

import numpy as np
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
