"""The widest stress of a constraint matrix: a nonnegative self-stress positive on as many rows as possible.

Rows of ``A`` are constraints ``a_i . x >= 0`` on a motion ``x``; a stress is
``w >= 0`` with ``A^T w = 0``.  Every stress vanishes outside one largest
support, and on that support the constraints are *forced*: a motion keeping
all of them satisfies them with equality (Farkas).  The second-order test
(:mod:`~interlock.verify.second_order`, prestress stability) and the
periodic facial reduction (:mod:`~interlock.verify.periodic`, main paper
Sec. 4.1) both need that support.

LP (support maximisation): ``max sum y`` over ``(w, y)`` with
``U^T w = 0``, ``0 <= y <= 1``, ``y <= w``, ``w >= 0``.  By homogeneity the
optimum has ``y_i = 1`` exactly on the largest support.  ``U`` is an
orthonormal basis of ``A``'s column space (rank by ``rtol``), so
``U^T w = 0`` is ``A^T w = 0`` written without ``A``'s scale: a model turned
by 1e-7 rad put entries of 1e-10 into ``A``, which HiGHS drops (below its
1e-9) and then, with its presolve, reported a support of 4 rows instead of
10 (second order) or "unknown" (periodic cell).  HiGHS runs without presolve.
Above :data:`DENSE_ENTRIES` entries the SVD would cost more than the LP, and
``A^T w = 0`` goes to HiGHS as it is (sparse).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from scipy.optimize import linprog

__all__ = ["WidestStress", "widest_stress", "SPAN_RTOL", "DENSE_ENTRIES"]

#: Singular values of ``A`` at most this times the largest do not span its column space.
SPAN_RTOL = 1e-9
#: Up to this many entries (rows times columns) ``A^T w = 0`` is written as ``U^T w = 0`` (a dense SVD of ``A``).
DENSE_ENTRIES = 4_000_000


@dataclass(frozen=True)
class WidestStress:
    """The result of :func:`widest_stress`.

    Attributes
    ----------
    stress : ndarray (m,)
        ``w >= 0`` with ``A^T w = 0``, zero off ``support``.
    support : ndarray of bool (m,)
        The rows where ``w`` is positive: the forced constraints.
    value : float
        The LP's optimum ``sum min(w, 1)`` (the size of the support when solved; 0 when the LP failed).
    """

    stress: np.ndarray
    support: np.ndarray
    value: float


def widest_stress(A, rtol: float = SPAN_RTOL, stress_tol: float = 0.0) -> WidestStress:
    """A stress ``w >= 0``, ``A^T w = 0``, positive on as many rows of ``A`` as possible (module docstring).

    Parameters
    ----------
    A : ndarray or sparse matrix (m, n)
        One constraint per row.
    rtol : float
        Rank tolerance of ``A`` (relative to its largest singular value) for the basis ``U``.
    stress_tol : float
        Rows whose weight is at most this are left out of the support even where the LP marked them.

    Examples
    --------
    Two opposite constraints on a line (``x >= 0`` and ``-x >= 0``) are forced; a third, ``y >= 0``, is not.

    >>> import numpy as np
    >>> found = widest_stress(np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]]))
    >>> found.support.tolist(), round(found.value, 9)
    ([True, True, False], 2.0)
    """
    m, n = A.shape
    if m == 0:
        return WidestStress(np.zeros(0), np.zeros(0, dtype=bool), 0.0)
    if m * n <= DENSE_ENTRIES:
        u, sigma, _ = scipy.linalg.svd(A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float),
                                       full_matrices=False, check_finite=False)
        equation = sp.csr_matrix(u[:, sigma > rtol * (sigma.max(initial=0.0) or 1.0)].T)
    else:
        equation = sp.csr_matrix(A).T.tocsr()
    result = linprog(np.concatenate([np.zeros(m), -np.ones(m)]),
                     A_ub=sp.hstack([-sp.identity(m), sp.identity(m)]).tocsr(), b_ub=np.zeros(m),
                     A_eq=sp.hstack([equation, sp.csr_matrix((equation.shape[0], m))]).tocsr(),
                     b_eq=np.zeros(equation.shape[0]),
                     bounds=[(0, None)] * m + [(0, 1)] * m, method="highs", options={"presolve": False})
    if result.status != 0:
        return WidestStress(np.zeros(m), np.zeros(m, dtype=bool), 0.0)
    w = result.x[:m]
    support = (result.x[m:] > 0.5) & (w > stress_tol)
    return WidestStress(np.where(support, w, 0.0), support, float(-result.fun))
