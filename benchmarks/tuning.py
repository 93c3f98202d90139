"""Choose the recommended filter's defaults, each dataset in turn held out, and tune VQF the same way.

    python -m quadcosim.benchmarks.tuning DATA [--filter explicit|vqf] [--limit N] [--gyro-bias DEG]
                                               [--out FILE] [--figures DIR]
    python -m quadcosim.benchmarks.tuning DATA --score-folds [--json FILE]

DATA holds one sub-folder per dataset, as :mod:`quadcosim.benchmarks.datasets` describes; the datasets are
:data:`quadcosim.benchmarks.real_recordings.DEVELOPMENT`.

The score of a gain set is made of its mean total RMSE over VQF's (at VQF's package defaults) on
each dataset it is scored on, so that each dataset counts alike whatever its number of recordings:
the mean of the worst dataset's ratio and of the mean ratio. The worst alone would choose the set
that loses least where it loses most but leaves the parameters that dataset does not care about
to drift; the mean lets every dataset speak.

Each dataset is scored twice: as recorded, and with a constant gyro bias of :data:`GYRO_BIAS_DEG`
(1 deg/s, a consumer MEMS gyro's zero-rate offset) added to every recording in a direction drawn
per recording (:func:`with_gyro_bias`), VQF too; the two count as two datasets in the score. The
development datasets come from gyros calibrated or nearly bias-free: a search on them alone learns
the bias slowly, which fails where the gyro is raw (a phone's, as the iPhones').

The search is a compass search on a logarithmic grid: around the current point, each parameter
alone at ``1/STEP`` and ``STEP`` times its value (2n + 1 gain sets, in one batch call per
recording) is scored; the search moves to the best when it gains more than :data:`MIN_GAIN` and
repeats until the best is the centre, so that no chosen value sits on the edge of the grid it was
chosen on (the grid is widened, by recentring, until none does).

Leave one dataset out (:func:`leave_one_out`): the search is run once per dataset with that
dataset held out (:class:`Fold`: it is not read), then once on all of them: the defaults. The
search reads every recording of each dataset, or at most ``--limit`` of them (spread over it,
:func:`spread`). Then each parameter is swept
alone over ``STEP^-3 .. STEP^3`` times its chosen value, the others held: the sensitivity curves,
drawn per dataset with the score (``--figures``). The record (``--out``,
``benchmarks/data/tuning_KIND.json``) holds the defaults, every fold's values and the sweeps.
``--score-folds`` reads the committed records only and scores each fold, on every recording of the
dataset it held out, against VQF at its defaults and VQF tuned by the same fold
(:func:`score_folds`): the held-out table; then, for the fold that loses most, each parameter on
which it and the defaults differ swapped between them (:func:`swaps`).

Parameters, all physical (:data:`SEARCH`): for ``explicit`` (the recommended filter, corrections
on), the time constants of inclination, heading and bias (s, :func:`quadcosim.estimators.explicit.explicit_gains`),
the magnetic disturbance thresholds on the field's norm (µT at the lab's 47 µT field; the filter
applies it relative to the reference norm, so any magnetometer unit works) and on its dip (deg),
the magnetic reference's time (s: its tracking time constant, and how long a new field must last
to be adopted) and the longest rejection (s); the time constants start where the earlier search started,
the magnetic rule at VQF's published one. For ``vqf``, its two time constants ``tauAcc`` and ``tauMag``
(s), from its defaults.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import zlib
from pathlib import Path

import numpy as np
from quadcosim.benchmarks import datasets
from quadcosim.benchmarks.real_recordings import DEVELOPMENT, errors
from quadcosim.fmus import vehicle

from quadcosim.infra.files import save_figure, write_text

STEP = 2.0  # ratio between neighbouring grid values
SWEEP = 3  # the sensitivity sweeps reach STEP**SWEEP either side of the chosen value
LIMIT = None  # recordings of a dataset in the search at most (spread); None: all, as the held-out folds are scored
MIN_GAIN = 1e-3  # a move must lower the score by more than this; the scores of means over tens of recordings
# differ by less than this in directions no dataset cares about
GYRO_BIAS_DEG = 1.0  # deg/s: a consumer MEMS gyro's zero-rate offset; each recording is also scored with one
BIASED = "+bias"  # the suffix of a dataset's variant scored with the gyro bias
LAB_FIELD_UT = vehicle.EARTH_FIELD_NORM * 1e6  # µT, the field the norm threshold is stated at
# parameter: (start, unit, description)
SEARCH = {
    "explicit": {
        "tau_inclination": (0.5, "s", "inclination time constant"),
        "tau_heading": (10.0, "s", "heading time constant"),
        "tau_bias": (200.0, "s", "bias time constant"),
        # the magnetic rule starts at VQF's published values: a field rejected once its norm is 10 % or its dip
        # 10 deg off the tracked reference (the weight's ramp is half-way there), a new field adopted and the
        # reference's time constant 20 s, a rejection bounded at 60 s
        "mag_norm_threshold": (0.2 * LAB_FIELD_UT, "µT", "magnetic norm threshold"),
        "mag_dip_threshold": (20.0, "deg", "magnetic dip threshold"),
        "mag_reference_time": (20.0, "s", "magnetic reference time"),
        "mag_rejection_time": (60.0, "s", "longest magnetic rejection"),
    },
    "vqf": {
        "tauAcc": (3.0, "s", "VQF's inclination time constant"),
        "tauMag": (9.0, "s", "VQF's heading time constant"),
    },
}


def filter_gains(kind: str, values: dict) -> dict:
    """The gains ``estimate`` takes for physical parameter values of :data:`SEARCH`.

    Parameters
    ----------
    kind : str
        The filter (a key of :data:`SEARCH`).
    values : dict
        Parameter name -> array of values; the thresholds in uT and degrees.

    Returns
    -------
    dict
        The gains: the thresholds become ``mag_norm_tolerance`` (1, relative to the lab's field)
        and ``mag_dip_tolerance`` (rad).
    """
    gains = dict(values)
    if "mag_norm_threshold" in gains:
        gains["mag_norm_tolerance"] = np.asarray(gains.pop("mag_norm_threshold")) / LAB_FIELD_UT
    if "mag_dip_threshold" in gains:
        gains["mag_dip_tolerance"] = np.radians(gains.pop("mag_dip_threshold"))
    return gains


def spread(recordings: list, limit: int | None) -> list:
    """At most ``limit`` of ``recordings``, evenly spaced in their order (all of them when ``limit`` is
    None): a dataset's recordings are sorted by name, so the pick spans its people, motions and devices."""
    if limit is None or len(recordings) <= limit:
        return list(recordings)
    return [recordings[k] for k in np.linspace(0, len(recordings) - 1, limit).round().astype(int)]


def with_gyro_bias(dataset: str, label: str, data: dict, bias_deg: float) -> dict:
    """The recording ``data`` with a constant gyro bias of ``bias_deg`` (deg/s) added, in a direction of the
    body frame drawn from a generator seeded by ``dataset`` and ``label``: the same for a recording in
    every search, whatever else is read.

    Parameters
    ----------
    dataset, label : str
        The dataset and the recording's name in it.
    data : dict
        The recording, as :mod:`quadcosim.benchmarks.datasets` loads it (``gyro`` in rad/s, body frame).
    bias_deg : float
        The bias's norm, deg/s.

    Returns
    -------
    dict
        A copy of ``data`` whose ``gyro`` is offset; the other arrays are shared.
    """
    direction = np.random.default_rng(zlib.crc32(f"{dataset}/{label}".encode())).normal(size=3)
    bias = np.radians(bias_deg) * direction / np.linalg.norm(direction)
    return data | {"gyro": np.asarray(data["gyro"]) + bias}


class Scorer:
    """Mean total, heading and inclination RMSE (deg) of gain sets on datasets, and their total over
    VQF's at its defaults; every gain set is scored once per dataset (kept in ``memo``).

    Parameters
    ----------
    folder : str or pathlib.Path
        Folder of the datasets (see :mod:`quadcosim.benchmarks.datasets`).
    names : sequence of str
        The datasets scored; the development ones by default.
    limit : int, optional
        At most this many recordings of each dataset (:func:`spread`); all by default.
    gyro_bias_deg : float
        Each dataset is also scored with this gyro bias added to every recording (deg/s,
        :func:`with_gyro_bias`; variant ``NAME+bias``); 0: as recorded only.
    """

    def __init__(self, folder, names=DEVELOPMENT, limit: int | None = None, gyro_bias_deg: float = GYRO_BIAS_DEG):
        self.recordings = {}
        for name in names:
            found = spread(datasets.load(folder, name), limit)
            if found:
                self.recordings[name] = found
        if not self.recordings:
            raise FileNotFoundError(f"none of the datasets {', '.join(names)} is under {folder}")
        self.gyro_bias_deg = float(gyro_bias_deg)
        self.scored = {}  # variant -> recordings: each dataset as recorded and, with a gyro bias, biased
        for name, found in self.recordings.items():
            self.scored[name] = found
            if self.gyro_bias_deg > 0.0:
                self.scored[name + BIASED] = [(label, with_gyro_bias(name, label, data, self.gyro_bias_deg))
                                              for label, data in found]
        self.memo = {}
        self.vqf = {variant: self.means("vqf", variant, {}) for variant in self.scored}
        self.evaluated = 0

    def variants(self, name: str) -> list[str]:
        """The variants of the dataset ``name`` that are scored: as recorded, and with the gyro bias."""
        return [name] + ([name + BIASED] if name + BIASED in self.scored else [])

    def means(self, kind: str, variant: str, gains: dict) -> dict:
        """Per metric, the (G,) mean over the recordings of ``variant`` (:meth:`variants`) of the filter ``kind``
        with ``gains``."""
        if kind == "vqf":
            sets = _sets(gains)
            rows = [[errors("vqf", data, s) for s in sets] for _, data in self.scored[variant]]
            return {m: np.mean([[r[m][0] for r in row] for row in rows], axis=0) for m in rows[0][0]}
        rows = [errors(kind, data, filter_gains(kind, gains)) for _, data in self.scored[variant]]
        return {m: np.mean([r[m] for r in rows], axis=0) for m in rows[0]}

    def ratios(self, kind: str, gains: dict, names=None) -> dict:
        """Variant (:meth:`variants`: ``NAME`` and ``NAME+bias``) -> (G,) mean total RMSE over VQF's (defaults,
        on the same variant); also keeps the means in ``self.last``.

        Parameters
        ----------
        kind : str
            The filter.
        gains : dict
            Gain name -> (G,) array: G gain sets scored at once; those scored before come from ``memo``.
        names : sequence of str, optional
            The datasets scored, each in all its variants (all of :attr:`recordings` by default); no other is
            read.
        """
        names = list(self.recordings) if names is None else list(names)
        variants = [variant for name in names for variant in self.variants(name)]
        sets = _sets(gains)
        self.last = {}
        for name in variants:
            keys = [(kind, name, tuple(sorted(s.items()))) for s in sets]
            todo = [k for k, key in enumerate(keys) if key not in self.memo]
            if todo:
                found = self.means(kind, name, {g: np.array([sets[k][g] for k in todo]) for g in gains})
                for j, k in enumerate(todo):
                    self.memo[keys[k]] = {m: float(v[j]) for m, v in found.items()}
                self.evaluated += len(todo)
            self.last[name] = {m: np.array([self.memo[key][m] for key in keys]) for m in self.memo[keys[0]]}
        return {name: self.last[name]["total_rmse_deg"] / self.vqf[name]["total_rmse_deg"] for name in variants}


class Fold:
    """The :class:`Scorer` ``scorer`` restricted to the datasets ``names``: what a search sees when
    the others are held out."""

    def __init__(self, scorer: Scorer, names):
        self.scorer = scorer
        self.recordings = {name: scorer.recordings[name] for name in names}

    def ratios(self, kind: str, gains: dict) -> dict:
        """As :meth:`Scorer.ratios`, on this fold's datasets only.

        Parameters
        ----------
        kind : str
            The filter.
        gains : dict
            Gain name -> (G,) array of gain sets.
        """
        found = self.scorer.ratios(kind, gains, list(self.recordings))
        self.last = self.scorer.last
        return found


def _sets(gains: dict) -> list[dict]:
    if not gains:
        return [{}]
    count = len(next(iter(gains.values())))
    return [{k: float(v[g]) for k, v in gains.items()} for g in range(count)]


def score(ratios: dict) -> np.ndarray:
    """The mean of the worst development dataset's ratio and of the mean ratio, per gain set.

    Parameters
    ----------
    ratios : dict
        Dataset -> (G,) ratio to VQF, as :meth:`Scorer.ratios` returns.
    """
    stacked = np.vstack(list(ratios.values()))
    return 0.5 * (np.max(stacked, axis=0) + np.mean(stacked, axis=0))


def _neighbours(point: dict) -> dict:
    """``point`` and, for each parameter alone, ``point`` with it divided and multiplied by :data:`STEP`."""
    sets = [dict(point)]
    for name, value in point.items():
        sets += [point | {name: value / STEP}, point | {name: value * STEP}]
    return {name: np.array([s[name] for s in sets]) for name in point}


def search(scorer: Scorer, kind: str, start: dict | None = None, log=print) -> dict:
    """The compass search of the module docstring.

    Parameters
    ----------
    scorer : Scorer
        Scores gain sets on the development datasets.
    kind : str
        The filter (a key of :data:`SEARCH`).
    start : dict, optional
        The first point; :data:`SEARCH`'s first values by default.
    log : callable
        Called with one line per step.

    Returns
    -------
    dict
        The chosen values, the score there and every gain set scored (``history``).
    """
    point = {name: float(v[0]) for name, v in SEARCH[kind].items()} | (start or {})
    history = []
    while True:
        grid = _neighbours(point)
        ratios = scorer.ratios(kind, grid)
        scores = score(ratios)
        for g in range(len(scores)):
            history.append({"values": {k: float(v[g]) for k, v in grid.items()}, "score": float(scores[g]),
                            "ratios": {n: float(r[g]) for n, r in ratios.items()}})
        best = int(np.argmin(scores))
        if scores[best] > scores[0] - MIN_GAIN:
            best = 0  # the centre: no move gains enough
        chosen = {name: float(v[best]) for name, v in grid.items()}
        log(f"{kind}: around {point} best {scores[best]:.4f} at {chosen}")
        if chosen == point:
            return {"values": point, "score": float(scores[best]),
                    "ratios": {n: float(r[best]) for n, r in ratios.items()},
                    "means": {n: {m: float(v[best]) for m, v in found.items()} for n, found in scorer.last.items()},
                    "history": history}
        point = chosen


def sweeps(scorer: Scorer, kind: str, chosen: dict) -> dict:
    """Each parameter over ``STEP**-SWEEP .. STEP**SWEEP`` times its chosen value, the others held.

    Parameters
    ----------
    scorer : Scorer
        Scores gain sets on the development datasets.
    kind : str
        The filter.
    chosen : dict
        The chosen values, parameter -> value.

    Returns
    -------
    dict
        Parameter -> {"values", "ratios" (dataset -> list), "score"}.
    """
    out = {}
    for name, value in chosen.items():
        values = value * STEP ** np.arange(-SWEEP, SWEEP + 1, dtype=float)
        grid = {k: (values if k == name else np.full(len(values), v)) for k, v in chosen.items()}
        ratios = scorer.ratios(kind, grid)
        out[name] = {"values": values.tolist(), "ratios": {n: r.tolist() for n, r in ratios.items()},
                     "score": score(ratios).tolist()}
    return out


def figures(kind: str, swept: dict, chosen: dict, folder) -> list[Path]:
    """One figure per parameter: the ratio to VQF of every development dataset and the score
    against the parameter, the chosen value marked.

    Parameters
    ----------
    kind : str
        The filter.
    swept : dict
        As :func:`sweeps` returns.
    chosen : dict
        The chosen values, parameter -> value.
    folder : str or pathlib.Path
        Where the PNG files are written.

    Returns
    -------
    list of pathlib.Path
        The figures written.
    """
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, found in swept.items():
        _, unit, label = SEARCH[kind][name]
        fig, ax = plt.subplots(figsize=(5.5, 3.6))
        try:
            colours = {}
            for variant, ratios in found["ratios"].items():
                dataset = variant.removesuffix(BIASED)
                style = {"ls": "--", "marker": "x"} if variant.endswith(BIASED) else {"marker": "o"}
                line, = ax.plot(found["values"], ratios, ms=3, lw=1, label=variant, color=colours.get(dataset), **style)
                colours[dataset] = line.get_color()
            ax.plot(found["values"], found["score"], color="k", lw=2.2, label="score")
            ax.axvline(chosen[name], color="0.4", ls="--", lw=1, label=f"chosen {chosen[name]:g} {unit}")
            ax.axhline(1.0, color="0.6", lw=0.8)
            ax.set_xscale("log")
            ax.set_xticks(found["values"], [f"{v:g}" for v in found["values"]])
            ax.xaxis.set_minor_locator(matplotlib.ticker.NullLocator())
            ax.set_xlabel(f"{label} ({unit})")
            ax.set_ylabel("mean total RMSE / VQF's")
            ax.set_title(f"{kind}: {label}, the others at their chosen values", fontsize=9)
            ax.legend(fontsize=7)
            fig.tight_layout()
            path = folder / f"tuning_{kind}_{name}.png"
            save_figure(fig, path, dpi=110)
            paths.append(path)
        finally:
            plt.close(fig)
    return paths


def leave_one_out(scorer: Scorer, kind: str, start: dict | None = None, log=print) -> dict:
    """Each dataset of ``scorer`` in turn held out of the search: :func:`search` on the others alone
    (:class:`Fold`; the held-out dataset is not read).

    Parameters
    ----------
    scorer : Scorer
        Scores gain sets on all the datasets.
    kind : str
        The filter (a key of :data:`SEARCH`).
    start : dict, optional
        The first point of every fold's search; :data:`SEARCH`'s first values by default.
    log : callable
        Called with one line per step.

    Returns
    -------
    dict
        Held-out dataset -> ``{"searched_on": [names], "values": chosen, "score": in-sample score,
        "ratios": in-sample ratios}``.
    """
    out = {}
    for held in scorer.recordings:
        others = [name for name in scorer.recordings if name != held]
        found = search(Fold(scorer, others), kind, start, log=lambda text, h=held: log(f"without {h}: {text}"))
        out[held] = {"searched_on": others, "values": found["values"], "score": found["score"],
                     "ratios": found["ratios"]}
    return out


def record_path(kind: str) -> Path:
    """The committed search record of the filter ``kind``: ``benchmarks/data/tuning_KIND.json``."""
    from quadcosim.benchmarks.real_recordings import TUNING_RECORDS

    return TUNING_RECORDS / f"tuning_{kind}.json"


def _mean_errors(kind: str, recordings: list, gains: dict | None) -> dict:
    rows = [errors(kind, data, gains) for _, data in recordings]
    return {m: float(np.mean([r[m][0] for r in rows])) for m in rows[0]}


def score_folds(folder, log=print) -> dict:
    """Each fold of the committed records (:func:`record_path`, ``folds``) scored on every recording
    of the dataset it held out: the explicit filter at the fold's values, VQF at its defaults and
    VQF at the fold's values (tuned by the same procedure without that dataset).

    Parameters
    ----------
    folder : str or pathlib.Path
        Folder of the datasets.
    log : callable
        Called with one line per dataset.

    Returns
    -------
    dict
        Held-out dataset -> ``{"recordings", "explicit", "vqf", "vqf_tuned"`` (each metric -> mean
        deg), ``"explicit_over_vqf", "explicit_over_vqf_tuned", "vqf_tuned_over_vqf"}``.
    """
    records = {kind: json.loads(record_path(kind).read_text()) for kind in ("explicit", "vqf")}
    out = {}
    for held, fold in records["explicit"]["folds"].items():
        recordings = datasets.load(folder, held)
        if not recordings:
            continue
        values = {k: np.array([v]) for k, v in fold["values"].items()}
        found = {"explicit": _mean_errors("explicit", recordings, filter_gains("explicit", values)),
                 "vqf": _mean_errors("vqf", recordings, None),
                 "vqf_tuned": _mean_errors("vqf", recordings, records["vqf"]["folds"][held]["values"])}
        total = {k: v["total_rmse_deg"] for k, v in found.items()}
        out[held] = {"recordings": len(recordings), **found,
                     "explicit_over_vqf": total["explicit"] / total["vqf"],
                     "explicit_over_vqf_tuned": total["explicit"] / total["vqf_tuned"],
                     "vqf_tuned_over_vqf": total["vqf_tuned"] / total["vqf"]}
        log(f"{held} held out: explicit {total['explicit']:.2f}, VQF {total['vqf']:.2f}, VQF tuned "
            f"{total['vqf_tuned']:.2f} deg; explicit / VQF {out[held]['explicit_over_vqf']:.2f}, / VQF tuned "
            f"{out[held]['explicit_over_vqf_tuned']:.2f}")
    return out


def worst_fold(scores: dict) -> str:
    """The held-out dataset of :func:`score_folds`' ``scores`` on which the explicit filter loses most to VQF."""
    return max(scores, key=lambda held: scores[held]["explicit_over_vqf"])


def swaps(folder, held: str) -> dict:
    """What makes the fold that held out ``held`` lose there: each parameter on which that fold's values
    (the committed record's) and the defaults differ, put at the defaults' value in the fold's values,
    and at the fold's value in the defaults; every recording of ``held``, mean total RMSE over VQF's.

    Parameters
    ----------
    folder : str or pathlib.Path
        Folder of the datasets.
    held : str
        The held-out dataset.

    Returns
    -------
    dict
        ``{"fold": ratio, "defaults": ratio, "swapped": {parameter: {"into_fold": ratio,
        "into_defaults": ratio}}}``.
    """
    record = json.loads(record_path("explicit").read_text())
    fold, chosen = record["folds"][held]["values"], record["chosen"]
    differ = [name for name in fold if fold[name] != chosen[name]]
    sets = [fold, chosen] + [fold | {n: chosen[n]} for n in differ] + [chosen | {n: fold[n]} for n in differ]
    recordings = datasets.load(folder, held)
    gains = filter_gains("explicit", {n: np.array([s[n] for s in sets]) for n in fold})
    total = np.mean([errors("explicit", data, gains)["total_rmse_deg"] for _, data in recordings], axis=0)
    ratio = total / _mean_errors("vqf", recordings, None)["total_rmse_deg"]
    count = len(differ)
    return {"fold": float(ratio[0]), "defaults": float(ratio[1]),
            "swapped": {n: {"into_fold": float(ratio[2 + k]), "into_defaults": float(ratio[2 + count + k])}
                        for k, n in enumerate(differ)}}


def main(argv=None) -> int:
    """Command line (see the module docstring); prints the chosen values, returns 0 (2 for a bad
    folder). ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.tuning", description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--filter", default="explicit", choices=sorted(SEARCH))
    parser.add_argument("--limit", type=int, default=LIMIT,
                        help="at most this many recordings of each dataset in the search (default: all)")
    parser.add_argument("--gyro-bias", type=float, default=GYRO_BIAS_DEG,
                        help=f"each dataset is also scored with a gyro bias of this norm, deg/s "
                             f"(default {GYRO_BIAS_DEG:g}; 0: as recorded only)")
    parser.add_argument("--out", help="write the search record (JSON) here")
    parser.add_argument("--figures", help="write the sensitivity figures (PNG) into this folder")
    parser.add_argument("--score-folds", action="store_true",
                        help="score each committed fold on the dataset it held out (all its recordings)")
    parser.add_argument("--json", help="with --score-folds: write the held-out scores here")
    args = parser.parse_args(argv)
    if not Path(args.folder).is_dir():
        from quadcosim.infra.errors import UsageError

        raise UsageError(f"{args.folder} is not a folder: give the folder of the datasets")
    started = time.perf_counter()
    if args.score_folds:
        scores = score_folds(args.folder)
        print(fold_table(scores))
        worst = worst_fold(scores)
        found = swaps(args.folder, worst)
        print(f"\n{worst}: the fold's values {found['fold']:.2f}, the defaults {found['defaults']:.2f} x VQF; each "
              "differing parameter at the defaults' value in the fold, at the fold's value in the defaults:")
        for name, ratios in found["swapped"].items():
            print(f"  {name}: {ratios['into_fold']:.2f}, {ratios['into_defaults']:.2f}")
        if args.json:
            write_text(args.json, json.dumps(scores, indent=1) + "\n")
        return 0
    log = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731
    scorer = Scorer(args.folder, limit=args.limit, gyro_bias_deg=args.gyro_bias)
    folds = leave_one_out(scorer, args.filter, log=log)
    chosen = search(scorer, args.filter, log=log)
    swept = sweeps(scorer, args.filter, chosen["values"])
    record = {"filter": args.filter, "development": list(scorer.recordings), "step": STEP, "limit": args.limit,
              "gyro_bias_deg": scorer.gyro_bias_deg,
              "recordings": {n: [label for label, _ in found] for n, found in scorer.recordings.items()},
              "chosen": chosen["values"], "score": chosen["score"], "ratios": chosen["ratios"],
              "means": chosen["means"],
              "folds": folds,
              "vqf_defaults": {n: {m: float(v[0]) for m, v in found.items()} for n, found in scorer.vqf.items()},
              "sweeps": swept, "history": chosen["history"], "gain_sets": scorer.evaluated,
              "seconds": round(time.perf_counter() - started, 1)}
    print(json.dumps({k: record[k] for k in ("filter", "chosen", "score", "ratios", "gain_sets", "seconds")}
                     | {"folds": {h: f["values"] for h, f in folds.items()}}, indent=1))
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        write_text(args.out, json.dumps(record, indent=1) + "\n")
    if args.figures:
        for path in figures(args.filter, swept, chosen["values"], args.figures):
            print(path)
    return 0


def fold_table(scores: dict) -> str:
    """The held-out table of :func:`score_folds`' ``scores`` (markdown): per dataset, the mean total
    RMSE (deg) of each filter while it was held out, and the ratios."""
    lines = ["| held out (recordings) | explicit | VQF | VQF tuned | explicit / VQF | explicit / VQF tuned | "
             "VQF tuned / VQF |", "|---" * 7 + "|"]
    for held, found in scores.items():
        lines.append(f"| {held} ({found['recordings']}) | " + " | ".join(
            f"{found[k]['total_rmse_deg']:.2f}" for k in ("explicit", "vqf", "vqf_tuned")) + " | " + " | ".join(
            f"{found[k]:.2f}" for k in ("explicit_over_vqf", "explicit_over_vqf_tuned", "vqf_tuned_over_vqf")) + " |")
    return "\n".join(lines)


if __name__ == "__main__":  # the same as quadcosim bench tuning
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench tuning").run, main)
