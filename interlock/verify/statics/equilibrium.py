"""The equilibrium problem that RBE and CRA share (CRA paper, Eqs. (1)-(5), App. B): its matrices and input checks.

:class:`EquilibriumSystem` holds the LP of rigid-block equilibrium without its
right-hand side (which gravity alone sets); :func:`~interlock.verify.statics.rbe.rbe`
solves it once, :func:`~interlock.verify.statics.cra.cra` couples it with the
blocks' motion.  The theory is in ``docs/statics.md``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from numbers import Real

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError
from interlock.files import json_float
from interlock.verify.budget import Budget, TimeLimitReached
from interlock.verify.first_order import SOLVER_THREADS
from interlock.verify.statics.interfaces import statics_contacts

__all__ = ["StabilityError", "StabilityResult", "EquilibriumSystem", "equilibrium_matrix", "friction_block",
           "friction_matrix", "friction_utilisation", "gravity_vector", "nonnegative", "positive",
           "block_densities", "force_units", "json_float", "CONES", "DEFAULT_SIDES", "LARGE_LP", "DEFAULT_EPS",
           "DEFAULT_ETA",
           "FRICTION_RTOL", "MU_MIN", "MU_MAX", "RBE_ITERATIONS", "contact_words", "clarabel_lp", "clarabel_solve",
           "friction_coefficient", "highs_lp", "Budget", "TimeLimitReached"]

#: Linearised friction cones: "paper" circumscribes the Coulomb cone (App. B, faces tangent to it, so it
#: allows up to 1/cos(pi/sides) more friction between its faces), "inner" is inscribed (conservative).
CONES = ("paper", "inner")
#: Sides of the friction pyramid (App. B: eight).
DEFAULT_SIDES = 8
#: Up to this many force unknowns, once Clarabel has found an equilibrium, HiGHS' simplex finds the one of least
#: ``sum f_n`` (a vertex of the LP: forces on the pyramid's faces); above, Clarabel's forces are reported.  The
#: simplex took 22 s for that on a 108-block RhomBlock hexagon (4,374 unknowns, block 0 fixed) that Clarabel
#: decides in 0.5 s; on the CRA paper's models (at most a few hundred unknowns) it takes milliseconds.
LARGE_LP = 2000
#: CRA's overlap ``eps`` of a loaded contact vertex, as a fraction of the model size (paper: 1e-5 .. 1e-4 of the
#: block dimension).
DEFAULT_EPS = 1e-5
#: Bound ``eta`` on every relative virtual displacement, as a fraction of the model size (paper: 1e-3 .. 1e-2).
#: Only ``eta / eps`` changes the verdict: here 100.  Upstream compas_cra uses 10 (1e-4 and 1e-3 absolute);
#: then a block closing two faces of a V groove slides at least 1.73 eps down them, so friction along the
#: groove tilts by 10 degrees or more and type-a gives 20.7 instead of 21.8 degrees (Table 2).
DEFAULT_ETA = 1e-3
#: Friction utilisation counts only vertices whose normal force is at least this fraction of the largest one.
#: Below it, forces are at the solver's tolerance and their ratio is noise: on the armadillo (Clarabel, 10,000
#: vertices) vertices with f_n ~ 5e-10 of the largest gave 1.39 (paper cone) and 1.21 (inner); counting those above
#: 1e-6 / 1e-5 / 1e-4 of it gives 1.08267 / 1.082413 / 1.082394 (paper; the octagon's bound 1.082392) and
#: 1.00016 / 1.000012 / 1.000002 (inner, bound 1).
FRICTION_RTOL = 1e-5
#: The friction coefficients the solvers represent: 0 (no friction) or ``MU_MIN <= mu <= MU_MAX``.  A squeeze held
#: by friction needs normal forces of ``1 / mu`` times the load: three unit cubes in a row with the ends fixed are
#: RBE-stable for every ``mu > 0``, and HiGHS finds it down to ``mu = 1e-6`` (forces 5e5 times the weight) but calls
#: it infeasible at ``1e-9``, where the forces' differences fall below double precision at its ``1e-7``
#: tolerance.  Above ``MU_MAX`` a friction row's ``mu`` reaches HiGHS' largest matrix value (1e15: "Model
#: error"); the rows are scaled to ``(-1, cos a / mu, sin a / mu)`` for ``mu > 1``, so up to ``MU_MAX`` friction is
#: represented, and beyond about ``1e9`` it is unbounded to the solvers' precision.
MU_MIN = 1e-6
MU_MAX = 1e15
#: Most iterations of one HiGHS LP of RBE (``maxiter``, simplex or interior point), so that a stalled solve ends
#: the same way on every machine: the LP goes to the next solver, and if none decides the answer is "inconclusive
#: (solver: ...)".  The largest RBE LP decided in the tests (the armadillo's 31,000 unknowns) takes about 9,000
#: simplex iterations.
RBE_ITERATIONS = 50_000
#: ``parameters["contacts"]["model"]`` of a system whose contact search ran out of time: it has no contacts, and
#: every solve of it raises TimeLimitReached ("the contacts") instead of answering "no contacts carry the load".
CONTACTS_OUT_OF_TIME = "not found: time limit reached in the contacts"


class StabilityError(InterlockError):
    """Input that the stability analysis cannot work with."""


@dataclass(frozen=True, eq=False)
class StabilityResult:
    """The outcome of :func:`rbe`.

    Attributes
    ----------
    stable : bool or None
        An equilibrium with compressive, friction-admissible contact forces exists (Eqs. (1), (2), (5)); ``None``
        when no solver decided (a solver's error, an iteration or the time limit): "inconclusive", never a guess.
    forces : ndarray (s, 3)
        Per contact vertex ``(f_n, f_u, f_v)`` in the contact's frame ``(normal, basis[0], basis[1])``,
        acting on block ``j`` (block ``i`` receives the opposite); NaN when unstable.
    vertex_contact : ndarray of int (s,)
        The contact (index into ``contacts``) of each row of ``forces``.
    points : ndarray (s, 3)
        The contact vertices where the forces act.
    resultants : ndarray (c, 3)
        Per contact, the sum of its vertex forces in world coordinates (on block ``j``).
    centres_of_pressure : ndarray (c, 3)
        Per contact, ``sum f_n p / sum f_n`` (NaN where ``sum f_n`` is 0).
    friction_utilisation : float
        ``max |f_t| / (mu f_n)`` over the vertices whose ``f_n`` is at least :data:`FRICTION_RTOL`
        times the largest ``f_n``: the largest use of the *round* Coulomb cone at one vertex (0 when no
        counted vertex carries friction, inf if friction is needed with ``mu = 0``; NaN when unstable).
        It is at most 1 with ``cone="inner"`` (the inscribed pyramid) and at most
        ``1 / cos(pi / sides)`` (1.0824 for eight sides) with ``cone="paper"``, whose corners lie
        outside the round cone by that factor; beyond these bounds only by the solver's tolerance
        (about 1e-5). Not a safety factor: the forces minimise ``sum f_n`` and sit on the pyramid's
        faces wherever friction helps.
    status : int
        0 solved, 2 infeasible (no equilibrium); otherwise undecided (the last solver's status, as
        ``scipy.optimize.linprog`` numbers them).
    message : str
        The deciding solver's words; for an undecided answer ``"solver: ..."`` (what each solver said) or
        ``"time limit reached in <stage>"``.
    contacts : tuple of Contact
    parameters : dict
        ``mu``, ``cone``, ``sides``, ``density``, ``gravity``, ``frame``, the units (:func:`force_units`:
        ``unit``, ``density_unit``, ``force_unit``: forces are density x volume, the volume in the model's unit
        cubed), and ``contacts``: how the
        contacts were found (:func:`~interlock.verify.statics.interfaces.statics_contacts`; by default
        the interface rule of :func:`~interlock.verify.statics.interfaces.interfaces` and its tolerances).
    timings : dict
        Seconds spent on ``contacts``, ``build`` and ``solve``.
    """

    stable: bool | None
    forces: np.ndarray
    vertex_contact: np.ndarray
    points: np.ndarray
    resultants: np.ndarray
    centres_of_pressure: np.ndarray
    friction_utilisation: float
    status: int
    message: str
    contacts: tuple = field(repr=False)
    parameters: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    def __bool__(self):
        raise TypeError("the truth value of a StabilityResult is ambiguous (it may be inconclusive): use "
                        "result.stable, which is True, False or None (inconclusive)")

    def __str__(self) -> str:
        verdict = {True: "stable", False: "unstable"}.get(self.stable, f"inconclusive ({self.message})")
        p = self.parameters
        extra = f", friction utilisation {self.friction_utilisation:.3g}" if self.stable is True else ""
        units = f", forces in {p['force_unit']}" if self.stable is True and "force_unit" in p else ""
        return (f"RBE {verdict} (mu {p.get('mu')}, {p.get('cone')} cone with {p.get('sides')} sides): "
                f"{len(self.contacts)} contacts{contact_words(p)}, {len(self.forces)} vertex forces{extra}{units}; "
                f"{sum(self.timings.values()):.3g} s")

    def to_dict(self) -> dict:
        """JSON-serialisable summary (forces and resultants as lists)."""
        return {"stable": self.stable, "status": self.status, "message": self.message,
                "friction_utilisation": json_float(self.friction_utilisation),
                "forces": np.nan_to_num(self.forces, nan=0.0).tolist(),
                "vertex_contact": self.vertex_contact.tolist(),
                "resultants": np.nan_to_num(self.resultants, nan=0.0).tolist(),
                "contacts": [(c.i, c.j) for c in self.contacts],
                "parameters": dict(self.parameters), "timings": dict(self.timings)}


@dataclass(frozen=True, eq=False)
class EquilibriumSystem:
    """The LP of :func:`rbe` without its right-hand side (which gravity alone sets)."""

    a_eq: sp.csr_matrix
    a_ub: sp.csr_matrix
    cone_rows: np.ndarray  # friction_block(mu, cone, sides): one vertex's rows of a_ub
    cost: np.ndarray
    bounds: np.ndarray
    weights: np.ndarray
    arms: np.ndarray
    free: np.ndarray
    frames: np.ndarray
    points: np.ndarray
    vertex_contact: np.ndarray
    contacts: tuple
    parameters: dict
    timings: dict

    @classmethod
    def build(cls, assembly, mu, density, frame, cone, sides, contacts, budget=None) -> EquilibriumSystem:
        """The system of ``assembly``'s equilibrium.  With a ``budget``, the contact search runs under it; when
        it runs out there, the system has no contacts and :meth:`solve` under the same budget answers
        "inconclusive: time limit reached in the contacts" (never "unstable")."""
        if not isinstance(assembly, Assembly):
            raise StabilityError(f"expected an interlock Assembly, got {type(assembly).__name__}")
        mu, density = friction_coefficient(mu), block_densities(density, len(assembly))
        if cone not in CONES:
            raise StabilityError(f"cone must be one of {CONES}, got {cone!r}")
        if isinstance(sides, bool) or not isinstance(sides, (int, np.integer)) or sides < (4 if cone == "paper" else 3):
            raise StabilityError(f"sides must be an integer >= {4 if cone == 'paper' else 3}, got {sides!r}")
        fixed = assembly.block_indices(assembly.frame if frame is None else frame, "frame")
        if not fixed:
            raise StabilityError("the assembly has no frame: give the fixed blocks (supports) with frame=[...] "
                                 "or Assembly.with_frame; without supports nothing can carry the weight")
        started = time.perf_counter()
        try:
            found, contact_model = statics_contacts(assembly, contacts, budget)
        except TimeLimitReached:
            found, contact_model = (), {"model": CONTACTS_OUT_OF_TIME}
        found_at = time.perf_counter()
        free = np.setdiff1d(np.arange(len(assembly)), fixed)
        column_of = np.full(len(assembly), -1)
        column_of[free] = np.arange(len(free))
        used = tuple(c for c in found if column_of[c.i] >= 0 or column_of[c.j] >= 0)
        counts = np.array([len(c.vertices) for c in used], dtype=int)
        vertex_contact = np.repeat(np.arange(len(used)), counts)
        points = np.vstack([c.vertices for c in used]) if used else np.empty((0, 3))
        frames = np.array([[c.normal, c.basis[0], c.basis[1]] for c in used]).reshape(-1, 3, 3)[vertex_contact]
        length = assembly.scale
        a_eq = equilibrium_matrix(assembly, used, vertex_contact, points, frames, column_of, length)
        cone_rows = friction_block(mu, cone, sides)
        a_ub = friction_matrix(len(points), cone_rows)
        weights = density[free] * assembly.volumes[free]
        arms = np.zeros((len(free), 3))  # weight acts at the centroid: no moment about it
        bounds = np.tile([[0.0, np.inf], [-np.inf, np.inf], [-np.inf, np.inf]], (len(points), 1))
        cost = np.tile([1.0, 0.0, 0.0], len(points))
        built = time.perf_counter()
        uniform = bool(np.all(density == density[0])) if len(density) else True
        parameters = {"mu": float(mu), "cone": cone, "sides": int(sides),
                      "density": float(density[0]) if uniform and len(density) else density.tolist(),
                      **force_units(assembly.unit), "frame": list(fixed), "contacts": contact_model}
        timings = {"contacts": found_at - started, "build": built - found_at}
        return cls(a_eq, a_ub, cone_rows, cost, bounds, weights, arms, free, frames, points, vertex_contact, used,
                   parameters, timings)

    def solve_lp(self, gravity: np.ndarray, least_force: bool, budget: Budget | None = None):
        """``(x, status, message, total)`` of ``A_eq f = -p / W``, ``A_fr f <= 0``, ``f_n >= 0`` (``W``: total weight).

        Clarabel (interior point) decides first: on a 69-block p4 patch HiGHS' simplex took 13-60 s to find the
        LP infeasible, depending only on the order of the vertices (the same patch read from COMPAS JSON or OBJ),
        Clarabel 0.07 s.  With ``least_force`` and a feasible LP of at most :data:`LARGE_LP` unknowns, HiGHS'
        simplex then finds the vertex of least ``sum f_n`` (forces on the pyramid's faces; Clarabel's forces are
        kept if it does not).  If Clarabel does not decide, HiGHS' interior point and simplex are asked in turn
        (each within :data:`RBE_ITERATIONS`).  ``status`` is 0 (solved), 2 (infeasible) or, when no solver
        decided, the last one's status with ``message`` ``"solver: ..."`` saying what each said.  ``budget``
        bounds every solve (:class:`~interlock.verify.budget.TimeLimitReached` when it runs out).
        """
        if self.parameters["contacts"].get("model") == CONTACTS_OUT_OF_TIME:  # no contacts, not "none carry it"
            raise TimeLimitReached("the contacts")
        budget = budget or Budget()
        load = np.outer(self.weights, gravity)
        total = float(np.abs(load).sum()) or 1.0
        b_eq = -np.hstack([load, self.arms]).ravel() / total
        if not self.a_eq.shape[1]:
            solved = bool(np.allclose(b_eq, 0.0))
            return None, (0 if solved else 2), ("no contact forces" if solved else "no contacts carry the load"), total
        said = []
        decided = self._clarabel(b_eq, least_force, budget)
        if isinstance(decided, str):
            said.append(decided)
        elif decided[1] == 2 or not least_force or self.a_eq.shape[1] > LARGE_LP:
            return (*decided, total)
        else:  # decided: the least-force vertex if the simplex finds it in time, else Clarabel's forces
            try:
                outcome = self._highs(self.cost, b_eq, "highs", budget)
            except TimeLimitReached:
                return (*decided, total)
            return (outcome.x, 0, str(outcome.message), total) if outcome.status == 0 else (*decided, total)
        status = 4
        for cost, method in ((self.cost, "highs-ipm"), (np.zeros_like(self.cost), "highs")):
            outcome = self._highs(cost, b_eq, method, budget)
            if outcome.status in (0, 2):
                return outcome.x, int(outcome.status), str(outcome.message), total
            status = int(outcome.status)
            said.append(f"HiGHS {'interior point' if method == 'highs-ipm' else 'simplex'}: {outcome.message}")
        return None, status, "solver: " + "; ".join(said), total

    def _highs(self, cost, b_eq, method: str, budget: Budget):
        return highs_lp(cost, budget, "RBE", A_ub=self.a_ub, b_ub=np.zeros(self.a_ub.shape[0]), A_eq=self.a_eq,
                        b_eq=b_eq, bounds=self.bounds, method=method, options={"maxiter": RBE_ITERATIONS})

    def _clarabel(self, b_eq, least_force: bool, budget: Budget):
        """The LP by Clarabel's interior point (the armadillo's 31,000 unknowns in 0.7 s against 40 s for HiGHS'
        simplex); ``(x, status, message)``, or what Clarabel said when it does not decide."""
        n = self.a_eq.shape[1]
        normal = np.flatnonzero(self.bounds[:, 0] == 0.0)
        nonnegative = sp.csr_matrix((-np.ones(len(normal)), (np.arange(len(normal)), normal)), shape=(len(normal), n))
        constraints = sp.vstack([self.a_eq, self.a_ub, nonnegative], format="csc")
        right = np.concatenate([b_eq, np.zeros(self.a_ub.shape[0] + len(normal))])
        cost = self.cost if least_force else np.zeros(n)
        solution = clarabel_lp(cost, constraints, right, equalities=self.a_eq.shape[0], budget=budget, stage="RBE")
        status = str(solution.status)
        if status == "Solved":
            return np.asarray(solution.x), 0, "Clarabel: solved"
        if status == "PrimalInfeasible":
            return None, 2, "Clarabel: infeasible (no equilibrium)"
        return f"Clarabel: {status}"

    def feasible(self, gravity: np.ndarray, budget: Budget | None = None) -> tuple[bool | None, str]:
        """``(verdict, message)``: whether an equilibrium exists under ``gravity`` (``None``: undecided, the
        message says why; the time limit raises :class:`~interlock.verify.budget.TimeLimitReached`)."""
        _, status, message, _ = self.solve_lp(gravity, least_force=False, budget=budget)
        return {0: True, 2: False}.get(status), message

    def solve(self, gravity: np.ndarray, budget: Budget | None = None) -> StabilityResult:
        started = time.perf_counter()
        try:
            if budget is not None:
                budget.check("the contacts")
            x, status, message, total = self.solve_lp(gravity, least_force=True, budget=budget)
        except TimeLimitReached as out:
            x, status, message, total = None, 1, str(out), 1.0
        timings = {**self.timings, "solve": time.perf_counter() - started}
        parameters = {**self.parameters, "gravity": gravity.tolist()}
        stable = {0: True, 2: False}.get(status)
        count = len(self.points)
        if stable is True and x is not None:
            forces = x.reshape(-1, 3) * total
        else:
            forces = np.full((count, 3), 0.0 if stable is True else np.nan)
        world = np.einsum("sk,skd->sd", forces, self.frames)
        resultants = np.zeros((len(self.contacts), 3))
        np.add.at(resultants, self.vertex_contact, world)
        normal_sum = np.zeros(len(self.contacts))
        np.add.at(normal_sum, self.vertex_contact, forces[:, 0])
        moments = np.zeros((len(self.contacts), 3))
        np.add.at(moments, self.vertex_contact, forces[:, :1] * self.points)
        with np.errstate(invalid="ignore", divide="ignore"):
            centres = np.where(normal_sum[:, None] > 0, moments / normal_sum[:, None], np.nan)
        utilisation = friction_utilisation(forces, self.parameters["mu"]) if stable is True else math.nan
        return StabilityResult(stable, forces, self.vertex_contact, self.points, resultants, centres, utilisation,
                               status, message, self.contacts, parameters, timings)


def clarabel_lp(cost, constraints, right, equalities: int = 0, tolerance: float | None = None,
                budget: Budget | None = None, stage: str = "an LP"):
    """Clarabel's interior point on ``min cost . x`` subject to ``constraints x = right`` on the first
    ``equalities`` rows and ``<= right`` on the rest; Clarabel's solution (``status``, ``x``, ``z``).
    ``tolerance``, ``budget`` and ``stage``: as for :func:`clarabel_solve`.

    The large LPs of statics go here (RBE above :data:`LARGE_LP` unknowns, CRA on large models): the
    armadillo's 31,000 unknowns in 0.7 s against 40 s for HiGHS' simplex.

    >>> solution = clarabel_lp([1.0, 1.0], sp.csc_matrix([[1.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]), [2.0, 0.0, 0.0], 1)
    >>> str(solution.status), [round(v, 6) for v in solution.x]
    ('Solved', [1.0, 1.0])
    """
    import clarabel

    cones = ([clarabel.ZeroConeT(equalities)] if equalities else []) + \
        [clarabel.NonnegativeConeT(constraints.shape[0] - equalities)]
    return clarabel_solve(None, cost, constraints, right, cones, tolerance, budget, stage)


def clarabel_solve(quadratic, cost, constraints, right, cones, tolerance: float | None = None,
                   budget: Budget | None = None, stage: str = "a cone program"):
    """Clarabel on ``min x.Q x / 2 + cost . x`` subject to ``right - constraints x`` in ``cones`` (Clarabel's
    cone objects), quietly and on :data:`~interlock.verify.first_order.SOLVER_THREADS` threads; ``quadratic`` ``Q``
    may be ``None`` (an LP).  The one place the statics set Clarabel up (:func:`clarabel_lp`, and the cone
    program of :func:`~interlock.verify.statics.cra_coulomb.tresca`).  ``tolerance``, if given, replaces
    Clarabel's gap and feasibility tolerances (1e-8 by default; solutions that must pass an exact check use
    :data:`~interlock.verify.statics.cra_coulomb.CHECKED_TOLERANCE`).  ``budget``: Clarabel's ``time_limit`` is
    the time it has left; running out raises :class:`~interlock.verify.budget.TimeLimitReached` naming
    ``stage``.  Clarabel's iteration limit (200) keeps the solve bounded on every machine."""
    import clarabel

    n = constraints.shape[1]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_threads = SOLVER_THREADS
    if tolerance is not None:
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tolerance
    limit = None if budget is None else budget.solver_limit()
    if limit is not None:
        budget.check(stage)
        settings.time_limit = limit
    quadratic = sp.csc_matrix((n, n)) if quadratic is None else sp.csc_matrix(quadratic)
    solution = clarabel.DefaultSolver(quadratic, np.asarray(cost, dtype=float), sp.csc_matrix(constraints),
                                      np.asarray(right, dtype=float), cones, settings).solve()
    if str(solution.status) == "MaxTime":
        raise TimeLimitReached(stage)
    return solution


def highs_lp(cost, budget: Budget | None, stage: str, **problem):
    """:func:`scipy.optimize.linprog` (HiGHS) on ``problem`` with the time ``budget`` has left as its
    ``time_limit``; running out raises :class:`~interlock.verify.budget.TimeLimitReached` naming ``stage``.
    ``problem``: linprog's keywords (``options`` are kept; ``method`` defaults to ``"highs"``).

    >>> highs_lp([1.0], Budget.start(60), "an LP", bounds=[(2.0, None)]).x.tolist()
    [2.0]
    """
    options = dict(problem.pop("options", None) or {})
    limit = None if budget is None else budget.solver_limit()
    if limit is not None:
        budget.check(stage)
        options["time_limit"] = limit
    problem.setdefault("method", "highs")
    outcome = linprog(cost, options=options, **problem)
    if outcome.status == 1 and "time limit" in str(outcome.message).lower():
        raise TimeLimitReached(stage)
    return outcome


def friction_coefficient(mu) -> float:
    """``mu`` as a float if the solvers represent it (0, or :data:`MU_MIN` to :data:`MU_MAX`), else
    :class:`StabilityError` saying why and what is accepted."""
    mu = nonnegative("mu", mu)
    if mu and not MU_MIN <= mu <= MU_MAX:
        why = (f"friction below {MU_MIN:g} needs forces above {1 / MU_MIN:g} times the weight, beyond double "
               f"precision at the solvers' tolerance" if mu < MU_MIN else
               f"above {MU_MAX:g} friction is unbounded to double precision and the solvers' matrices overflow")
        raise StabilityError(f"mu = {mu:g} is outside the range the solvers represent ({why}): give mu = 0 (no "
                             f"friction) or {MU_MIN:g} <= mu <= {MU_MAX:g}")
    return mu


def equilibrium_matrix(assembly, used, vertex_contact, points, frames, column_of, length) -> sp.csr_matrix:
    """``A_eq`` (Eq. (2)): rows ``6 k .. 6 k + 5`` = force and moment (over ``length``) on free block ``k``.

    Column ``3 v + a`` is component ``a`` (n, u, v) of vertex ``v``; on block
    ``j`` it contributes ``(e_a, r_j x e_a)``, on block ``i`` the negative with ``r_i``.
    """
    count = len(points)
    if not count:
        return sp.csr_matrix((6 * int((column_of >= 0).sum()), 0))
    i = np.array([c.i for c in used])[vertex_contact]
    j = np.array([c.j for c in used])[vertex_contact]
    rows, cols, data = [], [], []
    for blocks, sign in ((j, 1.0), (i, -1.0)):
        on = column_of[blocks] >= 0
        arm = (points[on] - assembly.centroids[blocks[on]]) / length
        axes = frames[on]  # (m, 3 components, 3 coordinates)
        values = sign * np.concatenate([axes, np.cross(arm[:, None, :], axes)], axis=2)  # (m, 3, 6)
        vertex = np.flatnonzero(on)
        rows.append((6 * column_of[blocks[on]][:, None, None] + np.arange(6)[None, None, :]).repeat(3, axis=1))
        cols.append(np.broadcast_to((3 * vertex[:, None] + np.arange(3))[:, :, None], values.shape))
        data.append(values)
    matrix = sp.csr_matrix((np.concatenate([d.ravel() for d in data]),
                            (np.concatenate([r.ravel() for r in rows]), np.concatenate([c.ravel() for c in cols]))),
                           shape=(6 * int((column_of >= 0).sum()), 3 * count))
    matrix.eliminate_zeros()
    return matrix


def friction_block(mu: float, cone: str, sides: int) -> np.ndarray:
    """The rows ``(-m, cos a_k, sin a_k)`` of one vertex's linearised cone (Eq. (5), App. B), ``(sides, 3)``.

    ``block @ (f_n, f_u, f_v) <= 0`` with ``a_k = 2 pi k / sides``, ``m = mu`` for the
    circumscribed ("paper") pyramid and ``m = mu cos(pi / sides)`` for the inscribed ("inner") one.
    """
    bound = mu * (math.cos(math.pi / sides) if cone == "inner" else 1.0)
    angles = 2.0 * math.pi * np.arange(sides) / sides
    block = np.column_stack([np.full(sides, -bound), np.cos(angles), np.sin(angles)])
    block[np.abs(block) < 1e-15] = 0.0
    return block


def friction_matrix(count: int, block: np.ndarray) -> sp.csr_matrix:
    """``A_fr`` (Eq. (5), App. B): ``block`` (:func:`friction_block`) once per vertex, each row divided by its
    largest coefficient (``mu`` when ``mu > 1``), so that a large ``mu`` stays within the solvers' range
    (:data:`MU_MAX`)."""
    scaled = block / np.maximum(np.abs(block[:, :1]), 1.0)
    return sp.kron(sp.eye(count, format="csr"), sp.csr_matrix(scaled), format="csr")


def friction_utilisation(forces: np.ndarray, mu: float, rtol: float = FRICTION_RTOL) -> float:
    """``max |f_t| / (mu f_n)`` over vertices with ``f_n >= rtol * max f_n`` and friction above ``1e-9`` of the
    largest force (see :attr:`StabilityResult.friction_utilisation`); 0 if there are none."""
    tangential = np.hypot(forces[:, 1], forces[:, 2])
    normal = forces[:, 0]
    scale = max(float(np.abs(forces).max(initial=0.0)), 1e-300)
    largest = float(normal.max(initial=0.0))
    loaded = (tangential > 1e-9 * scale) & ((normal >= rtol * largest) | (largest <= 0.0))
    if not loaded.any():
        return 0.0
    if mu == 0.0:
        return math.inf
    with np.errstate(divide="ignore"):
        return float(np.max(tangential[loaded] / (mu * normal[loaded])))


def contact_words(parameters: dict) -> str:
    """`` (interfaces: faces within ...)`` for a result's one-line summary: what the contacts assumed."""
    model = parameters.get("contacts") or {}
    if model.get("model") == "interfaces":
        return (f" (interfaces: faces within {model['gap_thickness']:g} of the thinner block's thickness, "
                f"tilted <= {model['angle']:g} rad)")
    return {"exact": " (exact: touching faces)", "given": " (given)"}.get(model.get("model"), "")


def gravity_vector(gravity) -> np.ndarray:
    try:
        g = np.asarray(gravity, dtype=float)
    except (TypeError, ValueError):
        raise StabilityError(f"gravity must be a 3-vector of numbers, got {gravity!r}") from None
    if g.shape != (3,) or not np.all(np.isfinite(g)):
        raise StabilityError(f"gravity must be a finite 3-vector, got {g.tolist()}")
    if not np.linalg.norm(g) > 0:
        raise StabilityError("gravity is zero: give its direction and magnitude, e.g. (0, 0, -1)")
    return g


def nonnegative(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or value < 0:
        raise StabilityError(f"{name} must be a finite number >= 0, got {value!r}")
    return float(value)


def positive(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) or value <= 0:
        raise StabilityError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def force_units(unit: str | None) -> dict[str, str | None]:
    """How the forces of a model in ``unit`` are measured: ``density`` is a weight per cubic ``unit`` (a block
    weighs density x volume, the volume in ``unit`` cubed) and every force is in the density's weight unit
    times ``unit`` cubed: with density 24 kN/m^3 and a model in metres, kN.

    >>> force_units("m")["force_unit"], force_units("m")["density_unit"]
    ('density x m^3', 'weight per cubic m (with a density in kN/m^3, forces are in kN)')
    >>> force_units(None)["density_unit"]
    'weight per cubic model unit (the model states no unit)'
    """
    if unit is None:
        return {"unit": None, "density_unit": "weight per cubic model unit (the model states no unit)",
                "force_unit": "density x model unit^3"}
    example = "kN" if unit == "m" else "N"
    return {"unit": unit, "force_unit": f"density x {unit}^3",
            "density_unit": f"weight per cubic {unit} (with a density in {example}/{unit}^3, forces are in {example})"}


#: Densities above this are refused: the weights (density x volume, squared in the solvers' scaling) would overflow
#: and an overflow must never read as physics (a density of 1e308 answered "stable" where 1 answers "unstable").
MAX_DENSITY = 1e30


def block_densities(density, count: int) -> np.ndarray:
    """``density`` as one positive finite value per block, at most :data:`MAX_DENSITY`; StabilityError otherwise."""
    if np.ndim(density) == 0:
        value = positive("density", density)
        if value > MAX_DENSITY:
            raise StabilityError(f"density must be at most {MAX_DENSITY:g} (choose the unit of mass so that it is), "
                                 f"got {value:g}")
        return np.full(count, value)
    try:
        values = np.asarray(density, dtype=float)
    except (TypeError, ValueError):
        raise StabilityError(f"density must be a number or one number per block, got {density!r}") from None
    if values.shape != (count,) or not np.all(np.isfinite(values)) or not np.all(values > 0) \
            or not np.all(values <= MAX_DENSITY):
        raise StabilityError(f"density must be > 0 and at most {MAX_DENSITY:g}, one value or {count} (one per "
                             f"block); got shape {values.shape}, from {values.min(initial=np.inf):g} to "
                             f"{values.max(initial=-np.inf):g}")
    return values
