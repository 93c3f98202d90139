"""Attitude estimators: the lab's ``Quaternion_estim`` variants, and their analysis.

- :class:`QuaternionEstim`: the streaming block (``linear``, ``explicit``, ``passive``);
- :func:`estimate`: the same filters on recorded arrays, many gain sets at once;
- :mod:`estimators.analysis`: python-control analyses of the gains.
"""

from estimators.filters import DEFAULT_GAINS, QuaternionEstim, estimate

__all__ = ["DEFAULT_GAINS", "QuaternionEstim", "estimate"]
