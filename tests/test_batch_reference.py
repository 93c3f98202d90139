"""The C reference of the batch explicit filter (benchmarks/c/batch_explicit.c) computes what
the compiled batch path computes, to the last bit: the benchmark's ratio compares equal work."""

import numpy as np
import pytest
from quadcosim.benchmarks.estimators import _batch_case, _c_batch, _numba_batch


@pytest.mark.parametrize("discretisation", ["exp", "euler"])
def test_the_c_reference_gives_the_batch_path_s_estimates_to_the_last_bit(discretisation):
    case = _batch_case(gain_sets=6, samples=3000, discretisation=discretisation)
    q_numba, q_c = _numba_batch(case), _c_batch(case)
    assert q_c.shape == q_numba.shape == (6, 3000, 4)
    assert np.array_equal(q_c.view(np.uint64), q_numba.view(np.uint64))
    assert len(np.unique(q_numba[:, -1, 1])) == 6  # six gain sets, six different estimates
