"""CRA's problem (11) through Coulomb friction: a fixed point of convex frictional-contact problems.

A motion of the blocks that *settles* under the load, with friction that
resists every slide, realises an equilibrium the way (11) asks. This module
finds such motions with convex problems. Nothing here proves anything by
itself: a motion is "stable" only if the exact LP of (11) (``CRAProblem.exact``)
at it is feasible.

**The convex problem (Tresca friction with elastic slip).** Fix a threshold
``s_v >= 0`` per contact vertex and a stiffness ``k > 0``. In the solver's
units (motions over ``eps``, forces over the free blocks' weight), solve

    min_q  b^T q + sum_v h_v(dd_t,v)   s.t.  dd_n + 1 >= 0,  |dd| <= eta / eps,        (T)

where ``dd = A_eq^T q`` (Eq. (8)), ``-b^T q`` is the work of the load, and
``h_v`` is the Huber function ``k |x|^2 / 2`` for ``|x| <= s_v / k`` and
``s_v |x| - s_v^2 / (2 k)`` beyond. It is a second-order cone program
(``h_v(x) = min_y k |y|^2 / 2 + s_v |x - y|``), solved by Clarabel.

**Why its solutions solve (11).** Let ``f_n`` be the multipliers of
``dd_n + 1 >= 0`` and ``f_t = -grad h_v(dd_t)``. The optimality conditions of
(T), when no bound ``|dd| <= eta / eps`` is active, are:

- equilibrium ``A_eq f = b``: Eq. (7b);
- ``f_n >= 0``, ``dd_n + 1 >= 0``, ``f_n (dd_n + 1) = 0``: Eq. (10);
- ``f_t = -alpha dd_t`` with ``alpha = k`` (stick) or ``s_v / |dd_t|``
  (slip), so ``alpha >= 0``: Eq. (9);
- ``|f_t| <= s_v``.

So if ``s_v <= m f_n,v`` at every vertex, with ``m`` the radius of the round
cone inside the friction pyramid (``mu`` for the paper's circumscribed
pyramid, ``mu cos(pi / sides)`` for the inner one), the forces lie in the
pyramid (Eqs. (4)-(5)) and ``(f, q)`` solves (11). Coulomb's law
``s_v = m f_n,v`` is therefore a fixed point of the map ``s -> m f_n(s)``, and
:func:`coulomb_fixed_point` looks for it from the normal forces of the
least-friction equilibrium, by Anderson acceleration (type II, Walker and Ni
2011): with ``g = m f_n(s) - s`` and the differences ``dS``, ``dG`` of the
last ``memory`` rounds, ``gamma = argmin |g - dG gamma|`` and
``s <- s + damping g - (dS + damping dG) gamma`` (clipped at 0; with
``memory = 0`` the plain damped step ``s <- s + damping g``). An active bound
``eta`` spoils the argument (its multipliers act as forces that (11) does not
have): the exact LP then decides.

Each round's motion first goes to the least ``|A_eq f - b|_1`` over the forces
(11) allows at it (:func:`unbalanced`, one conic solve). Only a motion at which
it leaves at most :data:`SHUT_RESIDUAL` of the load unbalanced goes to the exact
LP (farther from 0 the exact LP is infeasible; this saves it in most rounds).
Clarabel's motions close their vertices only to its tolerance, so a vertex
loaded in (T) may sit at ``dd_n + 1 = 1e-6`` and count as open in the exact
LP. A motion that the exact LP rejects is checked again with the vertices
within :data:`SHUT_TOL` of closed shut exactly (:func:`shut_nearly_closed`, the
L1-nearest such motion by HiGHS: a vertex of its LP; Clarabel's interior
solution of the same LP left 2e-4 unbalanced).

The iteration need not converge; where it does (shelf-stable, Fig. 12), it
proves "stable" with linear and conic solves only. On the Armadillo vault
it proves the 398 blocks other than block 238 stable in 14 rounds, but not
the whole vault, where 238 slides to the bound ``eta`` in every round from the
third (:func:`bound_blocks`; :mod:`~interlock.verify.statics.cra_split` holds it
out): see docs/statics.md, "CRA at scale".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp

from interlock.verify.statics.equilibrium import TimeLimitReached, clarabel_lp, clarabel_solve

__all__ = ["COULOMB_ITERATIONS", "COULOMB_DAMPING", "COULOMB_MEMORY", "THRESHOLD_RTOL", "SHUT_TOL", "SHUT_RESIDUAL",
           "SHUT_MARGIN", "STUCK_ROUNDS", "CHECKED_TOLERANCE", "bound_blocks", "slack_lp", "LeastUnbalanced",
           "least_unbalanced",
           "TrescaSolution", "FixedPoint", "tresca", "coulomb_fixed_point", "shut_nearly_closed", "unbalanced",
           "describe"]

#: Most rounds of the fixed point (shelf-stable is accepted after 15).
COULOMB_ITERATIONS = 40
#: Weight of the new thresholds ``m f_n`` in each round (1: plain fixed point; it oscillates on shelf-stable).
COULOMB_DAMPING = 0.5
#: Rounds that Anderson acceleration remembers (0: the damped fixed point). With 3, the armadillo vault without
#: block 238 is proved in 14 rounds; damped alone, it cycles at 1e-6 - 3e-4 of the load.
COULOMB_MEMORY = 3
#: Vertices within ``SHUT_TOL * eps`` of closed in (T)'s motion are also tried shut exactly (Clarabel's
#: tolerance leaves loaded vertices open by 1e-7 - 1e-5 eps) ...
SHUT_TOL = 1e-5
#: ... when the exact LP with slack leaves at most this fraction of the load unbalanced at the motion.
SHUT_RESIDUAL = 1e-6
#: :func:`shut_nearly_closed` starts from the bounds of (11) within this many ``eps`` of the motion, and adds
#: those its step leaves by more than ``SHUT_MARGIN_TOL`` (HiGHS' feasibility tolerance).
SHUT_MARGIN = 0.1
SHUT_MARGIN_TOL = 1e-7
#: Rounds in a row with the same blocks at the bound ``eta`` after which the large route stops the fixed point
#: and holds those blocks out (:mod:`~interlock.verify.statics.cra_split`).
STUCK_ROUNDS = 5
#: Thresholds below this fraction of the largest are taken as 0 (no friction there).  Interior-point forces
#: leave thousands of vertices at the solver's tolerance (1e-10 of the largest); a cone each for them took
#: Clarabel 44 iterations on the armadillo vault where 24 do without (3.6 s -> 1.8 s a round).  A block whose
#: contacts carry less than this share of the largest vertex force gets no friction in (T): the fixed point may
#: then not settle it (the exact LP still judges every motion, so the answer is at worst "inconclusive").
THRESHOLD_RTOL = 1e-6
#: Clarabel's gap and feasibility tolerances for LPs whose solutions go to the exact check (``MotionLP.holds``): at
#: its default, 1e-8, the slack LP's forces at the armadillo's certificate miss the equilibrium by 1.6 times
#: ``CHECK_RTOL``; at 1e-10 they pass with 200 times to spare (0.6 s, two more iterations).
CHECKED_TOLERANCE = 1e-10
#: Unbalanced load per free block (in units of the free blocks' weight) below which a block counts as balanced.
BALANCED_RTOL = 1e-7


@dataclass(frozen=True)
class TrescaSolution:
    """A solution of the convex problem (T) (module docstring), in the solver's units.

    Attributes
    ----------
    motion : ndarray (6 f,)
        ``q``, twists of the free blocks over ``eps``.
    forces : ndarray (s, 3)
        ``(f_n, f_u, f_v)`` per vertex: the multipliers of ``dd_n + 1 >= 0`` and ``-grad h_v``.
    eta_active : int
        Components of ``dd`` at the bound ``eta / eps``; nonzero means the forces need not balance the load.
    status : str
        Clarabel's status.
    """

    motion: np.ndarray
    forces: np.ndarray
    eta_active: int
    status: str


@dataclass(frozen=True)
class FixedPoint:
    """What :func:`coulomb_fixed_point` found.

    Attributes
    ----------
    found : (motion, forces) or None
        A motion the exact LP accepts (as (T) gave it, or with its nearly closed vertices shut), with its forces.
    rounds : int
        Rounds run.
    closest : ndarray (6 f,) or None
        The motion that came closest: the least :func:`unbalanced` residual (the accepted one when found).
    residual : float or None
        That residual, a fraction of the load (``None`` if no round's motion stayed within the bounds of (11)).
    unbalanced_blocks : tuple of int
        The free blocks (assembly indices) the closest motion leaves unbalanced.
    at_bound : tuple of int
        The free blocks that slid to the bound ``eta`` in the last round (:func:`bound_blocks`): those that
        (T) cannot hold, where :mod:`~interlock.verify.statics.cra_split` takes over.
    history : tuple of (ndarray (s,), ndarray (s,))
        Anderson's memory after the last round: ``(thresholds, m f_n - thresholds)`` of the last
        ``memory + 1`` rounds, oldest first.  Restricted to part of the model, it continues the iteration there
        (``coulomb_fixed_point(..., history=)``; :func:`~interlock.verify.statics.cra_split.split_route`).
    """

    found: tuple | None
    rounds: int
    closest: np.ndarray | None
    residual: float | None
    unbalanced_blocks: tuple
    at_bound: tuple = ()
    history: tuple = ()


def tresca(problem, b_eq, thresholds, stiffness: float) -> TrescaSolution | None:
    """Solve (T) of the module docstring for ``thresholds`` ``s_v`` and ``stiffness`` ``k``; ``None`` if
    Clarabel does not solve it.  The bound ``eta`` keeps (T) bounded: where the thresholds cannot hold the load,
    blocks slide until it stops them (``eta_active > 0``), and its multipliers carry the rest.

    Unknowns ``(q, y, t)``: ``y_v`` is the elastic part of the slide, ``t_v >= |dd_t,v - y_v|`` (a second-order
    cone per vertex), and the cost is ``b^T q + sum k |y_v|^2 / 2 + s_v t_v``.  A vertex with ``s_v = 0`` has no
    friction (``h_v = 0``): it gets no ``y_v``, ``t_v`` or cone.

    Examples
    --------
    A unit cube on a fixed one, thresholds from a normal force of its weight and ``mu = 0.5``: it settles by
    ``eps`` and carries its weight on its four corners.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> problem = CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)
    >>> b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    >>> solved = tresca(problem, b_eq, np.full(4, 0.125), 0.25)
    >>> round(float(solved.motion[2]), 6), round(float(solved.forces[:, 0].sum()), 6), solved.eta_active
    (-1.0, 1.0, 0)
    """
    import clarabel

    d = problem.kinematic.tocsr()
    s, n_q = d.shape[0] // 3, d.shape[1]
    if s == 0:
        return None
    ratio = problem.ratio
    thresholds = np.asarray(thresholds, dtype=float)
    rubbing = np.flatnonzero(thresholds > 0)  # vertices with friction; elsewhere y = 0 and t drops out
    r = len(rubbing)
    rows = np.arange(r)
    # second-order cone rows per rubbing vertex, in the order (t_v, x_u - y_u, x_v - y_v)
    place = [sp.csr_matrix((np.ones(r), (3 * rows + a, rows)), shape=(3 * r, r)) for a in range(3)]
    slides = place[1] @ d[3 * rubbing + 1] + place[2] @ d[3 * rubbing + 2]
    constraints = sp.vstack([
        sp.hstack([-d[0::3], sp.csr_matrix((s, 3 * r))]),  # dd_n + 1 >= 0
        sp.hstack([d, sp.csr_matrix((3 * s, 3 * r))]),  # dd <= ratio
        sp.hstack([-d, sp.csr_matrix((3 * s, 3 * r))]),  # -dd <= ratio
        sp.hstack([-slides, place[1], place[2], -place[0]]),  # (t, x - y) in the cone
    ], format="csc")
    right = np.concatenate([np.ones(s), np.full(6 * s, ratio), np.zeros(3 * r)])
    quadratic = sp.block_diag([sp.csc_matrix((n_q, n_q)), stiffness * sp.eye(2 * r), sp.csc_matrix((r, r))],
                              format="csc")
    cost = np.concatenate([b_eq, np.zeros(2 * r), thresholds[rubbing]])
    solution = clarabel_solve(quadratic, cost, constraints, right,
                              [clarabel.NonnegativeConeT(7 * s)] + [clarabel.SecondOrderConeT(3)] * r,
                              budget=problem.budget, stage="the Coulomb fixed point")
    status = str(solution.status)
    if status not in ("Solved", "AlmostSolved"):
        return None
    x, z = np.asarray(solution.x), np.asarray(solution.z)
    motion = x[:n_q]
    forces = np.zeros((s, 3))
    forces[:, 0] = z[:s]
    forces[rubbing, 1:] = -stiffness * x[n_q:n_q + 2 * r].reshape(2, r).T
    eta_active = int(np.count_nonzero(np.abs(d @ motion) >= ratio * (1 - 1e-6)))
    return TrescaSolution(motion, forces, eta_active, status)


def coulomb_fixed_point(problem, b_eq, normal_forces, check, iterations: int = COULOMB_ITERATIONS,
                        damping: float = COULOMB_DAMPING, memory: int = COULOMB_MEMORY, progress=None,
                        stuck: int | None = None, history=()):
    """Iterate (T) towards Coulomb's law (module docstring) and return a :class:`FixedPoint`.

    Parameters
    ----------
    problem : CRAProblem
    b_eq : ndarray (6 f,)
        The load, ``-p`` over the free blocks' weight.
    normal_forces : ndarray (s,) or None
        Normal forces of an RBE equilibrium (the least-friction one): the first thresholds are ``m`` times them
        (not used when ``history`` is given).
    check : callable
        ``check(motion)`` -> forces solving (11) exactly at ``motion``, or ``None`` (the exact LP).
    iterations, damping, memory : int, float, int
        Most rounds, the weight of the new thresholds, and the rounds Anderson acceleration remembers
        (:data:`COULOMB_ITERATIONS`, :data:`COULOMB_DAMPING`, :data:`COULOMB_MEMORY`).  The rounds are counted,
        not timed, so the iteration ends the same way on every machine; ``problem.budget`` is checked before
        each round (:class:`~interlock.verify.budget.TimeLimitReached`).
    progress : callable, optional
        Called with ``"Coulomb fixed point, round k"`` as each round starts.
    stuck : int, optional
        Stop once the same blocks have slid to the bound ``eta`` (:func:`bound_blocks`) in this many rounds
        in a row: (T) cannot hold them (the armadillo's block 238 from round 3 on, in every round after).
    history : sequence of (ndarray (s,), ndarray (s,)), optional
        Continue an earlier iteration (its :attr:`FixedPoint.history`, restricted to this problem's vertices):
        the first thresholds are Anderson's step from it.  The armadillo's rest (without block 238), continued
        from the whole's round 7, is proved in 7 more rounds; started afresh, in 14.

    Returns
    -------
    FixedPoint

    The stiffness is ``|b|_1 / s``: a vertex carrying an average share of the load
    slides by about ``eps`` before it slips.
    """
    radius = -float(problem.system.cone_rows[:, 0].max())  # the round cone inside the pyramid
    history = list(history)  # (thresholds, step) of the last rounds
    s = len(history[-1][0]) if history else len(normal_forces)
    stiffness = float(np.abs(b_eq).sum()) / max(s, 1)
    thresholds = _floored(_anderson(history, damping) if history else radius * np.maximum(normal_forces, 0.0))
    closest, best, blocks, rounds, at_bound, repeats = None, None, (), 0, (), 0
    while rounds < iterations:
        problem.budget.check(f"the Coulomb fixed point, round {rounds + 1}")
        rounds += 1
        if progress is not None:
            progress(f"Coulomb fixed point, round {rounds}")
        solved = tresca(problem, b_eq, thresholds, stiffness)
        if solved is None:
            break
        before, at_bound = at_bound, bound_blocks(problem, solved.motion) if solved.eta_active else ()
        repeats = repeats + 1 if at_bound and at_bound == before else 1
        residual, unbalanced_at = unbalanced(problem, b_eq, solved.motion)
        if closest is None or (residual is not None and (best is None or residual < best)):
            closest, best, blocks = solved.motion, residual, unbalanced_at
        if residual is None or residual <= SHUT_RESIDUAL:  # nearly a solution (farther, the exact LP fails):
            forces = check(solved.motion)  # the motion, then with its nearly closed vertices shut exactly
            if forces is not None:
                return FixedPoint((solved.motion, forces), rounds, solved.motion, 0.0, ())
            shut = None if residual is None else shut_nearly_closed(problem, solved.motion)
            forces = None if shut is None else check(shut)
            if forces is not None:
                return FixedPoint((shut, forces), rounds, shut, 0.0, ())
        step = radius * np.maximum(solved.forces[:, 0], 0.0) - thresholds
        history = (history + [(thresholds, step)])[-(memory + 1):]
        if stuck is not None and at_bound and repeats >= stuck:
            break
        thresholds = _floored(_anderson(history, damping))
    return FixedPoint(None, rounds, closest, best, blocks, at_bound, tuple(history))


def bound_blocks(problem, motion) -> tuple:
    """The free blocks (assembly indices) that account for the displacements at the bound ``eta`` of
    ``motion``: fewest blocks touching every contact with a component at the bound (greedy: the block in most
    such contacts first; between blocks in as many, the one that moved most).

    A block that (T) cannot hold slides until ``eta`` stops it, at each of its contacts; its neighbours have
    one such contact each.  On the armadillo the 8 components at the bound lie in contacts 228-238 and
    238-343, and the answer is ``(238,)``.

    Examples
    --------
    Three cubes on a fixed one; the middle free cube slides by ``eta`` against both its neighbours.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in range(4)]
    >>> problem = CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)
    >>> motion = np.zeros(18)
    >>> motion[6:9] = [problem.ratio, 0.0, -1.0]
    >>> bound_blocks(problem, motion)
    (2,)
    """
    system = problem.system
    dd = (problem.kinematic @ motion).reshape(-1, 3)
    at = np.flatnonzero((np.abs(dd) >= problem.ratio * (1 - 1e-6)).any(axis=1))
    pairs = {(system.contacts[c].i, system.contacts[c].j) for c in np.unique(system.vertex_contact[at])}
    moved = dict(zip(system.free.tolist(), np.linalg.norm(motion.reshape(-1, 6), axis=1)))
    chosen = []
    while pairs:
        counts: dict[int, int] = {}
        for pair in pairs:
            for k in pair:
                if k in moved:
                    counts[k] = counts.get(k, 0) + 1
        if not counts:
            break
        block = max(counts, key=lambda k: (counts[k], moved[k]))
        chosen.append(block)
        pairs = {pair for pair in pairs if block not in pair}
    return tuple(sorted(chosen))


def _floored(thresholds: np.ndarray) -> np.ndarray:
    """``thresholds`` clipped at 0, and those below :data:`THRESHOLD_RTOL` times the largest set to 0."""
    thresholds = np.maximum(thresholds, 0.0)
    return np.where(thresholds > THRESHOLD_RTOL * thresholds.max(initial=0.0), thresholds, 0.0)


def _anderson(history, damping: float) -> np.ndarray:
    """The next thresholds from the ``(s, g)`` of the last rounds (module docstring); the damped step alone
    while there is only one (and always with ``memory = 0``)."""
    thresholds, step = history[-1]
    if len(history) < 2:
        return thresholds + damping * step
    d_s = np.column_stack([b[0] - a[0] for a, b in zip(history[:-1], history[1:])])
    d_g = np.column_stack([b[1] - a[1] for a, b in zip(history[:-1], history[1:])])
    gamma = np.linalg.lstsq(d_g, step, rcond=None)[0]
    return thresholds + damping * step - (d_s + damping * d_g) @ gamma


def shut_nearly_closed(problem, motion, tolerance: float = SHUT_TOL):
    """The motion nearest (L1) to ``motion`` that closes exactly (``dd_n = -eps``) the vertices within
    ``tolerance * eps`` of closed and keeps every vertex within the bounds of (11) (``dd_n >= -eps``,
    ``|dd| <= eta``); ``None`` if there are no such vertices or the LP fails.  An LP in the step
    ``q - motion = u - v`` (``u, v >= 0``, ``min sum(u + v)``) whose rows are the ranged bounds on
    ``dd = D q`` (one row per component, not two), by HiGHS: a vertex of the LP (Clarabel's interior
    solution of the same LP left 2e-4 of the load unbalanced where this one proved "stable").  Only the rows
    within :data:`SHUT_MARGIN` of a bound enter it at first; the rows its step violates are added until none
    is, so the step is the whole LP's optimum (on the armadillo without block 238: 2,500 of 32,000 rows, one
    round, 0.8 s; all rows at once took 7 s).  The exact LP judges the result.

    Examples
    --------
    A cube on a fixed one, pushed down by ``(1 - 1e-6) eps``: its four corners are shut exactly.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> problem = CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)
    >>> shut = shut_nearly_closed(problem, np.array([0.0, 0.0, -(1 - 1e-6), 0.0, 0.0, 0.0]))
    >>> np.allclose(problem.kinematic[0::3] @ shut, -1.0, rtol=0.0, atol=1e-12)
    True
    """
    d = problem.kinematic.tocsr()
    dd = d @ motion
    near = dd[0::3] + 1.0 <= tolerance
    if not near.any():
        return None
    n_q, s, ratio = d.shape[1], d.shape[0] // 3, problem.ratio
    low, high = np.tile([-1.0, -ratio, -ratio], s) - dd, np.full(3 * s, ratio) - dd
    shut = 3 * np.flatnonzero(near)
    low[shut] = high[shut] = -1.0 - dd[shut]
    rows = np.minimum(-low, high) <= SHUT_MARGIN
    rows[shut] = True
    while True:
        taken = np.flatnonzero(rows)
        limit = problem.budget.solver_limit()
        if limit is not None:
            problem.budget.check("shutting nearly closed vertices")
        outcome = milp(np.ones(2 * n_q), bounds=Bounds(0.0, np.inf),  # no integer variables: HiGHS' LP
                       constraints=LinearConstraint(sp.hstack([d[taken], -d[taken]], format="csr"), low[taken],
                                                    high[taken]),
                       options={} if limit is None else {"time_limit": limit})
        if outcome.status == 1 and "time limit" in str(outcome.message).lower():
            raise TimeLimitReached("shutting nearly closed vertices")
        if outcome.status != 0:
            return None
        step = outcome.x[:n_q] - outcome.x[n_q:]
        moved = d @ step
        violated = ~rows & ((moved < low - SHUT_MARGIN_TOL) | (moved > high + SHUT_MARGIN_TOL))
        if not violated.any():
            return motion + step
        rows |= violated


def unbalanced(problem, b_eq, motion):
    """``(residual, blocks)``: the least ``|A_eq f - b|_1`` over forces that (11) allows at ``motion``, as a
    fraction of ``|b|_1``, and the free blocks (assembly indices) left unbalanced; ``(None, ())`` if the motion
    leaves the bounds of (11) or Clarabel does not solve the LP.  0 would mean "stable"."""
    least = least_unbalanced(problem, b_eq, motion)
    if least is None:
        return None, ()
    per_block = np.abs(least.slack).reshape(-1, 6).sum(axis=1)
    scale = float(np.abs(b_eq).sum())
    blocks = np.asarray(problem.system.free)[per_block > BALANCED_RTOL * scale]
    return least.residual / scale, tuple(int(k) for k in blocks)


@dataclass(frozen=True)
class LeastUnbalanced:
    """The solution of :func:`slack_lp` at a motion.

    Attributes
    ----------
    lp : MotionLP
        (11) at the motion.
    x : ndarray
        Its unknowns ``(f_n, alpha)`` (clipped at 0): the forces, ``lp.forces(x)``.
    slack : ndarray (6 f,)
        ``b - A_eq x``, what they leave unbalanced, per row of ``b_eq``.
    residual : float
        ``|slack|_1``, in the units of ``b_eq`` (from ``x`` clipped at 0: the LP's own optimum may be -1e-8).
    dual : ndarray (6 f,)
        The LP's multipliers of the equilibrium rows, ``d residual / d b``: for every ``x`` that (11) allows at
        the motion, ``dual . (b - A_eq x) <= |b - A_eq x|_1`` and the two are equal at the optimum.
    """

    lp: object
    x: np.ndarray
    slack: np.ndarray
    residual: float
    dual: np.ndarray


def least_unbalanced(problem, b_eq, motion, tolerance: float | None = None) -> LeastUnbalanced | None:
    """The forces (11) allows at ``motion`` that leave the least ``|A_eq f - b|_1`` (:func:`slack_lp`, by
    Clarabel with ``tolerance``, see :func:`~interlock.verify.statics.equilibrium.clarabel_solve`); ``None``
    if the motion leaves the bounds of (11) or Clarabel does not solve the LP.  About 0.6 s on the armadillo
    vault (HiGHS' simplex: 4-13 s).

    Examples
    --------
    A cube on a fixed one that settles by ``eps`` carries its weight: nothing is left unbalanced.

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.cra import CRAProblem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> problem = CRAProblem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5)
    >>> b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    >>> least = least_unbalanced(problem, b_eq, np.array([0.0, 0.0, -1.0, 0.0, 0.0, 0.0]))
    >>> round(least.residual, 9), round(float(least.lp.forces(least.x)[:, 0].sum()), 6)
    (0.0, 1.0)
    """
    lp = problem.motion_lp(motion)
    if lp is None:
        return None
    n, m = lp.a_eq.shape[1], lp.a_eq.shape[0]
    cost, equalities, inequalities = slack_lp(lp)
    inequalities = sp.vstack([inequalities, -sp.eye(n + 2 * m)])
    solution = clarabel_lp(cost, sp.vstack([equalities, inequalities], format="csc"),
                           np.concatenate([b_eq, np.zeros(inequalities.shape[0])]), equalities=m,
                           tolerance=tolerance, budget=problem.budget, stage="the exact LP with slack")
    if str(solution.status) not in ("Solved", "AlmostSolved"):
        return None
    solved = np.asarray(solution.x)
    x = np.maximum(solved[:n], 0.0)
    slack = b_eq - lp.a_eq @ x
    return LeastUnbalanced(lp, x, slack, float(np.abs(slack).sum()), -np.asarray(solution.z)[:m])


def slack_lp(lp):
    """``(cost, a_eq, a_ub)`` of the least ``|A_eq f - b|_1`` over the forces (11) allows at a motion (``lp``: a
    ``MotionLP``), in ``(x, s+, s-) >= 0``: ``a_eq = [A, I, -I]`` (right-hand side ``b``), ``a_ub = [A_ub, 0, 0]``
    (right-hand side 0), ``cost = (0, 1, 1)``."""
    n, m = lp.a_eq.shape[1], lp.a_eq.shape[0]
    identity = sp.eye(m, format="csr")
    return (np.concatenate([np.zeros(n), np.ones(2 * m)]), sp.hstack([lp.a_eq, identity, -identity], format="csr"),
            sp.hstack([lp.a_ub, sp.csr_matrix((lp.a_ub.shape[0], 2 * m))], format="csr"))


def describe(fixed_point: FixedPoint) -> str:
    """What the Coulomb fixed point left undone, at its closest motion, in words."""
    rounds, blocks = fixed_point.rounds, fixed_point.unbalanced_blocks
    if fixed_point.closest is None:
        return f"the Coulomb fixed point stopped after {rounds} rounds: its convex problem had no solution"
    if fixed_point.residual is None:
        return f"the Coulomb fixed point ran {rounds} rounds; its closest motion leaves the bounds of (11)"
    shown = ", ".join(map(str, blocks[:8])) + (", ..." if len(blocks) > 8 else "")
    return (f"the Coulomb fixed point ran {rounds} rounds; at its closest motion the exact LP leaves "
            f"{fixed_point.residual:.2g} of the load unbalanced, at {len(blocks)} blocks ({shown})")
