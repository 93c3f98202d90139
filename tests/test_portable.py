"""The portable elementary functions: accurate to a few ulp, and the same bits whichever kernels
the machine offers, where numpy's own functions are not (the C library without FMA stands in
for another CPU)."""

import subprocess
import sys

import numpy as np
import pytest
from quadcosim.orchestrator import portable

ANGLES = np.random.default_rng(7).uniform(-60.0, 60.0, 200_000)
RATIOS = np.random.default_rng(8).uniform(-1, 1, 200_000) * 10.0 ** np.random.default_rng(9).uniform(-8, 8, 200_000)
WITHOUT_FMA = {"GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-FMA4",
               "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"}


def ulps(value, exact):
    return np.max(np.abs(value - exact) / np.spacing(np.abs(exact)))


@pytest.mark.parametrize(("ours", "numpy_own", "x", "bound"),
                         [(portable.sin, np.sin, ANGLES, 2), (portable.cos, np.cos, ANGLES, 2),
                          (portable.arctan, np.arctan, RATIOS, 5)])
def test_each_function_is_within_a_few_ulp_of_numpy(ours, numpy_own, x, bound):
    error = ulps(ours(x), numpy_own(x))
    print(f"{ours.__name__}: {error:.0f} ulp at most")
    assert error <= bound  # measured 2, 2 and 5 ulp


def test_quadrants_signs_and_zeros():
    quarter = np.pi / 2 * np.arange(-8, 9)
    assert np.allclose(portable.sin(quarter), np.round(np.sin(quarter)), atol=1e-15)
    assert np.allclose(portable.cos(quarter), np.round(np.cos(quarter)), atol=1e-15)
    assert portable.arctan(np.array([1.0]))[0] == pytest.approx(np.pi / 4, rel=2e-16)
    assert np.array_equal(portable.arctan(-RATIOS), -portable.arctan(RATIOS))  # odd, to the bit
    assert np.array_equal(portable.sin(-ANGLES), -portable.sin(ANGLES))
    assert portable.arctan(np.array([1e150]))[0] == pytest.approx(np.pi / 2, rel=2e-16)


DIGESTS = """
import hashlib, sys
import numpy as np
sys.path.insert(0, {root!r})
from quadcosim.orchestrator import portable
rng = np.random.default_rng(7)
x = rng.uniform(-60.0, 60.0, 200_000)
for f in (portable.sin, portable.arctan, np.sin, np.arctan):
    print(hashlib.sha256(f(x).tobytes()).hexdigest()[:16])
"""


def test_the_bits_do_not_depend_on_the_machines_kernels():
    import os
    from pathlib import Path

    code = DIGESTS.format(root=str(Path(__file__).resolve().parents[1]))
    own = {name: value for name, value in os.environ.items() if name not in WITHOUT_FMA}
    here, other = (subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                  env=environment).stdout.split() for environment in (own, own | WITHOUT_FMA))
    assert here[:2] == other[:2]  # ours: the same bits
    if " fma " in Path("/proc/cpuinfo").read_text():
        assert here[2:] != other[2:]  # numpy's own: other bits, so the change of kernels took effect


def test_the_inverse_inverts_and_refuses_a_singular_matrix():
    from quadcosim.flight.mixer import allocation_matrix

    mixer = allocation_matrix()
    inverse = portable.inverse(mixer)
    assert np.abs(inverse @ mixer - np.eye(4)).max() <= 2 * np.spacing(1.0)  # measured 2.3e-16
    assert np.abs(inverse - np.linalg.inv(mixer)).max() <= 2 * np.spacing(np.abs(inverse).max())  # measured 1 ulp
    shuffled = np.random.default_rng(3).normal(size=(5, 5))
    assert np.abs(portable.inverse(shuffled) @ shuffled - np.eye(5)).max() < 3e-15  # measured 1.5e-15
    with pytest.raises(ValueError, match="singular"):
        portable.inverse([[1.0, 2.0], [2.0, 4.0]])
    with pytest.raises(ValueError, match="square"):
        portable.inverse(np.ones((2, 3)))
