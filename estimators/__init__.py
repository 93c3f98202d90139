"""Attitude estimators: the lab's ``Quaternion_estim`` variants, published filters, and analysis.

- :class:`QuaternionEstim`: the streaming block (``linear``, ``explicit``, ``passive``, and the
  published ``vqf`` and ``madgwick`` for comparison);
- :data:`RECORDED`: the filter for recorded data, :func:`estimate`'s default (``vqf``, the published filter);
- :data:`RECOMMENDED`: the lab's filter recommended for real recordings (``explicit``, at :data:`DEFAULT_GAINS`,
  set by the time constants :data:`DEFAULT_TIME_CONSTANTS` through :func:`explicit_gains`);
- :func:`estimate`: the same filters on recorded arrays, many gain sets at once
  (:func:`gain_grid` builds them), with errors against a reference reduced in the loop;
- :func:`score`: the quaternion-error RMSE (total, inclination, heading);
- :mod:`quadcosim.estimators.recording`: recorded files (``.npz``, ``.mat``, ``.csv``) in and out;
- :mod:`quadcosim.estimators.analysis`: python-control analyses of the gains.
"""

from quadcosim.infra import numba_cache

# before the modules below decorate their functions: numba picks a function's cache folder then
numba_cache.install()

from quadcosim.estimators.filters import (
    CORRECTIONS,
    DEFAULT_GAINS,
    DEFAULT_TIME_CONSTANTS,
    GAIN_MEANINGS,
    LAB_GAINS,
    RECOMMENDED,
    RECORDED,
    QuaternionEstim,
    estimate,
    explicit_gains,
    gain_grid,
    parse_corrections,
    references,
    score,
)

__all__ = ["CORRECTIONS", "DEFAULT_GAINS", "DEFAULT_TIME_CONSTANTS", "GAIN_MEANINGS", "LAB_GAINS", "RECOMMENDED",
           "RECORDED", "QuaternionEstim", "estimate", "explicit_gains", "gain_grid", "parse_corrections", "references",
           "score"]
