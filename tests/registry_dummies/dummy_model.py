"""A dummy interference model for the registry test: no interference at all."""

import numpy as np
from quadcosim.calibration.flight.models import Fitted


class Nothing:
    """Explains nothing: a zero field, identified by any flight."""

    name = "nothing"

    def refusal(self, parts):
        return None

    def fit(self, parts):
        return Fitted("nothing", 0.0, {"K_T": [0.0, 0.0, 0.0]}, lambda data: np.zeros((len(data.time), 3)))
