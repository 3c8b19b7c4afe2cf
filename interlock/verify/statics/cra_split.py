"""Blocks the Coulomb fixed point cannot hold: prove the rest without them, then place them (a decomposition of (11)).

The Coulomb fixed point (:mod:`~interlock.verify.statics.cra_coulomb`) finds
motions that *settle* under the load.  A block held only by friction in a wedge
that narrows upwards (the Armadillo vault's block 238) needs a squeeze, a
self-stress through its neighbours, which no settling motion carries: round
after round it slides out until the bound ``eta`` stops it
(:func:`~interlock.verify.statics.cra_coulomb.bound_blocks` names it).  Problem
(11) allows the squeeze; this module looks for it where it lives, around those
few blocks ``H``, with the rest ``R`` held at a proved motion.

1. **The rest.**  (11) without the blocks ``H`` (their rows and every vertex
   touching them removed, :func:`without_blocks`) is solved by the Coulomb fixed
   point and the exact LP: a motion ``q_R`` and forces that balance ``R``.  The
   fixed point continues the whole's (its Anderson memory restricted to the
   rest's vertices) rather than starting afresh.
2. **The held-out blocks, placed.**  With ``q_R`` fixed, (11) for ``H`` alone is
   small: their twists ``q_H``, and ``(f_n, alpha)`` at their vertices ``V``,
   with ``dd_V = G q_H + d_0`` (``d_0``: what ``q_R`` moves them by),
   equilibrium ``A_H f = b_H``, the pyramid, ``f_t = -alpha dd_t``,
   ``0 <= f_n`` and ``dd_n + 1 >= 0`` with ``f_n (dd_n + 1) = 0``.  IPOPT solves
   it (CasADi, optional) with Scholtes' relaxation ``f_n (dd_n + 1) <= tau``,
   ``tau`` lowered to 1e-8 (:data:`SCHOLTES`), from seeded random starts.  The
   vertices it leaves within :data:`SHUT_TOLS` of closed are shut exactly (least
   squares in ``q_H``), and (11) for ``H`` at that motion must hold (an LP).
3. **The whole, checked.**  At ``q = (q_R, q_H)`` the least ``|A_eq f - b|_1``
   over the forces (11) allows is found
   (:func:`~interlock.verify.statics.cra_coulomb.least_unbalanced`, Clarabel at
   :data:`~interlock.verify.statics.cra_coulomb.CHECKED_TOLERANCE`).  If its forces
   pass the exact check of (11) (``MotionLP.holds``:
   equilibrium and pyramid to ``1e-7`` of the load): **stable**, whatever found
   them.  Otherwise the rest cannot
   carry what ``H`` puts on it, and the LP's dual ``y`` says so: for every force
   ``f_V`` at ``H``'s vertices that the rest can carry at ``q_R`` (its rows:
   ``A_R f_R + E f_V = b_R``), ``y_R^T (b_R - E f_V) <= 0``, a linear cut on
   ``f_V`` (a Benders feasibility cut; it removes every force that balances ``H``
   at the rejected ``q_H``).  Step 2 runs again with the cuts, up to
   :data:`SPLIT_ROUNDS` times.

On the armadillo vault (399 blocks, ``H = (238,)``) the rest is proved in 7
more rounds after the whole's 7, and the placements take 1-11 IPOPT solves
(seeds 0-9 of :func:`place_blocks` at one proved rest; docs/statics.md, "CRA at
scale").  Nothing here can say "unstable": a failure is "inconclusive".
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial

import numpy as np
from interlock.verify.statics import cra_coulomb, cra_ipopt, cra_local
from interlock.verify.statics.equilibrium import TimeLimitReached, friction_matrix, highs_lp

__all__ = ["SPLIT_MOST_BLOCKS", "SPLIT_ROUNDS", "SPLIT_ATTEMPTS", "SCHOLTES", "PLACEMENT_ITERATIONS", "SHUT_TOLS",
           "without_blocks", "split_route", "place_blocks", "named"]

#: Most blocks held out: more would make step 2 a large nonconvex problem again.
SPLIT_MOST_BLOCKS = 3
#: Most placements checked against the rest (each the whole's slack LP, 0.6-0.9 s on the armadillo; seeds 0-9 need
#: 1-9), and most IPOPT solves (about 1 s each; a failed one is followed by a new random start), before
#: "inconclusive".
SPLIT_ROUNDS = 24
SPLIT_ATTEMPTS = 40
#: Scholtes' relaxation: ``f_n (dd_n + 1) <= tau`` for these ``tau`` in turn, each solve warm started.
SCHOLTES = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8)
#: Most IPOPT iterations per Scholtes stage.
PLACEMENT_ITERATIONS = 600
#: Vertices of a placement within these distances of closed (units of ``eps``) are shut, the least first.
SHUT_TOLS = (1e-8, 1e-6, 1e-4)


def without_blocks(problem, blocks):
    """``(rest, rows, vertices)``: (11) without the free blocks ``blocks`` (assembly indices), and the masks of
    the rows of ``b_eq`` (6 per free block) and of the contact vertices it keeps.

    The rest has the same units as ``problem`` (forces over the whole's weight, motions over ``eps``), so its
    load is ``b_eq[rows]``.  A vertex touching a held-out block goes with it, whichever side it is on.

    Examples
    --------
    Three cubes stacked on a fixed one; without the top one, the two below keep one contact each.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in range(4)]
    >>> problem = CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)
    >>> rest, rows, vertices = without_blocks(problem, (3,))
    >>> rest.system.free.tolist(), int(rows.sum()), int(vertices.sum()), len(rest.system.contacts)
    ([1, 2], 12, 8, 2)
    """
    system = problem.system
    rows, kept_contacts = _kept(problem, blocks)
    vertices = kept_contacts[system.vertex_contact]
    held = ~rows[::6]
    columns = np.repeat(vertices, 3)
    a_eq = system.a_eq[rows][:, columns].tocsr()
    renumbered = np.cumsum(kept_contacts) - 1
    rest_system = replace(
        system, a_eq=a_eq, a_ub=friction_matrix(int(vertices.sum()), system.cone_rows), cost=system.cost[columns],
        bounds=system.bounds[columns], weights=system.weights[~held], arms=system.arms[~held],
        free=system.free[~held], frames=system.frames[vertices], points=system.points[vertices],
        vertex_contact=renumbered[system.vertex_contact[vertices]],
        contacts=tuple(c for c, kept in zip(system.contacts, kept_contacts) if kept))
    return replace(problem, system=rest_system, kinematic=a_eq.T.tocsr()), rows, vertices


def split_route(problem, b_eq, blocks, exact, progress=None, seed: int = 0, history=()):
    """``((motion, forces), how)`` solving (11) for the whole, found by holding ``blocks`` out (module
    docstring), or ``(None, why not)``.

    ``exact(problem, b_eq, motion)`` is the exact LP (forces or ``None``) for the rest; the rest's Coulomb
    fixed point and the placements are bounded by their rounds and attempts and by ``problem.budget``; ``seed``
    the placements' random starts;
    ``progress(words)``, if given, is told as each stage starts;
    ``history``: the whole's :attr:`~interlock.verify.statics.cra_coulomb.FixedPoint.history`, if the
    Coulomb fixed point ran on it: the rest's continues from it (on the armadillo, 7 rounds where a fresh start
    from the rest's least-friction equilibrium takes 14), else it starts afresh.
    """
    blocks = tuple(int(k) for k in blocks)
    held = named(blocks)
    if not cra_ipopt.available():
        return None, f"holding out {held} needs IPOPT ({cra_ipopt.MISSING_MESSAGE})"
    if progress is not None:
        progress(f"the rest, without {held}")
    rest, rows, vertices = without_blocks(problem, blocks)
    b_rest = b_eq[rows]
    restricted = [(thresholds[vertices], step[vertices]) for thresholds, step in history]
    frugal = None if restricted else cra_local.least_friction(rest, b_rest, interior=True)
    proved, how, _ = cra_local.coulomb_route(rest, b_rest, frugal, partial(exact, rest, b_rest), progress=progress,
                                             history=restricted)
    if proved is None:
        return None, f"holding out {held}: the rest is not proved either ({how})"
    motion = np.zeros(problem.kinematic.shape[1])
    motion[rows] = proved[0]
    found, words = place_blocks(problem, b_eq, blocks, motion, progress, seed)
    return found, f"holding out {held} (the rest proved by {how}; {words})"


def place_blocks(problem, b_eq, blocks, motion, progress=None, seed: int = 0):
    """``((motion, forces), how)``: ``motion`` with the free blocks ``blocks`` placed so that (11) holds for the
    whole (steps 2 and 3 of the module docstring), or ``(None, why not)``.

    ``motion`` (solver units, every free block) is held fixed except at ``blocks``; it should be a proved motion
    of the rest (:func:`without_blocks`).  ``progress`` and ``seed`` as for :func:`split_route`; at most
    :data:`SPLIT_ATTEMPTS` IPOPT solves and :data:`SPLIT_ROUNDS` checks, and ``problem.budget``.  The whole is
    judged by the forces of its slack LP, checked residual by residual (step 3): no least-``sum f_n`` LP after
    it.  At Clarabel's default tolerance (1e-8) those forces failed the check at the armadillo's certificate; at :data:`~interlock.verify.statics.cra_coulomb.CHECKED_TOLERANCE` they
    pass, in 0.6 s where HiGHS' simplex took 4-13 s for the slack LP and 12 s for the exact one.
    """
    rows, kept_contacts = _kept(problem, blocks)
    placement = _Placement.build(problem, b_eq, motion, rows, ~kept_contacts[problem.system.vertex_contact])
    b_rest = b_eq[rows]
    rng = np.random.default_rng(seed)
    start, cuts, checked, attempt = None, [], 0, 0
    while attempt < SPLIT_ATTEMPTS and checked < SPLIT_ROUNDS:
        problem.budget.check(f"placing {named(blocks)}")
        attempt += 1
        if progress is not None:
            progress(f"placing {named(blocks)}, attempt {attempt}")
        x, solved = placement.solve(placement.random_start(rng) if start is None else start, cuts)
        placed = placement.shut(x)  # IPOPT's "infeasible" point may still balance the held-out blocks
        start = x if solved and placed is not None else None  # on from here with one cut more, or a new start
        if placed is None:
            continue
        checked += 1
        candidate = motion.copy()
        candidate[placement.dofs] = placed
        least = cra_coulomb.least_unbalanced(problem, b_eq, candidate, tolerance=cra_coulomb.CHECKED_TOLERANCE)
        if least is None:
            start = None
            continue
        if least.lp.holds(least.x, b_eq):
            return ((candidate, least.lp.forces(least.x)),
                    f"placed by IPOPT: {attempt} solves, {checked} checked against the rest")
        cuts.append(placement.cut(least.dual[rows], b_rest))
    return None, (f"none of the {checked} placements checked against the rest ({attempt} IPOPT solves) was "
                  f"carried by it")


def named(blocks) -> str:
    """``blocks`` (assembly indices) in words: ``"block 238"``, ``"blocks 3, 7"``."""
    return f"block{'s' if len(blocks) > 1 else ''} {', '.join(map(str, blocks))}"


def _kept(problem, blocks):
    """Masks of the rows of ``b_eq`` (6 per free block) and of the contacts that do not involve ``blocks``."""
    system = problem.system
    ends = np.array([[c.i, c.j] for c in system.contacts]).reshape(-1, 2)
    return np.repeat(~np.isin(system.free, blocks), 6), ~np.isin(ends, blocks).any(axis=1)


class _Placement:
    """(11) for the held-out blocks with the rest's motion fixed (module docstring, step 2), in the held-out
    blocks' load units (forces over ``|b_H|_1``)."""

    def __init__(self, problem, motion, vertices, kinematic, offset, a_held, b_held, carry, dofs):
        self.problem, self.motion, self.vertices, self.dofs = problem, motion, vertices, dofs
        self.kinematic, self.offset, self.a_held, self.carry = kinematic, offset, a_held, carry
        self.cone_rows, self.ratio = problem.system.cone_rows, problem.ratio
        self.scale = float(np.abs(b_held).sum()) or 1.0
        self.b_held = b_held / self.scale
        self.count = len(offset) // 3

    @classmethod
    def build(cls, problem, b_eq, motion, rows, vertices):
        dofs = np.flatnonzero(~rows)
        columns = np.flatnonzero(np.repeat(vertices, 3))
        d = problem.kinematic.tocsr()[columns]
        fixed = motion.copy()
        fixed[dofs] = 0.0
        a_eq = problem.system.a_eq.tocsr()[:, columns]
        return cls(problem, motion, vertices, d[:, dofs].toarray(), d @ fixed, a_eq[dofs].toarray(), b_eq[dofs],
                   a_eq[rows], dofs)

    def random_start(self, rng):
        n = self.count
        return np.concatenate([rng.normal(0.0, self.ratio / 10, len(self.dofs)), np.full(n, 0.1), np.full(n, 1e-3)])

    def solve(self, start, cuts):
        """``(x, solved)``: IPOPT's point ``(q_H, f_n, alpha)`` after the Scholtes stages, from ``start``."""
        import casadi as ca

        n, k = self.count, len(self.dofs)
        x = ca.MX.sym("x", k + 2 * n)
        q, normal, alpha = x[:k], x[k:k + n], x[k + n:]
        dd = ca.mtimes(ca.DM(self.kinematic), q) + ca.DM(self.offset)
        gap, friction_u, friction_v = dd[0::3] + 1, -alpha * dd[1::3], -alpha * dd[2::3]
        a = self.a_held
        balance = (ca.mtimes(ca.DM(a[:, 0::3]), normal) + ca.mtimes(ca.DM(a[:, 1::3]), friction_u)
                   + ca.mtimes(ca.DM(a[:, 2::3]), friction_v) - ca.DM(self.b_held))
        pyramid = [row[0] * normal + row[1] * friction_u + row[2] * friction_v for row in self.cone_rows]
        cut_rows = [self.scale * (ca.dot(ca.DM(w[0::3]), normal) + ca.dot(ca.DM(w[1::3]), friction_u)
                                  + ca.dot(ca.DM(w[2::3]), friction_v)) - bound for w, bound in cuts]
        tau = ca.MX.sym("tau")
        constraints = ca.vertcat(balance, gap, *pyramid, normal * gap - tau, dd, *cut_rows)
        sides = len(self.cone_rows)
        lower = np.concatenate([np.zeros(k + n), np.full((sides + 1) * n, -np.inf), np.full(3 * n, -self.ratio),
                                np.full(len(cuts), -np.inf)])
        upper = np.concatenate([np.zeros(k), np.full(n, np.inf), np.zeros((sides + 1) * n), np.full(3 * n, self.ratio),
                                np.zeros(len(cuts))])
        stage, budget = "placing the held-out blocks (IPOPT)", self.problem.budget
        options, clock = cra_ipopt.deadline_options(budget, stage, x.numel(), constraints.numel(), 1)
        solver = ca.nlpsol("placement", "ipopt", {"x": x, "f": ca.sum1(normal), "g": constraints, "p": tau},
                           {"ipopt.print_level": 0, "print_time": 0, "ipopt.sb": "yes",
                            "ipopt.max_iter": PLACEMENT_ITERATIONS, "ipopt.tol": 1e-10, **options})
        point = start
        for relaxation in SCHOLTES:
            point = np.asarray(solver(x0=point, p=relaxation, lbg=lower, ubg=upper,
                                      lbx=np.concatenate([np.full(k, -np.inf), np.zeros(2 * n)]))["x"]).ravel()
            if cra_ipopt.timed_out(str(solver.stats()["return_status"]), budget):
                raise TimeLimitReached(stage)
        del clock
        return point, solver.stats()["return_status"] in ("Solve_Succeeded", "Solved_To_Acceptable_Level")

    def shut(self, x):
        """``q_H`` with the vertices IPOPT nearly closed shut exactly (least squares), the first of
        :data:`SHUT_TOLS` at which (11) for the held-out blocks holds; ``None`` if none does."""
        q = x[:len(self.dofs)]
        rows = self.kinematic[0::3]
        gap = rows @ q + self.offset[0::3] + 1.0
        for tolerance in SHUT_TOLS:
            near = gap <= tolerance
            if near.any():
                shut = q + np.linalg.lstsq(rows[near], -gap[near], rcond=None)[0]
                if self.holds(shut):
                    return shut
        return None

    def holds(self, q) -> bool:
        """Whether (11) for the held-out blocks has a solution at ``q_H``: the rows and vertices of the held-out
        blocks in ``CRAProblem.motion_lp`` of the whole at ``(q_R, q_H)`` (its tolerances and bounds), by HiGHS."""
        whole = self.motion.copy()
        whole[self.dofs] = q
        lp = self.problem.motion_lp(whole)
        if lp is None:
            return False
        columns = np.concatenate([self.vertices[lp.closed], self.vertices[lp.sliding]])
        if not columns.any():
            return False
        pyramid = lp.a_ub[np.repeat(self.vertices[lp.sliding], len(self.cone_rows))][:, columns]
        outcome = highs_lp(lp.cost[columns], self.problem.budget, "placing the held-out blocks",
                           A_ub=pyramid if pyramid.shape[0] else None,
                           b_ub=np.zeros(pyramid.shape[0]) if pyramid.shape[0] else None,
                           A_eq=lp.a_eq[self.dofs][:, columns], b_eq=self.b_held * self.scale,
                           bounds=(0, None))  # the whole's units, as its exact LP sees them
        return outcome.status == 0

    def cut(self, y_rest, b_rest):
        """The Benders cut ``y_R^T (b_R - E f_V) <= 0`` as ``(w, bound)``: ``w . f_V <= bound`` (``f_V`` in the
        whole's units), normalised to ``max |w| scale = 1``."""
        w = -(self.carry.T @ y_rest)
        bound = -float(y_rest @ b_rest)
        size = float(np.abs(w).max()) * self.scale
        return (w / size, bound / size) if size > 0 else (w, bound)
