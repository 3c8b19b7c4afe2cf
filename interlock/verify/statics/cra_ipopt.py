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

__all__ = ["MISSING_MESSAGE", "IPOPT_ITERATIONS", "available", "local_solutions"]

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


def local_solutions(a_eq, a_ub, b_eq, ratio: float, starts, iterations: int = IPOPT_ITERATIONS):
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
        Most IPOPT iterations per start.

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
    solver = casadi.nlpsol("cra", "ipopt", {"x": variables, "f": casadi.sumsqr(normal) + casadi.sumsqr(alpha),
                                            "g": constraints},
                           {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
                            "ipopt.max_iter": int(iterations), "ipopt.tol": IPOPT_TOLERANCE})
    for motion, forces in starts:
        x0 = np.concatenate([np.zeros(n_q) if motion is None else motion,
                             np.zeros(3 * s) if forces is None else np.ravel(forces), np.zeros(s)])
        solution = solver(x0=x0, lbx=low, ubx=np.inf, lbg=lower, ubg=upper)
        x = np.asarray(solution["x"]).ravel()
        yield x[:n_q], x[n_q:n_q + 3 * s].reshape(-1, 3), str(solver.stats()["return_status"])


def _times(matrix, vector):
    """``matrix @ vector`` for a SciPy sparse matrix and a CasADi symbol, keeping the sparsity."""
    import casadi

    matrix = sp.csc_matrix(matrix)
    sparsity = casadi.Sparsity(matrix.shape[0], matrix.shape[1], matrix.indptr.tolist(), matrix.indices.tolist())
    return casadi.mtimes(casadi.DM(sparsity, matrix.data), vector)
