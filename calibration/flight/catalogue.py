"""The interference models a flight calibration fits, registered one line each in the entry-point
group ``quadcosim.interference`` (:mod:`quadcosim.infra.members`)::

    [project.entry-points."quadcosim.interference"]
    current = "quadcosim.calibration.flight.models:CURRENT"

The line's value is a :class:`Model`: how the model is built, its rank and what can carry it, the
calibration file (:class:`quadcosim.calibration.Calibration`) and the autopilots' parameters
(:mod:`quadcosim.calibration.flight.export`). :func:`models` gives them in the order they are fitted
(a model may start from one fitted before it).

Adding a model is one file (its class: ``refusal(parts)`` and ``fit(parts)``, as
:mod:`quadcosim.calibration.flight.models`, and its :class:`Model`) and one registry line; the
command line's ``--models``, the calibration's metrics, the file's choice and the documentation's
table follow.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from quadcosim.calibration.dynamic import MotorFieldModel

#: The entry-point group of the interference models.
GROUP = "quadcosim.interference"


@dataclass(frozen=True)
class Model:
    """One interference model.

    Attributes
    ----------
    name : str
        As ``--models``, ``metrics.json`` and the calibration file name it.
    build : callable
        The models fitted before it, by name (dict of :class:`quadcosim.calibration.flight.models.Fitted`),
        to the model to fit: an object with ``refusal(parts)`` (the reason the flights cannot
        identify it, or None) and ``fit(parts)`` (a ``Fitted``).
    preference : int
        Rank, richest first, shared by the file and the export: each carries the first model
        it can that the flights identify.
    to_file : callable or None
        ``(fitted, motors)``: the fitted model (a :class:`quadcosim.calibration.flight.models.Fitted`) on
        a vehicle of ``motors`` motors as the calibration file carries it, a
        :class:`quadcosim.calibration.MotorFieldModel`; None: the file cannot carry it.
    autopilot : bool
        The autopilots' motor compensation can carry it (ArduPilot ``COMPASS_MOTCT`` or
        ``COMPASS_PMOT``, PX4 ``CAL_MAG_COMP_TYP``: the names an autopilot's ``motor_models`` gives,
        :class:`quadcosim.flightlogs.autopilots.Autopilot`).
    order : int
        Its place in the fitting order: the models are fitted by increasing ``order`` (ties by name),
        so ``build`` may start from the models of a lower order (by default after the package's own).
    """

    name: str
    build: Callable[[dict], object]
    preference: int
    to_file: Callable[[object, int], MotorFieldModel] | None = None
    autopilot: bool = False
    order: int = 10

    @property
    def in_file(self) -> bool:
        """The calibration file can carry it."""
        return self.to_file is not None


def models() -> dict[str, Model]:
    """The installed interference models, name: :class:`Model`, in the order they are fitted.

    Raises
    ------
    quadcosim.infra.members.RegistrationRefused
        A registry line names something that is not a :class:`Model` of the line's own name.
    """
    from quadcosim.infra.members import loaded

    return dict(sorted(loaded(GROUP, Model).items(), key=lambda pair: (pair[1].order, pair[0])))


def preferred(capable: str) -> tuple[str, ...]:
    """The models ``capable`` (``"in_file"`` or ``"autopilot"``) can carry, richest first."""
    known = models()
    return tuple(sorted((name for name, model in known.items() if getattr(model, capable)),
                        key=lambda name: known[name].preference))
