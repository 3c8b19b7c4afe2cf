"""Second-order blocking of first-order motions: prestress stability of the contact gap functions.

The interlocking matrix ``A`` (Def. 3.3) is the first-order part of the
*gap functions* of the contacts: ``g_k(q) >= 0`` for every admissible pose
``q`` of the free blocks, ``g_k(0) = 0`` and ``grad g_k(0) = A_k``.  When
``A`` has a kernel, the assembly is not infinitesimally interlocked, yet the
blocks may still be unable to move: a first-order motion can be blocked at
second order.  The test here is *prestress stability* (Connelly and
Whiteley, "Second-order rigidity and prestress stability for tensegrity
frameworks", 1996), for unilateral contacts:

Let ``lambda >= 0`` be a stress on gap functions ``g_S`` (``A_S^T lambda = 0``,
``lambda > 0`` on ``S``) and ``Q_k`` the Hessian of ``g_k`` at the pose.  Along
any motion ``q(s) = s x + s^2 y / 2 + ...``

    ``sum_k lambda_k g_k(q(s)) = s^2 / 2 (lambda^T A_S y + sum_k lambda_k Q_k(x, x)) + O(s^3)
    = s^2 / 2 Omega_lambda(x, x) + O(s^3)``,

because ``lambda^T A_S = 0``.  If ``Omega_lambda`` is negative definite on
``ker A_S``, the left side is negative for every small pose ``q != 0`` with
``g_S(q) >= 0`` (such a pose is within ``O(|q|^2)`` of ``ker A_S``), which
is impossible: the pose is isolated, and no set of free blocks can move —
the assembly is *interlocked (second order)*.  :func:`prestress_stability`
looks for such a stress (a cutting-plane LP over the stress cone, exact when
the kernel is one-dimensional).

Only gap functions that are smooth *and necessary* may enter ``S``.  For a
vertex ``X`` of a contact polygon that lies strictly inside block ``Q``'s
face, the material point ``X`` of the other block ``P`` may not cross
``Q``'s face plane (for small motions):

    ``g(q) = (R_Q m) . (x_P(q) - x_Q(q)) / L``,  ``x_B(q) = c_B + R_B (X - c_B) + L tau_B``,  ``R_B = exp([omega_B])``,

with ``m`` the outward normal of ``Q``'s face (pointing into ``P``'s side),
``c_B`` the centroid and ``L`` the model size (the columns of ``A``, see
:func:`~interlock.verify.matrix.interlocking_matrix`).  Its second-order
part, with ``r_B = (X - c_B) / L`` and ``z = (omega_P, tau_P, omega_Q, tau_Q)``, is

    ``Q(z, z) = m.(omega_P x (omega_P x r_P)) - m.(omega_Q x (omega_Q x r_Q))
    + 2 (omega_Q x m).(omega_P x r_P + tau_P - omega_Q x r_Q - tau_Q)``.

A polygon vertex on the boundary of both faces (coinciding corners, crossing
edges) has no single smooth gap function, and is left out.  A contact with
fewer than three vertices (point or segment contacts given by hand) is taken
as block ``j``'s points on block ``i``'s face.

For face-to-face contacts, first-order motions that keep a contact closed are
planar slides of the contact, for which the gap is zero to every order: the
form then vanishes and the test says "not blocked" — which is why point and
edge contacts (n-pods, see ``docs/npod.md``) are where second order matters.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import shapely
from scipy.optimize import linprog

from interlock.blocks.assembly import Assembly
from interlock.errors import InterlockError
from interlock.verify.contacts import DEFAULT_ANGLE_TOL, DEFAULT_CONTACT_RTOL
from interlock.verify.contacts import model_contacts
from interlock.verify.stress import widest_stress

__all__ = ["SecondOrder", "SecondOrderError", "second_order", "prestress_stability", "gap_expansion",
           "SECOND_ORDER_RTOL", "INTERIOR_RTOL", "CUTTING_PLANES", "MAX_COLUMNS"]

#: The form is negative definite when its largest eigenvalue on the kernel is below ``-SECOND_ORDER_RTOL``
#: times the largest (Frobenius) norm of a gap Hessian; no stress makes it so when the cutting-plane bound is above that.
SECOND_ORDER_RTOL = 1e-8
#: A contact vertex is inside a face when farther than this (relative to the model size) from its boundary.
INTERIOR_RTOL = DEFAULT_CONTACT_RTOL
#: Rank tolerance of ``A_S`` (relative to its largest singular value), as :data:`~interlock.verify.check.RANK_RTOL`.
KERNEL_RTOL = 1e-9
#: Most cutting planes (LPs) spent looking for a stress that makes the form negative definite.
CUTTING_PLANES = 60
#: Larger problems (columns: 6 per free block) are not analysed.
MAX_COLUMNS = 1200


class SecondOrderError(InterlockError):
    """Gap constraints that do not fit together (shapes, block indices, non-finite values)."""


@dataclass(frozen=True)
class SecondOrder:
    """The outcome of :func:`second_order` / :func:`prestress_stability`.

    Attributes
    ----------
    blocked : bool or None
        True: a stress makes the second-order form negative definite on the
        kernel, so no set of free blocks can move (interlocked, second order).
        False: no stress on the usable gap functions does (the form has a
        non-negative direction for every stress, within ``rtol``) — which does
        *not* mean that the blocks can move.  None: undecided (tolerance band,
        cutting-plane limit, or too large).
    status : str
        What was found, in words.
    constraints : int
        Gap functions that are smooth and necessary (usable); ``skipped`` polygon
        vertices had none (on the boundary of both faces).
    support : int
        Gap functions carrying the stress (``S``).
    kernel_dimension : int
        ``dim ker A_S``.
    largest_eigenvalue : float or None
        Of ``Omega_lambda`` on ``ker A_S`` for the best stress found (relative to ``scale``).
    bound : float or None
        Lower bound on that eigenvalue over all stresses (from the cutting planes).
    stress : ndarray or None
        ``lambda`` on the usable gap functions, ``sum = 1`` (zero outside ``S``).
    tolerances : dict
    """

    blocked: bool | None
    status: str
    constraints: int = 0
    skipped: int = 0
    support: int = 0
    kernel_dimension: int = 0
    largest_eigenvalue: float | None = None
    bound: float | None = None
    stress: np.ndarray | None = field(default=None, repr=False)
    tolerances: dict = field(default_factory=dict)

    def __str__(self) -> str:
        word = {True: "blocked at second order", False: "not blocked at second order",
                None: "second order undecided"}[self.blocked]
        return f"{word}: {self.status}"

    def to_dict(self) -> dict:
        """JSON-serialisable summary (without the stress vector)."""
        return {"blocked": self.blocked, "status": self.status, "constraints": self.constraints,
                "skipped": self.skipped, "support": self.support, "kernel_dimension": self.kernel_dimension,
                "largest_eigenvalue": self.largest_eigenvalue, "bound": self.bound,
                "tolerances": dict(self.tolerances)}


def gap_expansion(points, normals, point_centres, plane_centres, length_scale: float = 1.0):
    """Gradient and Hessian of point-on-plane gap functions at the pose.

    For each constraint: the material point ``X`` of block ``P`` (centroid
    ``point_centres``) on the face plane of block ``Q`` (centroid
    ``plane_centres``) with outward normal ``m`` (``normals``, pointing into
    ``P``'s side).  Columns ``(omega_P, tau_P, omega_Q, tau_Q)``, lengths over
    ``length_scale``; ``g ~ grad . z + z^T H z / 2`` (module docstring).

    Returns
    -------
    gradients : ndarray (k, 12)
    hessians : ndarray (k, 12, 12), symmetric

    Examples
    --------
    A corner ``(1, 0, 0)`` of a block (centroid ``(0, 0, 1)``) on the floor
    (normal ``+z``).  Lifting the block (``tau_z``) opens the gap at rate 1;
    turning it about the vertical through its centroid (``omega_z``) keeps the
    corner at its height to every order; turning it about the horizontal
    ``x`` axis through its centroid swings the corner, which is below the
    axis, up by ``omega_x^2 / 2``.

    >>> g, H = gap_expansion([[1.0, 0, 0]], [[0, 0, 1.0]], [[0, 0, 1.0]], [[0, 0, -1.0]])
    >>> float(g[0, 5]), float(g[0, 2]), float(H[0, 2, 2]), float(H[0, 0, 0])
    (1.0, 0.0, 0.0, 1.0)
    """
    m = np.asarray(normals, dtype=float).reshape(-1, 3)
    x = np.asarray(points, dtype=float).reshape(-1, 3)
    r_p = (x - np.asarray(point_centres, dtype=float).reshape(-1, 3)) / length_scale
    r_q = (x - np.asarray(plane_centres, dtype=float).reshape(-1, 3)) / length_scale
    gradients = np.hstack([np.cross(r_p, m), m, -np.cross(r_q, m), -m])

    def form(z):  # Q(z, z) per constraint, z of shape (k, 12)
        w_p, t_p, w_q, t_q = z[:, 0:3], z[:, 3:6], z[:, 6:9], z[:, 9:12]
        first = np.cross(w_p, r_p) + t_p - np.cross(w_q, r_q) - t_q
        return (np.einsum("ki,ki->k", m, np.cross(w_p, np.cross(w_p, r_p)))
                - np.einsum("ki,ki->k", m, np.cross(w_q, np.cross(w_q, r_q)))
                + 2 * np.einsum("ki,ki->k", np.cross(w_q, m), first))

    # the matrix of a quadratic form by polarisation: H_ab = (Q(e_a + e_b) - Q(e_a) - Q(e_b)) / 2
    k, unit = len(m), np.eye(12)
    diagonal = np.stack([form(np.broadcast_to(unit[a], (k, 12))) for a in range(12)], axis=1)
    hessians = np.empty((k, 12, 12))
    for a in range(12):
        for b in range(a, 12):
            value = diagonal[:, a] if a == b else (form(np.broadcast_to(unit[a] + unit[b], (k, 12)))
                                                   - diagonal[:, a] - diagonal[:, b]) / 2
            hessians[:, a, b] = hessians[:, b, a] = value
    return gradients, hessians


def prestress_stability(points, normals, point_blocks, plane_blocks, centroids, free, length_scale: float = 1.0,
                        *, rtol: float = SECOND_ORDER_RTOL, skipped: int = 0, budget=None) -> SecondOrder:
    """Is there a stress that makes the second-order form negative definite on the kernel?

    ``points[k]`` is a material point of block ``point_blocks[k]`` on the face
    plane of block ``plane_blocks[k]`` with outward normal ``normals[k]``
    (pointing into the point's block); blocks not in ``free`` are fixed;
    ``centroids`` has a row per block.  Every constraint must be a smooth,
    necessary gap function (see the module docstring).

    1. The stress of largest support on the constraints (an LP): ``S``, ``lambda_0``.
    2. ``K`` = an orthonormal basis of ``ker A_S``; ``Omega_k = K^T H_k K``.
    3. Cutting planes (Kelley) for ``min over lambda of max eig sum_k lambda_k Omega_k`` over the cone
       ``lambda >= 0, A_S^T lambda = 0, sum lambda = 1``: each LP gives a lower bound ``t``; the top
       eigenvector at its ``lambda`` is the next cut.  A negative largest eigenvalue (for a mix with
       ``lambda_0``, so that every constraint of ``S`` is stressed) proves blocking; a bound ``t`` that is
       not negative proves that no stress blocks.

    Examples
    --------
    A block (0) whose two upper faces, with normals meeting at ``O = (0, 0, h)``, ``h = 1``, are held by
    fixed pins at ``x = +-1``, pushed up by pins at ``(0, y, -c)``, ``c = 2``, and held in ``y`` by pins at
    its ends.  The only first-order motion is the turn about the line through ``O`` along ``y``; the
    stressed form on it is proportional to ``1 - h c``, negative here: blocked.

    >>> s = 2 ** -0.5
    >>> pins = [[-1, y, 0] for y in (-.5, .5)] + [[1, y, 0] for y in (-.5, .5)] + [[0, y, -2] for y in (-.5, .5)]
    >>> faces = [[s, 0, s]] * 2 + [[-s, 0, s]] * 2 + [[0, 0, -1]] * 2      # the block's outward normals
    >>> pins += [[x, y, 0] for x in (-.5, .5) for y in (-1, 1)]
    >>> faces += [[0, y, 0] for x in (-.5, .5) for y in (-1, 1)]
    >>> r = prestress_stability(pins, faces, range(1, 11), [0] * 10, np.zeros((11, 3)), free=[0])
    >>> r.blocked, r.kernel_dimension
    (True, 1)
    """
    x = _finite("points", points)
    m = _finite("normals", normals)
    centres = np.asarray(centroids, dtype=float)
    if centres.ndim != 2 or centres.shape[1] != 3 or not np.isfinite(centres).all():
        raise SecondOrderError(f"centroids must be finite, shape (blocks, 3); got shape {centres.shape}")
    p_blocks = np.asarray(point_blocks, dtype=int).ravel()
    q_blocks = np.asarray(plane_blocks, dtype=int).ravel()
    if not (len(x) == len(m) == len(p_blocks) == len(q_blocks)):
        raise SecondOrderError(f"points, normals, point_blocks and plane_blocks need one entry per constraint; "
                               f"got {len(x)}, {len(m)}, {len(p_blocks)}, {len(q_blocks)}")
    blocks = len(centres)
    for name, values in (("point_blocks", p_blocks), ("plane_blocks", q_blocks), ("free", np.asarray(free, int))):
        if values.size and (values.min() < 0 or values.max() >= blocks):
            raise SecondOrderError(f"{name} must index the {blocks} centroids, got values {values.min()}..{values.max()}")
    if np.any(p_blocks == q_blocks):
        raise SecondOrderError("a gap constraint needs two different blocks (a point of one on the other's face)")
    if not length_scale > 0:
        raise SecondOrderError(f"length_scale must be positive, got {length_scale}")
    norms = np.linalg.norm(m, axis=1)
    if np.any(norms == 0):
        raise SecondOrderError("every normal must be non-zero")
    m = m / norms[:, None]
    free = np.unique(np.asarray(free, dtype=int))
    tolerances = {"second_order_rtol": rtol, "kernel_rtol": KERNEL_RTOL, "cutting_planes": CUTTING_PLANES}
    base = dict(constraints=len(x), skipped=skipped, tolerances=tolerances)
    column = np.full(blocks, -1)
    column[free] = np.arange(len(free))
    n = 6 * len(free)
    if n > MAX_COLUMNS:
        return SecondOrder(None, f"too large: {len(free)} free blocks ({n} columns, at most {MAX_COLUMNS})", **base)
    live = (column[p_blocks] >= 0) | (column[q_blocks] >= 0)
    if not live.any():
        return SecondOrder(False, "no usable gap function touches a free block", **base)
    gradients, hessians = gap_expansion(x[live], m[live], centres[p_blocks[live]], centres[q_blocks[live]],
                                        length_scale)
    ends = np.column_stack([column[p_blocks[live]], column[q_blocks[live]]])
    A = _rows(gradients, ends, n)
    widest = widest_stress(A, KERNEL_RTOL)
    stress = widest.stress
    if not widest.support.any():
        return SecondOrder(False, f"no stress on the {len(x)} usable gap functions", **base)
    support = np.flatnonzero(stress > 0)
    A_S = A[support].toarray()
    _, sigma, vt = scipy.linalg.svd(A_S, full_matrices=True)
    sigma = np.concatenate([sigma, np.zeros(n - len(sigma))])
    kernel = vt[sigma <= KERNEL_RTOL * (sigma.max(initial=0.0) or 1.0)].T
    base.update(support=len(support), kernel_dimension=kernel.shape[1])
    full = np.zeros(len(x))
    if kernel.shape[1] == 0:
        full[np.flatnonzero(live)[support]] = stress[support] / stress[support].sum()
        return SecondOrder(True, f"A_S of the {len(support)} stressed gap functions has full rank (first order)",
                           largest_eigenvalue=None, stress=full, **base)
    omegas = _reduced_forms(hessians[support], ends[support], kernel)
    scale = max(float(np.linalg.norm(hessians[support], axis=(1, 2)).max()), 1e-300)  # Frobenius: rotation invariant
    lam, top, bound = _cutting_planes(A_S.T, omegas, stress[support], rtol * scale, budget)
    full[np.flatnonzero(live)[support]] = lam
    found = dict(largest_eigenvalue=top / scale, bound=None if bound is None else bound / scale, stress=full)
    if top < -rtol * scale:
        return SecondOrder(True, f"a stress on {len(support)} gap functions makes the second-order form negative "
                                 f"definite on the {kernel.shape[1]}-dimensional kernel (largest eigenvalue "
                                 f"{top / scale:.3g})", **base, **found)
    if bound is not None and bound >= -rtol * scale:
        return SecondOrder(False, f"no stress makes the form negative definite on the {kernel.shape[1]}-dimensional "
                                  f"kernel (its largest eigenvalue is at least {bound / scale + 0.0:.3g} for every stress)",
                           **base, **found)
    bound_text = "no bound (the cutting-plane LP failed)" if bound is None else f"the bound {bound / scale:.3g}"
    return SecondOrder(None, f"after at most {CUTTING_PLANES} cutting planes the best largest eigenvalue is "
                             f"{top / scale:.3g} and {bound_text}: undecided within the tolerance", **base, **found)


def second_order(assembly: Assembly, frame=None, *, contacts=None, rtol: float = SECOND_ORDER_RTOL,
                 interior_rtol: float = INTERIOR_RTOL, budget=None) -> SecondOrder:
    """Prestress stability of an assembly's contacts (module docstring): is every first-order motion blocked?

    Each contact-polygon vertex strictly inside one block's face (farther than
    ``interior_rtol`` times the model size from its boundary) gives the gap
    function of the other block's material point on that face; vertices on
    the boundary of both faces are skipped (counted in ``skipped``), and so
    are point contacts other than a corner inside a face (edge-edge crossings
    and cones of normals: no gap function of a point on a face).  ``budget``
    (:class:`~interlock.verify.budget.Budget`): checked between the cutting
    planes ("beyond"), its time left given to every LP.

    Examples
    --------
    A cube squeezed between a fixed floor and ceiling slides: the form vanishes on the slides.

    >>> import trimesh
    >>> floor = trimesh.creation.box(bounds=[[-2, -2, -1], [2, 2, 0]])
    >>> ceiling = trimesh.creation.box(bounds=[[-2, -2, 1], [2, 2, 2]])
    >>> cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    >>> r = second_order(Assembly.from_meshes([floor, ceiling, cube]), frame=[0, 1])
    >>> r.blocked, r.constraints, r.kernel_dimension
    (False, 8, 3)
    """
    if not isinstance(assembly, Assembly):
        raise SecondOrderError(f"second_order needs an Assembly, got {type(assembly).__name__}")
    fixed = set(assembly.frame if frame is None else assembly.block_indices(frame, "frame"))
    free = [b for b in range(len(assembly)) if b not in fixed]
    found = model_contacts(assembly, contacts)
    points, normals, p_blocks, q_blocks, skipped = _gap_constraints(assembly, found, set(free), interior_rtol)
    if budget is not None:
        budget.check("beyond")
    result = prestress_stability(points, normals, p_blocks, q_blocks, assembly.centroids, free, assembly.scale,
                                 rtol=rtol, skipped=skipped, budget=budget)
    result.tolerances["interior_rtol"] = interior_rtol
    return result


# --- gap functions of an assembly ------------------------------------------------------------------


def _gap_constraints(assembly: Assembly, found, free: set, interior_rtol: float):
    """(points, normals, point blocks, plane blocks, skipped vertices) of the usable gap functions."""
    scale = assembly.scale
    tol = interior_rtol * scale
    meshes = {}
    points, normals, p_blocks, q_blocks, skipped = [], [], [], [], 0
    for c in found:
        if c.i not in free and c.j not in free:
            continue
        vertices = np.asarray(c.vertices, dtype=float)
        if c.kind == "vertex-face" and c.normals is None:  # a corner of one block strictly inside the other's face
            on_i = c.facet_i >= 0  # the face is block i's: the corner is block j's
            inside_i, inside_j = np.array([on_i]), np.array([not on_i])
        elif c.kind != "face":  # edge-edge, vertex-edge, vertex-vertex: no gap function of a point on a face
            skipped += len(vertices)
            continue
        elif len(vertices) < 3:  # point or segment contact given by hand: block j's points on block i's face
            inside_i, inside_j = np.ones(len(vertices), bool), np.zeros(len(vertices), bool)
        else:
            for b in (c.i, c.j):
                if b not in meshes:
                    meshes[b] = assembly.mesh(b)
            xy = shapely.points((vertices - c.origin) @ np.asarray(c.basis).T)
            inside_i = _inside(_face_region(meshes[c.i], c, 1.0, tol), xy, tol)
            inside_j = _inside(_face_region(meshes[c.j], c, -1.0, tol), xy, tol)
        for inside, point_block, plane_block, sign in ((inside_i, c.j, c.i, 1.0), (inside_j, c.i, c.j, -1.0)):
            points.append(vertices[inside])
            normals.append(np.broadcast_to(sign * np.asarray(c.normal, float), (int(inside.sum()), 3)))
            p_blocks.append(np.full(int(inside.sum()), point_block))
            q_blocks.append(np.full(int(inside.sum()), plane_block))
        skipped += int((~inside_i & ~inside_j).sum())
    if not points:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int), np.zeros(0, int), skipped
    return (np.vstack(points), np.vstack(normals), np.concatenate(p_blocks), np.concatenate(q_blocks), skipped)


def _face_region(mesh, contact, side: float, tol: float):
    """The union of ``mesh``'s triangles in the contact plane facing ``side * normal``, in plane coordinates."""
    normal = side * np.asarray(contact.normal, dtype=float)
    triangles = mesh.triangles
    offsets = (triangles - contact.origin) @ np.asarray(contact.normal, dtype=float)
    on_plane = (mesh.face_normals @ normal > np.cos(DEFAULT_ANGLE_TOL)) & (
        np.abs(offsets).max(axis=1) <= tol + contact.separation)
    flat = (triangles[on_plane] - contact.origin) @ np.asarray(contact.basis).T
    return shapely.union_all(shapely.buffer(shapely.polygons(flat), 0.0))


def _inside(region, xy, tol: float) -> np.ndarray:
    """Points of ``xy`` inside ``region`` and farther than ``tol`` from its boundary."""
    return shapely.contains(region, xy) & (shapely.distance(shapely.boundary(region), xy) > tol)


# --- numerics ----------------------------------------------------------------------------------------


def _rows(gradients, ends, n) -> sp.csr_matrix:
    """The gradients as rows over the free blocks' columns (fixed blocks' parts dropped)."""
    k = len(gradients)
    data, rows, cols = [], [], []
    for part, block_column in ((gradients[:, :6], ends[:, 0]), (gradients[:, 6:], ends[:, 1])):
        on = block_column >= 0
        data.append(part[on].ravel())
        rows.append(np.repeat(np.flatnonzero(on), 6))
        cols.append((6 * block_column[on][:, None] + np.arange(6)).ravel())
    return sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(k, n))


def _reduced_forms(hessians, ends, kernel) -> np.ndarray:
    """``Omega_k = Z_k^T H_k Z_k`` with ``Z_k`` the kernel's rows of constraint k's two blocks."""
    d = kernel.shape[1]
    padded = np.vstack([kernel, np.zeros((6, d))])  # row block -1 (a fixed block) reads zeros
    index = np.where(ends[:, :, None] >= 0, 6 * ends[:, :, None] + np.arange(6), len(kernel) + np.arange(6))
    Z = padded[index.reshape(len(ends), 12)]  # (k, 12, d)
    return np.einsum("kad,kab,kbe->kde", Z, hessians, Z)


def _cutting_planes(A_T: np.ndarray, omegas: np.ndarray, start: np.ndarray, tol: float, budget=None):
    """``(lambda, largest eigenvalue at lambda, lower bound over all stresses)`` (Kelley's method).

    ``budget`` (:class:`~interlock.verify.budget.Budget`): checked before each cut ("beyond"), its time left
    given to each LP."""
    k, d, _ = omegas.shape
    start = start / start.sum()
    cuts = [np.eye(d)[i] for i in range(d)] + list(np.linalg.eigh(np.einsum("k,kde->de", start, omegas))[1].T)
    best_lam, best_top, bound = start, np.linalg.eigvalsh(np.einsum("k,kde->de", start, omegas))[-1], None
    A_eq = np.vstack([np.hstack([A_T, np.zeros((A_T.shape[0], 1))]), np.r_[np.ones(k), 0.0]])
    b_eq = np.r_[np.zeros(A_T.shape[0]), 1.0]
    for _ in range(CUTTING_PLANES):
        options = {}
        if budget is not None:
            budget.check("beyond")
            if budget.solver_limit() is not None:
                options["time_limit"] = budget.solver_limit()
        values = np.array([np.einsum("d,kde,e->k", v, omegas, v) for v in cuts])
        result = linprog(np.r_[np.zeros(k), 1.0], A_ub=np.hstack([values, -np.ones((len(cuts), 1))]),
                         b_ub=np.zeros(len(cuts)), A_eq=A_eq, b_eq=b_eq,
                         bounds=[(0, None)] * k + [(None, None)], method="highs", options=options)
        if result.status != 0:
            break
        lam, bound = result.x[:k], float(result.x[k])
        # a little of the widest stress keeps every constraint of S stressed (definiteness is an open condition)
        mixed = 0.999 * lam + 0.001 * start
        eigenvalues, vectors = np.linalg.eigh(np.einsum("k,kde->de", mixed, omegas))
        if eigenvalues[-1] < best_top:
            best_lam, best_top = mixed, float(eigenvalues[-1])
        if best_top < -tol or bound >= -tol:
            break
        cuts.append(vectors[:, -1])
    return best_lam, float(best_top), bound


def _finite(name, values) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.size == 0:
        return array.reshape(0, 3)
    if array.ndim != 2 or array.shape[1] != 3 or not np.isfinite(array).all():
        raise SecondOrderError(f"{name} must be finite 3D vectors, shape (k, 3); got shape {array.shape}")
    return array
