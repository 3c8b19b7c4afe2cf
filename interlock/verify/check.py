"""Deciding infinitesimal interlocking: LP + rank (main paper Def. 2.7, Def. 3.3, Prop. 3.10)."""

from __future__ import annotations

import dataclasses
import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from numbers import Real

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from threadpoolctl import threadpool_limits

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError
from interlock.verify.admissible import (MOVING_RTOL, bent_contacts, moving_names, rigid_across_bends, unless_bent,
                                         unless_cones, unless_missed)
from interlock.verify.point_contacts import contact_kinds
from interlock.verify.budget import Budget, TimeLimitReached
from interlock.verify.first_order import (DENSE_COLUMNS, FARKAS_CLOSED_RTOLS, FIRST_KERNEL_PROBE, GRAM_RESOLUTION,
                                         GRAM_SURE_RTOL, INVERSE_ITERATIONS, LP_TOL, MAX_KERNEL_PROBE,
                                         PROJECTION_ROUNDS, RANK_CLEAR_RTOL, SOLVER_THREADS, matrix_rank,
                                         interior_motion, opening_motion, positive_stress, rigid_cluster_motion)
from interlock.verify.contacts import (CONTACT_MODELS, PRESS_RTOL, Contact, contacts as find_contacts, model_contacts,
                                      search_distances)
from interlock.verify.margin import Margin, assess, motion_bound, row_tolerances
from interlock.verify.precision import PRECISION_FACTOR, Precision, block_precision
from interlock.verify.matrix import InterlockingMatrix, interlocking_matrix
from interlock.verify.tolerances import (COARSE_RATIO, NOISE_CONTACTS, NOISE_SPREAD, block_depths, block_noise,
                                        coarseness, coarsest, contact_tolerances, tolerance_source, too_coarse)
from interlock.verify.validate import refuse_overlaps_without_contact, validate as check_overlaps

__all__ = ["Verdict", "check", "beyond_first_order", "block_noise", "opening_motion", "contact_tolerances",
           "FARKAS_CLOSED_RTOLS", "PROJECTION_ROUNDS", "STAGES", "RANK_RTOL", "RANK_CLEAR_RTOL", "GRAM_RESOLUTION",
           "GRAM_SURE_RTOL", "LP_TOL", "LP_SOLVERS", "MOVING_RTOL", "DENSE_COLUMNS", "FIRST_KERNEL_PROBE",
           "COARSE_RATIO", "NOISE_CONTACTS", "NOISE_SPREAD", "SOLVER_THREADS", "MAX_KERNEL_PROBE",
           "INVERSE_ITERATIONS", "DEPTH_RTOL", "ESCAPE_BLOCKS", "ESCAPE_SEARCH", "NEAR_SPREAD"]

#: A singular value at most ``RANK_RTOL * sigma_max`` is zero ...
RANK_RTOL = 1e-9
#: Solvers for the stress LP. Clarabel (direct sparse LDL^T, feasibility form) took 24 s on the stress LP of a
#: 4,800-block RhomBlock hexagon where HiGHS' interior-point method took 206 s; HiGHS is the fallback.
LP_SOLVERS = ("clarabel", "highs")
#: A motion within tolerance that collides is followed again with interference up to each block's precision
#: (:func:`~interlock.verify.tolerances.block_depths`) only where that reaches this share of a block: float64
#: input reads ~1e-16, float32 ~1e-7, and below this the volume test has already decided.
DEPTH_RTOL = 1e-9
#: A motion of a noisy input must not push together faces that lie within this many times the noise of their two
#: blocks (:func:`~interlock.verify.contacts.block_noise`), found or not: a block's contacts read its noise low
#: (a face of two triangles fits its plane better than its vertices lie), and TopoLite's shell with Gaussian noise
#: of 2.7e-5 leaves a part 5e-5 from the frame where it touched, beyond NOISE_SPREAD times the noise read there.
NEAR_SPREAD = 20.0
NEAR_LACKING = (f"across faces within {NEAR_SPREAD:g} times the input's vertex noise of each other (a contact "
                "the noise may have opened); the file does not tell whether they touch")
#: ... and then with the single moving blocks that open the most, each moved alone as a rigid body: at most this many.
ESCAPE_BLOCKS = 4
#: Single blocks are tried only when at most this many move (one small LP each).
ESCAPE_SEARCH = 200
#: The stages of :func:`check`, in order, as reported to its ``progress`` callback and in ``timings``.
STAGES = ("validate", "contacts", "matrix", "rank", "lp", "margin", "motion", "certify", "beyond")



@dataclass(frozen=True)
class Verdict:
    """The answer of :func:`check`.

    ``interlocked`` is True (proved infinitesimally interlocked, hence
    interlocked by Prop. 3.10), False (a first-order motion exists: *not
    infinitesimally interlocked* — which does not by itself show that blocks
    can really move, see docs/interlocking.md) or None when the floating-point evidence is
    inconclusive.  An inconclusive verdict may still carry the candidate
    ``motion`` it could not confirm (see ``bent_contacts``).

    ``bent_contacts`` counts the contacts whose facets are planar only within
    the contact tolerances (:attr:`~interlock.verify.contacts.Contact.planar`):
    a first-order motion that slides across one of them is not reported as
    False, since the real, bent faces may block it.

    With ``order=2`` (:func:`check`), ``interlocked`` is True also when a
    first-order motion is blocked at second order (``second_order``), False
    only when a finite motion was shown (``finite_motion``), and None otherwise.
    """

    interlocked: bool | None
    status: str
    frame: tuple[int, ...]
    shape: tuple[int, int]
    rank: int
    lp_value: float | None
    motion: np.ndarray | None = None  # (n_blocks, 6): twist (omega, t) per block, zero for fixed ones
    motion_kind: str | None = None  # "sliding" (A x = 0) or "opening" (A x >= 0, A x != 0)
    moving: tuple[int, ...] = ()
    stress: np.ndarray | None = None  # one positive weight per row of A, A^T stress = 0
    certified: bool = False
    translational: bool = False
    contacts: int = 0
    bent_contacts: int = 0
    contact_kinds: dict = field(default_factory=dict)  # contacts per kind (Remark 3.11); "<kind> (cone)": no row
    tolerances: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    order: int = 1
    second_order: object = None  # SecondOrder (order 2)
    finite_motion: object = None  # FiniteMotion (order 2), the last one tried
    margin: Margin | None = None  # how far an "interlocked" answer holds beyond the exact input

    def __str__(self) -> str:
        word = {True: "interlocked", False: "not infinitesimally interlocked", None: "inconclusive"}[self.interlocked]
        if self.interlocked is False and self.motion_kind == "within tolerance":
            word = "not interlocked within tolerance"
        if self.interlocked is True and self.second_order is not None and self.second_order.blocked:
            word = "interlocked (second order)"
        elif self.interlocked is False and self.finite_motion is not None and self.finite_motion.shown:
            word = "not interlocked (finite motion shown)"
        exact_only = self.margin is not None and math.isfinite(self.margin.lower)  # the tolerance matters
        cert = (", certified" + (" for the exact input only" if exact_only else "")) if self.certified else ""
        kinds = ""
        if any(k != "face" and not k.endswith("(cone)") for k in self.contact_kinds):  # point contacts gave rows
            kinds = "; contacts: " + ", ".join(f"{n} {k}" for k, n in self.contact_kinds.items())
        return f"{word}{cert}: {self.status} (A {self.shape[0]}x{self.shape[1]}, rank {self.rank}{kinds})"

    def __bool__(self):
        raise TypeError("the truth value of a Verdict is ambiguous: it may be inconclusive; use verdict.interlocked "
                        "(True, False or None), e.g. `if check(a).interlocked:`")

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""
        return {
            "interlocked": self.interlocked,
            "status": self.status,
            "frame": list(self.frame),
            "shape": list(self.shape),
            "rank": self.rank,
            "lp_value": self.lp_value,
            "moving": list(self.moving),
            "motion_kind": self.motion_kind,
            "motion": None if self.motion is None else self.motion.tolist(),
            "stress_min": None if self.stress is None else float(self.stress.min()),
            "certified": self.certified,
            "translational": self.translational,
            "contacts": self.contacts,
            "bent_contacts": self.bent_contacts,
            "contact_kinds": dict(self.contact_kinds),
            "tolerances": dict(self.tolerances),
            "timings": dict(self.timings),
            "order": self.order,
            "second_order": None if self.second_order is None else self.second_order.to_dict(),
            "finite_motion": None if self.finite_motion is None else self.finite_motion.to_dict(),
            "margin": None if self.margin is None else self.margin.to_dict(),
        }


def check(assembly: Assembly, frame=None, translational: bool = False, certify: bool = False, *,
          rank_rtol: float = RANK_RTOL, lp_tol: float = LP_TOL, contacts=None, validate: bool = True,
          progress=None, lp_solver: str = "clarabel", order: int = 1, tolerance: float | None = None,
          time_limit: float | Budget | None = None) -> Verdict:
    """Decide whether the assembly is infinitesimally interlocked with the given frame.

    The assembly is infinitesimally interlocked (Def. 3.3) iff ``{x : A x >= 0} = {0}``
    for its interlocking matrix ``A``, i.e. iff both

    1. ``A^T w = 0`` has a solution ``w >= 1`` (a positive self-stress; by
       Stiemke's lemma, iff no ``x`` has ``A x >= 0, A x != 0``), and
    2. ``A`` has full column rank (no sliding motion ``A x = 0``).

    Both tests always run: an LP optimum of 0 with a rank deficit is *not*
    interlocked.  When (1) fails, the LP ``max 1^T A x, 0 <= A x <= 1`` gives a
    motion; when (2) fails, the kernel does.

    Parameters
    ----------
    assembly : Assembly
    frame : iterable of int, optional
        Fixed blocks; ``assembly.frame`` when omitted.  An empty frame is
        legal for a finite assembly and never interlocked.
    translational : bool
        Only translations (infinitesimal translational interlocking).
    certify : bool
        Re-check the verdict rigorously (:mod:`interlock.verify.certify`).
    rank_rtol, lp_tol : float
        Tolerances (see :data:`RANK_RTOL`, :data:`LP_TOL`); reported in the verdict.
    contacts : sequence of Contact, "all" or "faces", optional
        Precomputed contacts (e.g. to check several frames).  Default: the
        contacts the assembly carries (``info["contacts"]``, e.g.
        :func:`~interlock.blocks.presets.block_on_pins`), else the search of
        :func:`~interlock.verify.contacts.contacts` for contacts of every
        type (Remark 3.11: vertex-face, edge-edge, vertex-edge, vertex-vertex
        besides faces; ``"all"``).  ``"faces"``: face-to-face contacts only.
        ``contact_kinds`` of the verdict counts the contacts of each type.
    validate : bool
        First check that no two blocks overlap (:func:`~interlock.verify.validate.validate`).
    progress : callable, optional
        Called with the name of each stage as it starts (one of :data:`STAGES`).
    lp_solver : {"clarabel", "highs"}
        Solver of the stress LP; HiGHS also serves as fallback when Clarabel
        neither solves nor proves infeasibility.  Reported in ``tolerances``.
    tolerance : float, optional
        How far (a length, model units) the blocks' faces may be from the
        input's: an "interlocked" answer must hold for every assembly within
        it (docs/interlocking.md, "Margin and tolerance").  Default: what the
        coordinates' rounding implies (:func:`~interlock.verify.margin.rounding_tolerance`;
        float32 files: about 2e-7 of the largest coordinate).  Where some
        motion keeps every contact within it, that motion is followed for
        real: False ("not interlocked (finite motion shown)") when the blocks
        come apart, else None (the motion and the precision are comparable);
        where neither bound decides, None with the margin's bounds.
    order : {1, 2}
        1: the first-order verdict above.  2: a verdict that is not
        "interlocked" is taken further (:func:`beyond_first_order`): blocked at
        second order (:mod:`interlock.verify.second_order`) gives True
        ("interlocked (second order)"), a finite motion shown
        (:mod:`interlock.verify.motion`) gives False ("not interlocked"),
        anything else None, saying what was tried.
    time_limit : float, optional
        Seconds for the whole call (default: none).  Every stage runs under
        this one budget (:mod:`interlock.verify.budget`): the solvers get the
        time left, and when it is spent the answer is None, "inconclusive:
        time limit reached in <stage>".  The limit never changes which route
        is taken, only whether an answer arrives.  A
        :class:`~interlock.verify.budget.Budget` started earlier (the
        command line's, from the command's start) is used as it is.

    Notes
    -----
    The stress LP is solved as a feasibility problem by Clarabel (HiGHS'
    interior-point method on request or as fallback); a motion comes from
    its Farkas vector, cleaned (:func:`opening_motion`), or else from the
    motion LP by Clarabel, never a simplex over ``[A; -A]``.  Above
    :data:`DENSE_COLUMNS` columns, a clear kernel without bent or given
    contacts decides alone and the LP is skipped.  The rank by a dense SVD (of the triangular QR factor) up to
    :data:`DENSE_COLUMNS` columns, above by block inverse iteration on
    ``A^T A`` (one sparse LU), which finds at most
    :data:`MAX_KERNEL_PROBE` kernel directions (beyond that, ``rank`` is an
    upper bound and the status says so).

    Examples
    --------
    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    >>> v = check(Assembly.from_meshes(grid), frame=[0, 1, 2, 3, 5, 6, 7, 8])
    >>> v.interlocked, v.rank, v.moving, np.round(v.motion[4], 6).tolist()
    (False, 5, (4,), [0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    """
    _check_arguments(assembly, lp_solver, order, rank_rtol, lp_tol, tolerance, contacts)
    budget = time_limit if isinstance(time_limit, Budget) else Budget.start(time_limit)
    timings = {}
    try:
        return _decide(assembly, frame, translational, certify, rank_rtol, lp_tol, contacts, validate, progress,
                       lp_solver, order, tolerance, budget, timings)
    except TimeLimitReached as reached:
        fixed = tuple(sorted(set(assembly.block_indices(assembly.frame if frame is None else frame))))
        return Verdict(None, f"{reached} (time_limit = {budget.limit:g} s)", frame=fixed, shape=(0, 0),
                       rank=0, lp_value=None, translational=translational,
                       tolerances={"time_limit": budget.limit, "stage": reached.stage}, timings=timings, order=order)


def _check_arguments(assembly, lp_solver, order, rank_rtol, lp_tol, tolerance, contacts) -> None:
    """InterlockError naming the argument of :func:`check` that is out of range."""
    if not isinstance(assembly, Assembly):
        raise InterlockError(f"check needs an Assembly (see interlock.blocks.Assembly), got {type(assembly).__name__}")
    if lp_solver not in LP_SOLVERS:
        raise InterlockError(f"unknown lp_solver {lp_solver!r}; choose one of {', '.join(LP_SOLVERS)}")
    if len(assembly) == 0:
        raise InterlockError("the assembly has no blocks; there is nothing to check")
    if order not in (1, 2):
        raise InterlockError(f"order must be 1 (first order) or 2 (second order and finite motions), got {order!r}")
    for name, value in (("rank_rtol", rank_rtol), ("lp_tol", lp_tol)):
        if isinstance(value, bool) or not isinstance(value, Real) or not 0 < value < 1:
            raise InterlockError(f"{name} must be a relative tolerance strictly between 0 and 1 (default "
                                 f"{RANK_RTOL if name == 'rank_rtol' else LP_TOL:g}), got {value!r}")
    if tolerance is not None and (isinstance(tolerance, bool) or not isinstance(tolerance, Real)
                                  or not math.isfinite(tolerance) or tolerance < 0):
        raise InterlockError(f"tolerance must be a finite length >= 0 in model units (or None: read off the input's "
                             f"rounding), got {tolerance!r}")
    if contacts is not None and not (isinstance(contacts, str) and contacts in CONTACT_MODELS):
        if isinstance(contacts, (str, bytes)) or not hasattr(contacts, "__iter__"):
            raise InterlockError(f"contacts must be a sequence of Contact (from interlock.verify.contacts), "
                                 f"'all' or 'faces', got {contacts!r:.60}")
        wrong = next((c for c in contacts if not isinstance(c, Contact)), None)
        if wrong is not None:
            raise InterlockError(f"contacts must hold Contact objects (from interlock.verify.contacts), "
                                 f"got a {type(wrong).__name__}: {wrong!r:.60}")


def _decide(assembly, frame, translational, certify, rank_rtol, lp_tol, contacts, validate, progress, lp_solver,
            order, tolerance, budget, timings) -> Verdict:
    """The body of :func:`check` after its arguments were checked; raises TimeLimitReached when ``budget`` is spent."""
    kinds, contacts = (contacts, None) if isinstance(contacts, str) else ("all", contacts)  # the contact model
    precision = block_precision(assembly)
    if tolerance is not None:  # the caller's word on how exact the faces are: the search and the overlaps use it too
        precision = precision.widened(tolerance)
    distance = search_distances(assembly, precision)
    coarse = too_coarse(assembly, frame, precision)
    if coarse is not None:
        return Verdict(None, coarse, frame=tuple(assembly.block_indices(assembly.frame if frame is None else frame)),
                       shape=(0, 0), rank=0, lp_value=None, translational=translational, timings=timings, order=order,
                       tolerances={"tolerance": float(PRECISION_FACTOR * precision.delta.max()),
                                   "tolerance_from": precision.describe()})
    with _stage(timings, "validate" if validate else "contacts", progress, budget):
        # the contacts first: the noise and bends their faces show widen each block's tolerance for overlaps
        found = model_contacts(assembly, contacts, precision, budget, kinds)
        if validate:
            # a re-meshed or noisy block whose faces lie where they were may not overlap by a boolean's volume
            # alone: its measured depth must pass what its contacts accept (at least PRESS_RTOL of the block)
            distance = np.maximum(distance, PRESS_RTOL * assembly.block_sizes)
            for c in found:
                distance[[c.i, c.j]] = np.maximum(distance[[c.i, c.j]], c.tolerance or 0.0)
            held = assembly.block_indices(assembly.frame if frame is None else frame)
            shallow = check_overlaps(assembly, depth=distance, fixed=held)
    if validate:
        with _stage(timings, "contacts", progress, budget):  # overlaps that pass must still be touches
            deep = [o for o in shallow if o.deepness > distance[o.i] + distance[o.j]
                    and not (o.i in held and o.j in held)]  # two frame blocks give no row: their overlap is no concern
            widest = max((distance[o.i] + distance[o.j] for o in deep), default=0.0)
            refuse_overlaps_without_contact(assembly, deep, found, float(widest))
    with _stage(timings, "matrix", progress, budget):
        A = interlocking_matrix(assembly, frame, translational, contacts=found)
    fixed = tuple(sorted(set(range(len(assembly))) - set(A.free.tolist())))
    tolerances = {"rank_rtol": rank_rtol, "rank_clear_rtol": RANK_CLEAR_RTOL, "lp_tol": lp_tol,
                  "moving_rtol": MOVING_RTOL,
                  "length_scale": A.length_scale}
    if math.isfinite(budget.limit):
        tolerances["time_limit"] = budget.limit
    # the input's tolerance per contact: given, or from the rounding of its two blocks and the bend of its faces
    limits = contact_tolerances(found, precision, tolerance)
    # faces bent within the rounding the numbers show are planar as far as the input can tell; a bend beyond it
    # (even one computed float64 geometry might explain) may block a slide
    bent = bent_contacts(found, contact_tolerances(found, precision, tolerance, bends=False))
    rows_of = sum(c.normals is None for c in found)  # a cone of normals is no row (contact_kinds counts it)
    base = dict(frame=fixed, shape=A.shape, translational=translational, contacts=rows_of,
                contact_kinds=contact_kinds(found),
                bent_contacts=int(bent.sum()), tolerances=tolerances, timings=timings)
    if len(A.free) == 0:
        return Verdict(True, "every block is in the frame: nothing can move", rank=0, lp_value=0.0, **base)

    with threadpool_limits(SOLVER_THREADS, "blas"):
        with _stage(timings, "rank", progress, budget):
            # without bent or given contacts one kernel motion is the whole answer: probe for a few, not hundreds
            probe = MAX_KERNEL_PROBE if bent.any() or contacts is not None else FIRST_KERNEL_PROBE
            rank, kernel, rank_clear = matrix_rank(A.matrix, rank_rtol, budget, probe)
        n = A.shape[1]
        # a clear kernel decides "not interlocked" by itself unless a bent contact or given contacts may undo it
        sliding_decides = (rank_clear and rank < n and not bent.any() and contacts is None
                           and n > DENSE_COLUMNS)
        stress, lp_value, lp_motion, interior = None, None, None, None
        if not sliding_decides:
            with _stage(timings, "lp", progress, budget):
                stress, tolerances["lp_solver"], farkas = positive_stress(A.matrix, lp_tol, lp_solver, budget)
                if stress is not None:
                    lp_value = 0.0
                else:  # the stress problem's own infeasibility certificate is a motion; an LP only if it is not clean
                    lp_value, lp_motion = opening_motion(A.matrix, farkas, lp_tol)
                    tolerances["motion_from"] = "farkas" if lp_motion is not None else "lp"
                    if lp_motion is None:
                        interior, tolerances["lp_status"] = interior_motion(A.matrix, budget)
                        lp_value, lp_motion = opening_motion(A.matrix, interior, lp_tol)

    no_frame = " (no frame: a finite assembly without fixed blocks can always move as a whole)" if not fixed else ""
    motions = []  # candidate "not interlocked" verdicts: the first one that survives bent contacts is the answer
    if rank_clear and rank < n:
        rigid = rigid_across_bends(A, kernel, [c for c, b in zip(found, bent) if b], assembly.centroids)
        motion, moving = _motion(A, (rigid if rigid.shape[1] else kernel)[:, 0], len(assembly), reversible=True)
        at_least = "at least " if n > DENSE_COLUMNS and kernel.shape[1] >= min(probe, n) else ""
        motions.append(Verdict(False, f"{moving_names(moving)} a first-order motion that keeps every contact "
                               f"(A x = 0, kernel dimension {at_least}{n - rank}){no_frame}", rank=rank,
                               lp_value=lp_value, motion=motion, motion_kind="sliding", moving=moving, stress=stress,
                               **base))
    if stress is None and lp_value is not None and lp_value > lp_tol:
        motion, moving = _motion(A, lp_motion, len(assembly), reversible=False)
        motions.append(Verdict(False, f"{moving_names(moving)} a first-order motion that opens contacts "
                               f"(LP value {lp_value:.3g}){no_frame}", rank=rank, lp_value=lp_value,
                               motion=motion, motion_kind="opening", moving=moving, **base))
    if not motions and stress is None and (lp_value is None or lp_value <= lp_tol):
        # floating point left no clean motion; one that closes no contact by more than its tolerance still answers
        within = _within_tolerance(A, found, limits, interior, len(assembly), base, rank, no_frame)
        if within is not None:
            motions.append(within)
    if motions:
        if bent.any():  # a motion within tolerance already allows each contact its bend
            motions = [v if v.motion_kind == "within tolerance" else unless_bent(v, A, found, bent, assembly.centroids)
                       for v in motions]
        if contacts is not None:  # the caller's contacts may miss faces that touch: the default search is the judge
            motions = [_unless_missed(v, assembly, precision, tolerance) if v.interlocked is False else v
                       for v in motions]
        elif tolerance is None and block_noise(found).any():  # noise may have moved touching faces a little apart
            judged = [_unless_missed(v, assembly, precision, None, kinds, NEAR_SPREAD, NEAR_LACKING)
                      if v.interlocked is False else v for v in motions]
            if any(v.interlocked is False for v in motions) and not any(v.interlocked is False for v in judged):
                with _stage(timings, "near faces", progress, budget):
                    judged = _with_near_faces(assembly, frame, translational, rank_rtol, lp_tol, found, kinds,
                                              precision, lp_solver, budget, timings) + judged
            motions = judged
        motions = [unless_cones(v, found, assembly.centroids, A, budget) if v.interlocked is False else v
                   for v in motions]
        verdict = next((v for v in motions if v.interlocked is False), motions[0])
    elif stress is not None and rank_clear:
        verdict = Verdict(True, f"positive self-stress on all {A.shape[0]} rows and full column rank",
                          rank=rank, lp_value=0.0, stress=stress, **base)
    else:
        why = ("the rank is within the tolerance band" if not rank_clear
               else "the LPs found neither a stress nor a motion")
        if lp_value is None and stress is None and tolerances.get("motion_from") == "lp":
            status = tolerances.get("lp_status", "failed")
            how = ("its point could not be made an exact motion, nor one within tolerance"
                   if status in ("Solved", "AlmostSolved") else "no point")
            why = f"the LPs found neither a stress nor a motion (solver: Clarabel {status}; {how})"
        verdict = Verdict(None, f"floating point is not conclusive: {why}", rank=rank, lp_value=lp_value,
                          stress=stress, **base)
    if verdict.interlocked is True:
        with _stage(timings, "margin", progress, budget):
            source = "given" if tolerance is not None else tolerance_source(found, A, precision)
            verdict = _with_margin(verdict, assess(A, found, assembly.block_size, stress, limits, source,
                                                   per_contact=True, budget=budget), A, len(assembly),
                                   coarsest(found, A, limits) if tolerance is None else None)
            verdict = _with_play(verdict, A, found, budget)
    rough, roughest = coarseness(assembly, frame, precision)
    coarse = rough >= COARSE_RATIO and verdict.interlocked is False and verdict.finite_motion is None
    if verdict.motion is not None and (verdict.motion_kind == "within tolerance" or coarse):
        # a motion the tolerances leave open, or one that a coarse file's lost or bent contacts may have left open:
        # moved for real, it either shows the blocks coming apart or collides
        why = ("within the input's precision" if verdict.motion_kind == "within tolerance" else
               f"the input's precision {rough * assembly.block_sizes[roughest]:.2g} is coarse against its blocks "
               f"(block {roughest} is {assembly.block_sizes[roughest]:.3g} across)")
        # a block may reach into others by its precision, but never by more than COARSE_RATIO of itself: noise of
        # 1e-3 of the bunny reads depths of 5 % of a block, through which an interlocked part slips
        depths = np.minimum(block_depths(found, precision, len(assembly), tolerance),
                            COARSE_RATIO * assembly.block_sizes)
        with _stage(timings, "motion", progress, budget):
            verdict = _shown_finitely(assembly, verdict, depths,
                                      lambda: _rigid_escapes(A, found, limits, verdict, len(assembly), budget),
                                      budget, why)
    if certify:
        from interlock.verify.certify import certify_verdict

        with _stage(timings, "certify", progress, budget):
            verdict = certify_verdict(assembly, A, verdict, budget=budget)
    if order == 2 and verdict.interlocked is not True:
        with _stage(timings, "beyond", progress, budget):
            verdict = beyond_first_order(assembly, verdict, contacts=found, budget=budget)
    return verdict


def _within_tolerance(A: InterlockingMatrix, found, limits, x, blocks: int, base: dict, rank: int, no_frame: str):
    """"Not interlocked within tolerance" from an interior point ``x`` of the motion LP that no cleaning made exact,
    or None.

    ``x`` opens some contact and closes every row ``r`` by at most its tolerance ``eps_r``
    (:func:`~interlock.verify.margin.row_tolerances`) per unit of ``|x|_inf``, the test of the margin's motions
    (:func:`~interlock.verify.margin.tolerant_motion`): a motion of the assembly within the input's tolerance.
    """
    if x is None or not A.shape[0]:
        return None
    eps = row_tolerances(A, found, np.maximum(limits, np.finfo(float).tiny))
    y = A.matrix @ x
    size = float(np.abs(x).max(initial=0.0))
    if not size > 0 or not float(y.max(initial=0.0)) > 0:
        return None
    closing = float(max(0.0, float((-y / eps).max(initial=0.0)))) / size
    if closing > 1.0:
        return None
    motion, moving = _motion(A, x, blocks, reversible=False)
    base = {**base, "tolerances": {**base["tolerances"], "motion_from": "interior point"}}
    return Verdict(False, f"{moving_names(moving)} a first-order motion that opens contacts and closes none by more "
                          f"than {closing:.2g} of its tolerance (up to {float(limits.max()):.3g}; the LP's interior "
                          f"point, which floating point could not make exact){no_frame}", rank=rank, lp_value=None,
                   motion=motion, motion_kind="within tolerance", moving=moving, **base)


def _rigid_escapes(A: InterlockingMatrix, found, limits, verdict: Verdict, blocks: int,
                   budget: Budget | None = None) -> list:
    """Per-block twists (one array each) that move pieces of the verdict's moving blocks as rigid bodies within the
    tolerances (:func:`~interlock.verify.first_order.rigid_cluster_motion`): first every cluster the moving blocks'
    contacts join, then single blocks (up to :data:`ESCAPE_SEARCH` moving ones), the most opening first (at most
    :data:`ESCAPE_BLOCKS`)."""
    moving = np.asarray(verdict.moving, dtype=int)
    if len(moving) == 0 or A.translational:
        return []
    inside = np.zeros(blocks, dtype=bool)
    inside[moving] = True
    pairs = np.array([(c.i, c.j) for c in found if inside[c.i] and inside[c.j]], dtype=int).reshape(-1, 2)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(blocks, blocks))
    _, label = connected_components(graph, directed=False)
    clusters = [moving[label[moving] == k] for k in np.unique(label[moving])]
    eps = row_tolerances(A, found, np.maximum(limits, np.finfo(float).tiny))
    escapes = [rigid_cluster_motion(A, clusters, eps, budget)]
    if 1 < len(moving) <= ESCAPE_SEARCH:  # a part that slides out alone, where the LP's point moved others along
        alone = [(rigid_cluster_motion(A, [[b]], eps, budget), b) for b in moving]
        opened = sorted(((float(np.maximum(A.matrix @ x, 0.0).sum()), int(b), x) for x, b in alone if x is not None),
                        key=lambda item: (-item[0], item[1]))
        escapes += [x for _, _, x in opened[:ESCAPE_BLOCKS]]
    return [_motion(A, x, blocks, reversible=False)[0] for x in escapes if x is not None]


def _shown_finitely(assembly: Assembly, verdict: Verdict, depths: np.ndarray, escapes=list,
                    budget: Budget | None = None, why: str = "within the input's precision") -> Verdict:
    """A "not interlocked within tolerance" verdict (or a first-order one on a coarse input, ``why`` saying so) whose
    motion, followed for real, moves the blocks apart.

    The motion keeps every contact within the input's tolerance.  Followed as a finite motion
    (:func:`~interlock.verify.motion.finite_motion`), it may move the blocks apart without overlap beyond
    :data:`~interlock.verify.motion.OVERLAP_RTOL` of a block's volume; or else the pieces it moves, each as one rigid
    body (``escapes()``: :func:`_rigid_escapes`), may come apart with blocks reaching into each other by no more
    than the input's precision (``depths``: :func:`~interlock.verify.tolerances.block_depths`, the rounding and noise
    of each block, never a face's bend).  Then the answer is the plain "not interlocked (finite motion shown)".  A
    rounded file tilts the faces a part slides along by its rounding, so the part comes out only through
    interference of that size.  Otherwise the motion collides, and the answer is None: the motion and the
    input's precision are comparable, and the file does not say whether its blocks interlock.  (The depths hold no
    face's bend: a designed fold of 1e-7 blocks a unit block for real.)
    """
    from interlock.verify.motion import finite_motion

    shown = finite_motion(assembly, verdict.motion, frame=verdict.frame, budget=budget)
    if not shown.shown and np.any(depths > DEPTH_RTOL * assembly.block_sizes):
        # the motion LP's point may slide blocks of one piece into each other; a piece moved as a rigid body
        # (``escapes``) is what a part sliding out of the file does
        for motion in escapes() or [verdict.motion]:
            tried = finite_motion(assembly, motion, frame=verdict.frame, depth=depths, budget=budget)
            if tried.shown:
                return dataclasses.replace(verdict, interlocked=False, finite_motion=tried, motion=motion,
                                           moving=tried.moving,
                                           status=f"{tried.message}; first order: {verdict.status}")
    if not shown.shown:
        # a motion within the input's precision that no real motion confirms: the margin and the precision are
        # comparable, and the file does not tell whether its blocks are interlocked
        return dataclasses.replace(verdict, interlocked=None, finite_motion=shown, status=(
            f"{why}: {verdict.status}; followed for real, it collides ({shown.message})"))
    return dataclasses.replace(verdict, interlocked=False, finite_motion=shown,
                               status=f"{shown.message}; first order: {verdict.status}")


def beyond_first_order(assembly: Assembly, verdict: Verdict, *, contacts=None,
                       budget: Budget | None = None) -> Verdict:
    """Take a first-order verdict that is not "interlocked" to second order and to finite motions.

    1. Prestress stability (:func:`~interlock.verify.second_order.second_order`): a stress that makes the
       second-order form of the gap functions negative definite on the kernel proves that nothing moves:
       True, "interlocked (second order)".
    2. Otherwise the first-order motion (and its reverse, for a sliding one) is followed by the
       exponential map with growing steps (:func:`~interlock.verify.motion.finite_motion`); if the blocks
       move clear without overlap beyond tolerance: False, "not interlocked (finite motion shown)".
    3. Otherwise None, naming what was tried.

    Every solver and step runs under ``budget`` (the call's; TimeLimitReached when it is spent).

    Examples
    --------
    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    >>> v = check(Assembly.from_meshes(grid), frame=[0, 1, 2, 3, 5, 6, 7, 8], order=2)
    >>> v.interlocked, v.order, v.finite_motion.shown
    (False, 2, True)
    """
    from interlock.verify.motion import finite_motion, followable_motions
    from interlock.verify.second_order import second_order

    first = verdict.status
    if verdict.translational:  # the gaps are linear in translations: nothing to learn at second order
        second, tried = None, ["second order: not for translations only (the gaps are linear in them)"]
    else:
        second = second_order(assembly, frame=verdict.frame, contacts=contacts, budget=budget)
        tried = [f"second order: {second}"]
    verdict = dataclasses.replace(verdict, order=2, second_order=second)
    if second is not None and second.blocked:
        return dataclasses.replace(verdict, interlocked=True, status=f"{second.status}; first order: {first}")
    shown = None
    if verdict.motion is not None:
        # the verdict's motion (reversed too, when sliding), then local ones: slides of single groups of blocks
        candidates = followable_motions(assembly, verdict, contacts, budget=budget)
        for motion in candidates:
            shown = finite_motion(assembly, motion, frame=verdict.frame, budget=budget)
            if shown.shown:
                return dataclasses.replace(verdict, interlocked=False, finite_motion=shown,
                                           status=f"{shown.message}; first order: {first}")
            tried.append(f"finite motion: {shown.message}")
    else:
        tried.append("no first-order motion to follow")
    return dataclasses.replace(verdict, interlocked=None, finite_motion=shown,
                               status=f"inconclusive beyond first order ({first}): " + "; ".join(tried))


@contextmanager
def _stage(timings: dict, name: str, progress, budget: Budget | None = None):
    """Time one stage of :func:`check` into ``timings[name]``, announcing it to ``progress`` first.

    With a ``budget``, the stage does not start once the time is spent, and
    its end is checked too (TimeLimitReached naming the stage).
    """
    if budget is not None:
        budget.check(name)
    if progress is not None:
        progress(name)
    start = time.perf_counter()
    yield
    timings[name] = time.perf_counter() - start
    if budget is not None:
        budget.check(name)


# --- numerics ---------------------------------------------------------------------


def _with_play(verdict: Verdict, A: InterlockingMatrix, found, budget: Budget | None = None) -> Verdict:
    """An "interlocked" verdict on contacts across gaps, with the play the gaps allow to first order.

    Rows ``r`` of a contact across a gap ``g_r`` (:attr:`~interlock.verify.contacts.Contact.separation`)
    may close by ``g_r``: every motion with ``A x >= -g`` is a play.  :func:`~interlock.verify.margin.motion_bound`
    (with ``eps = g``: the verdict's stress, or the load paths) proves ``|x|_inf <= B`` for every such motion: no
    block turns by more than ``B`` radians nor moves by more than ``B L``.
    """
    gaps = np.array([c.separation for c in found], dtype=float)
    if verdict.interlocked is not True or not len(A.row_contact) or not gaps[A.row_contact].any():
        return verdict
    row_gaps = gaps[A.row_contact]
    # rows without a gap may not open at all: a floor far below the gaps keeps the bound's tolerances positive
    bound = motion_bound(A.matrix, np.maximum(row_gaps, 1e-9 * row_gaps.max()), verdict.stress, A.block_size,
                         budget=budget)
    if math.isinf(bound):
        return dataclasses.replace(verdict, status=f"{verdict.status}; gaps up to {row_gaps.max():.3g} within the "
                                                   "contact tolerance (no bound on their play proved)")
    play = A.length_scale * bound
    widest = float(gaps[A.row_contact].max())
    return dataclasses.replace(verdict, status=f"{verdict.status}; play at most {play:.3g}: the largest motion the "
                                               f"gaps permit (gaps up to {widest:.3g} within the contact tolerance)",
                               tolerances={**verdict.tolerances, "play": play, "widest_gap": widest})


def _unless_missed(verdict: Verdict, assembly: Assembly, precision: Precision, tolerance, kinds: str = "faces",
                   noise_spread: float = NOISE_SPREAD, lacking: str | None = None) -> Verdict:
    """:func:`~interlock.verify.admissible.unless_missed` against the default search of the moving blocks (its
    ``kinds``, noisy blocks' faces within ``noise_spread`` times their noise), each contact its tolerance."""
    reference = find_contacts(assembly, involving=verdict.moving, precision=precision, kinds=kinds,
                              noise_spread=noise_spread)
    # the rounding alone: unless_missed adds each contact's bend itself, and judges slides across faces bent beyond it
    return unless_missed(verdict, assembly, reference,
                         contact_tolerances(reference, precision, tolerance, bends=False), lacking)


def _with_near_faces(assembly: Assembly, frame, translational, rank_rtol, lp_tol, found, kinds: str, precision,
                     lp_solver, budget, timings: dict) -> list:
    """``[verdict]`` "not interlocked" on the found contacts together with every pair of faces within
    :data:`NEAR_SPREAD` times their blocks' noise, taken as contacts too; ``[]`` when those contacts leave no motion.

    Every motion the noisy input's LP found pushed together faces that may touch (:data:`NEAR_LACKING`).  A motion
    that keeps those faces as well is a motion whether they touch or not (more contacts are more rows of ``A``), so
    the answer stands for the design either way.  The TopoLite bunny with vertex noise 1e-9 to 1e-5 and one part
    fixed: a part comes out, and the first motion found had pushed two blocks within the noise into each other.
    """
    near = find_contacts(assembly, precision=precision, kinds=kinds, noise_spread=NEAR_SPREAD, budget=budget)
    again = _decide(assembly, frame, translational, False, rank_rtol, lp_tol, tuple(found) + tuple(near), False,
                    None, lp_solver, 1, None, budget, {})
    if again.interlocked is not False:
        return []
    return [dataclasses.replace(again, timings=timings,  # the whole call's stages, this one among them
                                status=f"{again.status}; it keeps the faces within {NEAR_SPREAD:g} times the input's "
                                       "vertex noise of each other as well, touching or not")]


def _with_margin(verdict: Verdict, margin: Margin, A: InterlockingMatrix, blocks: int, coarsest=None) -> Verdict:
    """An "interlocked" verdict with its margin: kept above 1, False with a motion within tolerance, else None.

    ``coarsest`` (the largest tolerance of a contact against its size, and that size): where the margin does not
    exceed 1, no motion within tolerance was found and the input's tolerance is at least :data:`COARSE_RATIO` of a
    contact's size, the answer is None, saying that the file's precision is coarser than its blocks' contacts.
    """
    verdict = dataclasses.replace(verdict, margin=margin, tolerances={**verdict.tolerances,
                                                                      "tolerance": margin.tolerance,
                                                                      "tolerance_from": margin.source})
    if margin.lower > 1.0:
        if math.isinf(margin.lower):  # the tolerance is negligible: nothing to state
            return verdict
        return dataclasses.replace(verdict, status=f"{verdict.status}; {margin}")
    if margin.motion is not None and margin.upper <= 1.0:  # followed for real next: shown, or inconclusive
        motion, moving = _motion(A, margin.motion, blocks, reversible=False)
        return dataclasses.replace(
            verdict, interlocked=False, motion=motion, motion_kind="within tolerance", moving=moving,
            status=f"{moving_names(moving)} a first-order motion that keeps every contact within the tolerance "
                   f"{margin.tolerance:.3g} ({margin}); the exact input is interlocked")
    if coarsest is not None and coarsest[0] >= COARSE_RATIO * coarsest[1]:
        return dataclasses.replace(verdict, interlocked=None, status=(
            f"the file's precision {coarsest[0]:.2g} is coarser than its blocks' contacts (one is "
            f"{coarsest[1]:.2g} across; {margin}); the exact input is interlocked ({verdict.status})"))
    return dataclasses.replace(verdict, interlocked=None, status=(
        f"not conclusive within the tolerance {margin.tolerance:.3g}: {margin}; "
        f"the exact input is interlocked ({verdict.status})"))


def _motion(A: InterlockingMatrix, x, blocks: int, reversible: bool):
    """A column vector as per-block twists, normalised to a largest velocity scale of 1, and who moves.

    A kernel motion (``reversible``) is signed so that its largest translation
    component is positive, for reproducible output; an LP motion keeps its sign.
    """
    twists = A.twists(x)
    size = np.maximum(np.linalg.norm(twists[:, :3], axis=1) * A.length_scale, np.linalg.norm(twists[:, 3:], axis=1))
    top = size.max()
    if top > 0:
        twists = twists / top
        size = size / top
    motion = np.zeros((blocks, 6))
    motion[A.free] = twists
    moving = tuple(int(b) for b in A.free[size > MOVING_RTOL])
    flat = motion[:, 3:].ravel()
    if reversible and flat.size and flat[np.argmax(np.abs(flat))] < 0:
        motion = -motion
    return motion, moving
