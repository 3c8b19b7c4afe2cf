"""The CRA paper's own route to problem (11): a local interior-point solve with IPOPT (optional, through CasADi).

The paper solves (11) with IPOPT [75] and calls an assembly unstable when
IPOPT reports the problem infeasible.  A local solver proves nothing either
way, so :func:`~interlock.verify.statics.cra.cra` uses it only where the exact routes
have not decided (after the quick answers; after the MILP, or before it on
models too large for it) and checks what it returns with the exact LP: a
motion that passes is a solution of (11), whatever found it; one that does
not, or "infeasible", leaves the verdict "inconclusive".

CasADi's PyPI wheels carry IPOPT, so ``pip install "interlock[nlp]"`` is all
it needs (:data:`MISSING_MESSAGE` otherwise).

The formulation is (11) over all contact vertices, in the solver's units
(forces over the free blocks' weight, lengths over ``eps``):

- ``min sum f_n^2 + sum alpha^2``;
- ``A_eq f = b``, ``A_fr f <= 0``, ``f_n >= 0`` (Eqs. (7b)-(7d));
- ``f_n (dd_n + 1) <= 0`` with ``dd_n + 1 >= 0``: Eq. (10);
- ``f_t + alpha dd_t = 0``, ``alpha >= 0``: Eq. (9);
- ``|dd| <= eta / eps``, with ``dd = A_eq^T q``: Eq. (8).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from interlock.verify.budget import TimeLimitReached

__all__ = ["MISSING_MESSAGE", "IPOPT_ITERATIONS", "available", "local_solutions", "deadline_options",
           "timed_out"]

MISSING_MESSAGE = 'IPOPT is not installed: pip install "interlock[nlp]" (CasADi, whose wheels carry IPOPT)'
#: Most IPOPT iterations per start (shelf-stable takes 400-700; an iteration on the 36-voussoir arch 14 ms).
IPOPT_ITERATIONS = 1000
#: IPOPT's convergence tolerance; the exact LP decides afterwards, so it need not be tight.
IPOPT_TOLERANCE = 1e-9


def available() -> bool:
    """Whether CasADi (with IPOPT) can be imported."""
    try:
        import casadi
    except ImportError:
        return False
    return bool(casadi.has_nlpsol("ipopt"))


def local_solutions(a_eq, a_ub, b_eq, ratio: float, starts, iterations: int = IPOPT_ITERATIONS, budget=None):
    """Yield ``(motion, forces, status)`` of IPOPT on problem (11) from each start ``(motion, forces)``.

    Parameters
    ----------
    a_eq : sparse (6 f, 3 s)
        The equilibrium matrix ``A_eq``; the kinematic matrix is its transpose (Eq. (8)).
    a_ub : sparse (k, 3 s)
        The linearised friction cones ``A_fr``.
    b_eq : ndarray (6 f,)
        The load, ``-p`` over the free blocks' weight.
    ratio : float
        ``eta / eps``, the bound on every ``|dd|`` in units of ``eps``.
    starts : iterable of (ndarray or None, ndarray or None)
        Starting motions ``(6 f,)`` and forces ``(s, 3)``; ``None`` starts from zero.
    iterations : int
        Most IPOPT iterations per start (the limit that makes the route the same on every machine).
    budget : Budget, optional
        The call's time budget: each start gets the time left as IPOPT's ``max_wall_time``, and running out
        raises :class:`~interlock.verify.budget.TimeLimitReached` ("IPOPT on (11)").

    Yields
    ------
    motion : ndarray (6 f,)
    forces : ndarray (s, 3)
    status : str
        IPOPT's return status (e.g. ``"Solve_Succeeded"``, ``"Infeasible_Problem_Detected"``).

    Examples
    --------
    One unit cube on a fixed one, in units of its weight and of ``eps``:

    >>> import numpy as np, trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics.equilibrium import EquilibriumSystem
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> system = EquilibriumSystem.build(Assembly.from_meshes(cubes, frame=[0]), 0.5, 1.0, None, "paper", 8, None)
    >>> load = -np.array([0, 0, -1, 0, 0, 0.0])
    >>> motion, forces, status = next(local_solutions(system.a_eq, system.a_ub, load, 100.0, [(None, None)]))
    >>> status, round(float(forces[:, 0].sum()), 6), round(float(motion[2]), 6)
    ('Solve_Succeeded', 1.0, -1.0)
    """
    import casadi

    s, n_q = a_eq.shape[1] // 3, a_eq.shape[0]
    q, f, alpha = casadi.SX.sym("q", n_q), casadi.SX.sym("f", 3 * s), casadi.SX.sym("alpha", s)
    dd = _times(a_eq.T, q)
    normal = f[0::3]
    constraints = casadi.vertcat(_times(a_eq, f), _times(a_ub, f), normal * (dd[0::3] + 1.0),
                                 f[1::3] + alpha * dd[1::3], f[2::3] + alpha * dd[2::3], dd)
    n_ub = a_ub.shape[0]
    lower = np.concatenate([b_eq, np.full(n_ub + s, -np.inf), np.zeros(2 * s), np.tile([-1.0, -ratio, -ratio], s)])
    upper = np.concatenate([b_eq, np.zeros(n_ub + s), np.zeros(2 * s), np.full(3 * s, ratio)])
    variables = casadi.vertcat(q, f, alpha)
    low = np.concatenate([np.full(n_q, -np.inf), np.tile([0.0, -np.inf, -np.inf], s), np.zeros(s)])
    stage = "IPOPT on (11)"
    options, clock = deadline_options(budget, stage, variables.numel(), constraints.numel())
    solver = casadi.nlpsol("cra", "ipopt", {"x": variables, "f": casadi.sumsqr(normal) + casadi.sumsqr(alpha),
                                            "g": constraints},
                           {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                            "ipopt.max_iter": int(iterations), "ipopt.tol": IPOPT_TOLERANCE, **options})
    for motion, forces in starts:
        if budget is not None:
            budget.check(stage)
        x0 = np.concatenate([np.zeros(n_q) if motion is None else motion,
                             np.zeros(3 * s) if forces is None else np.ravel(forces), np.zeros(s)])
        solution = solver(x0=x0, lbx=low, ubx=np.inf, lbg=lower, ubg=upper)
        status = str(solver.stats()["return_status"])
        if timed_out(status, budget):
            raise TimeLimitReached(stage)
        x = np.asarray(solution["x"]).ravel()
        yield x[:n_q], x[n_q:n_q + 3 * s].reshape(-1, 3), status
    del clock


def deadline_options(budget, stage: str, variables: int, constraints: int, parameters: int = 0):
    """``(options, callback)``: CasADi options that stop IPOPT once ``budget`` has no time left (an iteration
    callback asking the budget after every iteration: IPOPT's own ``max_wall_time`` would count from each
    solve and miss the second or more that CasADi spends setting the solver up), and the callback, to keep
    alive as long as the solver.  ``({}, None)`` without a limit; :class:`~interlock.verify.budget.TimeLimitReached`
    naming ``stage`` if no time is left already.  ``variables``, ``constraints``, ``parameters``: the NLP's sizes."""
    if budget is None or budget.solver_limit() is None:
        return {}, None
    budget.check(stage)
    import casadi

    class Deadline(casadi.Callback):
        def __init__(self):
            casadi.Callback.__init__(self)
            self.construct("deadline", {})

        def get_n_in(self):
            return casadi.nlpsol_n_out()

        def get_n_out(self):
            return 1

        def get_name_in(self, i):
            return casadi.nlpsol_out(i)

        def get_name_out(self, i):
            return "ret"

        def get_sparsity_in(self, i):
            size = {"f": 1, "x": variables, "lam_x": variables, "g": constraints, "lam_g": constraints,
                    "p": parameters, "lam_p": parameters}[casadi.nlpsol_out(i)]
            return casadi.Sparsity.dense(size, 1) if size else casadi.Sparsity(0, 0)

        def eval(self, arg):
            return [1 if budget.remaining() <= 0 else 0]

    clock = Deadline()
    return {"iteration_callback": clock, "iteration_callback_ignore_errors": False}, clock


def timed_out(status: str, budget=None) -> bool:
    """Whether IPOPT stopped for the time: its own time limits, or the deadline callback
    (:func:`deadline_options`; "User_Requested_Stop") with ``budget`` spent."""
    return ("Time" in status and "Exceeded" in status) or (
        status == "User_Requested_Stop" and budget is not None and budget.remaining() <= 0)


def _times(matrix, vector):
    """``matrix @ vector`` for a SciPy sparse matrix and a CasADi symbol, keeping the sparsity."""
    import casadi

    matrix = sp.csc_matrix(matrix)
    sparsity = casadi.Sparsity(matrix.shape[0], matrix.shape[1], matrix.indptr.tolist(), matrix.indices.tolist())
    return casadi.mtimes(casadi.DM(sparsity, matrix.data), vector)
