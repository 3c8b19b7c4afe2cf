"""The MILP relaxation of CRA's problem (11) (step 1 of :func:`~interlock.verify.statics.cra.cra`).

A binary ``z_v`` per contact vertex switches Eq. (10) (``f_n <= M z_v``,
``dd_n + eps <= M (1 - z_v)``), and binaries over angular sectors of the
contact plane put the slide ``dd_t`` and the reversed friction ``-f_t`` in the
same sector, with a slide of at least ``min_slide`` along the sector's bisector
where there is friction (Eq. (9) up to the sector's width). Every solution of
(11) within the bounds is a solution of this MILP, so an infeasible MILP
proves "unstable"; a feasible one gives a motion for the exact LP
(``CRAProblem.exact``).

The big Ms are per vertex: :func:`vertex_reach` (how far an allowed motion can
open a vertex, an LP each) and :func:`force_bounds` (the largest normal force
of an RBE equilibrium within the virtual-work bound, an LP each). Rows that
every solution of (11) satisfies tighten it: the virtual-work row, friction
only at closed vertices, and :func:`face_cuts` (closed vertices span a face of
a convex contact polygon). docs/statics.md, "1. The MILP relaxation with
sectors", has the derivation.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
import shapely
from scipy.optimize import Bounds, LinearConstraint, milp

from interlock.verify.statics.equilibrium import TimeLimitReached, highs_lp

__all__ = ["BOUND_MARGIN", "LOOSE", "vertex_reach", "face_cuts", "force_bounds", "relaxation"]

#: Slack added to every bound the MILP derives by an LP (big Ms, the virtual-work bound and row), relative and
#: absolute (forces in units of the weight, motions of eps): a solution of (11) often attains them exactly (a
#: block pushed into a groove closes every vertex and does exactly the most work), and HiGHS' tolerances would
#: then call the MILP infeasible.
BOUND_MARGIN = 1e-3
#: Factor on the big Ms of the second, looser MILP that confirms an infeasibility (:func:`relaxation`).
LOOSE = 10.0


def vertex_reach(problem) -> np.ndarray:
    """Per vertex ``(max dd_n + eps, max |dd_t|)`` over the allowed motions (the MILP's big Ms), eps = 1.

    ``dd_n`` by an LP per vertex (the geometry often keeps it far below ``eta``, e.g. between two walls);
    ``|dd_t| <= sqrt(2) eta`` from the bound on each component, which LPs do not improve in practice.
    """
    d = problem.kinematic
    s = d.shape[0] // 3
    a_ub, b_ub = problem.allowed_motions
    normal = np.full(s, problem.ratio)
    for v in range(s):
        outcome = highs_lp(-d[3 * v].toarray().ravel(), problem.budget, "the MILP's bounds (vertex reach)",
                           A_ub=a_ub, b_ub=b_ub, bounds=(None, None))
        if outcome.status == 0:
            normal[v] = -outcome.fun
    normal = normal * (1 + BOUND_MARGIN) + BOUND_MARGIN + 1.0
    return np.column_stack([normal, np.full(s, math.hypot(problem.ratio, problem.ratio) * (1 + BOUND_MARGIN))])


def face_cuts(problem) -> np.ndarray:
    """Rows ``(a, c, b)`` of vertex indices with ``z_a + z_c - z_b <= 1``: the MILP's face cuts.

    ``dd_n`` is affine over a contact polygon and ``>= -eps`` at its
    vertices, so the vertices where it equals ``-eps`` span a face of the
    polygon (a vertex, an edge or all of it) when the polygon is convex.
    Two closed vertices whose diagonal crosses the interior close them all.

    Examples
    --------
    A cube on a fixed cube meets it in a square: two diagonals, each with two other corners.

    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> face_cuts(CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)).shape
    (4, 3)
    """
    triples, start = [], 0
    for contact in problem.system.contacts:
        count, polygon = len(contact.vertices), contact.polygon
        convex = not polygon.interiors and abs(polygon.convex_hull.area - polygon.area) <= 1e-9 * polygon.area
        if convex and count >= 4:
            ring = (contact.vertices - contact.origin) @ contact.basis.T
            inner = polygon.buffer(-1e-6 * math.sqrt(polygon.area))
            for a in range(count):
                for c in range(a + 2, count - (a == 0)):
                    if inner.contains(shapely.Point((ring[a] + ring[c]) / 2)):
                        triples += [(start + a, start + c, start + b) for b in range(count) if b not in (a, c)]
        start += count
    return np.array(triples, dtype=int).reshape(-1, 3)


def force_bounds(problem, b_eq, work: float) -> np.ndarray:
    """Per vertex, the largest ``f_n`` of any RBE equilibrium whose normal forces sum to at most
    ``work`` (``CRAProblem._most_work``), capped at ``force_bound`` (the MILP's big M)."""
    system = problem.system
    s = len(system.points)
    cap = min(problem.force_bound, work)
    bounds = np.full(s, cap)
    box = system.bounds.copy()
    box[0::3, 1] = cap
    total = sp.csr_matrix(np.tile([1.0, 0.0, 0.0], s))
    a_ub = sp.vstack([system.a_ub, total], format="csr")
    b_ub = np.concatenate([np.zeros(system.a_ub.shape[0]), [cap]])
    for v in range(s):
        cost = np.zeros(3 * s)
        cost[3 * v] = -1.0
        outcome = highs_lp(cost, problem.budget, "the MILP's bounds (vertex forces)", A_ub=a_ub, b_ub=b_ub,
                           A_eq=system.a_eq, b_eq=b_eq, bounds=box)
        if outcome.status == 0:
            bounds[v] = min(cap, -outcome.fun * (1 + BOUND_MARGIN) + BOUND_MARGIN)
    return bounds


def relaxation(problem, b_eq, force_bounds, sectors: int, nodes: int, tightened: bool = True, work: float = np.inf):
    """Forces and motion of the relaxation, ``None`` if infeasible, or a message if HiGHS did not decide.

    ``force_bounds`` are :func:`force_bounds` for this load, the big Ms of ``f_n``; ``nodes``: HiGHS'
    ``node_limit``, past which the MILP is undecided (the same on every machine); HiGHS' ``time_limit`` is the
    time ``problem.budget`` has left, and running out raises
    :class:`~interlock.verify.budget.TimeLimitReached`.  ``work``: the most work of the load
    (``CRAProblem._most_work``), which also bounds the friction: by virtual work ``alpha_v |dd_t,v|^2 <= work``
    at each vertex, so ``|f_t,v| = alpha_v |dd_t,v| <= work / min_slide`` where the MILP lets it carry friction.
    That keeps the friction's big M representable for a large ``mu`` (``mu_c M_v`` reached 1e18 at
    ``mu = 1e15``, beyond HiGHS' largest matrix value).

    Beside Eqs. (9)-(10) with big Ms, three families of rows hold for every solution of (11) and
    tighten the relaxation (``tightened``): the virtual-work row ``b.q + sum f_n <= 0``, friction
    only at closed vertices, and the face cuts of :func:`face_cuts`.  Without them, and with the big
    Ms :data:`LOOSE` times larger, the MILP is a second, numerically different route to the same
    answer, which ``CRAProblem.solve`` asks before it calls an assembly unstable.

    Examples
    --------
    Model H (CRA paper, Sec. 2.2): a block between two upright fixed walls. RBE holds it by a squeeze,
    but no motion closes both walls while it slides down, so the relaxation is infeasible.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> walls = [trimesh.creation.box(bounds=b) for b in ([[-1, 0, 0], [0, 1, 2]], [[1, 0, 0], [2, 1, 2]])]
    >>> middle = trimesh.creation.box(bounds=[[0, 0, 1], [1, 1, 2]])
    >>> problem = CRAProblem.build(Assembly.from_meshes(walls + [middle], frame=[0, 1]), 0.84)
    >>> b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    >>> work, _ = problem._most_work(b_eq)
    >>> relaxation(problem, b_eq, force_bounds(problem, b_eq, work), 4, nodes=100) is None
    True
    """
    system, d = problem.system, problem.kinematic
    s, free = len(system.points), system.a_eq.shape[0]
    if s == 0:
        return None if not np.allclose(b_eq, 0.0) else (np.zeros((0, 3)), np.zeros(free))
    n_f, n_q, n_z, n_s = 3 * s, free, s, s * sectors
    size = n_f + n_q + n_z + n_s
    of, oq, oz, os_ = 0, n_f, n_f + n_q, n_f + n_q + n_z
    ratio = problem.ratio
    mu_c = -system.cone_rows[0, 0] / math.cos(math.pi / len(system.cone_rows))  # the pyramid's widest |f_t| / f_n
    loose = 1.0 if tightened else LOOSE
    force_bounds = force_bounds * loose
    friction_cap = loose * (work * (1 + BOUND_MARGIN) + BOUND_MARGIN) / problem.min_slide
    big_t = np.maximum(np.minimum(mu_c * force_bounds, friction_cap), 1e-9)
    big_n, big_d = problem.reach[:, 0] * loose, problem.reach[:, 1] * loose + problem.min_slide
    d_n, d_u, d_v = d[0::3], d[1::3], d[2::3]
    vertices = np.arange(s)
    rows = []  # (matrix over x, lower, upper)

    def columns(block, offset):
        block = sp.csr_matrix(block)
        return sp.hstack([sp.csr_matrix((block.shape[0], offset)), block,
                          sp.csr_matrix((block.shape[0], size - offset - block.shape[1]))], format="csr")

    def select(offset, component, scale=1.0, stride=3):
        # one row per vertex v: scale_v * x[offset + stride v + component]
        return sp.csr_matrix((np.broadcast_to(scale, s), (vertices, offset + stride * vertices + component)),
                             shape=(s, size))

    rows.append((columns(system.a_eq, of), b_eq, b_eq))
    rows.append((columns(system.a_ub, of), -np.inf, 0.0))
    rows.append((select(of, 0) - select(oz, 0, force_bounds, 1), -np.inf, 0.0))  # f_n <= M_v z
    rows.append((columns(d_n, oq) + select(oz, 0, big_n, 1), -np.inf, big_n - 1.0))  # dd_n + 1 <= M_v (1 - z)
    angles = 2.0 * math.pi * np.arange(sectors + 1) / sectors
    edge = np.column_stack([np.cos(angles), np.sin(angles)])
    middle = np.column_stack([np.cos(angles[:-1] + math.pi / sectors), np.sin(angles[:-1] + math.pi / sectors)])
    one_sector = sp.csr_matrix((np.ones(n_s), (np.repeat(vertices, sectors), os_ + np.arange(n_s))),
                               shape=(s, size))
    if tightened:
        # virtual work: b.q = f.dd = -sum f_n - sum alpha |dd_t|^2 <= -sum f_n for any solution of (11)
        work = np.zeros(size)
        work[oq:oq + n_q], work[of:of + n_f:3] = b_eq, 1.0
        rows.append((sp.csr_matrix(work), -np.inf, BOUND_MARGIN))
        rows.append((one_sector - select(oz, 0, 1.0, 1), -np.inf, 0.0))  # friction only where closed
        cuts = problem.face_cuts
        if len(cuts):
            rows.append((sp.csr_matrix((np.tile([1.0, 1.0, -1.0], len(cuts)),
                                        (np.repeat(np.arange(len(cuts)), 3), oz + cuts.ravel())),
                                       shape=(len(cuts), size)), -np.inf, 1.0))
    else:
        rows.append((one_sector, -np.inf, 1.0))
    no_sector = sp.diags(big_t) @ one_sector
    for component in (1, 2):  # no sector, no friction
        rows.append((select(of, component) - no_sector, -np.inf, 0.0))
        rows.append((select(of, component) + no_sector, 0.0, np.inf))
    for k in range(sectors):
        a, b, g = edge[k], edge[k + 1], middle[k]
        slide_a = columns(a[0] * d_v - a[1] * d_u, oq)  # a x dd_t >= 0 in the sector
        slide_b = columns(b[1] * d_u - b[0] * d_v, oq)  # dd_t x b >= 0
        force_a = select(of, 1, a[1]) - select(of, 2, a[0])  # a x (-f_t) >= 0
        force_b = select(of, 2, b[0]) - select(of, 1, b[1])  # (-f_t) x b >= 0
        along = columns(g[0] * d_u + g[1] * d_v, oq)  # g . dd_t >= min_slide
        rows.append((slide_a - select(os_, k, big_d, sectors), -big_d, np.inf))
        rows.append((slide_b - select(os_, k, big_d, sectors), -big_d, np.inf))
        rows.append((force_a - select(os_, k, big_t, sectors), -big_t, np.inf))
        rows.append((force_b - select(os_, k, big_t, sectors), -big_t, np.inf))
        rows.append((along - select(os_, k, problem.min_slide + big_d, sectors), -big_d, np.inf))
    matrix = sp.vstack([r[0] for r in rows], format="csr")
    lower = np.concatenate([np.broadcast_to(r[1], r[0].shape[0]) for r in rows])
    upper = np.concatenate([np.broadcast_to(r[2], r[0].shape[0]) for r in rows])
    low = np.concatenate([np.tile([0.0, -np.inf, -np.inf], s), np.full(n_q, -np.inf), np.zeros(n_z + n_s)])
    high = np.concatenate([np.column_stack([force_bounds, np.full((s, 2), np.inf)]).ravel(), np.full(n_q, np.inf),
                           np.ones(n_z + n_s)])
    motion_rows = columns(d, oq)  # |dd| <= eta, dd_n >= -eps
    motion_low = np.tile([-1.0, -ratio, -ratio], s)
    integrality = np.concatenate([np.zeros(n_f + n_q), np.ones(n_z + n_s)])
    stage = f"the MILP with {sectors} sectors"
    options = {"node_limit": int(nodes), "presolve": True}
    limit = problem.budget.solver_limit()
    if limit is not None:
        problem.budget.check(stage)
        options["time_limit"] = limit
    outcome = milp(np.zeros(size), integrality=integrality, bounds=Bounds(low, high),
                   constraints=[LinearConstraint(matrix, lower, upper),
                                LinearConstraint(motion_rows, motion_low, np.full(3 * s, ratio))],
                   options=options)
    if outcome.status == 2:
        return None
    if outcome.x is None and "time limit" in str(outcome.message).lower():
        raise TimeLimitReached(stage)
    if outcome.x is None and (outcome.status == 1 or "solution limit" in str(outcome.message).lower()):
        return (f"the exact route is too large for this model: HiGHS did not decide the MILP "
                f"({n_z + n_s} binaries) within milp_nodes = {nodes} nodes")
    if outcome.x is None:
        return f"HiGHS did not decide the MILP ({n_z + n_s} binaries; solver: {outcome.message})"
    x = outcome.x
    return x[of:of + n_f].reshape(-1, 3), x[oq:oq + n_q]
