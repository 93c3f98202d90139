"""What the magnetometer does on a recording, and what the recommended filter's magnetic rule makes of it.

    python -m quadcosim.benchmarks.magnetic DATA [--recordings DATASET/NAME,...] [--figure FILE]

Per recording (DATA as :mod:`quadcosim.benchmarks.datasets` describes): the field's norm over the first
second's, its dip against the optical reference's vertical (the true one, not the estimate's),
the magnetometer's weight in the recommended filter at its defaults and with the earlier rule
(the first second's field the reference for ever, :data:`quadcosim.benchmarks.real_recordings.ABLATIONS`'
``fixed_reference``), and the heading error of both against the reference. Printed per
recording: the share of the time the field was rejected (weight under 0.5), the longest
rejection (s) and the heading RMSE (deg) of both rules and of VQF.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from quadcosim.benchmarks import datasets
from quadcosim.benchmarks.real_recordings import ABLATIONS, _options, errors
from quadcosim.estimators import estimate
from quadcosim.estimators.explicit import DEFAULT_TIME_CONSTANTS
from quadcosim.estimators.filters import DEFAULT_CORRECTIONS
from quadcosim.scenarios.replay import field_from_data

# an iPhone whose magnetometer the phone re-calibrates at the start, and a BROAD trial with a magnet
EXAMPLES = ("iphones/Jakob_iPhone5_NoDist_Phoning", "iphones/Guillaume_iPhone5_NoDist_AR",
            "broad/30_disturbed_stationary_magnet_C")
RULES = {"defaults": {}, "reference fixed at the first second": ABLATIONS["fixed_reference"]}


def _heading(q) -> np.ndarray:
    """Heading (deg) of body-to-ENU quaternions (N, 4), scalar first."""
    return np.degrees(np.arctan2(2 * (q[:, 1] * q[:, 2] + q[:, 0] * q[:, 3]), 1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2)))


def _longest(flags: np.ndarray) -> int:
    """The longest run of True in ``flags`` (samples)."""
    edges = np.diff(np.r_[0, flags.astype(int), 0])
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return int((stops - starts).max()) if len(starts) else 0


def analyse(data: dict) -> dict:
    """Series (per sample) and summaries of one recording (as :mod:`quadcosim.benchmarks.datasets` loads it).

    Returns
    -------
    dict
        ``t`` (s), ``norm`` (1, over the first second's), ``dip`` (deg, against the reference's
        vertical), ``first_dip`` (deg, the first second's, from the accelerometer: the filters'
        reference), per rule of :data:`RULES` ``weight`` (1) and ``heading_error`` (deg, its
        median removed) series, ``rejected_share`` (1), ``longest_rejection_s`` (s) and
        ``heading_rmse_deg`` (deg), and VQF's ``heading_rmse_deg``.
    """
    from scipy.spatial.transform import Rotation

    rate, mag, ref = float(data["rate"]), data["mag"], data["quat"]
    t = np.arange(len(mag)) / rate
    norm = np.linalg.norm(mag, axis=1)
    first = max(1, int(rate))
    tracked = np.isfinite(ref).all(axis=1)
    up = np.full((len(ref), 3), np.nan)
    up[tracked] = Rotation.from_quat(ref[tracked][:, [1, 2, 3, 0]]).inv().apply([0.0, 0.0, 1.0])
    out = {"t": t, "norm": norm / norm[:first].mean(),
           "dip": np.degrees(np.arcsin(np.clip(-(mag * up).sum(axis=1) / norm, -1.0, 1.0))),
           "first_dip": float(np.degrees(field_from_data(data["acc"], data["mag"], first)["dip"])), "rules": {}}
    names = sorted({k for v in RULES.values() for k in v})
    defaults = {"tau_bias": DEFAULT_TIME_CONSTANTS["tau_bias"]} | DEFAULT_CORRECTIONS["explicit"]
    gains = {n: np.array([rule.get(n, defaults[n]) for rule in RULES.values()]) for n in names}
    found = estimate("explicit", gains=gains, **(_options("explicit", data) | {"outputs": ("q", "weights")}))
    for k, rule in enumerate(RULES):
        weight = found["weights"][k][:, 1]
        error = (_heading(found["q"][k]) - _heading(np.where(tracked[:, None], ref, np.nan)) + 180.0) % 360.0 - 180.0
        out["rules"][rule] = {"weight": weight, "heading_error": error - np.nanmedian(error),
                              "rejected_share": float(np.mean(weight < 0.5)),
                              "longest_rejection_s": _longest(weight < 0.5) / rate,
                              "heading_rmse_deg": float(found["errors"]["heading_rmse_deg"][k])}
    out["vqf_heading_rmse_deg"] = float(errors("vqf", data)["heading_rmse_deg"][0])
    return out


def figure(found: dict, path) -> Path:
    """The series of :func:`analyse`, one column per recording, saved to ``path``.

    Parameters
    ----------
    found : dict
        Recording name -> :func:`analyse`'s result.
    path : str or pathlib.Path
        The PNG file written.

    Returns
    -------
    pathlib.Path
        The file written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from quadcosim.infra.files import save_figure

    fig, axes = plt.subplots(4, len(found), figsize=(4.4 * len(found), 8.0), sharex="col", squeeze=False)
    try:
        for c, (name, f) in enumerate(found.items()):
            axes[0, c].plot(f["t"], f["norm"], lw=0.6, color="k")
            axes[0, c].set_title(name, fontsize=8)
            axes[1, c].plot(f["t"], f["dip"], lw=0.6, color="k")
            axes[1, c].axhline(f["first_dip"], color="0.5", ls="--", lw=0.8, label="first second's (the reference)")
            for rule, series in f["rules"].items():
                axes[2, c].plot(f["t"], series["weight"], lw=0.7, label=rule)
                axes[3, c].plot(f["t"], series["heading_error"], lw=0.7,
                                label=f"{rule}: {series['heading_rmse_deg']:.1f} deg")
            axes[3, c].set_xlabel("time (s)")
            axes[3, c].legend(fontsize=7, title=f"VQF {f['vqf_heading_rmse_deg']:.1f} deg", title_fontsize=7)
        axes[0, 0].set_ylabel("|m| / first second's")
        axes[1, 0].set_ylabel("dip, true vertical (deg)")
        axes[1, 0].legend(fontsize=7)
        axes[2, 0].set_ylabel("magnetometer weight")
        axes[2, 0].legend(fontsize=7)
        axes[3, 0].set_ylabel("heading error (deg)")
        fig.tight_layout()
        return save_figure(fig, Path(path), dpi=90)
    finally:
        plt.close(fig)


def main(argv=None) -> int:
    """Command line (see the module docstring); returns 0 (2 for a bad folder or recording name).
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    parser = argparse.ArgumentParser(prog="python -m quadcosim.benchmarks.magnetic",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--recordings", default=",".join(EXAMPLES), help="comma-separated DATASET/NAME")
    parser.add_argument("--figure", help="draw the series into this PNG file")
    args = parser.parse_args(argv)
    wanted = [r.strip() for r in args.recordings.split(",") if r.strip()]
    found = {}
    for item in wanted:
        dataset, _, name = item.partition("/")
        recordings = dict(datasets.load(args.folder, dataset)) if dataset in datasets.LOADERS else {}
        if name not in recordings:
            from quadcosim.infra.errors import UsageError

            raise UsageError(f"no usable recording {item} under {args.folder}; give DATASET/NAME, DATASET one of "
                             f"{', '.join(datasets.LOADERS)}")
        found[item] = analyse(recordings[name])
        rules = found[item]["rules"]
        print(f"{item}: " + "; ".join(f"{rule}: rejected {r['rejected_share']:.0%} of the time, longest "
                                      f"{r['longest_rejection_s']:.1f} s, heading {r['heading_rmse_deg']:.2f} deg"
                                      for rule, r in rules.items())
              + f"; VQF heading {found[item]['vqf_heading_rmse_deg']:.2f} deg")
    if args.figure:
        print(figure(found, args.figure))
    return 0


if __name__ == "__main__":  # the same as quadcosim bench magnetic
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim bench magnetic").run, main)
