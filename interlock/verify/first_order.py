"""The two linear tests of first-order interlocking: rank and Stiemke's stress (main paper Def. 3.3, Prop. 3.10).

``A`` has full column rank and ``A^T w = 0`` has a solution ``w >= 1`` iff ``{x : A x >= 0} = {0}``.  Here are the
solvers of both tests and the motion that certifies a failure: :func:`matrix_rank` (dense SVD or sparse block
inverse iteration), :func:`positive_stress` (Clarabel, HiGHS' interior point as fallback), :func:`opening_motion`
(a Farkas vector cleaned into an exactly checked motion) and :func:`motion_lp`.  :func:`interlock.verify.check`
puts them together.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp
import scipy.sparse.linalg

from interlock.verify.budget import Budget

__all__ = ["matrix_rank", "positive_stress", "opening_motion", "motion_lp", "interior_motion", "rigid_cluster_motion",
           "clarabel_settings",
           "LP_TOL",
           "RANK_CLEAR_RTOL", "GRAM_RESOLUTION", "GRAM_SURE_RTOL", "FARKAS_CLOSED_RTOLS", "PROJECTION_ROUNDS",
           "DENSE_COLUMNS", "MAX_KERNEL_PROBE", "SOLVER_THREADS", "FIRST_KERNEL_PROBE", "INVERSE_ITERATIONS"]

#: LP feasibility and optimality tolerance (entries of A are O(1)).
LP_TOL = 1e-7
#: ... one at least ``RANK_CLEAR_RTOL * sigma_max`` is not; in between the rank is inconclusive.
RANK_CLEAR_RTOL = 1e-6
#: The sparse path works with A^T A, which resolves singular values down to about this (relative).
GRAM_RESOLUTION = 1e-7
#: A smallest singular value of A^T A at least this (relative) settles full rank without the dense SVD.
GRAM_SURE_RTOL = 1e-4
#: Rows of an interior-point motion below one of these fractions of its largest row are projected shut, tried
#: from the finest up (:func:`opening_motion`): interior points leave shut rows at 1e-10 .. 1e-4 of the largest.
FARKAS_CLOSED_RTOLS = (1e-6, 1e-5, 1e-4, 1e-3, 1e-2)
#: Projections of the shut rows per threshold of :func:`opening_motion`.
PROJECTION_ROUNDS = 2
#: Up to this many columns the rank comes from a dense SVD; above, from block inverse iteration on A^T A.
DENSE_COLUMNS = 1200
#: The sparse path looks for at most this many zero singular values (the kernel dimension is then a lower bound).
MAX_KERNEL_PROBE = 256
#: Threads for BLAS and Clarabel in the rank and LP stages.  On 2 shared cores with another job running, one
#: thread made the stress LP of a 4,800-block RhomBlock hexagon 2.5x faster (21-25 s -> 8.5 s) and a dense rank
#: of 241 blocks 60x faster (8.0 s -> 0.13 s); on an idle machine the two settings are within noise.
SOLVER_THREADS = 1
#: The sparse path starts with this many kernel directions; it doubles them only where the whole kernel is needed
#: (bent or given contacts).  On a 100 x 100 grid of cubes (kernel about 9,800) probing 256 took 39 s.
FIRST_KERNEL_PROBE = 12
#: Inverse-iteration sweeps of the sparse rank test (each gains a factor shift / sigma_min^2 on the kernel).
INVERSE_ITERATIONS = 4


def matrix_rank(A: sp.csr_matrix, rtol: float, budget: Budget | None = None, probe: int = MAX_KERNEL_PROBE):
    """(numerical rank, kernel basis as columns, whether the rank is clear of the tolerance band).

    Without rows every column is in the kernel; the basis returned is then
    the first :data:`MAX_KERNEL_PROBE` unit vectors (never an ``n x n``
    identity: 10,000 separate blocks would ask for 27 GB).
    """
    m, n = A.shape
    if m == 0:
        return 0, np.eye(n, min(n, MAX_KERNEL_PROBE)), True
    if n <= DENSE_COLUMNS:
        # cheap first: the Gram matrix's eigenvalues resolve sigma_min down to ~1e-8 sigma_max, which
        # settles well-conditioned matrices (far above the inconclusive band) without a dense QR
        gram_values = scipy.linalg.eigvalsh((A.T @ A).toarray())
        if gram_values[0] >= (GRAM_SURE_RTOL**2) * gram_values[-1] > 0:
            return n, np.zeros((n, 0)), True
        dense = A.toarray()
        if m > n:  # the SVD of the triangular factor is the SVD of A, and cheaper to take
            dense = scipy.linalg.qr(dense, mode="r", overwrite_a=True)[0][:n]
        _, sigma, vt = scipy.linalg.svd(dense, full_matrices=m < n)
        sigma = np.concatenate([sigma, np.zeros(n - len(sigma))])
        top = sigma.max(initial=0.0) or 1.0
        zero = sigma <= rtol * top
        clear = not np.any((sigma > rtol * top) & (sigma < RANK_CLEAR_RTOL * top))
        return int((~zero).sum()), vt[zero].T, clear
    return _sparse_rank(A, rtol, budget, probe)


def _sparse_rank(A: sp.csr_matrix, rtol: float, budget: Budget | None = None, probe: int = MAX_KERNEL_PROBE):
    """Rank and kernel from block inverse iteration on ``A^T A + s I`` (one sparse LU).

    The block converges to the eigenvectors of the smallest eigenvalues even
    when zero has a large multiplicity (where Lanczos misses copies); its
    Ritz values are upper bounds, so a zero is never reported where the
    smallest nonzero singular value lies.  The block doubles while all its
    Ritz values are zero, up to ``probe`` (at most :data:`MAX_KERNEL_PROBE`).
    """
    n = A.shape[1]
    gram = (A.T @ A).tocsc()
    top = float(scipy.sparse.linalg.norm(gram, 1))  # >= sigma_max^2, and as close as a Lanczos run for these matrices
    threshold = max(rtol, GRAM_RESOLUTION) * np.sqrt(top)
    shift = 1e-10 * top
    lu = scipy.sparse.linalg.splu((gram + shift * sp.identity(n, format="csc")).tocsc())
    rng = np.random.default_rng(0)
    k = min(FIRST_KERNEL_PROBE, n)
    while True:
        block = np.linalg.qr(rng.standard_normal((n, k)))[0]
        for _ in range(INVERSE_ITERATIONS):
            block = np.linalg.qr(lu.solve(block))[0]
            if budget is not None:
                budget.check("rank")
        values, rotation = np.linalg.eigh(block.T @ (gram @ block))
        sigma = np.sqrt(np.clip(values, 0, None))
        zero = sigma <= threshold
        if not zero.all() or k >= min(probe, MAX_KERNEL_PROBE, n):
            break
        k = min(2 * k, probe, MAX_KERNEL_PROBE, n)
    clear = not np.any((sigma > threshold) & (sigma < RANK_CLEAR_RTOL * np.sqrt(top)))
    return int(n - zero.sum()), (block @ rotation)[:, zero], clear


def positive_stress(A: sp.csr_matrix, tol: float, solver: str = "clarabel", budget: Budget | None = None):
    """``(w, solver used, certificate)``: ``w >= 1`` with ``A^T w = 0`` (Stiemke), or None when there is none.

    When Clarabel proves there is none, ``certificate`` is its Farkas vector
    (see :func:`opening_motion`), else None.

    Clarabel solves the feasibility problem; HiGHS' interior-point method
    minimises ``sum(w)`` (asked for, or when Clarabel neither solves nor
    proves infeasibility).  Either answer is accepted only if it passes the
    same residual check.  Both get the time left in ``budget``; a solver
    stopped by it raises TimeLimitReached.
    """
    m = A.shape[0]
    if m == 0:
        return None, "none", None
    w, status, farkas = _stress_clarabel(A, budget) if solver == "clarabel" else (None, "not run", None)
    if status == "PrimalInfeasible":
        return None, "clarabel", farkas
    if w is None:
        options = {"primal_feasibility_tolerance": tol, "dual_feasibility_tolerance": tol}
        if budget is not None and budget.solver_limit() is not None:
            options["time_limit"] = budget.solver_limit()
        result = scipy.optimize.linprog(np.ones(m), A_eq=A.T.tocsr(), b_eq=np.zeros(A.shape[1]), bounds=(1, None),
                                        method="highs-ipm", options=options)
        if result.status == 1 and budget is not None:
            budget.check("lp")
        w, solver = (result.x if result.status == 0 else None), "highs-ipm"
    if w is None:
        return None, solver, None
    residual = np.abs(A.T @ w).max(initial=0.0)
    if w.min() < 1 - tol or residual > tol * np.abs(w).max():
        return None, solver, None
    return w, solver, None


def clarabel_settings(budget: Budget | None):
    import clarabel

    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.direct_solve_method = "faer"
    settings.max_threads = SOLVER_THREADS
    if budget is not None and budget.solver_limit() is not None:
        settings.time_limit = budget.solver_limit()
    return settings


def _stress_clarabel(A: sp.csr_matrix, budget: Budget | None = None):
    """The stress as a feasibility problem in Clarabel's conic form.

    ``[A^T; -I] w + s = [0; -1]`` with ``s`` in the zero cone times the
    nonnegative cone, i.e. ``A^T w = 0`` and ``w >= 1``.
    """
    import clarabel

    m, n = A.shape
    constraints = sp.vstack([A.T, -sp.identity(m)]).tocsc()
    # a zero objective asks only for feasibility: 10 interior-point iterations instead of 31 for min sum(w),
    # and the point found lies inside the cone (every weight above 1), as a Stiemke certificate should
    solver = clarabel.DefaultSolver(sp.csc_matrix((m, m)), np.zeros(m), constraints,
                                    np.concatenate([np.zeros(n), -np.ones(m)]),
                                    [clarabel.ZeroConeT(n), clarabel.NonnegativeConeT(m)], clarabel_settings(budget))
    solution = solver.solve()
    status = str(solution.status)
    if status == "MaxTime" and budget is not None:
        budget.check("lp")
    farkas = np.asarray(solution.z)[:n] if status == "PrimalInfeasible" else None
    return (np.asarray(solution.x) if status == "Solved" else None), status, farkas


def opening_motion(A: sp.csr_matrix, x, tol: float = LP_TOL):
    """``(value, x)``: an interior-point motion cleaned into one with ``A x >= 0`` exactly checked, or ``(None, None)``.

    Clarabel proves ``A^T w = 0, w >= 1`` infeasible by a dual ``z = (x, A x)``
    with ``A x >= 0`` and ``1^T A x > 0`` (Farkas): a motion that opens
    contacts.  An interior point only approximates it: rows that the exact
    motion keeps shut come out at ``+-1e-10 .. 1e-4`` of the largest row,
    some of them negative (a 559-block peer matrix had 435 rows below
    ``-1e-7 max(A x)``).  For each threshold ``kappa`` of
    :data:`FARKAS_CLOSED_RTOLS`, from fine to coarse, the rows below
    ``kappa max(A x)`` are projected shut, ``x <- x - A_C^+ (A_C x)`` (least
    squares, one sparse LU of the regularised normal equations), and the
    result is accepted when every row is at least
    ``-tol max(A x)`` and some row stays open (up to
    :data:`PROJECTION_ROUNDS` projections per threshold; last, the vector as
    it came, if it passes unprojected).  The value is
    ``1^T A x / max(A x)``, a lower bound on the motion LP's.

    Examples
    --------
    >>> import scipy.sparse as sp
    >>> A = sp.csr_matrix(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]))
    >>> value, x = opening_motion(A, np.array([1.0, -1e-4]))  # the second row slightly negative: noise
    >>> round(value, 6), (np.round(x, 12) + 0.0).tolist()
    (2.0, [1.0, 0.0])
    """
    if x is None or not len(x):
        return None, None
    x = np.asarray(x, dtype=float)
    y = A @ x
    top = float(y.max(initial=0.0))
    if not top > 0:
        return None, None
    for kappa in FARKAS_CLOSED_RTOLS:
        moved, z = x, y
        for _ in range(PROJECTION_ROUNDS):  # a second round shuts what the first left slightly negative
            closed = np.flatnonzero(z <= kappa * float(z.max(initial=0.0)))
            if not len(closed):
                break
            moved = moved - _least_squares(A[closed], z[closed])
            z = A @ moved
            largest = float(z.max(initial=0.0))
            if largest > 0 and z.min() >= -tol * largest:
                return float(z.sum() / largest), moved / largest
            if not largest > 0:
                break
    if y.min() >= -tol * top:  # no projection keeps it a motion, but it is one as it came
        return float(y.sum() / top), x / top
    return None, None


def _least_squares(A: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
    """``argmin |A d - b|^2 + mu |d|^2`` with ``mu = 1e-12 |A^T A|_1``: nearly the least-norm least-squares
    solution, by one sparse LU (LSQR took 7,685 iterations, 1.4 s, on a 497-block p4 patch's shut rows).  The
    caller checks what it gives exactly, so the regularisation only decides how close it comes."""
    gram = (A.T @ A).tocsc()
    mu = 1e-12 * max(float(scipy.sparse.linalg.norm(gram, 1)), np.finfo(float).tiny)
    return scipy.sparse.linalg.splu((gram + mu * sp.identity(A.shape[1], format="csc")).tocsc()).solve(A.T @ b)


def interior_motion(A: sp.csr_matrix, budget: Budget | None = None):
    """``(x, status)``: Clarabel's interior point of ``max 1^T s`` with ``A x = s``, ``0 <= s <= 1``.

    ``x`` is None unless Clarabel reports "Solved" or "AlmostSolved" (its status says why).  The point is not
    cleaned: rows the exact optimum keeps shut come out slightly negative (:func:`opening_motion` cleans them).
    Never a simplex run over ``[A; -A]``, which took over 15 minutes on a 559-block peer matrix.
    """
    import clarabel

    m, n = A.shape
    if m == 0:
        return np.zeros(n), "no rows"
    # variables (x, s): minimise -1^T s subject to A x - s = 0, -s <= 0, s <= 1
    eye = sp.identity(m, format="csc")
    constraints = sp.vstack([sp.hstack([A, -eye]), sp.hstack([sp.csc_matrix((m, n)), -eye]),
                             sp.hstack([sp.csc_matrix((m, n)), eye])]).tocsc()
    rhs = np.concatenate([np.zeros(m), np.zeros(m), np.ones(m)])
    solver = clarabel.DefaultSolver(sp.csc_matrix((n + m, n + m)), np.concatenate([np.zeros(n), -np.ones(m)]),
                                    constraints, rhs, [clarabel.ZeroConeT(m), clarabel.NonnegativeConeT(2 * m)],
                                    clarabel_settings(budget))
    solution = solver.solve()
    status = str(solution.status)
    if status == "MaxTime" and budget is not None:
        budget.check("lp")
    if status not in ("Solved", "AlmostSolved"):
        return None, status
    return np.asarray(solution.x)[:n], status


def motion_lp(A: sp.csr_matrix, tol: float, budget: Budget | None = None):
    """``(value, x)``: the motion LP's interior point (:func:`interior_motion`) cleaned by :func:`opening_motion`.

    The fallback when the Farkas vector cannot be cleaned.  ``(None, None)`` when the solver fails or yields no
    clean motion; with no rows, ``(0.0, 0)``.
    """
    if A.shape[0] == 0:
        return 0.0, np.zeros(A.shape[1])
    x, _ = interior_motion(A, budget)
    return opening_motion(A, x, tol)


def rigid_cluster_motion(A, clusters, eps: np.ndarray, budget: Budget | None = None):
    """A column vector that moves each cluster of free blocks as one rigid body, opening contacts as far as it can
    while closing none by more than its tolerance, or None.

    ``A`` is an :class:`~interlock.verify.matrix.InterlockingMatrix`, ``clusters`` lists the blocks (assembly
    indices, all free) of each cluster, ``eps`` a tolerance per row (:func:`~interlock.verify.margin.row_tolerances`).
    Cluster ``k`` turns with ``omega_k`` and moves with ``t_k`` about its mean centre ``p_k``; a block ``b`` of it
    gets the columns ``(omega_k, (t_k + omega_k x (c_b - p_k)) / L)``, i.e. ``x = E y``.  The LP (HiGHS, 6 unknowns a
    cluster) is ``min delta`` subject to ``A E y >= -delta eps`` and ``1^T A E y = 1``: the direction that closes the
    least, in tolerances, for what it opens; accepted when ``delta <= |y|_inf``.  Translations first (a part slides
    out), then twists.  Rows within a cluster are
    zero in ``A E``: the motion a rounded file allows only by sliding its blocks into each other does not count.
    None when no rigid motion opens a contact within the tolerances, or the solver fails.

    Examples
    --------
    Two cubes stacked on a fixed one: together they lift off, as one piece.

    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify import interlocking_matrix
    >>> tower = Assembly.from_meshes([trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in range(3)],
    ...                              frame=[0])
    >>> A = interlocking_matrix(tower)
    >>> x = rigid_cluster_motion(A, [[1, 2]], np.full(A.shape[0], 1e-9))
    >>> twists = A.twists(x)
    >>> bool(np.allclose(twists[0], twists[1])), bool(np.all(twists[:, :3] == 0)), bool(twists[0, 5] > 0)
    (True, True, True)
    """
    if A.translational or not len(clusters):
        return None
    column_of = {int(b): k for k, b in enumerate(A.free)}
    rows, cols, vals = [], [], []
    for k, cluster in enumerate(clusters):
        members = [column_of[int(b)] for b in cluster]
        centre = A.centres[members].mean(axis=0)
        for g in members:
            d = (A.centres[g] - centre) / A.length_scale
            cross = np.array([[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]])
            block = np.block([[np.eye(3), np.zeros((3, 3))], [-cross, np.eye(3)]])
            r, c = np.nonzero(block)
            rows.extend(6 * g + r), cols.extend(6 * k + c), vals.extend(block[r, c])
    E = sp.csr_matrix((vals, (rows, cols)), shape=(A.shape[1], 6 * len(clusters)))
    B = (A.matrix @ E).tocsr()
    scale = np.abs(B).max(axis=1).toarray().ravel()
    keep = scale > 1e-9 * max(float(scale.max(initial=0.0)), 1e-300)
    if not keep.any():
        return None
    B, eps = B[keep], np.asarray(eps, dtype=float)[keep]
    turning = np.tile(np.arange(6) < 3, len(clusters))
    opening = np.asarray(B.sum(axis=0)).ravel()
    for allowed in (~turning, np.ones_like(turning)):  # a translation first: the way a part slides out
        # unknowns (y, delta): min delta subject to B y + delta eps >= 0 and 1^T B y = 1 (homogeneous: the
        # direction that closes the least, in tolerances, for the contact it opens)
        unknowns = int(allowed.sum())
        options = {} if budget is None or budget.solver_limit() is None else {"time_limit": budget.solver_limit()}
        result = scipy.optimize.linprog(np.r_[np.zeros(unknowns), 1.0], A_ub=-sp.hstack([B[:, allowed], eps[:, None]]),
                                        b_ub=np.zeros(B.shape[0]), A_eq=np.r_[opening[allowed], 0.0][None],
                                        b_eq=[1.0], bounds=[(None, None)] * unknowns + [(0, None)], method="highs",
                                        options=options)
        if budget is not None:
            budget.check("motion")
        if result.status != 0 or result.x is None:
            continue
        y = np.zeros(B.shape[1])
        y[allowed] = result.x[:unknowns]
        size = float(np.abs(y).max(initial=0.0))
        if size > 0 and result.x[unknowns] <= size:  # closes no row by more than its tolerance per unit of motion
            return E @ (y / size)
    return None
