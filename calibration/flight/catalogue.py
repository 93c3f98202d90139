"""The interference models a flight calibration fits, one line each in :data:`MODELS`, in the
order they are fitted (a model may start from one fitted before it), with what each can be
carried by: the calibration file (:class:`quadcosim.calibration.Calibration`) and the autopilots'
parameters (:mod:`quadcosim.calibration.flight.export`).

Adding a model is one file (its class: ``refusal(parts)`` and ``fit(parts)``, as
:mod:`quadcosim.calibration.flight.models`) and one line here; the command line's ``--models``, the
calibration's metrics and the file's choice follow.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from quadcosim.calibration.dynamic import MotorFieldModel
from quadcosim.calibration.flight.dynamic import DynamicModel
from quadcosim.calibration.flight.models import LinearModel, MetgeModel


def _vectors_field(vectors) -> MotorFieldModel:
    """Field vectors per motor (motors, 3) (T per unit command) as the file's model (eqs. 3, 4 of
    Metge et al.): unit directions and magnitudes, the field linear in each command."""
    norms = np.linalg.norm(vectors, axis=1)
    safe = np.where(norms > 0, norms, 1.0)
    directions = np.where(norms[:, None] > 0, vectors / safe[:, None], np.array([1.0, 0.0, 0.0]))
    return MotorFieldModel(directions, norms[:, None], (1, 0))


def _motors_field(fitted, motors: int) -> MotorFieldModel:
    return _vectors_field(fitted.extra["K"])


def _throttle_field(fitted, motors: int) -> MotorFieldModel:
    return _vectors_field(np.repeat(fitted.extra["K"] / motors, motors, axis=0))  # throttle = mean command


def _metge_field(fitted, motors: int) -> MotorFieldModel:
    return fitted.extra["field"]


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
        ``COMPASS_PMOT``, PX4 ``CAL_MAG_COMP_TYP``).
    """

    name: str
    build: Callable[[dict], object]
    preference: int
    to_file: Callable[[object, int], MotorFieldModel] | None = None
    autopilot: bool = False

    @property
    def in_file(self) -> bool:
        """The calibration file can carry it."""
        return self.to_file is not None


MODELS = {model.name: model for model in (
    Model("current", lambda fitted: LinearModel("current"), preference=1, autopilot=True),
    Model("throttle", lambda fitted: LinearModel("throttle"), preference=3, to_file=_throttle_field, autopilot=True),
    Model("motors", lambda fitted: LinearModel("motors"), preference=2, to_file=_motors_field, autopilot=True),
    Model("metge", lambda fitted: MetgeModel(fitted.get("motors")), preference=0, to_file=_metge_field),
    Model("dynamic", lambda fitted: DynamicModel(fitted.get("metge")), preference=4),
)}


def preferred(capable: str) -> tuple[str, ...]:
    """The models ``capable`` (``"in_file"`` or ``"autopilot"``) can carry, richest first."""
    return tuple(sorted((name for name, model in MODELS.items() if getattr(model, capable)),
                        key=lambda name: MODELS[name].preference))
