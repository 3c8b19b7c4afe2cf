"""CRA on large models (hundreds of blocks, thousands of contact vertices): interior-point candidates, exact checks.

:func:`~interlock.verify.statics.cra.cra` decides problem (11) by quick answers, a
MILP with a binary per vertex and sector, and an exact LP at a motion.  Past
:data:`LARGE_VERTICES` contact vertices the per-vertex LPs that bound the MILP
(two per vertex), the MILP itself (the shelf's 380 binaries are undecided in
10 minutes; the armadillo vault would have 54,505) and the dense local solvers
are out of reach, and HiGHS' simplex takes about a minute per LP.  Here:

1. RBE by Clarabel (:class:`~interlock.verify.statics.equilibrium.EquilibriumSystem`):
   no equilibrium means "unstable". This is the only implication between the
   two that holds in general: every solution of (11) satisfies (7b)-(7d), so
   CRA stable implies RBE stable, and RBE unstable implies CRA unstable (CRA
   paper, Sec. 2.2 and 3.1).  The converse fails (model H, Fig. 3): an RBE
   equilibrium, even one with compression only and friction inside the cone,
   proves nothing about (11) until a motion realises it (Eqs. (9)-(10)).
2. Candidate motions by Clarabel, each checked by the exact LP of (11) at the
   motion (:func:`exact`): the allowed motion of most work (by LP duality its
   multipliers are a frictionless equilibrium that it realises whenever the
   bound ``eta`` is nowhere active; where it is active, the multipliers are
   forces at displacements of ``eta``, which (11) does not allow).
3. The Coulomb fixed point (:mod:`interlock.verify.statics.cra_coulomb`): convex
   frictional-contact problems whose solutions solve (11) once the friction
   thresholds obey Coulomb's law, each motion checked by :func:`exact`.
4. With ``hold_out=True``, when the fixed point keeps sliding the same few
   blocks to the bound ``eta``: the rest proved without them, then they are
   placed (:mod:`interlock.verify.statics.cra_split`); else the message names
   them.
5. Otherwise "inconclusive", saying what was tried and why the exact routes do
   not reach the model, with the size of the MILP it would take.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from interlock.verify.statics import cra_coulomb, cra_ipopt, cra_local, cra_split
from interlock.verify.statics.equilibrium import clarabel_lp

__all__ = ["LARGE_VERTICES", "CHECK_RTOL", "most_work", "exact", "interior_forces", "carries", "decide_large"]

#: Contact vertices above which :func:`~interlock.verify.statics.cra.cra` takes this route (the shelves of
#: Fig. 7 and 12 have 60-90, the 36-voussoir arch 148, the armadillo vault 10,901).
LARGE_VERTICES = 2000
#: An interior-point solution of the exact LP is accepted when every residual of (11) at the motion
#: (equilibrium, ``f_n >= 0``, ``alpha >= 0``, the friction pyramid) is at most this times the load
#: (forces in units of the free blocks' weight): HiGHS' feasibility tolerance is 1e-7.
CHECK_RTOL = 1e-7
#: Closed vertices are those with ``dd_n + eps <= SNAP * eps`` in an interior-point motion (then made exact).
SNAP = 1e-6


def most_work(problem, b_eq):
    """The allowed motion on which the load does the most work (Clarabel), and the LP's multipliers.

    Returns ``(motion, forces)`` in the solver's units (``eps = 1``), ``forces = z_lower - z_upper`` per
    vertex component (an equilibrium: ``A_eq forces = b``), or ``(None, None)``.
    """
    a_ub, b_ub = problem.allowed_motions
    solved = _clarabel(b_eq, a_ub, b_ub, budget=problem.budget, stage="the motion of most work")
    if solved is None:
        return None, None
    q, z = solved
    s = a_ub.shape[0] // 6
    forces = z[3 * s:].reshape(-1, 3) - z[:3 * s].reshape(-1, 3)
    return q, forces


def exact(problem, b_eq, motion):
    """Forces solving (11) exactly at ``motion`` (least ``sum f_n``), or ``None``: the LP of
    ``CRAProblem.motion_lp`` solved by Clarabel, then every residual checked (:data:`CHECK_RTOL`)."""
    lp = problem.motion_lp(motion)
    return None if lp is None else interior_forces(lp, b_eq, problem.budget)


def interior_forces(lp, b_eq, budget=None):
    """Forces of the LP of (11) at a motion (``lp``: a ``MotionLP``) by Clarabel, if they pass ``lp.holds``;
    else ``None``.  ``budget``: the call's time budget."""
    n = len(lp.cost)
    constraints = sp.vstack([lp.a_eq, lp.a_ub, -sp.eye(n)], format="csc")
    right = np.concatenate([b_eq, np.zeros(lp.a_ub.shape[0] + n)])
    solved = _clarabel(lp.cost, constraints, right, equalities=lp.a_eq.shape[0], budget=budget, stage="the exact LP")
    if solved is None:
        return None
    x = np.maximum(solved[0], 0.0)
    return lp.forces(x) if lp.holds(x, b_eq) else None


def carries(problem, b_eq, closed: np.ndarray) -> bool | None:
    """Whether the vertices ``closed`` alone can carry the load with friction anywhere in the pyramid (RBE
    restricted to them, Clarabel); ``None`` if Clarabel does not decide.  A motion realising an equilibrium
    must close at least the vertices of one such set, so ``False`` says why a motion closing only these fails."""
    system = problem.system
    m = int(closed.sum())
    if not m:
        return False
    columns = np.flatnonzero(np.repeat(closed, 3))
    a_ub = system.a_ub[:, columns]
    a_ub = a_ub[np.flatnonzero(np.diff(a_ub.tocsr().indptr) > 0)]
    normal = sp.csr_matrix((-np.ones(m), (np.arange(m), 3 * np.arange(m))), shape=(m, 3 * m))
    constraints = sp.vstack([system.a_eq[:, columns], a_ub, normal], format="csc")
    right = np.concatenate([b_eq, np.zeros(constraints.shape[0] - len(b_eq))])
    status = str(clarabel_lp(np.tile([1.0, 0.0, 0.0], m), constraints, right, equalities=len(b_eq),
                             budget=problem.budget, stage="why the motion of most work fails").status)
    return True if status == "Solved" else False if status == "PrimalInfeasible" else None


def decide_large(problem, b_eq, binaries: int, timings: dict, progress=None, hold_out: bool = False):
    """``(status, forces, motion, message)`` for a large model (see the module docstring); forces in units of
    the free blocks' weight, the motion in units of ``eps``.  ``binaries``: the MILP's size, for the message;
    ``progress(words)``, if given, is told as each stage starts; ``hold_out``: hold out the blocks the fixed
    point cannot hold (:mod:`~interlock.verify.statics.cra_split`), else name them.  Every stage is bounded by
    its rounds or attempts (the same route on every machine) and by ``problem.budget``."""
    started = time.perf_counter()
    if progress is not None:
        progress("the motion of most work")
    motion, _ = most_work(problem, b_eq)
    found = None
    active, closed = 0, None
    if motion is not None:
        dd = (problem.kinematic @ motion).reshape(-1, 3)
        active = int(np.count_nonzero(np.abs(dd) >= problem.ratio * (1 - 1e-6)))
        snapped = motion.copy()
        near = dd[:, 0] + 1.0 <= SNAP
        closed = near
        if near.any():  # close the nearly closed vertices exactly: least-squares step along their rows
            rows = problem.kinematic[0::3][near]
            step = sp.linalg.lsqr(rows, -1.0 - rows @ motion, atol=1e-14, btol=1e-14, iter_lim=5000)[0]
            snapped = motion + step
        for candidate in (snapped, motion):
            forces = exact(problem, b_eq, candidate)
            if forces is not None:
                found = (candidate, forces, "the motion of most work")
                break
    coulomb = ""
    if found is None:
        frugal = cra_local.least_friction(problem, b_eq, interior=True)
        result, coulomb, fixed_point = cra_local.coulomb_route(
            problem, b_eq, frugal, lambda m: exact(problem, b_eq, m), progress,
            stuck=cra_coulomb.STUCK_ROUNDS if hold_out and cra_ipopt.available() else None)
        held = () if fixed_point is None else fixed_point.at_bound
        if result is not None:
            found = (*result, coulomb)
        elif hold_out and 0 < len(held) <= cra_split.SPLIT_MOST_BLOCKS:
            result, split = cra_split.split_route(problem, b_eq, held, exact, progress=progress,
                                                  history=fixed_point.history)
            if result is not None:
                found = (*result, split)
            else:
                coulomb = f"{coulomb}; {split}"
        elif 0 < len(held) <= cra_split.SPLIT_MOST_BLOCKS:
            them = "them" if len(held) > 1 else "it"
            coulomb = (f"{coulomb}; {cra_split.named(held)} slid to the bound eta in its last round: "
                       f"cra(..., hold_out=True) proves the rest without {them} and then places {them}")
    if found is not None:
        timings["lp"] = timings.get("lp", 0.0) + time.perf_counter() - started
        motion, forces, how = found
        return "stable", forces, motion, f"equilibrium realised by {how} (large model; exact check)"
    if motion is None:
        why = "the LP of most work did not solve"
    else:
        carried = carries(problem, b_eq, closed)
        why = (f"the motion of most work does not realise an equilibrium (the bound eta is active at {active} "
               f"displacement components, where its multipliers are forces at slides of eta that (11) does not "
               f"allow; the {int(closed.sum())} vertices it closes "
               + {False: "cannot carry the load even with friction anywhere in the cone",
                  True: "could carry the load, but not with friction against its slides",
                  None: "were not decided to carry the load"}[carried] + ")")
    timings["lp"] = timings.get("lp", 0.0) + time.perf_counter() - started
    return ("inconclusive", None, None,
            f"RBE has an equilibrium (necessary, not sufficient); {why}; {coulomb}; the MILP relaxation would "
            f"have {binaries} binaries, beyond the exact route (the shelf's 380 are undecided in 10 min); a local "
            f"solve of (11) as in the paper (compas_cra's IPOPT: 2,424 s on the armadillo, Table 5; "
            f"cra(..., backend='compas_cra') checks its motion exactly) was not tried")


def _clarabel(cost, constraints, right, equalities: int = 0, budget=None, stage: str = "an LP"):
    """``(x, z)`` (primal, dual) of :func:`~interlock.verify.statics.equilibrium.clarabel_lp` when Clarabel
    solves it, else ``None``."""
    solution = clarabel_lp(cost, constraints, right, equalities, budget=budget, stage=stage)
    if str(solution.status) != "Solved":
        return None
    return np.asarray(solution.x), np.asarray(solution.z)
