"""Interlocking of infinite periodic assemblies from one cell (main paper Sec. 4.1; docs/periodic.md)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from interlock.blocks.assembly import Assembly
from interlock.blocks.orbits import cell_patch
from interlock.errors import InterlockError
from interlock.verify.certify import certify_reduction
from interlock.verify.check import MOVING_RTOL, check
from interlock.verify.contacts import contacts
from interlock.verify.stress import widest_stress

__all__ = ["EdgeQuadruple", "Symbol", "PeriodicVerdict", "edge_quadruples", "symbol", "periodic_check",
           "KERNEL_RTOL", "STRESS_TOL", "POSITIVE_Z", "PATCH_RADII"]

#: Singular values of A(z) below this (relative) span its kernel at a torus point.
KERNEL_RTOL = 1e-9
#: Stress weights above this count as positive (rows that are forced closed).
STRESS_TOL = 1e-7
#: The positive points z at which periodic stresses are sought (fact 2 with weights w z^tau), in this order.
POSITIVE_Z = ((1.0, 1.0), (2.0, 1.0), (1.0, 2.0), (0.5, 1.0), (1.0, 0.5), (2.0, 0.5))
#: Radii (in cells) of the patches with a fixed ring tried when the reduction does not decide.
PATCH_RADII = (1, 2)
_ROUNDS = 64


@dataclass(frozen=True)
class EdgeQuadruple:
    """One contact row group of the infinite assembly: block ``i`` of cell 0 against block ``j`` of cell ``offset``.

    ``points`` are the contact polygon's vertices and ``normal`` points from
    ``i`` to ``j`` (the edge-representing data of Sec. 4.1); ``planar`` is
    :attr:`Contact.planar <interlock.verify.contacts.Contact.planar>`.
    """

    i: int
    j: int
    offset: tuple[int, int]
    normal: np.ndarray
    points: np.ndarray
    planar: bool = True  # False: faces bent by less than the contact tolerances (Contact.planar)


@dataclass(frozen=True, eq=False)
class Symbol:
    """``A(z) = sum_delta A_delta z^delta``: the infinite interlocking matrix of a periodic assembly.

    ``terms[delta]`` is a sparse (rows x columns) matrix; columns are 6 (or 3)
    per block of the cell.  Row ``r`` of the infinite matrix in cell ``tau``
    couples cell ``tau`` and ``tau + delta``; with twists about block
    centroids the coefficients do not depend on ``tau``.
    """

    terms: dict
    rows: int
    columns: int
    translational: bool
    length_scale: float = 1.0

    def __call__(self, z) -> np.ndarray:
        """``A(z)`` as a dense complex matrix, ``z`` a pair of non-zero complex numbers."""
        z1, z2 = complex(z[0]), complex(z[1])
        out = np.zeros((self.rows, self.columns), dtype=complex)
        for (d1, d2), term in self.terms.items():
            out += term.toarray() * (z1**d1 * z2**d2)
        return out

    def twists(self, x) -> np.ndarray:
        """A real column vector as one world-unit twist ``(omega, t)`` per block of the cell, shape (k, 6)."""
        size = 3 if self.translational else 6
        x = np.asarray(x, dtype=float).reshape(-1, size)
        if self.translational:
            return np.hstack([np.zeros_like(x), x])
        return np.hstack([x[:, :3] / self.length_scale, x[:, 3:]])


@dataclass(frozen=True)
class PeriodicVerdict:
    """The answer of :func:`periodic_check`; ``status`` is "interlocked", "not interlocked" or "inconclusive".

    ``motion`` (when found) has one twist ``(omega, t)`` per entry of
    ``motion_blocks``, the ``(a, b, i)`` of a block: block ``i`` of the cell
    moved by ``a v1 + b v2``; every block not listed stays put, so the motion
    has finite support.  ``moving`` indexes the rows of ``motion`` that move.
    ``lp_values`` lists, for every periodic-stress LP solved, the round, the
    positive ``z`` and the LP's value (``sum min(w, 1)``: how many rows it
    forced closed).  ``patch_radius`` is set when the motion (or the failure
    to find one) comes from :func:`~interlock.blocks.cell_patch`.
    """

    status: str
    reason: str
    generic_rank: int
    columns: int
    rounds: int
    forced_rows: int
    rows: int
    motion: np.ndarray | None = None
    motion_blocks: tuple[tuple[int, int, int], ...] = ()
    moving: tuple[int, ...] = ()
    lp_values: tuple[tuple[int, float, float, float], ...] = ()
    patch_radius: int | None = None
    certified: bool = False
    tolerances: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    def __str__(self) -> str:
        return (f"{self.status}: {self.reason} (generic rank {self.generic_rank} of {self.columns}, "
                f"{self.rounds} round(s), {self.forced_rows}/{self.rows} rows forced)")

    def to_dict(self) -> dict:
        return {"status": self.status, "reason": self.reason, "generic_rank": self.generic_rank,
                "columns": self.columns, "rounds": self.rounds, "forced_rows": self.forced_rows, "rows": self.rows,
                "motion": None if self.motion is None else self.motion.tolist(),
                "motion_blocks": [list(b) for b in self.motion_blocks], "moving": list(self.moving),
                "lp_values": [{"round": r, "z": [z1, z2], "value": v} for r, z1, z2, v in self.lp_values],
                "patch_radius": self.patch_radius, "certified": self.certified, "tolerances": dict(self.tolerances), "timings": dict(self.timings)}


def edge_quadruples(cell: Assembly) -> tuple[EdgeQuadruple, ...]:
    """The contacts of one cell with itself and its lattice translates, each contact of the infinite assembly once.

    A contact between block ``i`` of cell ``tau`` and block ``j`` of cell
    ``tau + delta`` is listed for ``tau = 0`` with ``delta > 0``
    lexicographically, or ``delta = 0`` and ``i < j``.

    >>> from interlock.blocks import presets
    >>> sorted(q.offset for q in edge_quadruples(presets.cube_grid_cell()))
    [(0, 1), (1, 0)]
    """
    _check_cell(cell)
    around = cell_patch(cell, 0)  # the cell first, then every translate that can touch it
    k = len(cell)
    found = []
    for c in contacts(around, involving=range(k)):
        for first, second, sign in ((c.i, c.j, 1.0), (c.j, c.i, -1.0)):
            if first >= k:
                continue
            a, b, j = around.labels[second]
            if (a, b) > (0, 0) or ((a, b) == (0, 0) and first < j):
                found.append(EdgeQuadruple(first, j, (a, b), sign * np.asarray(c.normal), np.asarray(c.vertices),
                                           c.planar))
    return tuple(found)


def symbol(cell: Assembly, translational: bool = False, quadruples=None) -> Symbol:
    """The symbol ``A(z)`` of the periodic assembly generated by ``cell`` (docs/periodic.md).

    Rows as in Def. 3.3: for a contact vertex ``p`` with normal ``n`` from
    block ``i`` (cell 0) to block ``j`` (cell ``delta``), ``-(r_i x n, n)`` in
    the columns of ``i`` and ``z^delta (r_j x n, n)`` in those of ``j``, with
    ``r`` measured from each block's centroid in its own cell, over the cell size.

    >>> from interlock.blocks import presets
    >>> A = symbol(presets.cube_grid_cell())
    >>> A.rows, A.columns, float(abs(A((1j, -1)) @ [0, 0, 0, 0, 0, 1]).max())
    (8, 6, 0.0)
    """
    _check_cell(cell)
    quadruples = edge_quadruples(cell) if quadruples is None else quadruples
    lattice = cell.lattice
    size = 3 if translational else 6
    length = float(np.linalg.norm(lattice, axis=1).max())
    centroids = cell.centroids
    points = [q.points[:1] if translational else q.points for q in quadruples]
    counts = np.array([len(p) for p in points], dtype=int)
    p = np.vstack(points) if points else np.empty((0, 3))
    n = np.repeat([q.normal for q in quadruples], counts, axis=0).reshape(-1, 3)
    i = np.repeat([q.i for q in quadruples], counts).astype(int)
    j = np.repeat([q.j for q in quadruples], counts).astype(int)
    offsets = np.repeat([q.offset for q in quadruples], counts, axis=0).reshape(-1, 2)
    shift = offsets @ lattice
    own = -_entries(p - centroids[i], n, length, translational)
    other = _entries(p - centroids[j] - shift, n, length, translational)
    rows = np.arange(len(p))
    columns = size * len(cell)
    terms = {(0, 0): _rows_matrix(rows, i, own, size, len(p), columns)}
    for delta in {tuple(o) for o in offsets.tolist()}:
        mask = np.all(offsets == delta, axis=1)
        term = _rows_matrix(rows[mask], j[mask], other[mask], size, len(p), columns)
        terms[delta] = terms[delta] + term if delta in terms else term
    return Symbol(terms, len(p), columns, translational, length)


def periodic_check(cell: Assembly, translational: bool = False, seed: int = 0,
                   patch_radii: tuple[int, ...] = PATCH_RADII, certify: bool = False) -> PeriodicVerdict:
    """Decide interlocking of the infinite assembly generated by a periodic cell (Def. 2.7, finite-support motions).

    The periodic facial reduction of docs/periodic.md: with ``P`` the admissible cell
    motions (all of ``R^{6k}`` at first), a maximal-support stress ``w >= 0``
    of ``A(z) P`` at a positive ``z`` (first ``z = (1, 1)``, then the others of
    :data:`POSITIVE_Z` while undecided) forces its rows closed (fact 2); the
    kernel of the forced rows of ``A(z) P`` at random torus points then decides
    (fact 1): zero means **interlocked**; non-zero with every row forced means
    **not interlocked**; a kernel that is the same real subspace at two points
    (fact 3) restricts ``P`` and the rounds repeat; a constant kernel that keeps
    every row is a motion of one cell alone.  Anything else is **inconclusive**
    after the reduction, and then patches of the radii ``patch_radii`` with a
    fixed ring (:func:`~interlock.blocks.cell_patch`) are checked: a motion
    found there is a finite-support motion, i.e. a proof of **not interlocked**.
    The same patches supply an explicit motion when fact 1 proves one exists.

    The reduction costs depend on the cell (``6k`` columns), not on any patch.

    ``certify=True`` replays the reduction in exact rational arithmetic
    (:func:`~interlock.verify.certify.certify_reduction`, python-flint) or
    certifies the patch verdict (``check(..., certify=True)``); ``certified``
    says whether it succeeded and ``reason`` says how.

    Examples
    --------
    >>> from interlock.blocks import presets
    >>> print(periodic_check(presets.interlocking_cubes_cell()).status)
    interlocked
    """
    _check_cell(cell)
    timings = {}
    start = time.perf_counter()
    quadruples = edge_quadruples(cell)
    A = symbol(cell, translational, quadruples)
    timings["symbol"] = time.perf_counter() - start
    start = time.perf_counter()
    rng = np.random.default_rng(seed)
    with threadpool_limits(1, "blas"):  # matrices of a few hundred rows: threads cost more than they give
        at_points = [A(z) for z in (np.exp(2j * np.pi * rng.random(2)) for _ in range(2))]
        generic_rank = A.columns - _kernel(at_points[0]).shape[1]
        reduction = _reduce(A, at_points)
    timings["reduction"] = time.perf_counter() - start
    status, reason, motion, blocks = reduction.status, reduction.reason, None, ()
    if reduction.motion is not None:
        motion, blocks = A.twists(reduction.motion), tuple((0, 0, i) for i in range(len(cell)))
    bent = [q for q in quadruples if not q.planar]
    if bent and status == "not interlocked" and (motion is None or _slides_across(cell, bent, motion)):
        status, motion, blocks = "inconclusive", None, ()
        reason += (f"; but {len(bent)} contact(s) are planar only within the contact tolerances (faces bent by a "
                   "small angle) and the motion slides across them: the real bend may block it")
    radius, certified = None, False
    if certify and status != "inconclusive" and reduction.ending in ("no kernel", "cell motion"):
        start = time.perf_counter()
        certified, note = certify_reduction(A, reduction.steps, reduction.ending)
        reason += f"; {note}"
        timings["certify"] = time.perf_counter() - start
    if status == "inconclusive" or (status == "not interlocked" and motion is None):
        start = time.perf_counter()
        radius, motion, blocks, certified = _patch_motion(cell, translational, patch_radii, certify)
        timings["patches"] = time.perf_counter() - start
        tried = ", ".join(map(str, patch_radii)) or "none"
        if motion is not None:
            status = "not interlocked"
            reason += f"; a patch of radius {radius} with its ring fixed moves (finite support)"
            reason += "; certified" if certified else ""
        else:
            reason += f"; patches of radius {tried} with their ring fixed found no motion"
    twists, moving = _normalised(motion)
    tolerances = {"kernel_rtol": KERNEL_RTOL, "stress_tol": STRESS_TOL, "seed": seed,
                  "positive_z": [list(z) for z in POSITIVE_Z], "patch_radii": list(patch_radii)}
    return PeriodicVerdict(status, reason, generic_rank, A.columns, reduction.rounds, reduction.forced, A.rows,
                           twists, blocks, moving, reduction.lp_values, radius, certified, tolerances, timings)


@dataclass(frozen=True)
class _Reduction:
    """The outcome of the facial reduction and the steps that led to it (replayed exactly by certification).

    ``steps`` holds ``("stress", z, rows, w)`` for every LP that forced rows
    (its support and weights) and ``("restrict", dimension)`` for every
    restriction of the cell motions to a constant kernel; ``ending`` is
    "no kernel", "cell motion", "fact 1" or "undecided".
    """

    status: str
    reason: str
    rounds: int
    forced: int
    lp_values: tuple
    steps: tuple
    ending: str
    motion: np.ndarray | None = None


def _reduce(A: Symbol, at_points) -> _Reduction:
    """The periodic facial reduction of :func:`periodic_check`, without the patch fallback."""
    basis = np.eye(A.columns)  # the admissible cell motions P, as orthonormal columns
    forced = np.zeros(A.rows, dtype=bool)
    lp_values, steps, rounds, z_index, fresh = [], [], 1, 0, True

    def ending(kind, status, reason, motion=None):
        return _Reduction(status, reason, rounds, int(forced.sum()), tuple(lp_values), tuple(steps), kind, motion)

    while rounds <= _ROUNDS:
        z = POSITIVE_Z[z_index]
        widest = widest_stress(A(z).real @ basis, KERNEL_RTOL, STRESS_TOL)
        new, value, w = widest.support, widest.value, widest.stress
        lp_values.append((rounds, float(z[0]), float(z[1]), value))
        grew = bool((new & ~forced).any())
        if grew:
            steps.append(("stress", z, new, w))
        forced |= new
        if grew or fresh:
            fresh = False
            kernels = [_kernel(at_points[0][forced] @ basis)]
            if kernels[0].shape[1]:
                kernels.append(_kernel(at_points[1][forced] @ basis))
            if kernels[0].shape[1] == 0:
                return ending("no kernel", "interlocked", "the forced rows admit no motion of finite support")
            constant = _real_basis(kernels[0]) if _same_real_subspace(*kernels) else None
            if constant is not None and _keeps_all(at_points, basis @ constant):
                return ending("cell motion", "not interlocked", "one cell has a first-order motion that keeps every contact: a "
                              "sliding motion of finite support", basis @ constant[:, 0])
            if forced.all():
                return ending("fact 1", "not interlocked", "every row is forced and A(z) keeps a kernel: a sliding "
                              "motion of finite support exists (fact 1)")
            if constant is not None and constant.shape[1] < basis.shape[1]:
                basis = basis @ constant  # fact 3: every finite-support motion stays in this subspace
                steps.append(("restrict", constant.shape[1]))
                rounds, z_index, fresh = rounds + 1, 0, True
                continue
        z_index += 1
        if z_index == len(POSITIVE_Z):
            break
    return ending("undecided", "inconclusive", "the kernel of the forced rows is not constant and no positive z "
                  "forces more rows")


def _patch_motion(cell: Assembly, translational: bool, radii, certify: bool):
    """The first motion of a patch of growing radius with its ring fixed: (radius, twists, (a, b, i) labels, certified)."""
    for radius in radii:
        assembly = cell_patch(cell, int(radius))
        verdict = check(assembly, translational=translational, validate=False, certify=certify)
        if verdict.interlocked is False and verdict.motion is not None:
            free = [b for b in range(len(assembly)) if b not in set(assembly.frame)]
            return int(radius), verdict.motion[free], tuple(assembly.labels[b] for b in free), verdict.certified
    return None, None, (), False


def _slides_across(cell: Assembly, quadruples, twists: np.ndarray) -> bool:
    """Whether moving one cell by ``twists`` (all other cells fixed) slides two blocks of a contact past each other.

    A contact within the cell moves both its blocks; one with a translate
    moves only the block of the moving cell (on either side of it).
    """
    centroids, lattice = cell.centroids, cell.lattice
    size = float(np.abs(twists[:, 3:]).max() + np.abs(twists[:, :3]).max() * cell.scale) or 1.0
    for q in quadruples:
        shift = np.asarray(q.offset) @ lattice
        v_i = np.cross(twists[q.i, :3], q.points - centroids[q.i]) + twists[q.i, 3:]
        v_j = np.cross(twists[q.j, :3], q.points - centroids[q.j] - shift) + twists[q.j, 3:]
        relative = [v_j - v_i] if q.offset == (0, 0) else [v_i, v_j]
        if max(np.abs(r).max() for r in relative) > MOVING_RTOL * size:
            return True
    return False


def _normalised(twists):
    """Twists ``(omega, t)`` per block with the largest component +1 (a motion's scale is arbitrary), and who moves."""
    if twists is None:
        return None, ()
    largest = twists.ravel()[np.argmax(np.abs(twists))]
    twists = twists / largest
    moving = tuple(int(b) for b in np.flatnonzero(np.abs(twists).max(axis=1) > 1e-6))
    return twists, moving


# --- helpers --------------------------------------------------------------------------------


def _check_cell(cell) -> None:
    if not isinstance(cell, Assembly) or cell.lattice is None:
        raise InterlockError("a periodic check needs a periodic cell: an Assembly with two lattice vectors "
                             "(e.g. interlock.blocks.periodic_cell(block) or Assembly(..., lattice=[v1, v2]))")


def _entries(r, n, length, translational) -> np.ndarray:
    """Row entries ``(r x n, n)`` (or ``n``) for many points at once, shape (points, 6 or 3)."""
    if translational:
        return np.asarray(n, dtype=float)
    return np.hstack([np.cross(r / length, n), n])


def _rows_matrix(rows, blocks, entries, size, count, columns) -> sp.csr_matrix:
    r = np.repeat(rows, size)
    c = (size * blocks[:, None] + np.arange(size)).ravel()
    return sp.csr_matrix((entries.ravel(), (r, c)), shape=(count, columns))


def _kernel(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis (columns) of the kernel of ``M``: right singular vectors below ``KERNEL_RTOL``."""
    m, n = M.shape
    if m == 0:
        return np.eye(n, dtype=complex)
    _, sigma, vh = scipy.linalg.svd(M, full_matrices=m < n, check_finite=False)  # vh is n x n either way
    top = sigma.max(initial=0.0) or 1.0
    rank = int((sigma > KERNEL_RTOL * top).sum())
    return vh[rank:].conj().T


def _same_real_subspace(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape[1] != b.shape[1] or a.shape[1] == 0:
        return False
    projector = a @ a.conj().T
    return bool(np.abs(projector @ b - b).max() < 1e-7)


def _real_basis(K: np.ndarray) -> np.ndarray | None:
    """A real orthonormal basis of the complex subspace spanned by ``K``, if it is the complexification of a real one."""
    if K.shape[1] == 0:
        return None
    stacked = np.hstack([K.real, K.imag])
    u, sigma, _ = scipy.linalg.svd(stacked, full_matrices=False)
    real = u[:, sigma > 1e-7 * (sigma.max(initial=0.0) or 1.0)]
    if real.shape[1] != K.shape[1]:
        return None
    return real


def _keeps_all(at_points, vectors) -> bool:
    """Whether the (real) vectors are in the kernel of every row of A(z) at the sample points."""
    return all(np.abs(M @ vectors).max() <= 1e-8 * (np.abs(M).max() or 1.0) for M in at_points)
