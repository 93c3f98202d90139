"""The Earth's magnetic field where and when a log was flown, from the World Magnetic Model.

The model is NOAA's World Magnetic Model (WMM), evaluated by the ``pygeomag`` package (pinned in
``pyproject.toml``): a pure-Python port of NOAA's own code that ships the coefficient sets of
WMM2010 to WMM2025 (so logs from 2010 to 2030), with no dependency of its own; IGRF packages
either need pandas or cover the recent epochs only. The coefficient set is chosen by the log's
year (``GeoMag(base_year=...)``), as the model is meant to be used.

With the field known, a flight that mostly turns about the vertical identifies all three offsets:
the vertical component no longer trades against the z offset. Without a GPS fix the field is
left free per flight, and the z offset (and any scale) of a flight without large tilts cannot be
told from the vertical component; the calibration says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NANOTESLA = 1e-9
FIRST_YEAR, LAST_YEAR = 2010.0, 2030.0  # the coefficient sets pygeomag ships


@dataclass(frozen=True)
class EarthField:
    """The model field at a log's position: ``ned`` (3,) (T, North-East-Down, true north),
    ``declination_deg``, ``inclination_deg``, ``model`` (``WMM-2015v2``) and ``where`` (text)."""

    ned: np.ndarray
    declination_deg: float
    inclination_deg: float
    model: str
    where: str


def model_field(position) -> tuple[EarthField | None, str]:
    """The World Magnetic Model's field at ``position`` (a :class:`quadcosim.flightlogs.Position`, or
    None), and a line saying what was used or why not."""
    if position is None:
        return None, ("no GPS fix in the log: the Earth field is left free per flight, so the z offset and the "
                      "scale cannot be told from the field's vertical component unless the flight tilts far")
    if not FIRST_YEAR <= position.year < LAST_YEAR:
        return None, (f"the log's date ({position.year:.1f}) is outside the World Magnetic Model's coefficient sets "
                      f"({FIRST_YEAR:.0f} to {LAST_YEAR:.0f}): the Earth field is left free per flight")
    from pygeomag import GeoMag

    geomag = GeoMag(base_year=int(position.year))
    try:
        result = geomag.calculate(glat=position.latitude_deg, glon=position.longitude_deg,
                                  alt=position.altitude_m / 1e3, time=position.year)
        ned = np.array([result.x, result.y, result.z]) * NANOTESLA
    except (ValueError, ArithmeticError):
        ned = np.full(3, np.nan)
    if not (np.isfinite(ned).all() and abs(position.latitude_deg) <= 90 and abs(position.altitude_m) < MAX_ALTITUDE_M):
        return None, (f"the log's GPS position ({position.latitude_deg:g}, {position.longitude_deg:g}, "
                      f"{position.altitude_m:g} m) is not one the World Magnetic Model covers (a damaged fix?): the "
                      "Earth field is left free per flight")
    where = (f"{geomag.model} at {position.latitude_deg:.4f}, {position.longitude_deg:.4f}, {position.year:.2f} "
             f"({position.source}): {np.linalg.norm(ned) * 1e6:.1f} uT, declination {result.d:.1f} deg, "
             f"inclination {result.i:.1f} deg")
    return EarthField(ned, float(result.d), float(result.i), geomag.model, where), where


MAX_ALTITUDE_M = 1e5  # the model is valid from below sea level to 850 km; a fix beyond 100 km is damaged
MOUNTING_TOLERANCE_DEG = 5.0  # a compass whose heading differs from the model's by more is reported


def align(train, test, fields: dict) -> tuple[list, list, dict]:
    """``train`` and ``test`` (FlightData of one compass) with the Earth field model of their logs
    (``fields``: log path -> :class:`EarthField` or None) attached, turned about the vertical by
    the heading offset the training flights show against it, and that offset checked.

    The model gives the field's magnitude and inclination; the compass's heading against the
    attitude (the model's declination, the compass's yaw mounting and the attitude's own heading
    bias together) comes from the training flights, as the free field's declination minus the
    model's. More than :data:`MOUNTING_TOLERANCE_DEG` is reported: a compass mounted at a yaw its
    orientation parameter does not say, or an attitude whose heading is off.

    The free field is fitted with the throttle's field beside it (one vector per unit throttle, the
    ``throttle`` model's regressor, which every calibrated log has): left out, the motors' field,
    which the flight's turns sample unevenly, leaks into the free field's heading. On the example
    logs that leak was -2.1, -0.6 and +0.6 deg (against 0: their attitude is the truth), and the
    field turned by it left 20 % of the current's horizontal field to the offsets; with the throttle
    beside it, -0.06, -0.08 and -0.05 deg.

    Returns
    -------
    train, test : lists of FlightData
        With ``earth`` set where a field model exists (else unchanged).
    check : dict
        ``offset_deg`` (the heading offset), ``within_tolerance`` and ``note``; empty without a model.
    """
    from dataclasses import replace

    from quadcosim.calibration.flight.linear import fit_linear
    from quadcosim.calibration.flight.models import LinearModel

    if any(fields.get(p.log.path) is None for p in [*train, *test]):
        return train, test, {}
    throttle = LinearModel("throttle")
    free = fit_linear([(p.rotation, p.raw, throttle.regressors(p, 0.0)) for p in train])
    offsets = []
    for p, nuisance in zip(train, free.nuisance, strict=True):
        model = fields[p.log.path].ned
        offsets.append(np.arctan2(nuisance[1], nuisance[0]) - np.arctan2(model[1], model[0]))
    offset = float(np.angle(np.mean(np.exp(1j * np.array(offsets)))))
    turn = np.array([[np.cos(offset), -np.sin(offset), 0.0], [np.sin(offset), np.cos(offset), 0.0], [0.0, 0.0, 1.0]])

    def attach(parts):
        return [replace(p, earth=turn @ fields[p.log.path].ned) for p in parts]

    degrees = float(np.degrees(offset))
    compass = train[0].log.compasses[train[0].compass]
    within = abs(degrees) <= MOUNTING_TOLERANCE_DEG
    note = (f"{compass.name}'s heading differs from the field model's by {degrees:+.1f} deg "
            + ("(within the tolerance)" if within else
               f"(more than {MOUNTING_TOLERANCE_DEG:g} deg: check its yaw mounting and orientation parameter)"))
    return attach(train), attach(test), {"offset_deg": degrees, "within_tolerance": within, "note": note}
