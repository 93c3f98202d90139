"""Six short runs whose every recorded signal is kept as a reference, and the tools around them.

The references (``tests/data/trajectories.npz``, with ``trajectory_tolerances.json``) hold each
signal at :data:`POINTS` instants spread over its run, and a tolerance per signal set from the
spread measured across BLAS kernels, numba's CPU target, numpy's SIMD dispatch and the C
library's FMA and non-FMA variants (:data:`VARIANTS`): ten times that spread.

- The co-simulation runs (:data:`RUNS`) are closed loops whose FMUs call the C library: one ulp
  there reaches every signal, and paths this machine cannot take (another CPU's BLAS kernels)
  may move what moved nowhere here. Their tolerance is never less than ten times four ulp of the
  signal's largest value. A gain changed by one part in a million goes far beyond it.
- The filters alone (:data:`FILTERS`), at the lab's gains, on inputs computed with
  :mod:`quadcosim.orchestrator.portable` (the same bits on every CPU): what moved nowhere must match to the
  bit. A sum reordered inside a filter fails them.

``tests/test_trajectories_unchanged.py`` compares a fresh run with them.

Run as a script (``python tests/trajectory_runs.py``):

- ``references``: re-run every variant in a subprocess and rewrite the references (after a
  deliberate change of physics or numerics);
- ``digests [--save]``: bit-exact digests of every signal on this machine, saved to
  ``build/trajectory-digests.json`` on the first call and compared on the next (``make
  digests``): the check to run before and after a refactor that must not change one bit.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REFERENCES = ROOT / "tests" / "data" / "trajectories.npz"
TOLERANCES = ROOT / "tests" / "data" / "trajectory_tolerances.json"
DIGESTS = ROOT / "build" / "trajectory-digests.json"

RUNS = {
    "tp-linear": ("tp", {"duration": 2.0}),
    "tp-explicit-noise-bias-nonstationary-estimate": ("tp", {"duration": 2.0, "estimator": "explicit", "noise": True,
                                                              "bias": True, "flight": "nonstationary",
                                                              "feedback": "estimate", "seed": 3}),
    "tp-passive-triad-magnetic": ("tp", {"duration": 2.0, "estimator": "passive", "ry": "triad", "bias": True,
                                         "magnetic": True, "noise": True}),
    "open-loop-noise": ("open-loop", {"duration": 1.0, "noise": True, "bias": True}),
    "rig": ("rig", {"reference": 0.2, "sweep": 0.2, "noise": True}),
    "ir-calibration": ("ir-calibration", {"duration": 20.0}),
}
#: The filters on :func:`synthetic_imu`: (kind, gains, options of :func:`quadcosim.estimators.estimate`).
#: The lab's (its gains, corrections off, as ``tp`` runs them), and the one recommended for real
#: recordings at its defaults.
_LAB = {"corrections": False}
FILTERS = {
    "filter-linear": ("linear", "lab", {}),
    "filter-explicit": ("explicit", "lab", _LAB),
    "filter-explicit-bias": ("explicit", {"kI": 0.01}, _LAB),
    "filter-passive-triad": ("passive", "lab", _LAB | {"ry": "triad"}),
    "filter-passive-euler": ("passive", "lab", _LAB | {"ry": "triad", "discretisation": "euler"}),
    "filter-recommended": ("recommended", None, {}),
}
#: Instants kept of each signal, spread evenly over its run (the first and the last included).
POINTS = 100
#: A floor of the spread, in ulp of a signal's largest value: one libm difference, a few times.
ULP_FLOOR = 4
#: How many times the measured spread a tolerance is.
MARGIN = 10.0
_NO_FMA = "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-FMA4"
#: The environments the spread is measured in: each changes which kernels compute the run.
VARIANTS = {
    "host": {},
    "openblas-haswell": {"OPENBLAS_CORETYPE": "Haswell"},
    "openblas-zen": {"OPENBLAS_CORETYPE": "Zen"},
    "openblas-prescott": {"OPENBLAS_CORETYPE": "Prescott"},
    "openblas-skylakex": {"OPENBLAS_CORETYPE": "SkylakeX"},  # AVX-512 machines only
    "numba-generic": {"NUMBA_CPU_NAME": "generic"},
    "numpy-baseline": {"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"},
    "libm-without-fma": {"GLIBC_TUNABLES": _NO_FMA},
}


def synthetic_imu(seconds: float = 4.0, dt: float = 1e-3) -> dict[str, np.ndarray]:
    """Gyro (rad/s), accelerometer (m/s^2) and magnetometer (T) of a body swinging in roll, pitch
    and yaw, with a gyro bias and uniform noise: the same bits on every CPU."""
    from quadcosim.estimators.filters import references
    from quadcosim.orchestrator import portable

    t = np.arange(int(round(seconds / dt))) * dt
    roll, pitch, yaw = 0.4 * portable.sin(1.3 * t), 0.3 * portable.sin(0.9 * t + 0.5), 1.2 * portable.sin(0.4 * t)
    rates = (0.4 * 1.3 * portable.cos(1.3 * t), 0.3 * 0.9 * portable.cos(0.9 * t + 0.5),
             1.2 * 0.4 * portable.cos(0.4 * t))
    cr, sr, cp, sp = portable.cos(roll), portable.sin(roll), portable.cos(pitch), portable.sin(pitch)
    cy, sy = portable.cos(yaw), portable.sin(yaw)
    # Z-Y-X: body rates from the Euler rates, and R (body to NED) transposed onto the references
    gyro = np.column_stack([rates[0] - sp * rates[2], cr * rates[1] + sr * cp * rates[2],
                            -sr * rates[1] + cr * cp * rates[2]])
    rows = [[cp * cy, cp * sy, -sp], [sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, sr * cp],
            [cr * sp * cy + sr * sy, cr * sp * sy - sr * cy, cr * cp]]
    gravity, field = references()[:2]
    body = [np.column_stack([sum(row[j] * v[j] for j in range(3)) for row in rows]) for v in (-np.asarray(gravity),
                                                                                             np.asarray(field))]
    rng = np.random.default_rng(5)
    noise = [rng.uniform(-1.0, 1.0, (len(t), 3)) * scale for scale in (0.01, 0.05, 2e-7)]
    return {"gyro": gyro + np.array([0.02, -0.01, 0.015]) + noise[0], "acc": body[0] + noise[1],
            "mag": body[1] + noise[2], "dt": dt}


def record(label: str) -> dict[str, np.ndarray]:
    """Every recorded signal of run ``label`` of :data:`RUNS` and ``time``, or every output of
    filter ``label`` of :data:`FILTERS`, whole."""
    if label in FILTERS:
        from quadcosim.estimators import LAB_GAINS, RECOMMENDED, estimate

        kind, gains, options = FILTERS[label]
        if kind == "recommended":
            kind = RECOMMENDED
        elif gains is not None:
            gains = LAB_GAINS[kind] | ({} if gains == "lab" else gains)
        out = estimate(kind, **synthetic_imu(), gains=gains, outputs=("q", "b"), **options)
        return {f"{name}{i}": np.asarray(out[name])[..., i].ravel() for name in ("q", "b")
                for i in range(np.asarray(out[name]).shape[-1])}
    from quadcosim import scenarios

    name, options = RUNS[label]
    result, _ = scenarios.run(name, dict(options))
    return {signal: np.asarray(result[signal]) for signal in result.names} | {"time": np.asarray(result.time)}


def kept(values: np.ndarray) -> np.ndarray:
    """The :data:`POINTS` instants of a signal that the references keep."""
    index = np.unique(np.linspace(0, len(values) - 1, POINTS).round().astype(int))
    return np.asarray(values)[index]


def key(label: str, signal: str) -> str:
    return f"{label}/{signal}"


def load_references() -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """The stored references (kept instants) and their tolerances, by :func:`key`."""
    with np.load(REFERENCES) as stored:
        arrays = {name: stored[name] for name in stored.files}
    return arrays, json.loads(TOLERANCES.read_text())["tolerances"]


def compare(label: str, signals: dict[str, np.ndarray], references: dict[str, np.ndarray],
            tolerances: dict[str, float]) -> list[str]:
    """What differs between a run's ``signals`` and the references: one line per signal whose
    largest difference at the kept instants exceeds its tolerance, or that is missing or new."""
    expected = {name.split("/", 1)[1] for name in references if name.startswith(label + "/")}
    problems = [f"{signal}: not recorded any more" for signal in sorted(expected - set(signals))]
    problems += [f"{signal}: recorded now, not in the references" for signal in sorted(set(signals) - expected)]
    for signal in sorted(expected & set(signals)):
        now, then = kept(signals[signal]), references[key(label, signal)]
        if now.shape != then.shape:
            problems.append(f"{signal}: shape {now.shape}, {then.shape} in the references")
            continue
        gap = np.abs(now - then)
        gap[np.isnan(now) & np.isnan(then)] = 0.0
        worst = float(np.max(gap, initial=0.0)) if not np.isnan(gap).any() else float("inf")
        if worst > tolerances[key(label, signal)]:
            problems.append(f"{signal}: differs by {worst:.3g}, tolerance {tolerances[key(label, signal)]:.3g}")
    return problems


def _save_variant(path: Path):
    """Every run, kept instants only, into ``path`` (a variant's subprocess)."""
    arrays = {}
    for label in [*RUNS, *FILTERS]:
        arrays |= {key(label, signal): kept(values) for signal, values in record(label).items()}
    np.savez(path, **arrays)


def _supported(environment: dict) -> bool:
    """Whether this CPU can run a variant (OpenBLAS's SkylakeX kernels need AVX-512)."""
    if environment.get("OPENBLAS_CORETYPE") != "SkylakeX":
        return True
    return "avx512f" in Path("/proc/cpuinfo").read_text()


def floor(name: str, values: np.ndarray) -> float:
    """The least spread a tolerance assumes: four ulp of the largest value for a co-simulation
    run, none for a filter alone."""
    if name.split("/", 1)[0] in FILTERS:
        return 0.0
    return ULP_FLOOR * float(np.spacing(np.nanmax(np.abs(values), initial=0.0)))


def make_references():
    """Run every supported variant, and write the host's signals with tolerances from the spread."""
    runs = {}
    with tempfile.TemporaryDirectory() as folder:
        for variant, environment in VARIANTS.items():
            if not _supported(environment):
                print(f"{variant}: skipped (this CPU cannot run it)")
                continue
            path = Path(folder) / f"{variant}.npz"
            subprocess.run([sys.executable, __file__, "_variant", str(path)], check=True,
                           env=os.environ | environment)
            with np.load(path) as arrays:
                runs[variant] = {name: arrays[name] for name in arrays.files}
            print(f"{variant}: {len(runs[variant])} signals")
    host = runs.pop("host")
    spread, tolerances = {}, {}
    for name, values in host.items():
        gaps = [np.nanmax(np.abs(other[name] - values), initial=0.0) for other in runs.values()]
        spread[name] = float(max(gaps, default=0.0))
        tolerances[name] = MARGIN * max(spread[name], floor(name, values))
    np.savez_compressed(REFERENCES, **host)
    TOLERANCES.write_text(json.dumps({
        "about": (f"Tolerance of each signal: {MARGIN:g} times the largest difference from the host run "
                  f"across the variants; for a co-simulation run, at least {MARGIN:g} times {ULP_FLOOR} ulp of "
                  "its largest value. Made by `python tests/trajectory_runs.py references`."),
        "variants": {v: VARIANTS[v] for v in ["host", *runs]},
        "spread": spread,
        "tolerances": tolerances,
    }, indent=1, sort_keys=True) + "\n")
    moved = sum(1 for s in spread.values() if s > 0)
    print(f"{len(host)} signals; {moved} moved across the variants, by {max(spread.values()):.3g} at most")


def digest(values: np.ndarray) -> str:
    return hashlib.sha256(np.ascontiguousarray(values).tobytes()).hexdigest()[:16]


def digests(save: bool) -> int:
    """Compare this machine's bit-exact digests with the saved ones (or save them); exit code."""
    now = {key(label, signal): digest(values) for label in [*RUNS, *FILTERS]
           for signal, values in record(label).items()}
    if save or not DIGESTS.is_file():
        DIGESTS.parent.mkdir(parents=True, exist_ok=True)
        DIGESTS.write_text(json.dumps(now, indent=1, sort_keys=True) + "\n")
        print(f"saved the digests of {len(now)} signals to {DIGESTS.relative_to(ROOT)}; "
              "run `make digests` again after your change to compare")
        return 0
    before = json.loads(DIGESTS.read_text())
    changed = sorted(name for name in before.keys() | now.keys() if before.get(name) != now.get(name))
    for name in changed:
        print(f"changed: {name}")
    print(f"{len(changed)} of {len(now)} signals changed to the bit" if changed else
          f"all {len(now)} signals unchanged to the bit")
    return 1 if changed else 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("references", help="re-measure the spread and rewrite the references")
    digest_parser = commands.add_parser("digests", help="bit-exact digests on this machine, saved or compared")
    digest_parser.add_argument("--save", action="store_true", help="save the digests even if some are saved")
    variant = commands.add_parser("_variant")
    variant.add_argument("path", type=Path)
    arguments = parser.parse_args(argv)
    if arguments.command == "references":
        make_references()
    elif arguments.command == "digests":
        return digests(arguments.save)
    else:
        _save_variant(arguments.path)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
