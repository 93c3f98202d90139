"""The interference models a flight calibration fits, one line each in :data:`MODELS`, in the
order they are fitted (a model may start from one fitted before it), with what each can be
carried by: the calibration file (:class:`calibration.Calibration`) and the autopilots'
parameters (:mod:`calibration.flight.export`).

Adding a model is one file (its class: ``refusal(parts)`` and ``fit(parts)``, as
:mod:`calibration.flight.models`) and one line here; the command line's ``--models``, the
calibration's metrics and the file's choice follow.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from calibration.flight.dynamic import DynamicModel
from calibration.flight.models import LinearModel, MetgeModel


@dataclass(frozen=True)
class Model:
    """One interference model.

    Attributes
    ----------
    name : str
        As ``--models``, ``metrics.json`` and the calibration file name it.
    build : callable
        The models fitted before it, by name (dict of :class:`calibration.flight.models.Fitted`),
        to the model to fit: an object with ``refusal(parts)`` (the reason the flights cannot
        identify it, or None) and ``fit(parts)`` (a ``Fitted``).
    preference : int
        Rank, richest first, shared by the file and the export: each carries the first model
        it can that the flights identify.
    in_file : bool
        The calibration file can carry it (as a :class:`calibration.MotorFieldModel`).
    autopilot : bool
        The autopilots' motor compensation can carry it (ArduPilot ``COMPASS_MOTCT`` or
        ``COMPASS_PMOT``, PX4 ``CAL_MAG_COMP_TYP``).
    """

    name: str
    build: Callable[[dict], object]
    preference: int
    in_file: bool = False
    autopilot: bool = False


MODELS = {model.name: model for model in (
    Model("current", lambda fitted: LinearModel("current"), preference=1, autopilot=True),
    Model("throttle", lambda fitted: LinearModel("throttle"), preference=3, in_file=True, autopilot=True),
    Model("motors", lambda fitted: LinearModel("motors"), preference=2, in_file=True, autopilot=True),
    Model("metge", lambda fitted: MetgeModel(fitted.get("motors")), preference=0, in_file=True),
    Model("dynamic", lambda fitted: DynamicModel(fitted.get("metge")), preference=4),
)}


def preferred(capable: str) -> tuple[str, ...]:
    """The models ``capable`` (``"in_file"`` or ``"autopilot"``) can carry, richest first."""
    return tuple(sorted((name for name, model in MODELS.items() if getattr(model, capable)),
                        key=lambda name: MODELS[name].preference))
