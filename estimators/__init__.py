"""Attitude estimators: the lab's ``Quaternion_estim`` variants, published filters, and analysis.

- :class:`QuaternionEstim`: the streaming block (``linear``, ``explicit``, ``passive``, and the
  published ``vqf`` and ``madgwick`` for comparison);
- :data:`RECORDED`: the filter for recorded data, :func:`estimate`'s default (``vqf``, the published filter);
- :data:`RECOMMENDED`: the lab's filter recommended for real recordings (``explicit``, at :data:`DEFAULT_GAINS`,
  set by the time constants :data:`DEFAULT_TIME_CONSTANTS` through :func:`explicit_gains`);
- :func:`estimate`: the same filters on recorded arrays, many gain sets at once
  (:func:`gain_grid` builds them), with errors against a reference reduced in the loop;
- :func:`score`: the quaternion-error RMSE (total, inclination, heading);
- the estimators by name, :mod:`quadcosim.estimators.kinds` (registered by the entry-point group
  ``quadcosim.estimators``), each a module with its gains and their units:
  :mod:`quadcosim.estimators.linear`, :mod:`quadcosim.estimators.explicit`,
  :mod:`quadcosim.estimators.passive`, :mod:`quadcosim.estimators.reference`; their corrections,
  :mod:`quadcosim.estimators.corrections`;
- :mod:`quadcosim.estimators.recording`: recorded files (``.npz``, ``.mat``, ``.csv``) in and out;
- :mod:`quadcosim.estimators.analysis`: python-control analyses of the gains.
"""

from quadcosim.infra import numba_cache

# before the modules below decorate their functions: numba picks a function's cache folder then
numba_cache.install()

from quadcosim.estimators.corrections import CORRECTIONS, parse_corrections
from quadcosim.estimators.explicit import DEFAULT_TIME_CONSTANTS, explicit_gains
from quadcosim.estimators.filters import (
    DEFAULT_GAINS,
    GAIN_MEANINGS,
    LAB_GAINS,
    RECOMMENDED,
    RECORDED,
    QuaternionEstim,
    estimate,
    gain_grid,
    references,
    score,
)

__all__ = ["CORRECTIONS", "DEFAULT_GAINS", "DEFAULT_TIME_CONSTANTS", "GAIN_MEANINGS", "LAB_GAINS", "RECOMMENDED",
           "RECORDED", "QuaternionEstim", "estimate", "explicit_gains", "gain_grid", "parse_corrections", "references",
           "score"]
