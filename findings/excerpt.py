"""Finding of the recording shipped with the package (``quadcosim.estimators.recording.EXAMPLE``): how long
it rests before it moves, by BROAD's own movement phases (``python -m quadcosim.estimators.recording``)."""

from __future__ import annotations

from findings import finding

COMMAND = "python -m quadcosim.estimators.recording"


def compute(quick: bool = False) -> list[dict]:
    """The excerpt's rest before its first scored sample (s); instant, the same with ``quick``."""
    from quadcosim.estimators import recording

    described = recording.describe(recording.load(recording.EXAMPLE))
    return [finding("excerpt.rest_s", described["before_first_scored_s"], "s", COMMAND, 0.05, 1)]
