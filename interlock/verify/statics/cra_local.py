"""Local repairs and local solves of CRA's problem (11); every motion they find is checked by the exact LP.

:func:`~interlock.verify.statics.cra.cra` decides (11) by quick answers, a MILP and
an exact LP at a motion (``CRAProblem.exact``).  The functions here find
candidate motions; none of them proves anything by itself:

- :func:`least_friction` and :func:`realise`: an RBE equilibrium that needs
  friction at few vertices, and a motion realising given forces (LPs);
- :func:`settled_motion`: where the assembly settles under its load (LPs);
- :func:`snap`: an interior-point motion with its nearly closed vertices shut (an LP);
- :func:`polish`: (11) solved locally with the closed set fixed (SLSQP);
- :func:`verify_local` and :func:`last_resort`: the chain of local solvers (the
  Coulomb fixed point of :mod:`interlock.verify.statics.cra_coulomb`, IPOPT
  through :mod:`interlock.verify.statics.cra_ipopt`, then SLSQP).

All work in the solver's units: forces over the free blocks' weight,
lengths of the motion over ``eps`` (``problem.kinematic`` maps a motion to the
relative displacements ``dd = A_eq^T q``, rows ``(n, u, v)`` per vertex).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
from scipy.linalg import null_space
from scipy.optimize import minimize

from interlock.verify.statics import cra_coulomb, cra_ipopt
from interlock.verify.statics.equilibrium import clarabel_lp, highs_lp

__all__ = ["least_friction", "realise", "realise_least_friction", "settled_motion", "snap", "polish",
           "verify_local", "last_resort", "coulomb_route"]

#: A vertex is closed when ``dd_n + eps <= ACTIVE_TOL * eps``.
ACTIVE_TOL = 1e-7
#: A closed vertex slides when ``|dd_t| > SLIDE_TOL * eps``.
SLIDE_TOL = 1e-7
#: Vertices within ``SNAP_TOL * eps`` of closed in a local solver's motion are snapped shut before checking.
SNAP_TOL = 1e-2
#: Most closed vertices for the local (SLSQP) repair of a MILP point; beyond, only the LP repairs run.
POLISH_LIMIT = 100
#: Most closed vertices for the last-resort SLSQP solve (dense: the 148 of the
#: 38-block arch take 30-60 s).
LAST_RESORT_LIMIT = 200
#: Most SLSQP iterations per local solve.
POLISH_ITERATIONS = 50
#: Weight of ``sum f_n`` beside the friction in the least-friction equilibrium (forces in units of the weight).
LEAST_FRICTION_NORMAL = 1e-3


def last_resort(problem, b_eq, rbe_forces, most_work, timings, progress=None, frugal=None):
    """``((motion, forces), how)`` of a local solve of (11) that the exact LP accepts, or ``(None, why not)``.

    In turn: the Coulomb fixed point (:func:`~interlock.verify.statics.cra_coulomb.coulomb_fixed_point`) from
    the least-friction equilibrium; if CasADi is installed, IPOPT on the whole problem (11) as in the paper
    (:mod:`interlock.verify.statics.cra_ipopt`) from the motion of most work with the least-friction forces, from
    rest, and from where the assembly settles (:func:`settled_motion`); then SLSQP from where it settles
    with those vertices kept closed (up to :data:`LAST_RESORT_LIMIT` of them).  ``progress(words)``, if
    given, is told as each solver starts; ``frugal``: the least-friction equilibrium when already known.
    """
    frugal = least_friction(problem, b_eq) if frugal is None else frugal
    found, coulomb, _ = coulomb_route(problem, b_eq, frugal, lambda motion: problem.exact(b_eq, motion),
                                      progress=progress)
    if found is not None:
        return found, coulomb
    settled = settled_motion(problem, b_eq)
    statuses = []
    if cra_ipopt.available():
        if progress is not None:
            progress("IPOPT on (11)")
        starts = [(most_work, frugal), (None, None), (settled, frugal)]
        started = time.perf_counter()
        try:
            for motion, forces, status in cra_ipopt.local_solutions(problem.system.a_eq, problem.system.a_ub, b_eq,
                                                                    problem.ratio, starts, budget=problem.budget):
                statuses.append(status)
                found = verify_local(problem, b_eq, motion, forces)
                if found is not None:
                    return found, f"IPOPT on problem (11) (start {len(statuses)} of {len(starts)})"
        finally:
            timings["ipopt"] = time.perf_counter() - started
    polished = None if settled is None else polish(problem, b_eq, rbe_forces, settled, limit=LAST_RESORT_LIMIT)
    exact = None if polished is None else problem.exact(b_eq, polished)
    if exact is not None:
        return (polished, exact), "a local solve (SLSQP) from where the assembly settles"
    if not statuses:
        return None, (f"no local solve found one ({coulomb}; SLSQP; {cra_ipopt.MISSING_MESSAGE} for the paper's "
                      f"solver)")
    return None, (f"no local solve found one ({coulomb}; SLSQP, and IPOPT, the paper's solver, from {len(statuses)} "
                  f"starts: {', '.join(statuses)}; which proves nothing)")


def coulomb_route(problem, b_eq, frugal, check, progress=None, **options):
    """``((motion, forces), how, fixed_point)`` of the Coulomb fixed point started from the least-friction
    equilibrium ``frugal`` (:func:`least_friction`; ``None`` if there is none), each motion judged by ``check``,
    or ``(None, why not, fixed_point)`` naming what its closest motion leaves unbalanced (``fixed_point``: the
    :class:`~interlock.verify.statics.cra_coulomb.FixedPoint`, ``None`` if it did not start).  ``options``:
    ``iterations``, ``stuck`` and ``history`` of
    :func:`~interlock.verify.statics.cra_coulomb.coulomb_fixed_point` (with a ``history``, it continues from
    there and ``frugal`` may be ``None``)."""
    continued = bool(options.get("history"))
    if frugal is None and not continued:
        return None, "the Coulomb fixed point did not start (no least-friction equilibrium)", None
    fixed_point = cra_coulomb.coulomb_fixed_point(problem, b_eq, None if frugal is None else frugal[:, 0], check,
                                                  progress=progress, **options)
    if fixed_point.found is not None:
        more = "more " if continued else ""
        return (fixed_point.found, f"the Coulomb fixed point ({fixed_point.rounds} {more}convex frictional-contact "
                                   f"solves)", fixed_point)
    return None, cra_coulomb.describe(fixed_point), fixed_point


def verify_local(problem, b_eq, motion, forces):
    """``(motion, forces)`` solving (11) exactly near a local solver's point, or ``None``.

    An interior-point solution closes its contacts only nearly: tried are its motion, the motion
    snapped shut (:func:`snap`), one realising its forces (:func:`realise`) and SLSQP from it
    (:func:`polish`) with its nearly closed vertices loaded.
    """
    dd = (problem.kinematic @ motion).reshape(-1, 3)
    near_forces = np.where((dd[:, 0] + 1.0 <= SNAP_TOL)[:, None], forces, 0.0)
    snapped = snap(problem, motion)
    for candidate in (lambda: motion, lambda: snapped, lambda: realise(problem, forces),
                      lambda: polish(problem, b_eq, near_forces, motion if snapped is None else snapped)):
        tried = candidate()
        exact = None if tried is None else problem.exact(b_eq, tried)
        if exact is not None:
            return tried, exact
    return None


def snap(problem, motion, tolerance: float = SNAP_TOL):
    """The motion nearest (L1) to ``motion`` that closes exactly the vertices it nearly closes
    (``dd_n + eps <= tolerance * eps``) and keeps the others open; ``None`` if there is none:
    :func:`~interlock.verify.statics.cra_coulomb.shut_nearly_closed` with the local solvers' :data:`SNAP_TOL`."""
    return cra_coulomb.shut_nearly_closed(problem, motion, tolerance)


def least_friction(problem, b_eq, interior: bool = False):
    """The RBE equilibrium with the least friction, or ``None``: minimise ``sum_v |f_u| + |f_v|`` (in each
    contact's ``(u, v)`` basis) plus ``LEAST_FRICTION_NORMAL`` times ``sum f_n``.

    CRA allows friction only where a vertex slides, against the slide
    (Eq. (9)); an equilibrium that needs friction at few vertices leaves
    the others free to slide any way, so a motion realising it
    (:func:`realise`) is easy to find.  The 36-voussoir arch: 68 of 148
    vertices carry friction, and a motion realises it exactly (RBE's
    least-force equilibrium is not realisable).

    ``interior=True`` solves it by Clarabel instead of HiGHS' simplex, which
    takes over ten minutes on the armadillo vault's 10,901 vertices.
    """
    system = problem.system
    s = len(system.points)
    if s == 0:
        return None
    # x = (f, t) with |f_u| <= t_u, |f_v| <= t_v
    tangential = sp.csr_matrix((np.ones(2 * s), (np.arange(2 * s), (3 * np.arange(s)[:, None] + [1, 2]).ravel())),
                               shape=(2 * s, 3 * s))
    identity = sp.eye(2 * s, format="csr")
    a_ub = sp.vstack([sp.hstack([system.a_ub, sp.csr_matrix((system.a_ub.shape[0], 2 * s))]),
                      sp.hstack([tangential, -identity]), sp.hstack([-tangential, -identity])], format="csr")
    a_eq = sp.hstack([system.a_eq, sp.csr_matrix((system.a_eq.shape[0], 2 * s))], format="csr")
    cost = np.concatenate([np.tile([LEAST_FRICTION_NORMAL, 0.0, 0.0], s), np.ones(2 * s)])
    if interior:
        normal = sp.csr_matrix((-np.ones(s), (np.arange(s), 3 * np.arange(s))), shape=(s, 5 * s))
        solution = clarabel_lp(cost, sp.vstack([a_eq, a_ub, normal], format="csc"),
                               np.concatenate([b_eq, np.zeros(a_ub.shape[0] + s)]), equalities=len(b_eq),
                               budget=problem.budget, stage="the least-friction equilibrium")
        return np.asarray(solution.x)[:3 * s].reshape(-1, 3) if str(solution.status) == "Solved" else None
    bounds = np.vstack([system.bounds, np.tile([0.0, np.inf], (2 * s, 1))])
    outcome = highs_lp(cost, problem.budget, "the least-friction equilibrium", A_ub=a_ub, b_ub=np.zeros(a_ub.shape[0]),
                       A_eq=a_eq, b_eq=b_eq, bounds=bounds)
    return outcome.x[:3 * s].reshape(-1, 3) if outcome.status == 0 else None


def realise_least_friction(problem, b_eq):
    """A motion realising the least-friction equilibrium (:func:`least_friction`), or ``None``."""
    forces = least_friction(problem, b_eq)
    return None if forces is None else realise(problem, forces)


def realise(problem, forces):
    """A motion realising the MILP's forces exactly (LP in ``dq`` and ``beta``), or ``None``.

    Loaded vertices close (``dd_n = -1``), the others may not overlap more;
    friction vertices slide along ``-f_t``: ``dd_t = -beta f_t`` with
    ``beta |f_t| >= min_slide``; vertices without friction may slide freely (``alpha = 0``).
    """
    d = problem.kinematic
    scale = max(float(np.abs(forces).max(initial=0.0)), 1e-300)
    loaded = forces[:, 0] > 1e-9 * scale
    friction = np.hypot(forces[:, 1], forces[:, 2])
    rubbing = loaded & (friction > 1e-9 * scale)
    s, n_q = len(forces), d.shape[1]
    n_b = int(rubbing.sum())
    d_n, d_t = d[0::3], (d[1::3], d[2::3])
    blocks_eq = [sp.hstack([d_n[loaded], sp.csr_matrix((int(loaded.sum()), n_b))])]
    b_eq = [np.full(int(loaded.sum()), -1.0)]
    which = np.flatnonzero(rubbing)
    for component in (0, 1):
        scaled = sp.csr_matrix((forces[which, 1 + component], (np.arange(n_b), np.arange(n_b))), shape=(n_b, n_b))
        blocks_eq.append(sp.hstack([d_t[component][which], scaled]))  # dd_t + beta f_t = 0
        b_eq.append(np.zeros(n_b))
    a_ub = sp.vstack([sp.hstack([-d, sp.csr_matrix((3 * s, n_b))]),
                      sp.hstack([d, sp.csr_matrix((3 * s, n_b))])], format="csr")
    b_ub = np.concatenate([np.tile([1.0, problem.ratio, problem.ratio], s), np.full(3 * s, problem.ratio)])
    low_beta = problem.min_slide / friction[which]
    bounds = [(None, None)] * n_q + [(lb, None) for lb in low_beta]
    outcome = highs_lp(np.zeros(n_q + n_b), problem.budget, "a motion realising forces", A_ub=a_ub, b_ub=b_ub,
                       A_eq=sp.vstack(blocks_eq, format="csr"), b_eq=np.concatenate(b_eq), bounds=bounds)
    return outcome.x[:n_q] if outcome.status == 0 else None


def settled_motion(problem, b_eq):
    """The allowed motion that closes as many vertices as an LP can (least ``sum dd_n``) and, keeping those
    closed, does the most work: where an assembly settles under its load (the start of :func:`polish`
    when the MILP does not decide).  ``None`` if an LP fails."""
    a_ub, b_ub = problem.allowed_motions
    d_n = problem.kinematic[0::3]
    closing = highs_lp(np.asarray(d_n.sum(axis=0)).ravel(), problem.budget, "where the assembly settles",
                       A_ub=a_ub, b_ub=b_ub, bounds=(None, None))
    if closing.status != 0:
        return None
    closed = d_n @ closing.x + 1.0 <= ACTIVE_TOL
    working = highs_lp(b_eq, problem.budget, "where the assembly settles", A_ub=a_ub, b_ub=b_ub, A_eq=d_n[closed],
                       b_eq=np.full(int(closed.sum()), -1.0), bounds=(None, None))
    return working.x if working.status == 0 else None


def polish(problem, b_eq, forces, motion, limit=POLISH_LIMIT):
    """Solve (11) locally from the MILP's point, with its closed vertices kept closed (SLSQP).

    Unknowns ``(dq, f_n, alpha)`` on the closed set ``S``; friction is
    ``f_t = -alpha dd_t`` exactly, so equilibrium is bilinear:
    ``A_n f_n - sum_v alpha_v A_t,v T_v dq = b``.  The objective is the
    paper's ``|f_n|^2 + |alpha|^2`` (7a)/(11).  Returns the motion, or ``None``.
    At most :data:`POLISH_ITERATIONS` iterations; ``problem.budget`` is checked after each.
    """
    problem.budget.check("SLSQP")
    system, d = problem.system, problem.kinematic
    dd = (d @ motion).reshape(-1, 3)
    closed = np.flatnonzero((dd[:, 0] + 1.0 <= 1e-4) | (forces[:, 0] > 1e-9))
    if not len(closed) or (limit is not None and len(closed) > limit):
        return None
    a = system.a_eq.toarray()
    kin = d.toarray()
    m = len(closed)
    normal = a[:, 3 * closed]
    tangential = [a[:, [3 * v + 1, 3 * v + 2]] @ kin[[3 * v + 1, 3 * v + 2]] for v in closed]  # M_v
    sides, bound = len(system.cone_rows), -system.cone_rows[0, 0]
    slide_rows = [system.cone_rows[:, 1:] @ kin[[3 * v + 1, 3 * v + 2]] for v in closed]  # (sides, n_q): c_k . T_v
    others = np.setdiff1d(np.arange(len(dd)), closed)

    # dq = q0 + N y keeps the closed vertices closed (the rows are often dependent, which SLSQP cannot take)
    closed_rows = kin[3 * closed]
    q0 = motion + np.linalg.lstsq(closed_rows, -1.0 - closed_rows @ motion, rcond=None)[0]
    basis = null_space(closed_rows)
    n_y = basis.shape[1]
    tangential_y = [mv @ basis for mv in tangential]
    slide_y = [rows @ basis for rows in slide_rows]

    def split(x):
        return q0 + basis @ x[:n_y], x[n_y:n_y + m], x[n_y + m:]

    def equilibrium(x):
        q, fn, alpha = split(x)
        return normal @ fn - sum(al * (mv @ q) for al, mv in zip(alpha, tangential)) - b_eq

    def equilibrium_jacobian(x):
        q, fn, alpha = split(x)
        return np.hstack([-sum(al * my for al, my in zip(alpha, tangential_y)), normal,
                          np.column_stack([-(mv @ q) for mv in tangential])])

    def cone(x):  # bound f_n + alpha (c_k . T_v dq) >= 0
        q, fn, alpha = split(x)
        return np.concatenate([bound * fn[i] + alpha[i] * (slide_rows[i] @ q) for i in range(m)])

    def cone_jacobian(x):
        q, fn, alpha = split(x)
        rows = np.zeros((m * sides, n_y + 2 * m))
        for i in range(m):
            block = slice(i * sides, (i + 1) * sides)
            rows[block, :n_y] = alpha[i] * slide_y[i]
            rows[block, n_y + i] = bound
            rows[block, n_y + m + i] = slide_rows[i] @ q
        return rows

    motion_rows = np.vstack([kin[3 * others], kin, -kin])
    motion_bounds = np.concatenate([np.full(len(others), -1.0), np.full(2 * len(kin), -problem.ratio)])
    motion_y = motion_rows @ basis
    constraints = [
        {"type": "eq", "fun": equilibrium, "jac": equilibrium_jacobian},
        {"type": "ineq", "fun": cone, "jac": cone_jacobian},
        {"type": "ineq", "fun": lambda x: motion_rows @ split(x)[0] - motion_bounds,
         "jac": lambda x: np.hstack([motion_y, np.zeros((len(motion_rows), 2 * m))])},
    ]
    slide = np.hypot(dd[closed, 1], dd[closed, 2])
    alpha0 = np.hypot(forces[closed, 1], forces[closed, 2]) / np.maximum(slide, 1e-3)
    x0 = np.concatenate([basis.T @ (motion - q0), forces[closed, 0], alpha0])
    bounds = [(None, None)] * n_y + [(0.0, None)] * (2 * m)
    outcome = minimize(lambda x: float(x[n_y:] @ x[n_y:]), x0,
                       jac=lambda x: np.concatenate([np.zeros(n_y), 2 * x[n_y:]]),
                       method="SLSQP", bounds=bounds, constraints=constraints,
                       options={"maxiter": POLISH_ITERATIONS, "ftol": 1e-12},
                       callback=lambda x: problem.budget.check("SLSQP"))
    q = split(outcome.x)[0]
    return q if np.all(np.isfinite(q)) else None
