"""Rigorous re-checks of floating-point verdicts (docs/certificates.md).

* "interlocked": first by verified floating point at the cost of one sparse
  factorisation (:mod:`interlock.verify.verified`: a proved lower bound on
  ``sigma_min(A)`` and the float stress's residual); where that does not
  decide, an exact positive self-stress.  Take the floating stress
  ``w >= 1``; pick ``n`` independent rows ``B`` of ``A`` (prove ``B``
  invertible, which proves full column rank); keep the other weights as exact
  rationals and solve ``B^T w_B = -A_rest^T w_rest`` exactly.  If ``w_B > 0``,
  then ``A^T w = 0`` with ``w > 0`` holds exactly: by Stiemke's lemma no ``x``
  has ``A x >= 0, A x != 0``.
* "not interlocked" by a sliding motion: an exact rational kernel vector of
  ``A`` (conclusive when the input coordinates are exact binary fractions,
  e.g. integers or halves); when the exact matrix has full column rank the
  slide exists only up to rounding or tolerance and is not certified
  (without python-flint: finite steps).
* "not interlocked" by a motion: the blocks moved along the motion by
  growing finite steps must not overlap (manifold3d intersection volume).

What is certified is the interlocking matrix as built from the contact
polygons, each float entry taken as the exact rational it represents.
Exact arithmetic uses python-flint (the ``exact`` extra).
"""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np
import scipy.linalg
import trimesh

from interlock.verify.matrix import InterlockingMatrix
from interlock.verify.verified import gamma, verified_sparse_stress

__all__ = ["certify_verdict", "certify_reduction", "FINITE_STEPS", "OVERLAP_RTOL", "RANK_POINTS"]

#: Finite steps (fractions of the model size) along a motion.
FINITE_STEPS = (1e-4, 1e-3, 1e-2)
#: Overlap volumes below this times the model size cubed count as none.
OVERLAP_RTOL = 1e-12


#: Up to this many columns an "interlocked" verdict is first certified by verified floating point
#: (:func:`verified_stress`, dense ``O(n^3)``, about 8 n^2 bytes per matrix).
VERIFIED_COLUMNS = 6000
#: Up to this many columns exact rational arithmetic is tried when verified floating point does not decide.
EXACT_COLUMNS = 2000


def certify_verdict(assembly, A: InterlockingMatrix, verdict, budget=None):
    """The verdict re-checked rigorously: ``certified`` set and the method added to ``status``.

    The rows of ``A`` are those of every contact that admits one normal: faces, vertex-face and edge-edge
    contacts (Remark 3.11) alike, so a stress certificate covers them all.  A verdict decided over the cones of
    normals of degenerate contacts (:func:`~interlock.verify.admissible.cone_search`) has no certificate on
    ``A`` alone: an "interlocked" one is left uncertified; a motion's certificate covers the rows of ``A``, and
    the contacts with a cone of normals were checked in floating point (``admissible.unless_cones``).
    ``budget`` (:class:`~interlock.verify.budget.Budget`): checked between the steps ("certify").
    """
    if budget is not None:
        budget.check("certify")
    if verdict.interlocked is None:
        return dataclasses.replace(verdict, status=verdict.status + "; nothing to certify")
    if verdict.interlocked and A.shape[1] == 0:
        return dataclasses.replace(verdict, certified=True)
    flint = _flint()
    if verdict.interlocked and verdict.stress is None:  # decided over cones of normals: no stress on A
        return _uncertified(verdict, "not certified: decided by branches over the cones of normals of vertex-edge "
                                     "and vertex-vertex contacts, which no stress of A certifies")
    if verdict.interlocked:
        ok, note = _stress_certificate(flint, A.matrix, verdict.stress)
        return dataclasses.replace(verdict, certified=ok, status=f"{verdict.status}; {note}")
    if budget is not None:
        budget.check("certify")
    if verdict.motion_kind == "opening":
        note = _opening_certificate(flint, A, verdict.motion)
        if note is not None:
            return dataclasses.replace(verdict, certified=True, status=f"{verdict.status}; {note}")
    if flint is not None and verdict.motion_kind == "sliding":
        if A.shape[1] > EXACT_COLUMNS:
            return _uncertified(verdict, f"not certified: a sliding motion needs an exact kernel vector, and "
                                         f"{A.shape[1]} columns are too many for exact arithmetic (at most "
                                         f"{EXACT_COLUMNS})")
        if _nullspace(flint, _fmpq_mat(flint, A.matrix)):
            return dataclasses.replace(verdict, certified=True,
                                       status=f"{verdict.status}; exact rational kernel vector of A")
        # finite steps cannot tell a true slide from one across faces bent below the tolerances
        return _uncertified(verdict, "not certified: the exact matrix has full column rank, so the sliding "
                                     "motion exists only up to rounding or tolerance")
    if budget is not None:
        budget.check("certify")
    ok, note = _finite_steps(assembly, verdict)
    return dataclasses.replace(verdict, certified=ok, status=f"{verdict.status}; {note}")


def _stress_certificate(flint, matrix, w: np.ndarray):
    m, n = matrix.shape
    if m < n:
        return False, "not certified: fewer rows than columns"
    proved = verified_sparse_stress(matrix, w)  # one sparse factorisation: the cost of the rank stage
    if proved.smallest > 0:
        return True, (f"certified: exact positive self-stress (smallest weight at least {proved.smallest:.3g}) and "
                      f"full column rank (smallest singular value at least {proved.sigma:.3g}), by verified "
                      "floating point")
    if flint is None:
        return False, "not certified: verified floating point did not decide and python-flint is missing " \
                      "(pip install 'interlock[exact]')"
    basis = None
    if n <= VERIFIED_COLUMNS:
        # rows by LU with partial pivoting first (ten times cheaper than QR with pivoting), then by QR
        for choose in (_lu_rows, _qr_rows):
            basis = choose(matrix)
            rest = np.setdiff1d(np.arange(m), basis)
            bound = verified_stress(matrix[basis].toarray(), matrix[rest], w[rest])
            if bound is not None and bound > 0:
                return True, (f"certified: exact positive self-stress (smallest weight at least {bound:.3g}, "
                              "by verified floating point) and an invertible row basis")
    if n > EXACT_COLUMNS:
        tried = "verified floating point did not decide" if basis is not None else \
            f"too many for verified floating point (at most {VERIFIED_COLUMNS})"
        return False, f"not certified: {n} columns, {tried}, and too many for exact rational arithmetic " \
                      f"(at most {EXACT_COLUMNS})"
    if basis is None:  # the QR rows of the loop above, else chosen now
        basis = _qr_rows(matrix)
        rest = np.setdiff1d(np.arange(m), basis)
    B = _fmpq_mat(flint, matrix[basis])
    try:
        if B.rank() < n:
            return False, "not certified: no invertible row basis found"
        rhs = -(_fmpq_mat(flint, matrix[rest]).transpose() * _fmpq_mat(flint, w[rest][:, None]))
        w_basis = B.transpose().solve(rhs)
    except ZeroDivisionError:
        return False, "not certified: the chosen row basis is singular"
    smallest = min(w_basis[k, 0] for k in range(n))
    if smallest <= 0:
        return False, "not certified: the exact stress is not positive on every row"
    return True, (f"certified: exact positive self-stress (smallest weight {float(smallest):.3g}) "
                  "and an exactly invertible row basis")


def _lu_rows(matrix) -> np.ndarray:
    """``n`` rows of an ``m x n`` matrix chosen by LU with partial pivoting (``A = L[p] U``: the pivot rows)."""
    p = scipy.linalg.lu(matrix.toarray(), p_indices=True)[0]
    return np.sort(np.argsort(p)[: matrix.shape[1]])


def _qr_rows(matrix) -> np.ndarray:
    """``n`` rows of an ``m x n`` matrix chosen by QR with column pivoting of its transpose (well conditioned)."""
    _, _, pivots = scipy.linalg.qr(matrix.toarray().T, pivoting=True, mode="economic")
    return np.sort(pivots[: matrix.shape[1]])


def verified_stress(basis: np.ndarray, rest, w_rest: np.ndarray) -> float | None:
    """A proved lower bound on the smallest weight of the exact stress ``w_b`` on a row basis, or None.

    The matrix's entries and the weights ``w_rest`` of the other rows are
    floats, hence exact rationals; ``w_b`` is the exact solution of
    ``B^T w_b = c`` with ``c = -R^T w_rest``, so that ``A^T w = 0`` exactly.
    With ``X`` a float inverse of ``B^T`` and every rounding bounded by the
    standard ``gamma_k = k u / (1 - k u)`` (Higham, Thm. 3.5; ``u = 2^-53``):
    if ``alpha = || |I - X B^T| + gamma (|X| |B^T|) ||_inf < 1``, then ``B^T``
    is invertible and ``||w_b - w~||_inf <= || |X| rho ||_inf / (1 - alpha)``
    for a bound ``rho`` on the residual ``c - B^T w~`` of the float solution
    ``w~`` (Rump's verification).  The bound returned is ``min w~`` minus
    that: positive means an exact positive self-stress exists and ``A`` has
    full column rank.  ``O(n^3)`` in floating point.
    """
    n = basis.shape[0]
    if np.any(w_rest <= 0):
        return None
    u = 2.0**-53
    Bt = basis.T
    absolute = abs(rest).T  # (n, m - n), exact
    per_column = int(np.diff(rest.tocsc().indptr).max(initial=0)) + 1
    c = -(rest.T @ w_rest)
    c_error = gamma(per_column) * (absolute @ np.abs(w_rest)) * (1 + gamma(per_column + 2))
    try:
        X = np.linalg.inv(Bt)
    except np.linalg.LinAlgError:
        return None
    w = X @ c
    abs_X, abs_Bt = np.abs(X), np.abs(Bt)
    products = abs_X @ abs_Bt
    E = np.abs(np.eye(n) - X @ Bt) * (1 + 2 * u) + gamma(n + 2) * products * (1 + gamma(n + 2))
    alpha = float(E.sum(axis=1).max()) * (1 + gamma(n + 2))
    if not alpha < 1:
        return None
    residual = np.abs(c - Bt @ w) * (1 + 2 * u) + gamma(n + 2) * (abs_Bt @ np.abs(w)) * (1 + gamma(n + 2)) + c_error
    spread = float((abs_X @ residual).max()) * (1 + gamma(n + 2)) / (1 - alpha)
    return float(w.min()) - spread


def _rref(M):
    """The reduced row echelon form of an exact matrix and its pivot columns."""
    reduced, rank = M.rref()
    pivots, row = [], 0
    for col in range(M.ncols()):
        if row < rank and reduced[row, col] != 0:
            pivots.append(col)
            row += 1
    return reduced, pivots


def _nullspace(flint, M) -> list[list]:
    """An exact basis of ``{x : M x = 0}`` (rational columns as lists), from the reduced row echelon form."""
    reduced, pivots = _rref(M)
    n = M.ncols()
    basis = []
    for free in (c for c in range(n) if c not in set(pivots)):
        x = [flint.fmpq(0)] * n
        x[free] = flint.fmpq(1)
        for r, col in enumerate(pivots):
            x[col] = -reduced[r, free]
        basis.append(x)
    return basis


def _opening_certificate(flint, A: InterlockingMatrix, motion) -> str | None:
    """Why the motion opens contacts exactly (``A x >= 0``, ``A x != 0``), or None.

    The rows that the float product ``A x`` shows open by more than its
    rounding bound ``gamma_k |A| |x|`` are open exactly (verified floating
    point; every row, for the spreading motions of the stress problem's
    Farkas certificate).  The others are made exactly closed by moving ``x``,
    on the columns they touch only, into the exact null space of those rows;
    the rows touching those columns are then evaluated exactly.
    """
    matrix = A.matrix.tocsr()
    x = A.columns(motion[A.free])
    y = matrix @ x
    per_row = int(np.diff(matrix.indptr).max(initial=0))
    error = gamma(per_row + 2) * (abs(matrix) @ np.abs(x)) * (1 + gamma(per_row + 4))
    unsure = np.flatnonzero(~(y > error))
    if not len(unsure):
        return "certified: A x > 0 on every row, by verified floating point"
    if flint is None or len(unsure) == len(y):
        return None
    touched = np.unique(matrix[unsure].indices)
    if len(touched) > EXACT_COLUMNS:
        return None
    basis = _nullspace(flint, _fmpq_mat(flint, matrix[unsure][:, touched]))
    if not basis:
        return None
    N = np.array([[float(v) for v in b] for b in basis]).T
    coefficients = np.linalg.lstsq(N, x[touched], rcond=None)[0]
    exact_c = [_exact(flint, c) for c in coefficients]
    exact_x = {col: _exact(flint, v) for col, v in enumerate(x.tolist())}
    for k, col in enumerate(touched.tolist()):
        exact_x[col] = sum((b[k] * c for b, c in zip(basis, exact_c)), flint.fmpq(0))
    rows = np.unique(matrix[:, touched].tocoo().row)
    values = []
    for r in rows.tolist():
        start, stop = matrix.indptr[r], matrix.indptr[r + 1]
        values.append(sum((_exact(flint, v) * exact_x[int(c)]
                           for c, v in zip(matrix.indices[start:stop], matrix.data[start:stop])), flint.fmpq(0)))
    if any(v < 0 for v in values) or not (any(v > 0 for v in values) or len(rows) < len(y)):
        return None
    return (f"certified: A x > 0 by verified floating point on {len(y) - len(unsure)} rows, and an exact rational "
            f"x that keeps the other {len(unsure)} closed")


def _exact(flint, value):
    """A float as the exact rational it represents."""
    return flint.fmpq(*Fraction(float(value)).as_integer_ratio())


def _finite_steps(assembly, verdict):
    """Move the moving blocks along the motion and measure overlaps with their neighbours."""
    scale = assembly.scale
    pairs = [(i, j) for i, j in assembly.neighbours.edges if i in verdict.moving or j in verdict.moving]
    worst = []
    for step in FINITE_STEPS:
        meshes = {}
        for b in {b for pair in pairs for b in pair}:
            mesh = assembly.mesh(b)
            if b in verdict.moving:
                mesh.apply_transform(_screw(verdict.motion[b], assembly.centroids[b], step * scale))
            meshes[b] = mesh
        overlap = 0.0
        if not all(m.is_volume for m in meshes.values()):
            return False, "not certified: finite steps need manifold blocks (manifold3d) and some are non-manifold"
        for i, j in pairs:
            common = trimesh.boolean.intersection([meshes[i], meshes[j]], engine="manifold")
            if len(common.faces):
                overlap = max(overlap, abs(float(common.volume)))
        worst.append(overlap)
        if overlap > OVERLAP_RTOL * scale**3:
            return False, (f"not certified: moving blocks {list(verdict.moving)[:8]} by {step:g} x model size "
                           f"along the motion overlaps a neighbour (volume {overlap:.3g})")
    steps = ", ".join(f"{s:g}" for s in FINITE_STEPS)
    return True, f"certified: finite steps of {steps} x model size along the motion cause no overlap"


def _screw(twist, centre, step) -> np.ndarray:
    """The rigid motion ``p -> c + R (p - c) + step * t`` with ``R = exp(step [omega]_x)``."""
    omega, t = np.asarray(twist[:3]), np.asarray(twist[3:])
    angle = np.linalg.norm(omega) * step
    matrix = np.eye(4)
    if angle > 0:
        matrix = trimesh.transformations.rotation_matrix(angle, omega, point=centre)
    matrix[:3, 3] += step * t
    return matrix


def _fmpq_mat(flint, matrix):
    """A dense array or a sparse matrix as an exact rational matrix (each float taken exactly)."""
    if isinstance(matrix, np.ndarray):
        rows, cols = matrix.shape
        return flint.fmpq_mat(rows, cols, [flint.fmpq(*Fraction(float(v)).as_integer_ratio()) for v in matrix.ravel()])
    coo = matrix.tocoo()
    out = flint.fmpq_mat(*coo.shape)
    for r, c, v in zip(coo.row.tolist(), coo.col.tolist(), coo.data.tolist()):
        out[r, c] = flint.fmpq(*Fraction(v).as_integer_ratio())
    return out


def _flint():
    try:
        import flint
    except ImportError:
        return None
    return flint


def _uncertified(verdict, note):
    return dataclasses.replace(verdict, certified=False, status=f"{verdict.status}; {note}")


#: Rational points ``z`` at which the exact rank of the forced rows is taken (full rank at one proves it generic).
RANK_POINTS = ((2, 3), (Fraction(3, 2), Fraction(-5, 7)))


def certify_reduction(symbol, steps, ending: str) -> tuple[bool, str]:
    """Replay the periodic facial reduction in exact rational arithmetic (docs/periodic.md).

    Every float entry of the symbol ``A(z) = sum A_delta z^delta`` is taken as
    the exact rational it represents, and the cell motions ``P`` are kept as
    an exact rational basis.  Each step is proved:

    * ``("stress", z, rows, w)``: an exact ``w' > 0`` on ``rows`` with
      ``(A(z) P)[rows]^T w' = 0`` (the free weights are the float ones, the
      pivot weights solved exactly and checked positive): fact 2 forces the rows.
    * ``("restrict", d)``: the exact kernel ``U`` of the forced rows at a
      rational point has dimension ``d`` and ``A_delta[forced] P U = 0`` for
      every ``delta``, so ``U`` is the kernel at every ``z`` (fact 3): ``P <- P U``.

    The ending is then proved: "no kernel" by full exact column rank of the
    forced rows at one rational ``z`` (the rank there bounds the generic rank
    from below; fact 1), "cell motion" directly by an exact non-zero ``u``
    with ``A_delta u = 0`` for every ``delta`` and every row (no step is
    needed).  "fact 1" (a kernel that is not constant) is not certified here.

    Returns ``(certified, note)``.
    """
    flint = _flint()
    if flint is None:
        return False, "certification needs python-flint (pip install 'interlock[exact]')"
    terms = {delta: _fmpq_mat(flint, term) for delta, term in symbol.terms.items()}
    n = symbol.columns
    P = flint.fmpq_mat(n, n, [flint.fmpq(int(i == j)) for i in range(n) for j in range(n)])
    forced = np.zeros(symbol.rows, dtype=bool)
    if ending == "cell motion":  # the motion alone is the proof: the steps only narrowed where to look
        return _cell_motion(flint, terms, symbol.rows, P)
    for step in steps:
        if step[0] == "stress":
            _, z, rows, w = step
            rows = _well_conditioned_first(symbol(z).real[rows] @ _float(P), np.flatnonzero(rows))
            if not _positive_kernel_vector(flint, _rows(flint, _at(flint, terms, z), rows) * P, w[rows]):
                return False, f"not certified: no exact positive stress at z = {tuple(map(float, z))}"
            forced[rows] = True
        else:
            U = _constant_kernel(flint, terms, forced, P)
            if U is None or U.ncols() != step[1]:
                return False, "not certified: the kernel of the forced rows is not exactly constant"
            P = P * U
    forced_rows = np.flatnonzero(forced)
    if ending == "no kernel":
        for z in RANK_POINTS:
            if (_rows(flint, _at(flint, terms, z), forced_rows) * P).rank() == P.ncols():
                return True, (f"certified: exact positive stresses force {len(forced_rows)} rows, which have full "
                              f"exact rank at z = ({z[0]}, {z[1]})")
        return False, "not certified: the forced rows are not of full exact rank at the rational test points"
    return False, f"not certified: the ending '{ending}' has no exact certificate"


def _cell_motion(flint, terms, rows: int, P):
    """An exact cell motion ``u != 0`` with ``A_delta u = 0`` for every delta: one cell moves, nothing opens."""
    everything = np.arange(rows)
    stacked = _stack(flint, [_rows(flint, term, everything) * P for term in terms.values()])
    if _nullspace(flint, stacked):
        return True, "certified: an exact rational cell motion keeps every row of every A_delta at zero"
    return False, "not certified: no exact cell motion keeps every contact (the exact matrices have no common kernel)"


def _at(flint, terms, z):
    """``A(z) = sum A_delta z^delta`` exactly, for rational ``z``."""
    z1, z2 = (flint.fmpq(*Fraction(v).as_integer_ratio()) for v in z)
    out = None
    for (d1, d2), term in terms.items():
        scaled = term * (z1**d1 * z2**d2)
        out = scaled if out is None else out + scaled
    return out


def _rows(flint, M, rows):
    return flint.fmpq_mat(len(rows), M.ncols(), [M[int(r), c] for r in rows for c in range(M.ncols())])


def _stack(flint, blocks):
    columns = blocks[0].ncols()
    entries = [B[r, c] for B in blocks for r in range(B.nrows()) for c in range(columns)]
    return flint.fmpq_mat(sum(B.nrows() for B in blocks), columns, entries)


def _constant_kernel(flint, terms, forced, P):
    """The exact kernel ``U`` of the forced rows at a rational point, if ``A_delta[forced] P U = 0`` for every delta."""
    rows = np.flatnonzero(forced)
    basis = _nullspace(flint, _rows(flint, _at(flint, terms, RANK_POINTS[0]), rows) * P)
    if not basis:
        return None
    U = flint.fmpq_mat(P.ncols(), len(basis), [b[k] for k in range(P.ncols()) for b in basis])
    for term in terms.values():
        product = _rows(flint, term, rows) * P * U
        if any(product[r, c] != 0 for r in range(product.nrows()) for c in range(product.ncols())):
            return None
    return U


def _well_conditioned_first(M: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``rows`` reordered so that a well-conditioned row basis of ``M`` comes first (QR with column pivoting)."""
    _, _, order = scipy.linalg.qr(M.T, pivoting=True, mode="economic")
    return rows[order]


def _float(M) -> np.ndarray:
    return np.array([[float(M[r, c]) for c in range(M.ncols())] for r in range(M.nrows())])


def _positive_kernel_vector(flint, M, w: np.ndarray) -> bool:
    """Whether an exact ``w' > 0`` with ``M^T w' = 0`` exists near ``w``: free weights from ``w``, pivots solved.

    The pivots are the first independent rows of ``M``: order them well-conditioned first.
    """
    if len(w) == 0 or np.any(w <= 0):
        return False
    reduced, pivots = _rref(M.transpose())
    m = M.nrows()
    exact = {j: flint.fmpq(*Fraction(float(w[j])).as_integer_ratio()) for j in range(m) if j not in set(pivots)}
    for r, p in enumerate(pivots):
        value = -sum((reduced[r, j] * wj for j, wj in exact.items()), flint.fmpq(0))
        if value <= 0:
            return False
    return True
