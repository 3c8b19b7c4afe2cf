"""Whether a first-order motion of the contact model also moves the real blocks: bent faces and missed contacts.

:func:`~interlock.verify.check.check` finds its motions on a set of
:class:`~interlock.blocks.contact.Contact` polygons.  Two things can make
such a motion a property of the model and not of the blocks:

- a contact whose facets the tolerances merged from triangles bent by a
  small angle stands for several planes; a motion that slides along it may
  be blocked by the real bend (:func:`unless_bent`);
- contacts given by the caller, found with tolerances below the input's
  noise, miss faces that really touch; a motion that pushes into one of them
  is no motion at all (:func:`unless_missed`);
- a vertex-edge, vertex-vertex or parallel-edge touch admits a cone of
  normals, which gives no row of ``A``; a motion that presses into it along
  every normal of the cone is no motion either (:func:`unless_cones`).

Either way the verdict becomes inconclusive (``interlocked`` None) and says
why (docs/interlocking.md, "Margin and tolerance").
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp

from interlock.verify.first_order import matrix_rank
from interlock.verify.margin import BEND_FACTOR, EXACT_RTOL, row_tolerances
from interlock.verify.matrix import InterlockingMatrix, interlocking_matrix

__all__ = ["moving_names", "rigid_across_bends", "unless_bent", "unless_missed", "unless_cones", "cone_pressure",
           "cone_search", "bent_contacts", "MOVING_RTOL", "CONE_BRANCHES", "CONE_RANK_RTOL", "CONE_LP_TOL"]

#: Blocks whose twist is below this fraction of the largest one do not move.
MOVING_RTOL = 1e-6


def moving_names(blocks) -> str:
    """'block 4 has' / 'blocks 0, 1 and 2 have' (at most 8 listed).

    >>> moving_names([4]), moving_names(range(10))
    ('block 4 has', 'blocks 0, 1, 2, 3, 4, 5, 6, 7 and 2 more have')
    """
    blocks = list(blocks)
    if len(blocks) == 1:
        return f"block {blocks[0]} has"
    shown = ", ".join(map(str, blocks[:8]))
    more = f" and {len(blocks) - 8} more" if len(blocks) > 8 else ""
    return f"blocks {shown}{more} have"


def bent_contacts(contacts, tolerance) -> np.ndarray:
    """Per contact: its faces are planar only within the contact tolerances, and bent by more than ``tolerance``.

    Faces bent by no more than the input's tolerance (a length, or one per
    contact) are planar as far as the input can tell (float32 rounding bends
    every face a little).
    """
    limits = np.broadcast_to(np.asarray(tolerance, dtype=float), (len(contacts),))
    return np.array([not c.planar and c.deviation > t for c, t in zip(contacts, limits)], dtype=bool)


def rigid_across_bends(A: InterlockingMatrix, kernel: np.ndarray, bent, centroids) -> np.ndarray:
    """The kernel motions that move no block relative to its neighbour across a bent contact (orthonormal columns).

    Such a motion keeps the real faces of a bent contact together whatever
    their bend, so it is a sliding motion of the real assembly too.  Two
    blocks move as one rigid body when their twists agree as motions of
    space: the same ``omega``, and translations about the two centroids that
    differ by ``omega x (c_j - c_i)``; a free block against a fixed one stands still.
    """
    if not len(bent) or not kernel.shape[1]:
        return kernel
    size = A.block_size
    column = {int(b): size * k for k, b in enumerate(A.free)}
    entries = []  # (equation, column, coefficient); equation e says sum coefficient * x[column] = 0
    for c in bent:
        i, j = column.get(c.i), column.get(c.j)
        if i is None and j is None:
            continue
        first = len(entries) and entries[-1][0] + 1
        for k in range(size):
            entries += [(first + k, col + k, sign) for col, sign in ((j, 1.0), (i, -1.0)) if col is not None]
        if i is not None and j is not None and not A.translational:
            # t_j - t_i = omega_i x (c_j - c_i), lengths over the model size: -(omega x arm) = arm x omega
            arm_x = np.cross(np.eye(3), (centroids[c.j] - centroids[c.i]) / A.length_scale)
            entries += [(first + 3 + r, i + q, arm_x[r, q]) for r in range(3) for q in range(3)]
    if not entries:
        return kernel
    equation, col, value = np.array(entries).T
    C = sp.csr_matrix((value, (equation.astype(int), col.astype(int))), shape=(int(equation.max()) + 1, A.shape[1]))
    _, sigma, vt = scipy.linalg.svd(np.atleast_2d(C @ kernel))
    sigma = np.concatenate([sigma, np.zeros(kernel.shape[1] - len(sigma))])
    return kernel @ vt[sigma <= MOVING_RTOL].T


def unless_bent(verdict, A: InterlockingMatrix, found, bent, centroids):
    """The "not interlocked" verdict, or an inconclusive one when its motion slides across a bent contact.

    ``bent`` flags the contacts of ``found`` (:func:`bent_contacts`).  A
    contact whose facets the tolerances merged from triangles bent by a small
    angle stands for several planes, the model for one.  A motion that keeps
    such a contact closed while one block moves along the other is admissible
    for the model, but the real bend may block it (a fold of any angle stops a
    slide across it): floating point cannot tell, so the verdict becomes
    None, naming the contacts.  A motion that opens the contact, or moves both
    blocks together, stays conclusive.
    """
    rows = np.flatnonzero(np.asarray(bent, dtype=bool)[A.row_contact])
    opening = np.asarray(A.matrix @ A.columns(verdict.motion[A.free]))
    if verdict.motion_kind == "opening":
        rows = rows[opening[rows] <= MOVING_RTOL * opening.max()]
    contacts = [found[c] for c in A.row_contact[rows]]
    points = np.array([c.vertices[v] for c, v in zip(contacts, A.row_vertex[rows])]).reshape(-1, 3)
    ends = np.array([(c.i, c.j) for c in contacts], dtype=int).reshape(-1, 2)
    motion = verdict.motion
    velocity = [np.cross(motion[b, :3], points - centroids[b]) + motion[b, 3:] for b in ends.T]
    sliding = np.linalg.norm(velocity[1] - velocity[0], axis=1) > MOVING_RTOL if len(rows) else np.zeros(0, bool)
    across = sorted(set(A.row_contact[rows[sliding]].tolist()))
    if not across:
        return verdict
    worst = max((found[c] for c in across), key=lambda c: c.deviation)
    return dataclasses.replace(verdict, interlocked=None, status=(
        f"floating point is not conclusive: {moving_names(verdict.moving)} a first-order {verdict.motion_kind} "
        f"motion, but it slides across {len(across)} contact(s) whose faces are planar only within the contact "
        f"tolerances (blocks {worst.i}-{worst.j}: faces bent by up to {worst.deviation:.3g}, "
        f"{worst.deviation / A.length_scale:.3g} x model size), which the real faces may block; smaller contact "
        "tolerances (contacts(..., rtol=, angle_tol=)) keep such faces apart"))


def unless_missed(verdict, assembly, reference, tolerance: float, lacking: str | None = None):
    """The "not interlocked" verdict found on the caller's contacts, or None where the ``reference`` contacts block it.

    ``reference`` are the contacts of the default search
    (:func:`~interlock.verify.contacts.contacts`), at least those of the
    moving blocks (``involving=verdict.moving``: the others do not move
    relative to each other).  Contacts found with
    tolerances below the noise of the input miss faces that touch: the
    triangles of a noisy face pair are then neither coplanar nor parallel
    within the tolerance, and a block without its contacts is free.  The
    motion ``x`` (scaled to ``max |x| = 1``) must therefore also satisfy
    ``(A_ref x)_r >= -eps_r`` on every reference row, with ``eps_r`` of
    :func:`~interlock.verify.margin.row_tolerances` for the length
    ``max(tolerance, BEND_FACTOR * deviation)`` of the row's contact, and
    must not slide across a reference contact bent beyond ``tolerance``
    (:func:`unless_bent`).  Otherwise the verdict is None, naming the pair and ``lacking``: why the verdict's
    contacts lack that one (default: the caller's contacts, with tolerances below the input's noise).
    """
    A = interlocking_matrix(assembly, verdict.frame, verdict.translational, contacts=reference)
    if not A.shape[0] or not len(A.free):
        return verdict
    x = A.columns(verdict.motion[A.free])
    top = float(np.abs(x).max(initial=0.0))
    if top == 0:
        return verdict
    deviation = np.array([c.deviation for c in reference], dtype=float)
    eps = row_tolerances(A, reference, np.maximum(tolerance, BEND_FACTOR * deviation))
    pushed = -(A.matrix @ (x / top)) / eps
    worst = int(np.argmax(pushed))
    if pushed[worst] > 1.0:
        contact = reference[A.row_contact[worst]]
        pairs = len({(reference[c].i, reference[c].j) for c in A.row_contact[pushed > 1.0]})
        lacking = lacking or ("where the default contact search finds a contact that the given contacts lack: "
                              "their tolerances are below the input's noise; use the default contacts or larger "
                              "rtol/angle_tol")
        return dataclasses.replace(verdict, interlocked=None, status=(
            f"floating point is not conclusive: {moving_names(verdict.moving)} a first-order "
            f"{verdict.motion_kind} motion, but it pushes blocks {contact.i} and {contact.j} into each other "
            f"({pushed[worst]:.3g} x the tolerance; {pairs} block pair(s) in all) {lacking}"))
    return unless_bent(verdict, A, reference, bent_contacts(reference, tolerance), assembly.centroids)


def cone_pressure(motion, found, centroids) -> np.ndarray:
    """Per contact of ``found``: how far ``motion`` presses into it along its least pressed admissible normal.

    ``motion`` is one world twist ``(omega, t)`` per block about its centroid.
    For a contact with normals ``n_k`` (its cone, or its one normal) at the
    point ``p``, the value is ``-max_k n_k . (v_j(p) - v_i(p))``: positive when
    every admissible normal sees block ``j`` move into block ``i``, which no
    admissible motion does to first order (main paper Remark 3.11).
    """
    motion = np.asarray(motion, dtype=float)
    out = np.zeros(len(found))
    for k, c in enumerate(found):
        p = np.asarray(c.vertices, dtype=float)[0]
        v = [np.cross(motion[b, :3], p - centroids[b]) + motion[b, 3:] for b in (c.i, c.j)]
        normals = np.asarray(c.normal if c.normals is None else c.normals, dtype=float).reshape(-1, 3)
        out[k] = -float((normals @ (v[1] - v[0])).max())
    return out


def unless_cones(verdict, found, centroids, A: InterlockingMatrix | None = None, budget=None):
    """The "not interlocked" verdict, or one decided over the cones of normals its motion presses into.

    A vertex-edge, vertex-vertex or parallel-edge touch admits a cone of
    normals (:attr:`~interlock.blocks.contact.Contact.normals`): to first
    order, some normal of the cone must see the blocks part or slide, which
    is no linear row of ``A``.  A motion of ``A`` that presses the blocks
    together along every normal of such a cone (by more than
    :data:`MOVING_RTOL` of the motion) is no first-order motion of the
    blocks.  A sliding motion may be reversed; when its reverse presses into
    no cone it is the answer.  Otherwise, given ``A``, :func:`cone_search`
    decides: a motion that presses into no cone (False, with it), none in any
    branch (True: infinitesimally interlocked with the cones), or too many
    branches (None, naming the contact).
    """
    cones = [c for c in found if c.normals is not None and c.kind != "face"]
    if verdict.motion is None or not cones:
        return verdict
    pressure = cone_pressure(verdict.motion, cones, centroids)
    if pressure.max() <= MOVING_RTOL:
        return verdict
    if verdict.motion_kind == "sliding" and cone_pressure(-verdict.motion, cones, centroids).max() <= MOVING_RTOL:
        return dataclasses.replace(verdict, motion=-verdict.motion)
    worst = cones[int(np.argmax(pressure))]
    pressed = int((pressure > MOVING_RTOL).sum())
    undecided = (f"floating point is not conclusive: {moving_names(verdict.moving)} a first-order "
                 f"{verdict.motion_kind} motion of the rows of A, but it presses into {pressed} {worst.kind} "
                 f"contact(s) along every admissible normal (blocks {worst.i}-{worst.j}: a cone of "
                 f"{len(worst.normals)} normals, which gives no row of A)")
    if A is None:
        return dataclasses.replace(verdict, interlocked=None, status=undecided + "; other motions were not searched")
    found_motion, kind, solves = cone_search(A, cones, centroids, budget=budget)
    if kind == "undecided":
        return dataclasses.replace(verdict, interlocked=None, status=(
            f"{undecided}; {solves} branches over the cones' normals did not decide (at most {CONE_BRANCHES})"))
    if kind == "none":
        proof = (f"no first-order motion: the rows of A leave motions, but each presses into a contact whose "
                 f"admissible normals are a cone ({len(cones)} such contacts; {solves} branches over their normals, "
                 "every one without a motion)")
        rounding = max((c.tolerance or 0.0 for c in found), default=0.0)
        if rounding > EXACT_RTOL * A.length_scale:  # no stress of A, so no margin against the input's rounding
            return dataclasses.replace(verdict, interlocked=None, status=(
                f"floating point is not conclusive: the exact input is interlocked ({proof}), but no margin against "
                f"the input's rounding ({rounding:.3g}) is assessed for a verdict decided over cones of normals"))
        return dataclasses.replace(verdict, interlocked=True, motion=None, motion_kind=None, moving=(), stress=None,
                                   status=proof)
    motion, moving = found_motion
    opening = kind == "opening"
    return dataclasses.replace(verdict, interlocked=False, motion=motion, moving=moving, motion_kind=kind, status=(
        f"{moving_names(moving)} a first-order motion that {'opens' if opening else 'keeps every'} contact"
        f"{'s' if opening else ''} and presses into none of the {len(cones)} contacts whose admissible normals are "
        f"a cone (found in {solves} branches over their normals)"))


#: At most this many branches (linear programs) over the normals of cone contacts (:func:`cone_search`); beyond,
#: the verdict stays inconclusive.  Each branch adds one normal of one pressed cone as a row.
CONE_BRANCHES = 256
#: The rank tolerance of the branches' matrices (relative to their largest singular value): that of ``check``.
CONE_RANK_RTOL = 1e-9
#: A branch's motion LP value above this opens a contact: ``check``'s LP tolerance.
CONE_LP_TOL = 1e-7


def cone_search(A: InterlockingMatrix, cones, centroids, budget=None, limit: int = CONE_BRANCHES):
    """A first-order motion of ``A`` that presses into none of the ``cones``, or a proof that there is none.

    Non-penetration at a contact with a cone of admissible normals
    ``n_1 .. n_k`` says ``max_k n_k . (v_j - v_i) >= 0``: a union of ``k``
    half-spaces.  The motions are searched branch by branch: a motion of the
    current rows (the motion LP ``max 1^T A' x, 0 <= A' x <= 1``, else the
    kernel of ``A'``) that presses into no cone is the answer; otherwise the
    most pressed cone is split, one branch per normal, each adding that
    normal's row.  The branches cover the union exactly, so when every
    branch ends without a motion, ``{x : A x >= 0, every cone kept} = {0}``.

    Returns
    -------
    ((motion, moving) or None, kind, branches)
        ``kind`` is ``"opening"`` or ``"sliding"`` (a motion: one twist per
        block, scaled so that ``max(|omega| L, |t|) = 1``), ``"none"`` (no
        motion in any branch) or ``"undecided"`` (more than ``limit``
        branches).
    """
    rows = [_cone_rows(A, c, centroids) for c in cones]
    stack = [sp.csr_matrix((0, A.shape[1]))]
    solves = 0
    while stack:
        if solves >= limit:
            return None, "undecided", solves
        if budget is not None:
            budget.check("lp")
        extra = stack.pop()
        solves += 1
        matrix = sp.vstack([A.matrix, extra]).tocsr()
        x, kind = _some_motion(matrix, budget)
        if x is None:
            continue
        candidates = [x] + ([-x] if kind == "sliding" else [])
        pressure = [np.array([-(r @ y).max() for r in rows]) for y in candidates]
        for y, p in zip(candidates, pressure):
            if p.max() <= MOVING_RTOL * np.abs(y).max():
                return _as_motion(A, y, len(centroids)), kind, solves
        worst = int(np.argmax(pressure[0]))
        order = np.argsort(rows[worst] @ x)  # the least pressed normal last: tried first
        for k in order:
            stack.append(sp.vstack([extra, sp.csr_matrix(rows[worst][k])]))
    return None, "none", solves


def _cone_rows(A: InterlockingMatrix, contact, centroids) -> np.ndarray:
    """One row of ``A``'s kind per normal of the contact's cone (dense, over ``A``'s columns)."""
    size = A.block_size
    column = {int(b): k for k, b in enumerate(A.free)}
    p = np.asarray(contact.vertices, dtype=float)[0]
    out = np.zeros((len(contact.normals), A.shape[1]))
    for n_index, n in enumerate(np.asarray(contact.normals, dtype=float)):
        for b, sign in ((contact.i, -1.0), (contact.j, 1.0)):
            k = column.get(int(b))
            if k is None:
                continue
            if A.translational:
                out[n_index, size * k:size * k + 3] = sign * n
            else:
                r = (p - centroids[b]) / A.length_scale
                out[n_index, size * k:size * k + 6] = sign * np.r_[np.cross(r, n), n]
    return out


def _some_motion(matrix, budget=None):
    """A non-zero ``x`` with ``matrix x >= 0``: opening by the motion LP, else a kernel vector; (None, None)."""
    m, n = matrix.shape
    if n == 0:
        return None, None
    if m:
        options = {}
        if budget is not None and budget.solver_limit() is not None:
            options["time_limit"] = budget.solver_limit()
        result = scipy.optimize.linprog(-np.asarray(matrix.sum(axis=0)).ravel(), A_ub=sp.vstack([-matrix, matrix]),
                                        b_ub=np.r_[np.zeros(m), np.ones(m)], bounds=(None, None), method="highs-ds",
                                        options=options)
        if result.status == 0 and -result.fun > CONE_LP_TOL:
            return result.x, "opening"
    rank, kernel, _ = matrix_rank(matrix, CONE_RANK_RTOL, budget)
    if kernel.shape[1]:
        return kernel[:, 0], "sliding"
    return None, None


def _as_motion(A: InterlockingMatrix, x, count: int):
    """A column vector as one twist per block (zero for fixed ones), scaled, and the blocks it moves."""
    twists = A.twists(x)
    size = np.maximum(np.abs(twists[:, :3]).max(axis=1) * A.length_scale, np.abs(twists[:, 3:]).max(axis=1))
    twists = twists / size.max()
    motion = np.zeros((count, 6))
    motion[A.free] = twists
    moving = tuple(int(b) for b, s in zip(A.free, size) if s > MOVING_RTOL * size.max())
    return motion, moving
