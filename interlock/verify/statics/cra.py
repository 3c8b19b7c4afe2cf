"""Coupled rigid-block analysis (CRA paper, Sec. 3.1, problem (11)), solved globally as a MILP.

RBE (:func:`interlock.verify.statics.rbe`) asks only for forces in
equilibrium.  CRA also asks for a virtual motion ``dq`` of the free blocks
that *realises* them:

- normal force only where the motion closes the contact by the overlap
  ``eps``, Eq. (10): ``f_n (dd_n + eps) = 0``, ``dd_n + eps >= 0``;
- friction opposite to the virtual slide, Eq. (9): ``f_t = -alpha dd_t``,
  ``alpha >= 0`` (no slide, no friction);
- small motions, ``|dd| <= eta`` per component;

where ``dd = A_eq^T dq`` (Eq. (8)) are the relative displacements at the
contact vertices.  The paper solves (11) locally with IPOPT; here it is
decided globally:

0. **Quick answers.**  No RBE equilibrium means "unstable" (CRA only removes
   solutions).  A motion that realises an equilibrium exactly (an LP) means
   "stable"; tried are the motion of a nearby load (:func:`decider`), the
   allowed motion on which the load does the most work (an LP: a block
   pushed into its seat; it settles 198 of the 235 stable wedge cases of
   Table 2's scans), one realising the equilibrium with the least friction
   (friction needs a slide, so the fewer vertices carry it the freer the
   motion: the 36-voussoir arch) and one realising RBE's least-force equilibrium.
1. **MILP relaxation.**  A binary per vertex switches Eq. (10); binaries over
   ``sectors`` angular sectors of the contact plane put the slide ``dd_t``
   and the reversed friction ``-f_t`` in the same sector, with a slide of at
   least ``min_slide`` along the sector's bisector where there is friction;
   the big Ms are per vertex (the largest RBE ``f_n``, the reach of the motion).
   Virtual work bounds the forces: for a solution of (11), ``f . dd = b . q``
   with ``f_n dd_n = -eps f_n`` and ``f_t . dd_t = -alpha |dd_t|^2``, so
   ``sum f_n <= -b . q / eps``, at most the work the load can do on any
   allowed motion (an LP); this row and the bound are in the MILP, beside face cuts
   (closed vertices span a face of a convex contact polygon).
   Every solution of (11) whose friction vertices slide at least ``min_slide``
   (and, if ``force_bound`` is below the virtual-work bound, whose forces stay
   below it) is a solution of the MILP, so an infeasible MILP proves "unstable"
   (HiGHS through :func:`scipy.optimize.milp`).
2. **Exact check.**  A feasible MILP gives a motion.  With the motion fixed,
   (11) is linear in ``(f_n, alpha)``: an LP over exactly the contacts it
   closes and the slides it makes.  A feasible LP is a solution of (11):
   "stable", with the forces and the motion.  If it fails (the MILP's
   friction was only in the right sector), the MILP's forces fix the
   active set and the friction directions and an LP looks for a motion that
   realises them exactly, and SLSQP solves (11) locally from the MILP's point; then the
   sectors are refined (``4 -> 8 -> 16``).
   If none of this gives a solution, or HiGHS does not decide within ``milp_nodes`` nodes, local solvers
   have the last word (above :data:`LOCAL_FIRST_BINARIES` binaries they go before the MILP): IPOPT
   on the whole of (11), as in the paper, if CasADi is installed (:mod:`interlock.verify.statics.cra_ipopt`),
   then SLSQP from where the assembly settles (the motion closing the most vertices that, keeping
   them closed, does the most work).  If the exact LP accepts a motion they find, the answer is
   "stable", otherwise "inconclusive" (a local solver's "infeasible" proves nothing).

Only the ratio ``eta / eps`` matters (the constraints are homogeneous in
``(dq, eps, eta)``); internally lengths of the motion are in units of ``eps``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from functools import cache

import numpy as np
import scipy.sparse as sp

from interlock.verify.statics import cra_large, cra_local, cra_milp
from interlock.verify.statics.cra_compas import upstream_solution
from interlock.verify.statics.cra_local import ACTIVE_TOL, SLIDE_TOL
from interlock.verify.statics.cra_milp import BOUND_MARGIN
from interlock.verify.statics.equilibrium import (DEFAULT_EPS, DEFAULT_ETA, DEFAULT_SIDES, Budget, EquilibriumSystem,
                                                  StabilityError, TimeLimitReached, contact_words, gravity_vector,
                                                  highs_lp, json_float, positive)

__all__ = ["CRAResult", "CRAProblem", "MotionLP", "cra", "decider", "DEFAULT_EPS", "DEFAULT_ETA", "DEFAULT_SECTORS",
           "DEFAULT_FORCE_BOUND", "DEFAULT_MIN_SLIDE", "REFINED_SECTORS", "SLIDE_TOL", "DEFAULT_TIME_LIMIT",
           "MILP_NODES"]

#: Angular sectors of the contact plane in the first MILP, and the refinements tried when its motion
#: cannot be made exact.
DEFAULT_SECTORS = 4
REFINED_SECTORS = (8, 16)
#: Largest normal force at one vertex, in units of the total weight of the free blocks.
DEFAULT_FORCE_BOUND = 1e3
#: Smallest virtual slide (along the sector bisector) of a vertex carrying friction, as a fraction of ``eps``.
DEFAULT_MIN_SLIDE = 1e-3
#: Seconds for the whole call: none by default.  The route CRA takes is chosen by iteration and size limits
#: (:data:`MILP_NODES`, the fixed point's rounds, IPOPT's and SLSQP's iterations), never by the clock, so a verdict
#: does not depend on the machine's speed; a time limit only turns it into "inconclusive: time limit reached in
#: <stage>".
DEFAULT_TIME_LIMIT = None
#: Branch-and-bound nodes HiGHS may explore in one MILP (``node_limit``) before the MILP counts as undecided and
#: the local solvers take over.  Model H's looser confirming MILP (40 binaries) needs between 2,000 and 20,000
#: (1.7 s for 2,000 here); the 8-voussoir arch tilted by 4 degrees (324 binaries), which 60 s did not decide,
#: explores them all (tests pass ``milp_nodes=1`` to reach the local solvers).
MILP_NODES = 50_000
#: Above this many binaries (vertices times ``1 + sectors``) the local solvers run before the MILP, which
#: rarely decides so large a model in time (the shelves of Fig. 7 and 12: 300-460; the wedges: 40-80).
LOCAL_FIRST_BINARIES = 200
#: Motions of earlier stable loads that :func:`decider` tries first.
WARM_STARTS = 3

STATUSES = ("stable", "unstable", "inconclusive")


@dataclass(frozen=True, eq=False)
class MotionLP:
    """Problem (11) at a fixed motion: ``min cost . x``, ``a_eq x = b_eq``, ``a_ub x <= 0``, ``x >= 0``, with
    ``x = (f_n at the closed vertices, alpha at the sliding ones)``; the friction of a sliding vertex is
    ``-alpha`` times its slide."""

    a_eq: sp.csr_matrix
    a_ub: sp.csr_matrix
    cost: np.ndarray
    closed: np.ndarray
    sliding: np.ndarray
    slide: np.ndarray

    def holds(self, x, b_eq) -> bool:
        """Whether ``x >= 0`` solves this LP to :data:`~interlock.verify.statics.cra_large.CHECK_RTOL` times the
        load: equilibrium (Eq. (7b)) and the friction pyramid (Eqs. (4)-(5)), residual by residual.  The exact
        check every "stable" of the solver's routes passes, whichever solver found ``x``."""
        scale = max(float(np.abs(b_eq).max()), 1e-300)
        return bool(np.abs(self.a_eq @ x - b_eq).max() <= cra_large.CHECK_RTOL * scale
                    and (self.a_ub @ x).max(initial=0.0) <= cra_large.CHECK_RTOL * scale)

    def forces(self, x) -> np.ndarray:
        """Per-vertex forces ``(f_n, f_u, f_v)`` from a solution ``x`` (clipped at 0: solvers return -1e-11)."""
        x = np.maximum(np.asarray(x, dtype=float), 0.0)
        n_closed = int(self.closed.sum())
        forces = np.zeros((len(self.closed), 3))
        forces[self.closed, 0] = x[:n_closed]
        forces[self.sliding, 1:] = -x[n_closed:, None] * self.slide[self.sliding]
        return forces


@dataclass(frozen=True, eq=False)
class CRAResult:
    """The outcome of :func:`cra`.

    Attributes
    ----------
    status : {"stable", "unstable", "inconclusive"}
        "stable": an exact solution of (11) was found (``forces`` and ``motion`` are one);
        "unstable": the MILP relaxation has no solution, so (11) has none within the bounds in
        ``parameters``; "inconclusive": the relaxation has one but no exact solution was found.
    stable : bool or None
        ``True``, ``False``, or ``None`` for inconclusive.
    forces : ndarray (s, 3)
        Per contact vertex ``(f_n, f_u, f_v)`` in the contact's frame, acting on block ``j`` (as in
        :class:`~interlock.verify.statics.StabilityResult`); NaN unless stable.
    motion : ndarray (f, 6)
        The realising virtual motion of each free block: ``(t, omega)`` (translation, rotation about the
        block's centroid) in world units, with loaded vertices overlapping by ``eps`` (absolute); NaN unless
        stable.
    free : ndarray of int (f,)
        The blocks that ``motion`` rows belong to.
    closed : ndarray of bool (s,)
        Vertices that the motion closes (``dd_n = -eps``), where normal force may act.
    sliding : ndarray (s, 2)
        The relative virtual slide ``dd_t`` in each contact's ``(u, v)`` basis, in units of ``eps``.
    points, vertex_contact, contacts
        As in :class:`~interlock.verify.statics.StabilityResult`.
    message : str
        What decided the verdict.
    parameters : dict
        ``mu``, ``cone``, ``sides``, ``eps`` and ``eta`` (relative and absolute), ``sectors`` tried,
        ``force_bound``, ``min_slide``, ``density``, ``gravity``, ``frame``.
    timings : dict
        Seconds for ``contacts``, ``build``, ``milp`` (all MILPs), ``lp`` (all exact checks and SLSQP) and,
        when it ran, ``ipopt``.
    """

    status: str
    forces: np.ndarray
    motion: np.ndarray
    free: np.ndarray
    closed: np.ndarray
    sliding: np.ndarray
    points: np.ndarray
    vertex_contact: np.ndarray
    message: str
    contacts: tuple = field(repr=False)
    parameters: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool | None:
        return {"stable": True, "unstable": False}.get(self.status)

    def __bool__(self):
        raise TypeError("the truth value of a CRAResult is ambiguous (it may be inconclusive): use "
                        "result.stable, which is True, False or None (inconclusive), or result.status")

    def __str__(self) -> str:
        p = self.parameters
        return (f"CRA {self.status} (mu {p.get('mu')}, {p.get('cone')} cone with {p.get('sides')} sides, "
                f"eta/eps {p.get('eta') / p.get('eps'):.3g}): {self.message}; "
                f"{len(self.contacts)} contacts{contact_words(p)}; {sum(self.timings.values()):.3g} s")

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {"status": self.status, "stable": self.stable, "message": self.message,
                "forces": np.nan_to_num(self.forces, nan=0.0).tolist(),
                "motion": np.nan_to_num(self.motion, nan=0.0).tolist(), "free": self.free.tolist(),
                "closed": self.closed.tolist(), "vertex_contact": self.vertex_contact.tolist(),
                "contacts": [(c.i, c.j) for c in self.contacts],
                "parameters": {k: (json_float(v) if isinstance(v, float) else v) for k, v in self.parameters.items()},
                "timings": dict(self.timings)}


def cra(assembly, mu: float, density: float = 1.0, gravity=(0.0, 0.0, -1.0), frame=None, cone: str = "paper",
        sides: int = DEFAULT_SIDES, eps: float = DEFAULT_EPS, eta: float = DEFAULT_ETA,
        sectors: int = DEFAULT_SECTORS, force_bound: float = DEFAULT_FORCE_BOUND,
        min_slide: float = DEFAULT_MIN_SLIDE, time_limit=DEFAULT_TIME_LIMIT, contacts=None,
        backend: str = "milp", progress=None, hold_out: bool = True, milp_nodes: int = MILP_NODES) -> CRAResult:
    """Coupled rigid-block analysis: is there an equilibrium that a virtual motion realises? (CRA paper, (11)).

    Forces ``f`` at the contact vertices and a virtual motion ``dq`` of the
    free blocks with relative vertex displacements ``dd = A_eq^T dq`` (Eq. (8)) must satisfy

    - equilibrium and the linearised friction cone, as in :func:`~interlock.verify.statics.rbe`
      (Eqs. (7b)-(7d)): ``A_eq f = -p``, ``A_fr f <= 0``, ``f_n >= 0``;
    - contact, Eq. (10): ``f_n (dd_n + eps) = 0`` with ``dd_n + eps >= 0``;
    - friction against the slide, Eq. (9): ``f_t = -alpha dd_t``, ``alpha >= 0``;
    - ``|dd| <= eta`` componentwise.

    The paper minimises ``|f_n|^2 + |alpha|^2`` locally; here the question
    "does (11) have a solution?" is decided globally by a MILP relaxation and
    an exact LP check at its motion (see the module docstring), and the forces
    reported minimise ``sum f_n`` for that motion.

    Parameters
    ----------
    assembly, mu, density, gravity, frame, cone, sides, contacts
        As for :func:`~interlock.verify.statics.rbe`.
    eps, eta : float
        Overlap and displacement bound as fractions of ``assembly.scale``; ``0 < eps < eta``.  Only
        ``eta / eps`` changes the verdict.
    sectors : int
        Angular sectors (``>= 3``) of the first MILP; :data:`REFINED_SECTORS` follow if needed.
    force_bound : float
        Largest vertex normal force in units of the free blocks' total weight.  The MILP's big M is
        the smaller of this and the virtual-work bound (the work the load can do on any allowed
        motion, which (11) implies), so with the default the bound rarely matters.
    min_slide : float
        Smallest slide of a friction-carrying vertex, as a fraction of ``eps``.
    time_limit : float, optional
        Seconds for the whole call, every stage included (contacts, RBE, the MILPs and their bounds, the
        Coulomb fixed point, IPOPT, SLSQP, the placements): IPOPT gets the time left as ``max_wall_time``,
        HiGHS and Clarabel as ``time_limit``, and loops check it between steps.  When it runs out the answer
        is "inconclusive: time limit reached in <stage>" (a little past the limit: a solver stops at its next
        check).  Default: no limit.  The clock never chooses the route (:data:`DEFAULT_TIME_LIMIT`).
    backend : {"milp", "compas_cra"}
        "milp" decides as above.  "compas_cra" (the optional upstream package, for assemblies too
        large for the MILP) asks its local solver for a motion and verifies it with the exact LP:
        "stable" if the LP accepts it, otherwise "inconclusive" (a local solver that finds nothing
        proves nothing).
    progress : callable, optional
        Called with a few words as each stage starts ("RBE", "the motion of most work",
        "Coulomb fixed point, round 3", "MILP with 4 sectors", ...); the CLI shows them.
    hold_out : bool
        On large models, when the Coulomb fixed point cannot hold a few blocks (they slide to the bound
        ``eta`` round after round), prove the rest without them and place them
        (:mod:`~interlock.verify.statics.cra_split`; needs IPOPT, ``pip install "interlock[nlp]"``).
        Each stage is bounded by its rounds and attempts: the armadillo vault is proved stable this way in
        about a minute (docs/statics.md, "CRA at scale").  ``False`` stops at the fixed point and names those blocks.
    milp_nodes : int
        Branch-and-bound nodes per MILP (:data:`MILP_NODES`); a MILP that explores them undecided hands over to
        the local solvers.  A deterministic limit: the same model takes the same route on any machine.

    Returns
    -------
    CRAResult

    Raises
    ------
    StabilityError
        Bad parameters (as for ``rbe``, and ``eps``, ``eta``, ``sectors``, ``force_bound``,
        ``min_slide``, ``milp_nodes``).
    InterlockError
        ``time_limit`` not a number of seconds > 0.

    Examples
    --------
    A block between two fixed walls: RBE holds it by prestress, CRA does not
    (model H, Sec. 2.2), unless the walls lean inwards (wedging).

    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify.statics import rbe
    >>> walls = [trimesh.creation.box(bounds=b) for b in ([[-1, 0, 0], [0, 1, 2]], [[1, 0, 0], [2, 1, 2]])]
    >>> middle = trimesh.creation.box(bounds=[[0, 0, 1], [1, 1, 2]])
    >>> h = Assembly.from_meshes(walls + [middle], frame=[0, 1])
    >>> rbe(h, mu=0.84).stable, cra(h, mu=0.84).status
    (True, 'unstable')
    """
    budget = Budget.start(time_limit)
    gravity, sectors = gravity_vector(gravity), _sector_count(sectors)
    if backend not in ("milp", "compas_cra"):
        raise StabilityError(f"backend must be 'milp' or 'compas_cra', got {backend!r}")
    problem = CRAProblem.build(assembly, mu, density, frame, cone, sides, eps, eta, force_bound, min_slide, contacts,
                               milp_nodes, budget)
    if backend == "compas_cra":
        return problem.check_upstream(assembly, gravity)
    return problem.solve(gravity, sectors, budget, progress=progress, hold_out=hold_out)


def decider(assembly, mu: float, sectors: int = DEFAULT_SECTORS, time_limit=DEFAULT_TIME_LIMIT,
            budget: Budget | None = None, hold_out: bool = False, **options):
    """``(gravity, budget=None) -> CRAResult``: :func:`cra` under many loads, with contacts and matrices built
    once (for :func:`~interlock.verify.statics.tilt_scan`); ``options`` as for :func:`cra`.  ``time_limit``:
    seconds for each load; ``budget``, if given, bounds the call as well (the scan's); given here, it also bounds
    the contact search.  ``hold_out``: as for :func:`cra`, but off by default (the scan's route so far;
    ``stability --no-hold-out --tilt-axis`` passed it to the problem's build, a TypeError).

    The motions of earlier stable loads are tried first (a tilt scan moves the load a little at a time).
    """
    Budget.start(time_limit)  # checked here, started per load
    problem = CRAProblem.build(assembly, mu, budget=budget, **options)
    sectors = _sector_count(sectors)
    known: list[np.ndarray] = []

    def solve(gravity, budget: Budget | None = None) -> CRAResult:
        own = Budget.start(time_limit)
        if budget is not None and budget.started + budget.limit < own.started + own.limit:
            own = budget
        result = problem.solve(gravity_vector(gravity), sectors, own, known, hold_out=hold_out)
        if result.stable:
            known.insert(0, problem.internal_motion(result.motion))
            del known[WARM_STARTS:]
        return result

    return solve


def json_limit(budget: Budget) -> float | None:
    """The budget's limit in seconds for a result's ``parameters`` (``None``: no limit)."""
    return None if budget.limit == float("inf") else budget.limit


def _silent(stage: str) -> None:
    """The default ``progress``: says nothing."""


def _node_count(nodes) -> int:
    if isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer)) or nodes < 1:
        raise StabilityError(f"milp_nodes must be an integer >= 1, got {nodes!r}")
    return int(nodes)


def _sector_count(sectors) -> int:
    if isinstance(sectors, bool) or not isinstance(sectors, (int, np.integer)) or sectors < 3:
        raise StabilityError(f"sectors must be an integer >= 3, got {sectors!r}")
    return int(sectors)


@dataclass(frozen=True, eq=False)
class CRAProblem:
    """The CRA problem of one assembly, without gravity (which only changes the equilibrium's right-hand side)."""

    system: EquilibriumSystem
    kinematic: sp.csr_matrix  # D = A_eq^T, rows (n, u, v) per vertex, motion in units of eps
    ratio: float  # eta / eps
    force_bound: float
    min_slide: float
    parameters: dict
    milp_nodes: int = MILP_NODES
    budget: Budget = field(default_factory=Budget)  # of the call being solved (:meth:`within`)
    memo: dict = field(default_factory=dict, repr=False)  # per-problem results shared by every call: reach, cuts

    @classmethod
    def build(cls, assembly, mu, density=1.0, frame=None, cone="paper", sides=DEFAULT_SIDES, eps=DEFAULT_EPS,
              eta=DEFAULT_ETA, force_bound=DEFAULT_FORCE_BOUND, min_slide=DEFAULT_MIN_SLIDE, contacts=None,
              milp_nodes=MILP_NODES, budget=None):
        """The problem; with a ``budget``, the contact search runs under it (when it runs out there, the system
        has no contacts and :meth:`solve` under the same budget answers "inconclusive: time limit reached in the
        contacts")."""
        system = EquilibriumSystem.build(assembly, mu, density, frame, cone, sides, contacts, budget)
        eps, eta = positive("eps", eps), positive("eta", eta)
        if not eps < eta:
            raise StabilityError(f"eps (overlap) must be smaller than eta (displacement bound), got {eps} >= {eta}")
        force_bound, min_slide = positive("force_bound", force_bound), positive("min_slide", min_slide)
        if not min_slide < eta / eps:
            raise StabilityError(f"min_slide must be below eta / eps = {eta / eps:.3g}, got {min_slide}")
        parameters = {**system.parameters, "eps": eps, "eta": eta, "eps_absolute": eps * assembly.scale,
                      "eta_absolute": eta * assembly.scale, "force_bound": force_bound, "min_slide": min_slide,
                      "length": assembly.scale, "milp_nodes": _node_count(milp_nodes)}
        return cls(system, system.a_eq.T.tocsr(), eta / eps, force_bound, min_slide, parameters, int(milp_nodes))

    def within(self, budget: Budget | None) -> CRAProblem:
        """This problem, its solvers bounded by ``budget`` (the matrices and :attr:`memo` shared)."""
        return replace(self, budget=budget or Budget())

    # --- the whole decision -----------------------------------------------------------------------------------

    def solve(self, gravity: np.ndarray, sectors: int, budget: Budget | None = None, known=(), progress=None,
              hold_out: bool = False) -> CRAResult:
        """:func:`cra` for this gravity within ``budget``: when it runs out, "inconclusive: time limit reached in
        <stage>"."""
        problem = self.within(budget)
        timings = {**self.system.timings, "milp": 0.0, "lp": 0.0}
        try:
            problem.budget.check("the contacts")
            return problem._solve(gravity, sectors, known, progress or _silent, hold_out, timings)
        except TimeLimitReached as out:
            parameters = {**self.parameters, "sectors": [], "gravity": gravity.tolist(),
                          "time_limit": json_limit(problem.budget)}
            return self._result("inconclusive", str(out), None, None, parameters, timings)

    def _solve(self, gravity, sectors, known, progress, hold_out, timings) -> CRAResult:
        b_eq, total = self._right_hand_side(gravity)
        tried, message, status = [], "", "inconclusive"
        started = time.perf_counter()
        progress("RBE")
        rbe_forces, status_rbe, rbe_message, _ = self.system.solve_lp(gravity, least_force=True, budget=self.budget)
        if status_rbe not in (0, 2):  # no solver decided RBE: nothing is known
            timings["lp"] += time.perf_counter() - started
            parameters = {**self.parameters, "sectors": tried, "gravity": gravity.tolist()}
            return self._result("inconclusive", f"RBE was not decided ({rbe_message}), so CRA cannot be either",
                                None, None, parameters, timings)
        if status_rbe == 0 and rbe_forces is None:  # nothing to carry (no free block touches anything)
            rbe_forces = np.zeros(0)
        if status_rbe == 0 and len(self.system.points) > cra_large.LARGE_VERTICES and not known:
            timings["lp"] += time.perf_counter() - started
            status, forces, motion, message = cra_large.decide_large(
                self, b_eq, len(self.system.points) * (1 + sectors), timings, progress, hold_out)
            parameters = {**self.parameters, "sectors": tried, "gravity": gravity.tolist(), "route": "large"}
            return self._result(status, message, None if forces is None else forces * total, motion, parameters,
                                timings)
        progress("quick answers")
        work, most_work = self._most_work(b_eq) if status_rbe == 0 else (np.inf, None)
        frugal = cache(lambda: cra_local.least_friction(self, b_eq))  # for _quick and _local, once
        quick = self._quick(b_eq, rbe_forces if status_rbe == 0 else None, known, most_work, frugal)
        timings["lp"] += time.perf_counter() - started
        if quick is not None:
            status, forces, motion, message = quick
            parameters = {**self.parameters, "sectors": tried, "gravity": gravity.tolist()}
            return self._result(status, message, forces * total if status == "stable" else None, motion,
                                parameters, timings)
        local = None  # (found, how) of the local solvers, once run
        binaries = len(self.system.points) * (1 + sectors)
        if binaries > LOCAL_FIRST_BINARIES:  # a MILP this large rarely decides in time: local solvers first
            local = self._local(b_eq, rbe_forces, most_work, frugal, timings, progress)
            if local[0] is not None:
                motion, forces = local[0]
                message = (f"equilibrium realised by a virtual motion, found by {local[1]} (tried before the MILP, "
                           f"which has {binaries} binaries)")
                parameters = {**self.parameters, "sectors": tried, "gravity": gravity.tolist()}
                return self._result("stable", message, forces * total, motion, parameters, timings)
        started = time.perf_counter()
        force_bounds = cra_milp.force_bounds(self, b_eq, work)  # the big Ms of every MILP below
        timings["milp"] += time.perf_counter() - started
        for count in (sectors,) + tuple(s for s in REFINED_SECTORS if s > sectors):
            tried.append(count)
            progress(f"MILP with {count} sectors")
            started = time.perf_counter()
            outcome = cra_milp.relaxation(self, b_eq, force_bounds, count, self.milp_nodes, work=work)
            if outcome is None:  # an infeasibility claim is checked on a looser formulation (floating point)
                outcome = cra_milp.relaxation(self, b_eq, force_bounds, count, self.milp_nodes, tightened=False,
                                              work=work)
            timings["milp"] += time.perf_counter() - started
            if outcome is None:
                status, message = "unstable", (f"no motion realises an equilibrium (MILP with {count} sectors "
                                               f"infeasible, with and without the cuts)")
                break
            if isinstance(outcome, str):
                message = outcome
                break
            forces, motion = outcome
            started = time.perf_counter()
            exact = self.exact(b_eq, motion)
            for repair in (lambda f: cra_local.realise(self, f), lambda f: cra_local.polish(self, b_eq, f, motion)):
                if exact is not None:
                    break
                repaired = repair(forces)
                exact = None if repaired is None else self.exact(b_eq, repaired)
                motion = motion if repaired is None else repaired
            timings["lp"] += time.perf_counter() - started
            if exact is not None:
                status, message = "stable", f"equilibrium realised by a virtual motion ({count} sectors)"
                forces = exact
                break
            message = f"the MILP's motions could not be made exact with up to {count} sectors"
        if status == "inconclusive":  # last resort: local solves of (11), checked by the exact LP
            found, how = local if local is not None else self._local(b_eq, rbe_forces, most_work, frugal,
                                                                     timings, progress)
            if found is not None:
                status, (motion, forces) = "stable", found
                message = (f"equilibrium realised by a virtual motion, found by {how} (the MILP did not decide: "
                           f"{message})")
            else:
                message += f"; {how}"
        parameters = {**self.parameters, "sectors": tried, "gravity": gravity.tolist()}
        return self._result(status, message, forces * total if status == "stable" else None,
                            motion if status == "stable" else None, parameters, timings)

    def _local(self, b_eq, rbe_forces, most_work, frugal, timings, progress):
        """:func:`~interlock.verify.statics.cra_local.last_resort`, timed (``lp``: SLSQP and the checks; ``ipopt``);
        ``frugal()`` gives the least-friction equilibrium."""
        started = time.perf_counter()
        found = cra_local.last_resort(self, b_eq, rbe_forces.reshape(-1, 3), most_work, timings, progress,
                                      frugal=frugal())
        timings["lp"] += time.perf_counter() - started - timings.get("ipopt", 0.0)
        return found

    def _quick(self, b_eq, rbe_forces, known=(), most_work=None, frugal=None):
        """Decide quickly where possible: no RBE equilibrium (``rbe_forces`` None) means "unstable" (CRA only
        removes solutions); a motion that realises an equilibrium exactly means "stable".  Tried in turn: a
        known motion (``known``, e.g. of a nearby load), the allowed motion on which the load does the most work
        (``most_work``: a block pushed into its seat), one realising the least-friction equilibrium
        (:func:`~interlock.verify.statics.cra_local.least_friction`; ``frugal()``, if given, returns it) and one
        realising RBE's least-force equilibrium.  ``None`` otherwise."""
        frugal = frugal or (lambda: cra_local.least_friction(self, b_eq))
        if rbe_forces is None:
            return "unstable", None, None, "RBE has no equilibrium, so no motion can realise one"
        forces = rbe_forces.reshape(-1, 3)
        candidates = [(lambda m=m: m, "the motion of a nearby load") for m in known]
        candidates += [(lambda: most_work, "the motion of most work"),
                       (lambda: None if frugal() is None else cra_local.realise(self, frugal()),
                        "a motion realising the least-friction equilibrium"),
                       (lambda: cra_local.realise(self, forces), "a motion realising RBE's least-force equilibrium")]
        candidates += [(lambda m=m: cra_local.polish(self, b_eq, forces, m),
                        "a local solve from the motion of a nearby load") for m in known]
        for candidate, how in candidates:
            motion = candidate()
            exact = None if motion is None else self.exact(b_eq, motion)
            if exact is not None:
                return "stable", exact, motion, f"equilibrium realised by {how}"
        return None

    def internal_motion(self, world: np.ndarray) -> np.ndarray:
        """World twists ``(t, omega)`` per free block (as in :attr:`CRAResult.motion`) in the solver's units:
        lengths over ``eps``, rotations times the model size over ``eps``, flattened."""
        eps, length = self.parameters["eps_absolute"], self.parameters["length"]
        return np.hstack([world[:, :3], world[:, 3:] * length]).ravel() / eps

    def _right_hand_side(self, gravity: np.ndarray):
        """``-p / W`` of Eq. (7b) for this gravity, and the total weight ``W``."""
        load = np.outer(self.system.weights, gravity)
        total = float(np.abs(load).sum()) or 1.0
        return -np.hstack([load, self.system.arms]).ravel() / total, total

    def check_upstream(self, assembly, gravity: np.ndarray) -> CRAResult:
        """Verify the motion of compas_cra's local solver with the exact LP (``backend="compas_cra"``)."""
        timings = {**self.system.timings, "milp": 0.0, "lp": 0.0}
        started = time.perf_counter()
        p = self.parameters
        solution = upstream_solution(assembly, p["mu"], gravity=gravity, density=p["density"], frame=p["frame"],
                                     eps=p["eps"], eta=p["eta"], contacts=self.system.contacts)
        timings["compas_cra"] = time.perf_counter() - started
        parameters = {**p, "sectors": [], "gravity": gravity.tolist(), "backend": "compas_cra"}
        if solution is None:
            return self._result("inconclusive", "compas_cra's local solver found no solution (which proves "
                                "nothing)", None, None, parameters, timings)
        world, upstream_forces = (np.asarray(part, dtype=float) for part in solution)
        world = world.reshape(-1, 6)
        motion = self.internal_motion(world)
        b_eq, total = self._right_hand_side(gravity)
        started = time.perf_counter()
        found = cra_local.verify_local(self, b_eq, motion, upstream_forces)
        timings["lp"] = time.perf_counter() - started
        if found is None:
            return self._result("inconclusive", "compas_cra's motion does not realise an equilibrium exactly",
                                None, None, parameters, timings)
        motion, exact = found
        return self._result("stable", "equilibrium realised by compas_cra's motion (verified exactly)",
                            exact * total, motion, parameters, timings)

    # --- motions and the MILP's bounds -------------------------------------------------------------------------

    @property
    def allowed_motions(self) -> tuple[sp.csr_matrix, np.ndarray]:
        """``(A, b)`` with ``A q <= b`` exactly when ``dd_n >= -eps`` and ``|dd| <= eta`` (eps = 1)."""
        if "allowed_motions" not in self.memo:
            d = self.kinematic
            s = d.shape[0] // 3
            self.memo["allowed_motions"] = (
                sp.vstack([d, -d], format="csr"),
                np.concatenate([np.full(3 * s, self.ratio), np.tile([1.0, self.ratio, self.ratio], s)]))
        return self.memo["allowed_motions"]

    @property
    def reach(self) -> np.ndarray:
        """:func:`~interlock.verify.statics.cra_milp.vertex_reach`, once per problem (a tilt scan solves many loads)."""
        if "reach" not in self.memo:
            self.memo["reach"] = cra_milp.vertex_reach(self)
        return self.memo["reach"]

    @property
    def face_cuts(self) -> np.ndarray:
        """:func:`~interlock.verify.statics.cra_milp.face_cuts`, once per problem."""
        if "face_cuts" not in self.memo:
            self.memo["face_cuts"] = cra_milp.face_cuts(self)
        return self.memo["face_cuts"]

    def _most_work(self, b_eq):
        """``(bound, motion)``: the most work ``-b.q`` the load can do on an allowed motion (``dd_n >= -eps``,
        ``|dd| <= eta``), with margin, and a motion doing it (``None`` if the LP fails).

        By virtual work, ``-b.q = sum f_n + sum alpha |dd_t|^2`` (eps = 1) for
        every solution of (11), so the bound caps the sum of its normal forces;
        and the motion itself often realises an equilibrium (a block pushed
        into its seat closes every contact), which :meth:`_quick` tries.
        """
        a_ub, b_ub = self.allowed_motions
        outcome = highs_lp(b_eq, self.budget, "the motion of most work", A_ub=a_ub, b_ub=b_ub, bounds=(None, None))
        if outcome.status != 0:
            return np.inf, None
        return -outcome.fun * (1 + BOUND_MARGIN) + BOUND_MARGIN, outcome.x

    # --- exact checks -----------------------------------------------------------------------------------------

    def motion_lp(self, motion) -> MotionLP | None:
        """The LP of (11) at a fixed motion, in ``(f_n, alpha)``; ``None`` if the motion leaves the bounds
        ``dd_n >= -1``, ``|dd| <= ratio`` or closes no vertex."""
        system = self.system
        dd = (self.kinematic @ motion).reshape(-1, 3)
        closed = dd[:, 0] + 1.0 <= ACTIVE_TOL
        slide = dd[:, 1:]
        sliding = closed & (np.hypot(slide[:, 0], slide[:, 1]) > SLIDE_TOL)
        if np.any(dd[:, 0] < -1.0 - 1e-6) or np.any(np.abs(dd) > self.ratio * (1 + 1e-6)) or not closed.any():
            return None
        normal_columns = system.a_eq[:, 0::3][:, closed]
        slide_columns = (-(system.a_eq[:, 1::3] @ sp.diags(slide[:, 0]))
                         - (system.a_eq[:, 2::3] @ sp.diags(slide[:, 1])))[:, sliding]
        a_eq = sp.hstack([normal_columns, slide_columns], format="csr")
        # per sliding vertex and cone row k: -m f_n + alpha (-(cos a_k) dd_u - (sin a_k) dd_v) <= 0
        cone_rows = system.cone_rows / max(1.0, -float(system.cone_rows[0, 0]))  # rows within range for large mu
        sides = len(cone_rows)
        n_closed, n_sliding = int(closed.sum()), int(sliding.sum())
        which = np.flatnonzero(sliding)
        row = np.arange(n_sliding * sides)
        column_of_normal = np.repeat((np.cumsum(closed) - 1)[which], sides)
        normal_part = sp.csr_matrix((np.tile(cone_rows[:, 0], n_sliding), (row, column_of_normal)),
                                    shape=(len(row), n_closed))
        alpha_values = -(slide[which] @ cone_rows[:, 1:].T).ravel()
        alpha_part = sp.csr_matrix((alpha_values, (row, np.repeat(np.arange(n_sliding), sides))),
                                   shape=(len(row), n_sliding))
        a_ub = sp.hstack([normal_part, alpha_part], format="csr")
        cost = np.concatenate([np.ones(n_closed), np.zeros(n_sliding)])
        return MotionLP(a_eq, a_ub, cost, closed, sliding, slide)

    def exact(self, b_eq, motion):
        """Forces solving (11) for this motion (least ``sum f_n``), or ``None``: :meth:`motion_lp` by HiGHS,
        its solution checked (:meth:`MotionLP.holds`).  HiGHS meets its tolerance
        in its own scaling, so a vertex slipping at the cone's limit can leave a row violated by 1e-5 of the
        load (shelf-stable); then Clarabel's interior solution, checked the same way, decides."""
        lp = self.motion_lp(motion)
        if lp is None:
            return None
        outcome = highs_lp(lp.cost, self.budget, "the exact LP", A_ub=lp.a_ub, b_ub=np.zeros(lp.a_ub.shape[0]),
                           A_eq=lp.a_eq, b_eq=b_eq, bounds=(0, None))
        if outcome.status != 0:
            return None
        x = np.maximum(outcome.x, 0.0)
        return lp.forces(x) if lp.holds(x, b_eq) else cra_large.interior_forces(lp, b_eq, self.budget)

    # --- the result -------------------------------------------------------------------------------------------

    def _result(self, status, message, forces, motion, parameters, timings) -> CRAResult:
        system = self.system
        s, free = len(system.points), len(system.free)
        eps_absolute = parameters["eps_absolute"]
        if motion is None:
            world_motion = np.full((free, 6), np.nan)
            dd = np.full((s, 3), np.nan)
        else:
            twists = motion.reshape(-1, 6)
            world_motion = np.hstack([twists[:, :3], twists[:, 3:] / parameters["length"]]) * eps_absolute
            dd = (self.kinematic @ motion).reshape(-1, 3)
        closed = np.nan_to_num(dd[:, 0], nan=np.inf) + 1.0 <= ACTIVE_TOL
        return CRAResult(status, forces if forces is not None else np.full((s, 3), np.nan), world_motion,
                         system.free.copy(), closed, dd[:, 1:], system.points, system.vertex_contact, message,
                         system.contacts, parameters, timings)
