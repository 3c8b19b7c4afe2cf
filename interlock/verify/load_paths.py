"""A proved lower bound on the margin from load paths: small LPs per block and load, batched.

The margin of :mod:`interlock.verify.margin` is ``rho = 1 / R`` with
``R = max over x in P of ||x||_inf``, ``P = {x : A x >= -eps}``.  Each
coordinate bound is an LP whose dual is a *load path*: ``+-x_j <= eps . u``
for every ``u >= 0`` with ``A^T u = -+e_j`` (compressive forces at the contact
vertices that carry a unit load on coordinate ``j`` to the frame).  The ``2n``
LPs are exact but far too slow; one positive self-stress added to a
least-squares ``u`` (:func:`~interlock.verify.margin.margin_lower_bound`) is
cheap but pays the stress of the whole assembly for every coordinate and
falls 100 to 300 times short.  :func:`load_path_bound` builds the load paths
block by block instead.

**Local step.**  For a load ``l`` on the columns of one free block ``g`` let
``C(l) = min {eps . u : u >= 0, A^T u = -l}`` (``+inf`` if none), so that
``l . x <= C(l)`` on ``P`` (weak duality).  Write ``a_r^g`` for the part of row
``r`` on block ``g`` and ``o(r)`` for the row's other block (none against the
frame).  Forces ``f_r >= 0`` on the rows of ``g`` with ``sum_r f_r a_r^g = -l``
balance ``l`` on ``g`` and load each neighbour ``o(r)`` with ``f_r a_r^o``.  If
``u_r >= 0`` carries that (``A^T u_r = -a_r^o``, cost ``gamma_r``), then
``u = f + sum_r f_r u_r`` has ``A^T u = -l``, ``u >= 0``, so

    C(l) <= sum_r f_r (eps_r + gamma_r),       gamma_r = 0 against the frame.   (1)

The unknowns are ``gamma_i`` for every *incidence* ``i = (r, g)`` (the load
``a_r^g``); (1) for ``l = a_r^g`` is one 6-row LP per incidence, and for
``l = +-e_k`` it gives the coordinate bounds ``V_g(+-k)``.

**The proof.**  Fix for every incidence ``i`` a feasible ``f`` of (1) (a
*policy*): ``c_i = sum_r f_r eps_r > 0`` and ``P_ij = f_r`` for ``j`` the
incidence that row ``r`` passes on to.  Any ``gamma > 0`` with
``c + P gamma <= gamma`` gives ``P gamma <= gamma - c < gamma``, so the spectral
radius of ``P >= 0`` is below 1 and the recursion ``u_i = f + sum P_ij u_j``
converges: a certificate for every incidence of cost ``((I - P)^-1 c)_i <=
gamma_i``.  With those ``gamma``, (1) for ``+-e_k`` proves ``V_g(+-k)`` and

    rho >= 1 / max_{g, k, +-} V_g(+-k).

**The computation.**  Gauss-Seidel passes of (1) from ``gamma = 0`` over the
blocks in layers (by distance from the frame, outside in and back) settle
the local solutions; from pass :data:`LOAD_PATH_FIRST_TRY` on, the last
pass's solutions are the policy: its costs are found by value iteration,
inflated by the least share that makes them a supersolution, and the
inequality checked (:meth:`_Paths.evaluate`); a policy that does not pass
(loads that circulate) proves nothing, but the values its first 25
iteration steps reached start the next pass (modified policy iteration).
Then a pass of (1) for the unit loads gives ``V``; policy iteration
improves it (:data:`LOAD_PATH_IMPROVEMENTS`), and coordinates still above the
target get exact LPs over their neighbourhood (:func:`_regional`).  On
RhomBlock hexagons rounded to float32 the converged bound is within 25 % of
the exact LPs (n = 8); the first proof, which decides, is 2 to 25 times
weaker.  Where no policy passes within :data:`LOAD_PATH_PASSES` passes
nothing is proved: on p4 Escher patches of radius 9 and 12 the values
double with each pass (measured; carrying each vertex row's load apart
seems to lose too much there, and adding each contact's or each block
pair's mean row as a load of its own slows the growth only from 2.3 to
1.8 times a pass), so the passes stop once the values have grown like
that (:data:`LOAD_PATH_DIVERGENCE`).

Floating point: the 6 x 6 systems are solved in floats; each value is
inflated by :data:`LOAD_PATH_SAFETY` (the rounding of its few products and
sums) and negative rounding residues of the forces are dropped.  What the
forces then miss of their load is counted, not assumed away: each local
solution's residual ``|sum_r f_r a_r^g + l|_1`` (real rows only: a slack
left in the basis counts as residual) is computed and rounded up
(:data:`LOAD_PATH_ROUNDING`).  A policy's certificates then miss at most
``kappa gamma_i`` with ``kappa = max_i residual_i / c_i`` (the misses obey
the recursion of the costs with ``c`` replaced by the residuals), a unit
load's at most ``delta = residual + kappa V``, and an exact regional LP's
at most its residual plus ``kappa`` times its cost.  A load missed by
``s`` gives ``+-x_j <= V + |s|_1 ||x||_inf`` on ``P``, so over all
coordinates ``||x||_inf <= X = max V / (1 - max delta)`` and each
``V + delta X`` is proved (:func:`closed_bounds`; nothing where
``max delta >= 1``).  The supersolution inequality is checked with a
margin of :data:`LOAD_PATH_ROUNDING` of the values, above the rounding of
its sums of at most seven terms.  The local LPs are solved by
a revised primal simplex vectorised over all loads of a layer (numpy, 6 x 6
bases, the inverse updated per pivot): the slacks give a feasible start
(phase one), every pivot keeps feasibility, so stopping after
:data:`LOAD_PATH_PIVOTS` pivots still gives a feasible, hence usable, policy.
Cost per pass: about ``rows * 2 + 12 * blocks`` LPs of about 6 x 40.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from interlock.errors import InterlockError

__all__ = ["LoadPathBound", "LoadPathError", "load_path_bound", "LOAD_PATH_PASSES", "LOAD_PATH_PIVOTS",
           "LOAD_PATH_UNIT_PIVOTS", "LOAD_PATH_SAFETY", "LOAD_PATH_PERTURBATION", "LOAD_PATH_SLACK", "LOAD_PATH_EVALUATION_STEPS",
           "LOAD_PATH_BATCH", "LOAD_PATH_IMPROVEMENTS", "LOAD_PATH_FIRST_TRY", "LOAD_PATH_STALL",
           "LOAD_PATH_RADII", "LOAD_PATH_REGIONAL", "LOAD_PATH_DIVERGENCE", "LOAD_PATH_DIVERGING",
           "LOAD_PATH_ROUNDING", "closed_bounds"]

#: Gauss-Seidel passes at most before a policy must have proved (outside in, inside out, ...).  RhomBlock
#: hexagons rounded to float32 prove after 2 passes up to n = 10, after 4 at n = 12.
LOAD_PATH_PASSES = 12
#: Simplex pivots per local LP at most; a 6-row LP with about 40 columns needs 6 to 45 from the slacks
#: (measured on hexagons), 0 to 5 warm.  Stopping early keeps a feasible local solution.
LOAD_PATH_PIVOTS = 120
#: ... and per unit load (``+-e_k``), which always starts from the slacks: at n = 40 a third of the unit loads
#: above 1 after 120 pivots were below it after 400.
LOAD_PATH_UNIT_PIVOTS = 400
#: Every computed value is multiplied by ``1 + LOAD_PATH_SAFETY``: far above the rounding of 6 x 6 solves
#: with condition numbers up to ~1e6 (``1e6 * 2^-52`` ~ 2e-10 per step, summed over at most thousands of steps).
LOAD_PATH_SAFETY = 1e-6
#: The residuals of the local solutions are rounded up by this share of the sums of absolute values they are
#: computed from (at most 6 x 6 + 6 terms: the float error is below 40 * 2^-53 ~ 4e-15 of those sums), and the
#: supersolution inequality ``c + P gamma <= gamma`` must hold with this share of ``gamma`` to spare (each entry a
#: sum of at most 7 nonnegative terms: its rounding is below 8 * 2^-53 ~ 9e-16 of it).
LOAD_PATH_ROUNDING = 1e-13
#: The local LPs' loads are perturbed by this share (random, fixed seed) while pivoting: no degenerate pivots.  The
#: final forces, solved with the true loads, may then come out negative by about this share, and dropping them is a
#: residual that the proof counts: at 1e-7 it was as large as the tolerances paid (float32 RhomBlock hexagon
#: n = 20: ``kappa`` 1.17, which leaves no proof near a margin of 1; n = 10: none at all); at 1e-10 ``kappa`` is
#: below 1e-3 there, with as many pivots and bounds 0 to 10 % tighter.
LOAD_PATH_PERTURBATION = 1e-10
#: A policy's evaluated costs may be inflated by at most this share to become a supersolution (the proof).
LOAD_PATH_SLACK = 0.05
#: Value-iteration steps at most when a policy's costs are evaluated (each one product with the sparse ``P``).
LOAD_PATH_EVALUATION_STEPS = 1500
#: Blocks whose local LPs are solved in one batch by the Jacobi passes (memory: about 100 kB per block).
LOAD_PATH_BATCH = 500
#: The passes stop early, proving nothing, once the median incidence value has grown by at least this factor in
#: each of the last :data:`LOAD_PATH_DIVERGING` passes (counted from the first try): on p4 Escher patches of
#: radius 9 and 12 rounded to float32 it grows 2.3 and 3.9 times from the first try to the next, and then 2 to 4
#: times with every pass, and no policy ever proves; where a policy proves (RhomBlock hexagons, p4 radius up to 6)
#: the median falls or grows by at most 1.4x before it does.  It only saves time: the one-stress bound of
#: :mod:`~interlock.verify.margin` follows.
LOAD_PATH_DIVERGENCE = 2.0
LOAD_PATH_DIVERGING = 1
#: Policy-iteration steps at most (each: a pass of the unit loads, then of the incidences, and an evaluation).
LOAD_PATH_IMPROVEMENTS = 8
#: The first pass after which the local solutions are evaluated (tried as certificates); earlier ones rarely are.
LOAD_PATH_FIRST_TRY = 2
#: Coordinates still above the target are bounded again by exact LPs over the blocks within these radii
#: (contacts) of their block, the next radius only for those still above; none when more than
#: :data:`LOAD_PATH_REGIONAL` coordinates are above (one LP of a few hundred rows each: 0.1 s at radius 2).
LOAD_PATH_RADII = (2, 3)
LOAD_PATH_REGIONAL = 60
#: Policy iteration stops once a step improves the bound by less than this share.
LOAD_PATH_STALL = 0.01


class LoadPathError(InterlockError):
    """Bad input to :func:`load_path_bound`: a matrix, tolerances or a block size that do not fit."""


@dataclass(frozen=True)
class LoadPathBound:
    """What :func:`load_path_bound` proved.

    ``bound`` is ``R``: every ``x`` with ``A x >= -eps`` has
    ``||x||_inf <= bound`` (``inf``: nothing proved); ``coordinates`` is the
    bound per column and sign, shape ``(n, 2)`` (``+x_j``, ``-x_j``);
    ``passes`` the Gauss-Seidel passes and ``pivots`` the simplex pivots.
    """

    bound: float
    coordinates: np.ndarray
    passes: int
    pivots: int

    @property
    def margin(self) -> float:
        """The proved lower bound ``1 / bound`` on the margin ``rho``."""
        return 0.0 if math.isinf(self.bound) else (math.inf if self.bound <= 0 else 1.0 / self.bound)


def load_path_bound(A, eps, block_size: int = 6, *, start: float | None = None, passes: int = LOAD_PATH_PASSES,
                    target: float | None = None, pivots: int = LOAD_PATH_PIVOTS, budget=None,
                    stage: str = "margin") -> LoadPathBound:
    """A proved bound ``R >= max {||x||_inf : A x >= -eps}`` from load paths built block by block.

    Parameters
    ----------
    A : scipy.sparse matrix (m, n)
        The interlocking matrix, ``block_size`` columns per free block.
    eps : array (m,)
        Positive row tolerances.
    start : float, optional
        The guess every incidence bound starts from (not a proof; the values
        only have to settle from below).  Default: 0.
    passes : int
        Gauss-Seidel passes at most before a policy must have proved.
    target : float, optional
        Stop as soon as the bound is at most this (e.g. 1: the margin exceeds 1).
    pivots : int
        Simplex pivots per local LP at most.
    budget : Budget, optional
        The call's time budget (:mod:`interlock.verify.budget`): checked after
        every pass and every local LP of the regional step, so a spent budget
        raises TimeLimitReached naming ``stage``.

    Returns
    -------
    LoadPathBound
        ``R`` and the bound per coordinate; ``rho >= 1 / R`` (the module's
        docstring has the argument).

    Examples
    --------
    Three cubes in a row, the outer ones fixed: the middle one moves only
    within its tolerances.

    >>> A = sp.csr_matrix(np.array([[1.0], [-1.0]]))
    >>> result = load_path_bound(A, np.array([1e-3, 2e-3]), block_size=1)
    >>> round(result.bound, 6), result.coordinates.round(6).tolist()
    (0.002, [[0.002, 0.001]])
    """
    A = sp.csr_matrix(A, dtype=float)
    eps = np.asarray(eps, dtype=float)
    m, n = A.shape
    if block_size not in (1, 3, 6) or n % block_size:
        raise LoadPathError(f"block_size must be 6, 3 (or 1) and divide the {n} columns, got {block_size!r}")
    if eps.shape != (m,) or not np.all(np.isfinite(eps)) or np.any(eps <= 0):
        raise LoadPathError(f"eps must hold {m} finite positive row tolerances")
    if not np.all(np.isfinite(A.data)):
        raise LoadPathError("the matrix A has entries that are not finite")
    for name, value in (("passes", passes), ("pivots", pivots)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise LoadPathError(f"{name} must be a positive integer, got {value!r}")
    if start is None:
        start = 0.0
    if isinstance(start, bool) or not isinstance(start, (int, float, np.floating)) or not 0 <= start < math.inf:
        raise LoadPathError(f"start must be a finite guess >= 0, got {start!r}")
    if target is not None and not (isinstance(target, (int, float, np.floating)) and target > 0):
        raise LoadPathError(f"target must be a positive number or None, got {target!r}")
    blocks = n // block_size
    if blocks == 0:
        return LoadPathBound(0.0, np.zeros((0, 2)), 0, 0)
    paths = _Paths(A, eps, block_size)
    paths.gamma[:] = start
    total, best, done, policy = 0, None, 0, None
    proper, medians = False, []
    while done < passes:  # from below, until the local solutions form certificates (a proper policy)
        done += 1
        policy, count = paths.sweep(paths.layers if done % 2 else paths.layers[::-1], pivots)
        total += count
        if budget is not None:
            budget.check(stage)
        if done >= LOAD_PATH_FIRST_TRY:
            proper = paths.evaluate(policy)  # if not, the values are pushed up along the policy
            if proper or _diverging(medians, paths.gamma):
                break
    proved = paths.gamma.copy() if proper else None
    for _ in range(LOAD_PATH_IMPROVEMENTS if proper else 0):  # policy iteration: improve, evaluate again
        # the values V rest on the proved gamma; a unit load starts from the slacks, so it gets more pivots
        _, count = paths.policy(LOAD_PATH_UNIT_PIVOTS * pivots // LOAD_PATH_PIVOTS, units=True, incidences=False)
        total += count
        if budget is not None:
            budget.check(stage)
        bound = float(paths.V.max(initial=0.0))
        if best is not None and bound >= (1 - LOAD_PATH_STALL) * best.bound:
            break
        best = LoadPathBound(bound, paths.V.reshape(blocks * block_size, 2).copy(), done, total)
        # what the unit loads' certificates miss: their own residual and kappa times their cost
        finite = np.isfinite(paths.V)
        slack = np.where(finite, paths.V_miss + paths.kappa * np.where(finite, paths.V, 0.0), 0.0)
        slack = slack.reshape(blocks * block_size, 2)
        if target is not None and bound <= target:
            break
        policy, count = paths.policy(pivots, units=False, incidences=True)
        total += count
        if not paths.evaluate(policy):
            break
        proved = paths.gamma.copy()
    if best is not None and target is not None and best.bound > target:
        best, slack = _regional(A, eps, paths, proved, best, slack, target, budget, stage)
    if best is None:
        return LoadPathBound(math.inf, np.full((blocks * block_size, 2), np.inf), done, total)
    coordinates = closed_bounds(best.coordinates, slack)
    return LoadPathBound(float(coordinates.max(initial=0.0)), coordinates, best.passes, total)


def closed_bounds(bounds, slack) -> np.ndarray:
    """Bounds on ``+-x_j`` over ``P`` from ``+-x_j <= bounds_j + slack_j ||x||_inf`` for *every* coordinate and sign.

    Every ``x`` (a finite vector) then has ``||x||_inf <= max bounds + max slack ||x||_inf``, hence
    ``||x||_inf <= X = max bounds / (1 - max slack)`` when ``max slack < 1``, and ``+-x_j <= bounds_j + slack_j X``
    (rounded up by ``2^-40``, far above the rounding of these few operations).  Where ``max slack >= 1`` (or a
    bound is infinite) only the entries without slack keep their bound, the others get ``inf``.

    Examples
    --------
    >>> closed_bounds(np.array([0.5, 0.25]), np.array([0.0, 0.5])).round(9).tolist()  # ||x||_inf <= 0.5 / 0.5
    [0.5, 0.75]
    """
    bounds, slack = np.asarray(bounds, dtype=float), np.asarray(slack, dtype=float)
    up = 1.0 + 2.0**-40
    top, most = float(bounds.max(initial=0.0)), float(slack.max(initial=0.0))
    if not most < 1.0 or not math.isfinite(top):
        return np.where(slack > 0, math.inf, bounds) * up
    X = top / (1.0 - most) * up
    return (bounds + slack * X) * up


def _diverging(medians: list, gamma: np.ndarray) -> bool:
    """Record the median of ``gamma``; True once it grew by :data:`LOAD_PATH_DIVERGENCE` in each of the last
    :data:`LOAD_PATH_DIVERGING` passes (the first recorded value is the first try's)."""
    finite = gamma[np.isfinite(gamma)]
    medians.append(float(np.median(finite)) if len(finite) else math.inf)
    recent = medians[-(LOAD_PATH_DIVERGING + 1):]
    return len(recent) > LOAD_PATH_DIVERGING and all(
        later >= LOAD_PATH_DIVERGENCE * earlier for earlier, later in zip(recent, recent[1:]))


def _regional(A, eps, paths, proved, best: LoadPathBound, slack: np.ndarray, target: float, budget=None,
              stage: str = "margin") -> tuple[LoadPathBound, np.ndarray]:
    """Lower the coordinate bounds above ``target`` by exact LPs over the blocks near the coordinate's block.

    For block ``g`` and radius ``k`` take the blocks ``S`` within ``k``
    contacts of ``g`` and the rows touching ``S``: ``min eps' . u``,
    ``u >= 0``, ``(A^T u)_S = -+e_j`` with ``eps'_r = eps_r + gamma_i`` for a
    row whose other incidence ``i`` lies outside ``S`` (its load is carried on
    by the proved ``gamma``), ``eps_r`` otherwise.  As in (1) of the module,
    ``u`` and the certificates behind ``gamma`` make a certificate; what it
    misses (the solver's residual on ``S``, rounded up, and ``kappa`` times
    the cost carried by ``gamma``) becomes the coordinate's ``slack`` (bounds
    ``+-x_j <= V_j + slack_j ||x||_inf``, closed by :func:`closed_bounds`).
    Loads that cancel within ``S`` are no longer carried apart: radius 2 and
    3 take the worst coordinates of the 4,800-block hexagon from 1.4 to 0.35
    to 1.05.
    """
    import scipy.optimize

    size = paths.size
    V = best.coordinates.reshape(-1, size, 2).copy()
    missed = slack.reshape(-1, size, 2).copy()
    has = paths.other >= 0
    blocks = len(V)
    neighbours = sp.csr_matrix((np.ones(int(has.sum())), (paths.block[has], paths.block[paths.other[has]])),
                               shape=(blocks, blocks))
    rows_of = sp.csr_matrix((np.ones(len(paths.row)), (paths.block, paths.row)), shape=(blocks, A.shape[0]))
    for radius in LOAD_PATH_RADII:
        above = np.argwhere(V > target / (1 + LOAD_PATH_SAFETY))
        if len(above) == 0 or len(above) > LOAD_PATH_REGIONAL:
            break
        for g, k, side in above:
            region, front = np.array([g]), np.array([g])
            for _ in range(radius):
                front = np.setdiff1d(neighbours[front].indices, region)
                region = np.union1d(region, front)
            rows = np.unique(rows_of[region].indices)
            inside = np.zeros(blocks, dtype=bool)
            inside[region] = True
            cost = eps[rows].copy()
            outside = np.flatnonzero(np.isin(paths.row, rows) & ~inside[paths.block])
            cost[np.searchsorted(rows, paths.row[outside])] += proved[outside]
            if not np.all(np.isfinite(cost)):
                continue
            columns = (size * region[:, None] + np.arange(size)).ravel()
            local = A[rows][:, columns].T.tocsr()
            load = np.zeros(len(columns))
            load[np.searchsorted(region, g) * size + k] = 1.0 if side == 0 else -1.0
            options = {} if budget is None or budget.solver_limit() is None else {"time_limit": budget.solver_limit()}
            result = scipy.optimize.linprog(cost, A_eq=local, b_eq=-load, bounds=(0, None), method="highs",
                                            options=options)
            if budget is not None:
                budget.check(stage)
            if result.status != 0 or result.x is None:
                continue
            u = np.maximum(result.x, 0.0)
            value = float(cost @ u) * (1.0 + LOAD_PATH_SAFETY)
            residual = float(np.abs(local @ u + load).sum()) + LOAD_PATH_ROUNDING * float((abs(local) @ u).sum())
            miss = (residual + LOAD_PATH_ROUNDING) * (1.0 + LOAD_PATH_SAFETY) + paths.kappa * value
            if value + miss * target < V[g, k, side] + missed[g, k, side] * target:  # both proved: the smaller
                V[g, k, side], missed[g, k, side] = value, miss
    coordinates = V.reshape(-1, 2)
    return (LoadPathBound(float(coordinates.max(initial=0.0)), coordinates, best.passes, best.pivots),
            missed.reshape(-1, 2))


class _Paths:
    """The incidences (row, block) of ``A``, the bounds ``gamma`` per incidence and ``V`` per coordinate."""

    def __init__(self, A: sp.csr_matrix, eps: np.ndarray, size: int):
        m, n = A.shape
        self.size, self.eps = size, eps
        blocks = n // size
        coo = A.tocoo()
        keep = coo.data != 0
        rows, cols, vals = coo.row[keep], coo.col[keep], coo.data[keep]
        key = rows.astype(np.int64) * blocks + cols // size
        pairs, where = np.unique(key, return_inverse=True)
        self.row = (pairs // blocks).astype(np.int64)  # per incidence: its row and its block
        self.block = (pairs % blocks).astype(np.int64)
        self.vector = np.zeros((len(pairs), size))  # a_r^g
        np.add.at(self.vector, (where, cols % size), vals)
        # the other incidence of the same row (-1: the row is against the frame)
        self.other = np.full(len(pairs), -1, dtype=np.int64)
        first = np.r_[True, self.row[1:] != self.row[:-1]]
        starts = np.flatnonzero(first)
        counts = np.diff(np.r_[starts, len(pairs)])
        if np.any(counts > 2):
            raise LoadPathError("a row of A touches more than two blocks")
        two = starts[counts == 2]
        self.other[two], self.other[two + 1] = two + 1, two
        self.gamma = np.full(len(pairs), np.inf)
        self.bases = np.full((len(pairs), size), -1, dtype=np.int64)  # each incidence LP's last basis
        self.V = np.full((blocks, size, 2), np.inf)
        self.V_miss = np.zeros((blocks, size, 2))  # what the local solution of each unit load misses of it
        self.kappa = math.inf  # the proved gamma's certificates miss at most kappa * gamma of their loads
        # each block's incidences, padded
        order = np.argsort(self.block, kind="stable")
        per_block = np.bincount(self.block, minlength=blocks)
        self.width = int(per_block.max(initial=0))
        self.columns = np.full((blocks, self.width), -1, dtype=np.int64)
        offsets = np.r_[0, np.cumsum(per_block)[:-1]]
        slot = np.arange(len(order)) - offsets[self.block[order]]
        self.columns[self.block[order], slot] = order
        self.layers = _layers(self, blocks)

    def local(self, layer: np.ndarray, pivots: int, units: bool = True, incidences: bool = True):
        """The local LPs of the blocks ``layer`` at the current ``gamma``: every incidence load and every ``+-e_k``.

        Returns ``(incidences, values, eps_parts, carried, forces, misses)``
        for the incidence loads (``carried``: for each basic column the
        incidence whose load it passes on, -1 for none; ``misses``: the
        residuals of the forces, rounded up), ``(blocks, k, sign, values,
        misses)`` for the unit loads, and the pivots done.
        """
        size, width = self.size, self.width
        cols = self.columns[layer]  # (b, width)
        real = cols >= 0
        safe = np.maximum(cols, 0)
        vectors = np.where(real[..., None], self.vector[safe], 0.0)  # (b, width, size)
        other = np.where(real, self.other[safe], -1)
        carry = np.where(other >= 0, self.gamma[np.maximum(other, 0)], 0.0)
        own = np.where(real, self.eps[self.row[safe]], 0.0)
        cost = np.where(real, own + carry, np.inf)
        eye = np.eye(size)
        count = len(layer)
        # columns: the rows' vectors, then slacks -e_k and +e_k for a first phase (infinite cost)
        M = np.concatenate([vectors.transpose(0, 2, 1), np.broadcast_to(-eye, (count, size, size)),
                            np.broadcast_to(eye, (count, size, size))], axis=2)  # (b, size, width + 2 size)
        c = np.concatenate([cost, np.full((count, 2 * size), np.inf)], axis=1)
        e = np.concatenate([own, np.zeros((count, 2 * size))], axis=1)
        # the loads: each incidence of the block, then +e_k and -e_k
        loads = np.concatenate([vectors, np.broadcast_to(eye, (count, size, size)),
                                np.broadcast_to(-eye, (count, size, size))], axis=1)  # (b, width + 2 size, size)
        valid = np.concatenate([real & incidences, np.full((count, 2 * size), units)], axis=1)
        owner, which = np.nonzero(valid)
        slots = which < width
        warm = np.full((len(owner), size), -1, dtype=np.int64)
        warm[slots] = self.bases[cols[owner[slots], which[slots]]]
        values, parts, done, bases, forces, misses = _simplex(M[owner], c[owner], e[owner], -loads[owner, which],
                                                              pivots, warm)
        self.bases[cols[owner[slots], which[slots]]] = bases[slots]
        values = values * (1.0 + LOAD_PATH_SAFETY)
        used = np.take_along_axis(np.concatenate([other, np.full((count, 2 * size), -1)], axis=1)[owner], bases,
                                  axis=1)  # the incidence each basic column loads (-1: the frame or a slack)
        unit = which[~slots] - width
        return ((cols[owner[slots], which[slots]], values[slots], parts[slots], used[slots], forces[slots],
                 misses[slots]), (layer[owner[~slots]], unit % size, unit // size, values[~slots], misses[~slots]),
                done)

    def sweep(self, layers, pivots: int):
        """One Gauss-Seidel pass: each layer's local LPs at the latest values, which they replace.

        Returns the local solutions (a policy for :meth:`evaluate`) and the pivots done.
        """
        done, found = 0, []
        for layer in layers:
            incidence, _, count = self.local(layer, pivots, units=False)
            self.gamma[incidence[0]] = incidence[1]
            found.append(incidence)
            done += count
        return [np.concatenate(part) for part in zip(*found)], done

    def policy(self, pivots: int, units: bool, incidences: bool):
        """One Jacobi pass at the current ``gamma``: the bounds ``V`` it implies and/or each incidence's local solution."""
        done, found = 0, []
        everything = np.concatenate(self.layers)
        for start in range(0, len(everything), LOAD_PATH_BATCH):
            incidence, (g, k, sign, unit, miss), count = self.local(everything[start:start + LOAD_PATH_BATCH], pivots,
                                                                    units, incidences)
            self.V[g, k, sign], self.V_miss[g, k, sign] = unit, miss
            found.append(incidence)
            done += count
        return [np.concatenate(part) for part in zip(*found)], done

    def evaluate(self, policy) -> bool:
        """Set ``gamma`` to the proved cost of the certificates that ``policy`` builds; False where it proves nothing
        (``gamma`` then holds the values the policy's iteration reached: a guess for the next pass).

        Also sets ``kappa`` (the module's docstring, "Floating point").

        With the local solutions fixed, the costs solve ``gamma = c + P gamma``
        (``c`` the tolerances paid on the block, ``P >= 0`` the loads passed
        on).  A ``gamma > 0`` with ``c + P gamma <= gamma`` and ``c > 0``
        gives ``P gamma < gamma``, so the spectral radius of ``P`` is below 1:
        the recursion converges to a certificate of cost ``(I - P)^-1 c <=
        gamma``.  The costs are found by value iteration from the current
        values (at most :data:`LOAD_PATH_EVALUATION_STEPS` steps), inflated
        by the least share (at most :data:`LOAD_PATH_SLACK`) that makes them
        a supersolution, and that inequality is checked.
        """
        incidences, values, parts, used, forces, misses = policy
        count = len(self.gamma)
        finite = np.zeros(count, dtype=bool)
        finite[incidences[np.isfinite(values) & (parts > 0)]] = True
        while True:  # a solution that passes load to an unproved incidence proves nothing either
            bad = np.any((used >= 0) & (forces > 0) & ~finite[np.maximum(used, 0)], axis=1) & finite[incidences]
            if not bad.any():
                break
            finite[incidences[bad]] = False
        keep = finite[incidences]
        if not keep.any():
            return False
        index = np.full(count, -1)
        index[incidences[keep]] = np.arange(int(keep.sum()))
        rows = np.repeat(index[incidences[keep]], self.size)
        links, weights = used[keep].ravel(), forces[keep].ravel()
        take = (links >= 0) & (weights > 0)
        P = sp.csr_matrix((weights[take], (rows[take], index[links[take]])), shape=(keep.sum(), keep.sum()))
        c = parts[keep]
        solution = np.maximum(self.gamma[incidences[keep]], c)
        changes, pushed = [], None
        for _ in range(0, LOAD_PATH_EVALUATION_STEPS, 25):
            before = solution
            for _ in range(25):  # the costs of the fixed policy, from the current values (value iteration)
                solution = c + P @ solution
            pushed = solution if pushed is None else pushed
            changes.append(float(np.abs(solution - before).max()))
            if not np.all(np.isfinite(solution)) or (len(changes) > 4 and changes[-1] > 0.9 * changes[-4]):
                # not converging: the loads circulate (an improper policy) or too slowly.  The values after
                # the first steps are a better guess than before (modified policy iteration): the next pass
                # starts there
                self.gamma[incidences[keep]] = np.maximum(self.gamma[incidences[keep]], pushed)
                return False
            passed = solution - P @ solution  # a supersolution times (1 + eta) needs (1 + eta) passed >= c
            if np.all(passed > 0):
                eta = max(float(np.max(c / passed)) - 1.0, 0.0) + LOAD_PATH_SAFETY
                if eta <= LOAD_PATH_SLACK:
                    solution = solution * (1.0 + eta)
                    break
        else:
            return False
        if np.any(c + P @ solution > solution * (1.0 - LOAD_PATH_ROUNDING)):  # with room for the sums' rounding
            return False
        # the certificates miss rho = residuals + P rho <= kappa (I - P)^-1 c <= kappa gamma of their loads
        residuals = misses[keep]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratios = np.where(residuals > 0, residuals / c, 0.0)
        self.kappa = float(ratios.max(initial=0.0)) * (1.0 + LOAD_PATH_ROUNDING)
        self.gamma[:] = np.inf
        self.gamma[incidences[keep]] = solution
        return True


def _layers(paths: _Paths, blocks: int) -> list[np.ndarray]:
    """The free blocks by their distance (in contacts) from the frame: the blocks with a row against it first."""
    has_other = paths.other >= 0
    edges = sp.csr_matrix((np.ones(int(has_other.sum())), (paths.block[has_other],
                                                           paths.block[paths.other[has_other]])),
                          shape=(blocks, blocks))
    distance = np.full(blocks, -1)
    front = np.unique(paths.block[~has_other])
    level = 0
    while front.size:
        distance[front] = level
        reached = np.unique(edges[front].indices)
        front = reached[distance[reached] < 0]
        level += 1
    layers = [np.flatnonzero(distance == d) for d in range(level)]
    unreached = np.flatnonzero(distance < 0)
    return layers + ([unreached] if unreached.size else [])


def _simplex(M: np.ndarray, c: np.ndarray, e: np.ndarray, b: np.ndarray, pivots: int, warm=None):
    """``min c . f`` subject to ``M f = b``, ``f >= 0``, for a stack of small LPs.

    ``M`` has shape ``(N, s, p)`` whose last ``2 s`` columns are ``-I, +I``;
    columns of infinite cost are allowed (phase one keeps them at zero: the
    value is ``inf`` where it cannot).  Revised primal simplex from the slack
    basis (or ``warm``, a basis per LP, -1 for none, where still feasible),
    the inverse basis updated by each pivot, Dantzig's rule and then Bland's,
    vectorised over the stack.  Every iterate is feasible, so the value of
    the last basis is that of a feasible point even where the pivots ran out;
    the final forces are solved again from the basis.  Returns (values,
    ``e . f``, pivots done, final bases, the forces on them, and what the
    forces on real columns miss of ``b``: ``|M f - b|_1`` rounded up by
    :data:`LOAD_PATH_ROUNDING`, a slack left in the basis counted as missed).
    """
    N, s, p = M.shape
    if N == 0:
        return np.zeros(0), np.zeros(0), 0, np.zeros((0, s), dtype=np.int64), np.zeros((0, s)), np.zeros(0)
    infinite = ~np.isfinite(c)
    c1 = infinite.astype(float)  # phase one: the columns that have no proved cost
    c2 = np.where(infinite, 0.0, c)
    k = np.arange(s)
    # the right-hand sides perturbed a little (no ties in the ratio test, so no cycling); the final forces
    # are solved again with the true ones
    size = np.abs(b).max(axis=1, keepdims=True)
    perturbed = b + LOAD_PATH_PERTURBATION * size * np.random.default_rng(0).uniform(0.5, 1.0, b.shape) * \
        np.where(b >= 0, 1.0, -1.0)
    # the slack basis: +e_k (column p - s + k) where b_k >= 0, else -e_k (column p - 2 s + k)
    plus = perturbed >= 0
    basis = np.where(plus, p - s + k, p - 2 * s + k)
    x = np.abs(perturbed)
    inverse = np.zeros((N, s, s))
    inverse[:, k, k] = np.where(plus, 1.0, -1.0)
    if warm is not None:
        use = np.flatnonzero(warm[:, 0] >= 0)
        if use.size:
            start, solved = _solve(np.take_along_axis(M[use], warm[use][:, None, :], axis=2),
                                   np.broadcast_to(np.eye(s), (use.size, s, s)).copy())
            values = np.einsum("aij,aj->ai", start, perturbed[use])
            feasible = solved & np.all(values >= 0, axis=1)
            chosen = use[feasible]
            basis[chosen], x[chosen], inverse[chosen] = warm[chosen], values[feasible], start[feasible]
    scale = np.maximum(np.abs(c2).max(axis=1), 1e-300)
    count = 0
    work = np.arange(N)  # the LPs still pivoting (gathered afresh once half of them are done)
    Mw, c1w, c2w = M, c1, c2
    for step_number in range(pivots):
        if work.size == 0:
            break
        Bi, Ba = inverse[work], basis[work]
        y2 = np.einsum("aji,aj->ai", Bi, np.take_along_axis(c2w, Ba, axis=1))
        d2 = c2w - np.einsum("asp,as->ap", Mw, y2)
        first = np.take_along_axis(c1w, Ba, axis=1)
        if first.any():  # some LPs are still in phase one
            d1 = c1w - np.einsum("asp,as->ap", Mw, np.einsum("aji,aj->ai", Bi, first))
        else:
            d1 = c1w
        phase_one = (d1 < -1e-9).any(axis=1)
        candidates = np.where(phase_one[:, None], d1 < -1e-9, (d1 <= 1e-9) & (d2 < -1e-12 * scale[work, None]))
        np.put_along_axis(candidates, Ba, False, axis=1)  # a basic column's reduced cost is zero up to rounding
        improving = candidates.any(axis=1)
        if step_number < 3 * pivots // 4:  # Dantzig's rule first, then Bland's, which cannot cycle
            enter = np.where(phase_one, d1.argmin(axis=1), np.where(candidates, d2, np.inf).argmin(axis=1))
        else:
            enter = candidates.argmax(axis=1)
        column = np.take_along_axis(Mw, enter[:, None, None], axis=2)[:, :, 0]
        direction = np.einsum("aij,aj->ai", Bi, column)
        positive = direction > 1e-9 * np.abs(direction).max(axis=1, keepdims=True)
        ratios = np.where(positive, x[work] / np.where(positive, direction, 1.0), np.inf)
        step = ratios.min(axis=1)
        ties = ratios <= step[:, None] * (1 + 1e-12) + 1e-300
        leave = np.where(ties, Ba, p).argmin(axis=1)  # the tie of smallest column index
        move = improving & np.isfinite(step)
        a = np.flatnonzero(move)
        idx = work[a]
        # x and the inverse after the pivot: row ``leave`` divided by the pivot, eliminated from the others
        d, l = direction[a], leave[a]
        pivot = d[np.arange(a.size), l]
        x_new = x[idx] - step[a, None] * d
        x_new[np.arange(a.size), l] = step[a]
        x[idx] = np.maximum(x_new, 0.0)
        row = Bi[a, l, :] / pivot[:, None]
        Bi_new = Bi[a] - d[:, :, None] * row[:, None, :]
        Bi_new[np.arange(a.size), l, :] = row
        inverse[idx] = Bi_new
        basis[idx, l] = enter[a]
        count += int(a.size)
        if a.size <= work.size // 2:
            work, Mw, c1w, c2w = idx, M[idx], c1[idx], c2[idx]
        elif a.size < work.size:
            work, Mw, c1w, c2w = idx, Mw[a], c1w[a], c2w[a]
    # the forces solve M f = b only up to rounding: solve them again from the final basis, drop negative residues
    f, solved = _solve(np.take_along_axis(M, basis[:, None, :], axis=2), b[:, :, None])
    exact = np.where(solved[:, None], np.maximum(f[:, :, 0], 0.0), x)
    values = np.maximum((np.take_along_axis(c2, basis, axis=1) * x).sum(axis=1),
                        (np.take_along_axis(c2, basis, axis=1) * exact).sum(axis=1))
    cost1 = np.maximum((np.take_along_axis(c1, basis, axis=1) * x).sum(axis=1),
                       (np.take_along_axis(c1, basis, axis=1) * exact).sum(axis=1))
    parts = (np.take_along_axis(e, basis, axis=1) * exact).sum(axis=1) * (1.0 + LOAD_PATH_ROUNDING)
    basic = np.take_along_axis(M, basis[:, None, :], axis=2)
    real = np.where(basis < p - 2 * s, exact, 0.0)  # the slacks -e_k, +e_k are no rows of A
    missed = np.abs(np.einsum("aij,aj->ai", basic, real) - b).sum(axis=1)
    missed += LOAD_PATH_ROUNDING * (np.einsum("aij,aj->a", np.abs(basic), real) + np.abs(b).sum(axis=1))
    return np.where(cost1 > 1e-12, np.inf, values), parts, count, basis, exact, missed * (1.0 + LOAD_PATH_ROUNDING)


def _solve(matrices: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Batched ``solve(matrices, rhs)``; where a matrix is singular, zeros and False in the second array."""
    try:
        return np.linalg.solve(matrices, rhs), np.ones(len(matrices), dtype=bool)
    except np.linalg.LinAlgError:
        out, ok = np.zeros(rhs.shape), np.ones(len(matrices), dtype=bool)
        for i, (matrix, right) in enumerate(zip(matrices, rhs)):
            try:
                out[i] = np.linalg.solve(matrix, right)
            except np.linalg.LinAlgError:
                ok[i] = False
        return out, ok
