"""Elementary functions and a small inverse that give the same bits on every CPU, for what a run
computes once before it starts (input profiles, the mixer).

numpy evaluates ``sin`` or ``arctan`` of an array with whichever kernel the CPU offers: on a
CPU with AVX-512 its wheels call Intel's SVML (``__svml_sin8``, ``__svml_atan8``), elsewhere the
C library, whose own variants differ again with and without FMA. Each is accurate to an ulp or
so, but not the same ulp, so a profile drawn with them (a bank angle, a motor command) differs
in its last bits from one machine to the next, and so does every signal it drives.

These functions use only additions, multiplications, divisions and square roots, which IEEE 754
rounds the same way everywhere, in a fixed order: their result depends on the argument alone.
They are accurate to a few ulp, which a profile does not notice. They are for profiles computed
once before a run, not for a step's hot path.

LAPACK's inverse is no better: OpenBLAS picks its kernels by CPU (its AVX-512 ones on a CPU that
has them), and the inverse of the quad-X's allocation matrix comes out a few ulp apart between
them; :func:`inverse` solves in plain Python floats, in a fixed order.
"""

from __future__ import annotations

import numpy as np

# pi/2 split in three: the first two have 25 and 23 significant bits, so that k times them is exact
# for |k| < 2**26, and the reduction x - k pi/2 keeps its accuracy for |x| up to about 1e7 rad.
_HALF_PI_HI = float.fromhex("0x1.921fb5p+0")
_HALF_PI_MID = float.fromhex("0x1.110b44p-26")
_HALF_PI_LO = float.fromhex("0x1.08d313198a2e0p-49")
_TWO_OVER_PI = 0.6366197723675814

_SIN_TERMS = 9  # Taylor terms on |r| <= pi/4: the first left out is 0.79**19 / 19! < 1e-19
_ATAN_TERMS = 13  # on |u| <= tan(pi/16) = 0.199: the first left out is 0.199**27 / 27 < 1e-20


def _sin_cos_reduced(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin and cos of ``r`` in [-pi/4, pi/4] by their Taylor series, summed by Horner's rule."""
    z = r * r
    s = np.zeros_like(r)
    c = np.zeros_like(r)
    for n in range(_SIN_TERMS, 0, -1):
        # sin r = r (1 - z/(2*3) (1 - z/(4*5) (...))), cos r = 1 - z/(1*2) (1 - z/(3*4) (...))
        s = 1.0 - z / ((2 * n) * (2 * n + 1)) * s
        c = 1.0 - z / ((2 * n - 1) * (2 * n)) * c
    return r * s, c


def _reduce(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``x`` as ``r + k pi/2`` with ``r`` in [-pi/4, pi/4]: (r, k mod 4)."""
    k = np.rint(x * _TWO_OVER_PI)
    r = ((x - k * _HALF_PI_HI) - k * _HALF_PI_MID) - k * _HALF_PI_LO
    return r, np.mod(k, 4).astype(np.int64)


def sin(x) -> np.ndarray:
    """Sine, with the same bits on every CPU.

    Parameters
    ----------
    x : array_like
        Angles (rad), finite, of magnitude below about 1e7.

    Returns
    -------
    numpy.ndarray
        ``sin(x)``, float64, within a few ulp of the exact value.
    """
    r, quadrant = _reduce(np.asarray(x, dtype=float))
    s, c = _sin_cos_reduced(r)
    return np.choose(quadrant, (s, c, -s, -c))


def cos(x) -> np.ndarray:
    """Cosine, with the same bits on every CPU.

    Parameters
    ----------
    x : array_like
        Angles (rad), finite, of magnitude below about 1e7.

    Returns
    -------
    numpy.ndarray
        ``cos(x)``, float64, within a few ulp of the exact value.
    """
    r, quadrant = _reduce(np.asarray(x, dtype=float))
    s, c = _sin_cos_reduced(r)
    return np.choose(quadrant, (c, -s, -c, s))


def arctan(x) -> np.ndarray:
    """Arc tangent, with the same bits on every CPU.

    Three halvings of the angle, ``atan x = 2 atan(x / (1 + sqrt(1 + x^2)))``, bring the argument
    within tan(pi/16), where the Taylor series converges fast.

    Parameters
    ----------
    x : array_like
        Finite values (1), of magnitude below 1e150 (so that ``x^2`` does not overflow).

    Returns
    -------
    numpy.ndarray
        ``arctan(x)`` (rad), float64, in (-pi/2, pi/2), within a few ulp of the exact value.
    """
    u = np.asarray(x, dtype=float)
    for _ in range(3):
        u = u / (1.0 + np.sqrt(1.0 + u * u))
    z = u * u
    series = np.zeros_like(u)
    for n in range(_ATAN_TERMS, 0, -1):
        series = 1.0 / (2 * n + 1) - z * series  # u (1 - z/3 + z^2/5 - ...)
    return 8.0 * (u - u * z * series)


def inverse(matrix) -> np.ndarray:
    """Inverse of a small square matrix, with the same bits on every CPU.

    LU factorisation with partial pivoting (the largest magnitude first, the lowest row on a tie),
    then one forward and one back substitution per column of the identity, in Python floats: each
    operation rounded once, in a fixed order, whatever BLAS kernels or FMA units the CPU has.
    For matrices of a few rows computed once (a mixer), not for large systems.

    Parameters
    ----------
    matrix : array_like
        ``(n, n)`` finite values.

    Returns
    -------
    numpy.ndarray
        ``(n, n)`` float64 inverse.

    Raises
    ------
    ValueError
        If the matrix is not square and finite, or is singular (a zero pivot).
    """
    a = np.asarray(matrix, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or not np.isfinite(a).all():
        raise ValueError(f"inverse needs a finite square matrix, got shape {a.shape}")
    n = a.shape[0]
    lu = a.tolist()
    order = list(range(n))
    for k in range(n):
        pivot = max(range(k, n), key=lambda i: (abs(lu[i][k]), -i))
        if lu[pivot][k] == 0.0:
            raise ValueError(f"the matrix is singular (no pivot in column {k}): it has no inverse")
        lu[k], lu[pivot] = lu[pivot], lu[k]
        order[k], order[pivot] = order[pivot], order[k]
        for i in range(k + 1, n):
            lu[i][k] /= lu[k][k]
            for j in range(k + 1, n):
                lu[i][j] -= lu[i][k] * lu[k][j]
    result = np.empty((n, n))
    for column in range(n):
        y = [1.0 if order[i] == column else 0.0 for i in range(n)]
        for i in range(n):
            for j in range(i):
                y[i] -= lu[i][j] * y[j]
        for i in reversed(range(n)):
            for j in range(i + 1, n):
                y[i] -= lu[i][j] * y[j]
            y[i] /= lu[i][i]
        result[:, column] = y
    return result
