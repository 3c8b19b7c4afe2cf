"""Verified floating point for sparse interlocking matrices: ``sigma_min(A)`` bounded below, and a positive stress.

An "interlocked" verdict rests on two facts about the exact matrix ``A``
(each float entry taken as the rational it represents): full column rank,
and a positive self-stress ``A^T w = 0, w > 0`` (Stiemke).  Both follow
from a floating stress ``w~ > 0`` with a small residual and a proved lower
bound ``sigma`` on the smallest singular value of ``A``
(docs/certificates.md, section '"interlocked" at scale'):

- ``sigma > 0`` is full column rank;
- the exact correction ``delta = -A (A^T A)^{-1} r`` of the exact residual
  ``r = A^T w~`` makes ``A^T (w~ + delta) = 0`` and has
  ``||delta||_inf <= ||r||_2 / sigma``; so ``min w~ > ||r||_2 / sigma``
  proves ``w~ + delta > 0``.

``sigma`` comes from one sparse factorisation of the Gram matrix shifted
by ``s``: if ``P (G - s I) P^T = L D L^T + E`` with ``L`` unit lower
triangular and ``D > 0``, then ``L D L^T`` is positive definite, so
``lambda_min(G) >= s - ||E||_2``; ``E`` is measured a posteriori (the
residual of the computed factors, with every rounding of that product
bounded by ``gamma_k = k u / (1 - k u)``, Higham Thm. 3.5), whatever
algorithm produced them.  The cost is that of the rank stage: one sparse LU.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg

__all__ = ["VerifiedStress", "gamma", "singular_value_bound", "verified_sparse_stress", "GRAM_SHIFTS",
           "REFINEMENT_STEPS"]

#: Shifts ``s`` tried, relative to ``||G||_1`` (an upper bound of ``lambda_max``), largest first: the first whose
#: shifted factorisation has positive pivots gives ``lambda_min(G) >= s - ||E||``.
GRAM_SHIFTS = (1e-6, 1e-8, 1e-10, 1e-11)
#: Iterative-refinement steps that bring the float stress's residual down to rounding before it is bounded.
REFINEMENT_STEPS = 3

_UNIT = 2.0**-53


def gamma(k: int) -> float:
    """``gamma_k = k u / (1 - k u)``: ``k`` roundings (``u = 2^-53``) change a result by at most this share
    (Higham, Thm. 3.5); a sum of ``k`` products is within ``gamma_k`` of the exact sum of their magnitudes.

    >>> gamma(1) > 2.0 ** -53
    True
    """
    return k * _UNIT / (1.0 - k * _UNIT)


@dataclass(frozen=True)
class VerifiedStress:
    """The outcome of :func:`verified_sparse_stress`: ``smallest`` > 0 proves an exact positive stress and full rank.

    ``sigma`` is the proved lower bound on ``sigma_min(A)`` (0 when none was
    found), ``residual`` the bound on ``||A^T w~||_2`` and ``smallest`` the
    proved lower bound on the smallest weight of the exact stress.
    """

    smallest: float
    sigma: float
    residual: float


def _infinity_norm_bound(rows, columns) -> float:
    """``||B||_2 <= sqrt(||B||_1 ||B||_inf)`` from the row and column sums of a nonnegative ``B``."""
    return math.sqrt(float(np.max(rows, initial=0.0)) * float(np.max(columns, initial=0.0)))


def singular_value_bound(A: sp.spmatrix, shifts=GRAM_SHIFTS):
    """``(sigma, lu)``: a proved lower bound on ``sigma_min`` of the exact ``A`` and the factorisation used.

    Returns ``(0.0, None)`` when no shift of :data:`GRAM_SHIFTS` gives
    positive pivots (``A`` is rank deficient, or too ill-conditioned for a
    bound above rounding).  ``lu`` solves with ``G - s I`` (a preconditioner
    for least squares with ``A``).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> sigma, _ = singular_value_bound(sp.csr_matrix(np.diag([3.0, 2.0, 0.5])))
    >>> 0 < sigma <= 0.5  # a proof, not an estimate: sqrt(s - ||E||) for the first shift that works
    True
    >>> singular_value_bound(sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0]])))[0]
    0.0
    """
    A = sp.csc_matrix(A, dtype=float)
    n = A.shape[1]
    absolute = abs(A)
    gram = (A.T @ A).tocsc()
    per_column = int(np.diff(A.indptr).max(initial=0))
    # |G_exact - fl(G)| <= gamma_k |A|^T |A|, k the products summed per entry
    spread = absolute.T @ (absolute @ np.ones(n))
    gram_error = gamma(per_column + 2) * float(spread.max(initial=0.0)) * (1 + gamma(per_column + 2))
    top = float(scipy.sparse.linalg.norm(gram, 1))
    if top == 0:
        return 0.0, None
    identity = sp.identity(n, format="csc")
    for share in shifts:
        shift = share * top
        shifted = (gram - shift * identity).tocsc()
        try:
            lu = scipy.sparse.linalg.splu(shifted, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                          options={"SymmetricMode": True, "Equil": False})
        except RuntimeError:  # exactly singular
            continue
        factor_error = _factor_error(shifted, lu)
        if factor_error is None:
            continue
        diagonal_error = _UNIT / (1 - _UNIT) * float(np.abs(shifted.diagonal()).max(initial=0.0))
        lower = shift * (1 - _UNIT) - (factor_error + gram_error + diagonal_error) * (1 + 4 * _UNIT)
        if lower > 0:
            return math.sqrt(lower) * (1 - _UNIT), lu
    return 0.0, None


def _factor_error(M: sp.csc_matrix, lu):
    """A bound on ``||P M P^T - L D L^T||_2`` for the computed factors, or None if they are not ``L D L^T`` of ``M``.

    Needs a symmetric permutation, ``L`` unit lower triangular and ``D``
    (the diagonal of ``U``) positive; ``L D L^T`` is then positive definite.
    """
    n = M.shape[0]
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    L = lu.L.tocsr()
    d = lu.U.diagonal()
    if np.any(~(d > 0)) or not np.all(L.diagonal() == 1.0) or sp.triu(L, k=1).nnz:
        return None
    P = sp.csc_matrix((np.ones(n), (lu.perm_r, np.arange(n))), shape=(n, n))
    permuted = (P @ M @ P.T).tocsr()
    product = (L @ sp.diags(d) @ L.T).tocsr()
    residual = abs(permuted - product)
    k = int(np.diff(L.indptr).max(initial=0))
    absolute_l = abs(L)
    magnitude = absolute_l @ (d * (absolute_l.T @ np.ones(n)))  # row sums of |L| |D| |L^T| (symmetric)
    rows = np.asarray(residual.sum(axis=1)).ravel() * (1 + 2 * _UNIT) + gamma(k + 2) * magnitude
    columns = np.asarray(residual.sum(axis=0)).ravel() * (1 + 2 * _UNIT) + gamma(k + 2) * magnitude
    return _infinity_norm_bound(rows, columns) * (1 + gamma(n + 2))


def verified_sparse_stress(A: sp.spmatrix, stress, shifts=GRAM_SHIFTS) -> VerifiedStress:
    """Prove that the exact ``A`` has full column rank and a positive self-stress near the float ``stress``.

    The stress is first refined (``w <- w - A y``, ``y`` from the shifted
    Gram factorisation of :func:`singular_value_bound`,
    :data:`REFINEMENT_STEPS` times) so that its residual is at rounding
    level; then ``smallest = min w - ||A^T w||_2 / sigma`` with the exact
    residual bounded by ``|fl(A^T w)| + gamma_k |A|^T |w|``.
    ``smallest > 0`` is the proof (see the module docstring).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = sp.csr_matrix(np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]))
    >>> result = verified_sparse_stress(A, np.ones(4))
    >>> result.smallest > 0.99, 0 < result.sigma <= 2 ** 0.5
    (True, True)
    """
    A = sp.csr_matrix(A, dtype=float)
    w = np.asarray(stress, dtype=float).copy()
    sigma, lu = singular_value_bound(A, shifts)
    if sigma <= 0 or lu is None or np.any(~(w > 0)):
        return VerifiedStress(-math.inf, sigma, math.inf)
    for _ in range(REFINEMENT_STEPS):
        r = A.T @ w
        refined = w - A @ lu.solve(r)
        if not np.all(refined > 0) or np.linalg.norm(A.T @ refined) >= np.linalg.norm(r):
            break
        w = refined
    absolute = abs(A)
    per_column = int(np.diff(A.tocsc().indptr).max(initial=0))
    bound = np.abs(A.T @ w) + gamma(per_column + 2) * (absolute.T @ np.abs(w))
    residual = float(np.linalg.norm(bound)) * (1 + gamma(len(bound) + 2)) * (1 + gamma(per_column + 4))
    smallest = float(w.min()) - residual / sigma * (1 + 4 * _UNIT)
    return VerifiedStress(smallest, sigma, residual)
