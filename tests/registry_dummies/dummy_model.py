"""A dummy interference model for the registry test: no interference at all, added as a
maintainer adds one: this file (its class and its :class:`Model`) and one registry line
(``nothing = "dummy_model:NOTHING"`` in the group ``quadcosim.interference``)."""

import numpy as np
from quadcosim.calibration.flight.catalogue import Model
from quadcosim.calibration.flight.models import Fitted


class Nothing:
    """Explains nothing: a zero field, identified by any flight."""

    name = "nothing"

    def refusal(self, parts):
        return None

    def fit(self, parts):
        return Fitted("nothing", 0.0, {"K_T": [0.0, 0.0, 0.0]}, lambda data: np.zeros((len(data.time), 3)))


NOTHING = Model("nothing", lambda fitted: Nothing(), preference=5)
