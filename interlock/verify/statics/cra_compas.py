"""Candidate CRA motions from the optional upstream package compas_cra (its local IPOPT solve of problem (11))."""

from __future__ import annotations

import contextlib
import io
import numpy as np

from interlock.blocks.assembly import Assembly
from interlock.verify.statics.equilibrium import (DEFAULT_EPS, DEFAULT_ETA, StabilityError, block_densities,
                                                  gravity_vector, nonnegative, positive)
from interlock.verify.statics.interfaces import statics_contacts

__all__ = ["upstream_motion", "upstream_solution", "MISSING_MESSAGE", "UPSTREAM_VERSION"]

#: The compas_cra release whose conventions this module follows.
UPSTREAM_VERSION = "0.8.0"
#: The error when compas_cra does not import.
MISSING_MESSAGE = (f"compas_cra is not installed: pip install compas_cra=={UPSTREAM_VERSION} "
                   f"(optional, for cra(..., backend='compas_cra'))")


def upstream_motion(assembly, mu: float, gravity=(0.0, 0.0, -1.0), density=1.0, frame=None,
                    eps: float = DEFAULT_EPS, eta: float = DEFAULT_ETA, contacts=None) -> np.ndarray | None:
    """A virtual motion of the free blocks from compas_cra's local solution of (11), or ``None``.

    compas_cra (Kao et al. 2022) solves the CRA problem (11) locally with IPOPT
    (``compas_cra.equilibrium.cra_solve``).  Its solution holds a virtual
    displacement per free block; here it is only a *candidate*: pass it to
    the exact LP of :mod:`interlock.verify.statics.cra` (``CRAProblem.exact``) before
    trusting it.  The upstream model is built from *our* data, so that the
    two models agree vertex by vertex:

    - one upstream block per block (``Block.from_vertices_and_faces`` of the
      world mesh, so its ``volume()`` and ``center()`` (centre of mass) are
      ours); the frame blocks are upstream's supports;
    - one upstream interface per :class:`~interlock.verify.contacts.Contact`
      ``c`` with a free block, on the graph edge ``(c.i, c.j)``, with
      ``c.vertices`` as points and the frame ``(c.basis[0], c.basis[1],
      c.normal)`` (upstream's ``xaxis, yaxis, zaxis``).  Upstream's ``A_eq``
      puts the force on the edge's second block and its negative on the
      first, as ours does on ``j`` and ``i``; upstream's interface search is
      not used.

    Conventions found in compas_cra 0.8's source (``equilibrium/cra_helper.py``,
    ``cra_nlp.py``, ``cra_native.py``):

    - the load is ``p = (0, 0, -density * volume, 0, 0, 0)`` per free block at
      its centre of mass, so gravity is along ``-z``.  For another ``gravity``
      the model is turned by the rotation ``R`` with ``R g / |g| = (0, 0, -1)``
      (meshes, contact vertices and frames), the density is multiplied by
      ``|g|``, and the motion is turned back with ``R^T``;
    - the displacement of free block ``b`` (node attribute ``displacement``)
      is ``q_b = (t, omega)`` and the relative displacements are
      ``dd = A_eq^T q`` with ``A_eq``'s moment rows ``r x e`` about the
      centre of mass, not scaled: ``t`` is the translation of the centre of
      mass (model units) and ``omega`` the small rotation (radians) about it,
      the point ``x`` of the block moving by ``t + omega x (x - centre)``.
      ``dd_n < 0`` closes a contact; ``dd_n >= -eps`` and
      ``|dd| <= d_bnd`` componentwise, with absolute ``eps`` and ``d_bnd``;
    - friction uses the eight-sided pyramid with faces tangent to the
      Coulomb cone (our ``cone="paper"``, ``sides=8``).

    Parameters
    ----------
    assembly : Assembly
    mu : float
        Friction coefficient, ``>= 0``.
    gravity : array (3,)
        Gravity direction and magnitude, not zero.
    density : float or array (n,)
        Weight per volume; one value or one per block.
    frame : iterable of int, optional
        Fixed blocks; default ``assembly.frame``.
    eps, eta : float
        Overlap and displacement bound as fractions of ``assembly.scale``
        (upstream's ``eps`` and ``d_bnd`` are ``eps * scale`` and ``eta * scale``);
        ``0 < eps < eta``.  The defaults are :func:`~interlock.verify.statics.cra.cra`'s
        (upstream's own are ``1e-4`` and ``1e-3`` absolute).
    contacts : sequence of Contact, "interfaces" or "exact", optional
        As for :func:`~interlock.verify.statics.rbe` (default: the interfaces of
        :func:`~interlock.verify.statics.interfaces.interfaces`).

    Returns
    -------
    ndarray (f, 6) or None
        One row ``(t_x, t_y, t_z, omega_x, omega_y, omega_z)`` per free block
        in increasing block order (translation of the centre of mass and
        rotation about it, world units and radians, as
        :attr:`~interlock.verify.statics.cra.CRAResult.motion`); ``None`` when IPOPT
        fails (not optimal or acceptable), the problem is empty (free blocks
        but no contacts) or the answer is not finite.

    Raises
    ------
    StabilityError
        compas_cra is missing (:data:`MISSING_MESSAGE`); bad ``mu``,
        ``gravity``, ``density``, ``eps``, ``eta``; no frame; not an assembly.

    See Also
    --------
    interlock.verify.statics.cra.cra : decides (11) globally; its exact LP checks a motion.

    Notes
    -----
    One IPOPT solve of upstream's sparse NLP with ``4 s + 6 f`` unknowns for
    ``s`` contact vertices and ``f`` free blocks (upstream's tolerances and
    iteration cap).  A local solver: ``None`` proves nothing, and a motion
    proves nothing until our exact LP accepts it.

    Examples
    --------
    A cube on a fixed cube sinks into it by ``eps``:

    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> stack = Assembly.from_meshes(cubes, frame=[0])
    >>> motion = upstream_motion(stack, mu=0.5)  # doctest: +SKIP
    >>> motion.shape, bool(motion[0, 2] < 0)  # doctest: +SKIP
    ((1, 6), True)
    """
    solution = upstream_solution(assembly, mu, gravity, density, frame, eps, eta, contacts)
    return None if solution is None else solution[0]


def upstream_solution(assembly, mu: float, gravity=(0.0, 0.0, -1.0), density=1.0, frame=None,
                      eps: float = DEFAULT_EPS, eta: float = DEFAULT_ETA, contacts=None):
    """compas_cra's motion and contact forces, ``(motion, forces)``, or ``None``; see :func:`upstream_motion`.

    ``motion`` is :func:`upstream_motion`'s.  ``forces`` (s, 3) are upstream's
    ``(c_np, c_u, c_v)`` per contact vertex, acting on block ``j`` in the
    contact's frame ``(normal, basis[0], basis[1])``, with the vertices in the
    order of :class:`~interlock.verify.statics.cra.CRAResult` (the contacts with a
    free block, in the order given, each contact's vertices in order), in the
    units of the load ``density * volume * |gravity|``.  They fix the active
    set and the friction directions, e.g. for ``CRAProblem.realise``.
    """
    try:
        from compas.geometry import Frame
        from compas_assembly.datastructures import Block, Interface
        from compas_cra.datastructures import CRA_Assembly
        from compas_cra.equilibrium import cra_solve
    except ImportError:
        raise StabilityError(MISSING_MESSAGE) from None

    if not isinstance(assembly, Assembly):
        raise StabilityError(f"expected an interlock Assembly, got {type(assembly).__name__}")
    mu = nonnegative("mu", mu)
    g = gravity_vector(gravity)
    densities = block_densities(density, len(assembly))
    eps, eta = positive("eps", eps), positive("eta", eta)
    if not eps < eta:
        raise StabilityError(f"eps (overlap) must be smaller than eta (displacement bound), got {eps} >= {eta}")
    fixed = assembly.block_indices(assembly.frame if frame is None else frame, "frame")
    if not fixed:
        raise StabilityError("the assembly has no frame: give the fixed blocks (supports) with frame=[...]")
    free = np.setdiff1d(np.arange(len(assembly)), fixed)
    if not len(free):
        return np.zeros((0, 6)), np.zeros((0, 3))
    found = statics_contacts(assembly, contacts)[0]
    is_free = np.zeros(len(assembly), dtype=bool)
    is_free[free] = True
    used = [c for c in found if is_free[c.i] or is_free[c.j]]
    if not used:
        return None

    rotation = _to_minus_z(g)
    weight = float(np.linalg.norm(g))
    upstream = CRA_Assembly()
    for k, mesh in enumerate(assembly.world_meshes()):
        vertices = (mesh.vertices @ rotation.T).tolist()
        block = Block.from_vertices_and_faces(vertices, mesh.faces.tolist())
        block.attributes["density"] = float(densities[k]) * weight
        upstream.add_block(block, node=k)
    upstream.set_boundary_conditions([int(k) for k in fixed])
    interfaces = []
    for c in used:
        points = (np.asarray(c.vertices) @ rotation.T).tolist()
        u, v = np.asarray(c.basis) @ rotation.T
        origin = np.asarray(c.vertices).mean(axis=0) @ rotation.T
        interface = Interface(size=float(c.area), points=points,
                              frame=Frame(origin.tolist(), u.tolist(), v.tolist()))
        upstream.add_interface_to_interfaces(int(c.i), int(c.j), interface)
        interfaces.append(interface)

    length = assembly.scale
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            cra_solve(upstream, mu=mu, density=1.0, d_bnd=eta * length, eps=eps * length)
    except ValueError:  # upstream's "solve failed: <status>"
        return None
    motion = np.array([upstream.graph.node_attribute(int(k), "displacement") for k in free], dtype=float)
    if motion.shape != (len(free), 6) or not np.all(np.isfinite(motion)):
        return None
    forces = np.array([[f["c_np"], f["c_u"], f["c_v"]] for interface in interfaces for f in interface.forces],
                      dtype=float).reshape(-1, 3)
    if len(forces) != sum(len(c.vertices) for c in used) or not np.all(np.isfinite(forces)):
        return None
    return np.hstack([motion[:, :3] @ rotation, motion[:, 3:] @ rotation]), forces  # R^T per row


def _to_minus_z(gravity: np.ndarray) -> np.ndarray:
    """The rotation ``R`` (3 x 3) turning ``gravity / |gravity|`` to ``(0, 0, -1)`` (the least turn)."""
    a = gravity / np.linalg.norm(gravity)
    b = np.array([0.0, 0.0, -1.0])
    axis = np.cross(a, b)
    sine, cosine = float(np.linalg.norm(axis)), float(a @ b)
    if sine < 1e-15:
        return np.eye(3) if cosine > 0 else np.diag([1.0, -1.0, -1.0])  # half turn about x
    k = axis / sine
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + sine * cross + (1.0 - cosine) * cross @ cross
