"""Findings of the FMUs' numerics: their sub-steps converged, their Modelica twins matched.

``python -m quadcosim.fmus.agreement`` prints both, in parts per million (ppm) of each output's peak
(:mod:`quadcosim.fmus.agreement`); ``tests/test_substep.py`` and ``tests/test_twins.py`` bound the same
cases (``1`` ppm, and ``20`` ppm for the motors' twin). Deterministic: the tolerances are the
printed rounding. The twins need the ``modelica`` toolchain (a dev dependency): without it the
group is skipped.
"""

from __future__ import annotations

from findings import finding

COMMAND = "python -m quadcosim.fmus.agreement"
TOLERANCE_PPM = 0.01  # ppm: deterministic figures, printed to 2 decimals
DIGITS = 2
# finding name -> the case of quadcosim.fmus.agreement.TWIN_CASES
TWINS = {"quadrotor": "Quadrotor", "quadrotor_clamped": "Quadrotor clamped", "motor_magnetics": "MotorMagnetics",
         "motor_magnetics_bounds_free_wheeling": "MotorMagnetics on the current bounds, free-wheeling",
         "motor_magnetics_bounds_regenerative": "MotorMagnetics on the current bounds, regenerative",
         "imu": "IMU"}
SUBSTEPS = {"quadrotor": "Quadrotor", "motor_magnetics": "MotorMagnetics"}


def substeps() -> list[dict]:
    """Per integrating FMU, the change (ppm) when its default sub-step is halved, and when twice
    the default is halved."""
    from quadcosim.fmus import agreement

    found = []
    for name, model in SUBSTEPS.items():
        step = agreement.default_sub_step(model)
        for label, at in (("default", step), ("doubled", 2 * step)):
            found.append(finding(f"fmu_agreement.substep.{name}_{label}_ppm",
                                 agreement.change_when_halved(model, at) / agreement.PPM, "ppm",
                                 f"{COMMAND} --substeps", TOLERANCE_PPM, DIGITS))
    return found


def twins() -> list[dict]:
    """Per twin case, the largest difference (ppm of the peak) between the twin and its FMU."""
    import importlib.util

    if importlib.util.find_spec("modelica") is None:
        raise FileNotFoundError("the modelica toolchain is not installed (pip install -e '.[dev]')")
    from quadcosim.fmus import agreement

    return [finding(f"fmu_agreement.twin.{name}_ppm", agreement.twin_difference(label)[0] / agreement.PPM, "ppm",
                    f"{COMMAND} --twins", TOLERANCE_PPM, DIGITS) for name, label in TWINS.items()]


def compute(quick: bool = False) -> list[dict]:
    """The numerics findings; ``quick``: the sub-steps alone (seconds; the twins take minutes)."""
    return substeps() if quick else substeps() + twins()
