"""How an unstable assembly comes down: the virtual motion that proves no contact forces carry its weight."""

from __future__ import annotations

import numpy as np
import scipy.optimize
import scipy.sparse as sp

from interlock.blocks.assembly import Assembly
from interlock.verify.statics.equilibrium import EquilibriumSystem, gravity_vector

__all__ = ["collapse_twists", "COLLAPSE_ITERATIONS", "WORK_RTOL"]

#: Simplex iterations allowed to the collapse LP (it is drawn, never part of a verdict).
COLLAPSE_ITERATIONS = 50_000
#: A mechanism whose work is below this share of its largest unit is no collapse (the LP's own tolerance).
WORK_RTOL = 1e-7


def collapse_twists(assembly: Assembly, stability) -> np.ndarray | None:
    """Twists ``(omega, t)`` per block (about the centroids; zero for the frame) of a collapse mechanism, or None.

    Rigid-block equilibrium (:func:`~interlock.verify.rbe`) asks for forces
    ``f`` in the friction cones ``K`` with ``A_eq f = -p``.  It has none
    exactly when (Farkas) a virtual motion ``u`` of the free blocks has
    ``u . p > 0`` (the weight does work) while every contact vertex's relative
    motion ``d = A_eq^T u`` lies in the dual cone ``K*``: it opens the contact
    (``d_n >= 0``) and slides no more than the friction allows
    (``d = s n - C^T z`` with ``s, z >= 0`` and ``C`` the cone's rows).  This
    solves ``max u . p`` over such ``u`` with ``|u| <= 1`` (HiGHS), rebuilding
    the system from the result's contacts and parameters.

    Parameters
    ----------
    assembly : Assembly
        The one the stability result was computed for.
    stability : StabilityResult or CRAResult
        Its ``contacts`` and ``parameters`` (``mu``, ``cone``, ``sides``,
        ``density``, ``gravity``, ``frame``).

    Returns
    -------
    ndarray (n, 6) or None
        None when the LP finds no motion that does work (the result was not
        unstable, or the LP stopped).

    Examples
    --------
    >>> import trimesh
    >>> from interlock.blocks import Assembly
    >>> from interlock.verify import rbe
    >>> base = trimesh.creation.box(bounds=[[0, 0, -1], [2, 1, 0]])
    >>> top = trimesh.creation.box(bounds=[[1.5, 0, 0], [3.5, 1, 1]])  # overhangs its support by 3/4
    >>> pair = Assembly.from_meshes([base, top], frame=[0])
    >>> twists = collapse_twists(pair, rbe(pair, 0.5))
    >>> bool(twists[1, 5] < 0), bool(twists[1, 1] != 0)  # the top block goes down and tips over the edge
    (True, True)

    Notes
    -----
    The motion drawn is a first-order mechanism (associated flow: sliding
    comes with the dilatancy of the linearised cone), the certificate that no
    equilibrium exists, not a simulation of the fall.  One LP with
    ``6 f + v (1 + sides)`` unknowns for ``f`` free blocks and ``v`` contact vertices.
    """
    p = stability.parameters
    gravity = gravity_vector(p.get("gravity", (0.0, 0.0, -1.0)))
    density = p.get("density", 1.0)
    system = EquilibriumSystem.build(assembly, p["mu"], density, p.get("frame"), p.get("cone", "paper"),
                                     p.get("sides", 8), tuple(stability.contacts))
    free, vertices = len(system.free), len(system.points)
    if not free:
        return None
    cone = system.cone_rows
    sides = len(cone)
    normal = sp.csr_matrix((np.ones(vertices), (3 * np.arange(vertices), np.arange(vertices))),
                           shape=(3 * vertices, vertices))
    friction = sp.kron(sp.eye(vertices, format="csr"), sp.csr_matrix(cone.T), format="csr")  # (3v, v sides)
    equalities = sp.hstack([system.a_eq.T, -normal, friction], format="csr")
    load = np.hstack([np.outer(system.weights, gravity), np.zeros((free, 3))]).ravel()
    scale = float(np.abs(load).max()) or 1.0
    cost = np.concatenate([-load / scale, np.zeros(vertices * (1 + sides))])
    bounds = [(-1.0, 1.0)] * (6 * free) + [(0.0, None)] * (vertices * (1 + sides))
    outcome = scipy.optimize.linprog(cost, A_eq=equalities, b_eq=np.zeros(3 * vertices), bounds=bounds,
                                     method="highs", options={"maxiter": COLLAPSE_ITERATIONS})
    if outcome.status != 0 or -outcome.fun <= WORK_RTOL:
        return None
    u = outcome.x[:6 * free].reshape(free, 6)
    twists = np.zeros((len(assembly), 6))
    twists[system.free, :3] = u[:, 3:] / assembly.scale  # moment rows are divided by the length (equilibrium_matrix)
    twists[system.free, 3:] = u[:, :3]
    return twists
