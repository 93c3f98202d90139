"""Metge's studies on the closed loop: the yaw error of each estimator with the motor currents'
field compensated, the compensation on perturbed plants (:mod:`quadcosim.studies.metge_robustness`) and the
free set's ablation (:mod:`quadcosim.studies.metge_free`).

    python -m quadcosim.studies.metge --calibration FILE --out DIR
    python -m quadcosim.studies.metge --robustness [CASE ...] --out DIR
    python -m quadcosim.studies.metge --free-set [CASE ...] --out DIR
"""

from __future__ import annotations

from pathlib import Path

from quadcosim.estimators import kinds
from quadcosim.scenarios.compensation import COMPENSATIONS

from quadcosim.infra.files import write_json, write_text

# --- the closed loop: yaw error per estimator and compensation --------------------------

STUDY_ESTIMATORS = kinds.compared()


def yaw_study(out, calibration_path: str, flights=("quasi", "nonstationary"), estimators=tuple(STUDY_ESTIMATORS),
              duration: float = 20.0, noise: bool = True) -> dict:
    """``tp`` with the field of the motor currents off, then on with each compensation; the
    estimators' yaw RMS error (deg) for each, written to ``out/yaw_study.json`` and ``.md``.
    ``calibration_path``: the calibration file; ``flights``, ``estimators``: those compared;
    ``duration`` (s) and ``noise``: of every run."""
    from quadcosim import scenarios

    out = Path(out)
    table = {}
    cases = [("off", "none")] + [("on", mode) for mode in COMPENSATIONS]
    for flight in flights:
        for estimator in estimators:
            for magnetic, mode in cases:
                settings = {"estimator": estimator, "flight": flight, "noise": noise, "duration": duration,
                            "magnetic": magnetic == "on", "compensation": mode,
                            "calibration": calibration_path if mode != "none" else "",
                            **STUDY_ESTIMATORS[estimator]}
                _, m = scenarios.run("tp", settings)
                key = "magnetic_off" if magnetic == "off" else mode
                table.setdefault(flight, {}).setdefault(estimator, {})[key] = m["rms_error_deg"][2]
                print(f"{flight:14s} {estimator:9s} {key:13s} yaw RMS {m['rms_error_deg'][2]:8.3f} deg", flush=True)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "yaw_study.json", table)
    columns = ["magnetic_off", *COMPENSATIONS]
    lines = []
    for flight, rows in table.items():
        lines += [f"### {flight}", "", "| estimator | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
        lines += [f"| {e} | " + " | ".join(f"{r[c]:.3f}" for c in columns) + " |" for e, r in rows.items()]
        lines.append("")
    write_text(out / "yaw_study.md", "\n".join(lines))
    return table


def main(argv=None):
    """Command line of the studies: ``python -m quadcosim.studies.metge --calibration FILE --out DIR``
    (the yaw study), ``--robustness --out DIR`` (:mod:`quadcosim.studies.metge_robustness`) or
    ``--free-set --out DIR`` (:mod:`quadcosim.studies.metge_free`).
    ``argv``: the arguments (default ``sys.argv[1:]``)."""
    import argparse

    parser = argparse.ArgumentParser(description="Yaw error of each estimator with the motor field compensated "
                                                 "(--calibration), the compensation on perturbed plants "
                                                 "(--robustness), or the free set's ablation (--free-set).")
    parser.add_argument("--calibration", help="calibration file, e.g. from quadcosim run metge (the yaw study)")
    parser.add_argument("--robustness", nargs="*", metavar="CASE",
                        help="the robustness study (every case, or those named)")
    parser.add_argument("--free-set", nargs="*", metavar="CASE",
                        help="the free set's ablation (studies/metge_free.py; every case, or those named)")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument("--duration", type=float, default=20.0, help="simulated time of each run (s)")
    parser.add_argument("--estimators", default=",".join(STUDY_ESTIMATORS), help="comma-separated estimators")
    args = parser.parse_args(argv)
    from quadcosim.studies import metge_free, metge_robustness

    for chosen, study in ((args.free_set, metge_free), (args.robustness, metge_robustness)):
        if chosen is not None:  # a study of its own module, with its cases
            unknown = set(chosen) - set(study.cases())
            if unknown:
                parser.error(f"unknown case {', '.join(sorted(unknown))}; cases: {', '.join(study.cases())}")
            study.study(args.out, chosen or None)
            return
    if not args.calibration:
        parser.error("give --calibration FILE (the yaw study), --robustness or --free-set")
    yaw_study(args.out, args.calibration, estimators=tuple(args.estimators.split(",")), duration=args.duration)


if __name__ == "__main__":  # the same as quadcosim study metge
    from quadcosim.infra.command import Command, program

    program(Command("quadcosim study metge").run, main)
