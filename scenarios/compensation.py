"""The motor field compensated in a closed loop (``tp --set compensation=...``): a
:class:`quadcosim.calibration.MagCompensator` between the IMU's magnetometer and the estimator, with a
calibration file or one made on the clamped rig of the same vehicle
(:func:`quadcosim.scenarios.metge.rig_calibration`)."""

from __future__ import annotations

from quadcosim.calibration import Calibration
from quadcosim.orchestrator import System
from quadcosim.scenarios.metge import rig_calibration, vehicle_settings

#: The compensations a flight may run, ``none`` first (the option's choices).
COMPENSATIONS = ("none", "static", "metge", "dynamic")


def magnetometer_rate(system: System) -> float:
    """Rate (Hz) at which the system's IMU samples and holds its magnetometer."""
    from fmpy import read_model_description
    from quadcosim.fmus import fmu_path

    imu = system.blocks["IMU"]
    starts = {v.name: v.start for v in read_model_description(str(fmu_path(imu.model))).modelVariables}
    for name in ("mag_sample_rate", "sample_rate"):
        if name in starts:
            return float(imu.parameters.get(name, starts[name]))
    raise KeyError("the IMU declares no magnetometer rate (mag_sample_rate or sample_rate)")


def add_compensator(system: System, mode: str, path: str, options: dict, estimator: str = "Quaternion_estim"):
    """Put a MagCompensator between the IMU's magnetometer and the estimator (nothing for
    ``mode = "none"``): commands from the controller, voltage from the battery, ``b_d``
    refreshed at the magnetometer's sample instants. ``path``: a calibration file, or empty for
    :func:`quadcosim.scenarios.metge.rig_calibration` of the vehicle of the flight's ``options``.
    ``system``: the flight's system; ``estimator``: the name of its block."""
    from quadcosim.calibration import MagCompensator

    if mode == "none":
        if path:
            raise ValueError(f"calibration={path} is given with compensation=none, which uses no calibration: "
                             "choose compensation=static, metge or dynamic, or leave calibration empty")
        return None
    calibration = Calibration.load(path, motors=4) if path else rig_calibration(settings=vehicle_settings(options))
    block = system.add(MagCompensator(calibration, mode, sample_rate=magnetometer_rate(system)))
    system.connect("IMU.magneto", "MagCompensator.magneto")
    system.connect("Controller.c", "MagCompensator.c")
    system.connect("MotorMagnetics.u_batt", "MagCompensator.u_batt")
    system.connect("MagCompensator.magneto", f"{estimator}.magneto")
    return block
