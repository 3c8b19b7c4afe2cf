"""Stability under self-weight: rigid-block equilibrium (RBE) as a linear program (CRA paper, Sec. 2.1)."""

from __future__ import annotations

from interlock.blocks.assembly import Assembly
from interlock.verify.statics.equilibrium import (DEFAULT_SIDES, Budget, EquilibriumSystem, StabilityResult,
                                                  gravity_vector)

__all__ = ["rbe"]


def rbe(assembly: Assembly, mu: float, density: float = 1.0, gravity=(0.0, 0.0, -1.0), frame=None,
        cone: str = "paper", sides: int = DEFAULT_SIDES, contacts=None, time_limit=None) -> StabilityResult:
    """Rigid-block equilibrium: can contact forces carry the self-weight? (CRA paper, Eqs. (1)-(5)).

    Unknowns are forces at the contact-polygon vertices ``c`` in each contact's
    frame ``(n, u, v)`` (``n`` from block ``i`` to block ``j``): ``f = (f_n, f_u, f_v)``
    acts on ``j``, ``-f`` on ``i``.  The LP asks for

    - no tension, Eq. (1): ``f_n >= 0``;
    - equilibrium of every free block ``b``, Eq. (2): ``A_eq f = -p`` with, per
      vertex, the force ``f_n n + f_u u + f_v v`` and its moment
      ``(c - x_b) x (f_n n + f_u u + f_v v)`` about the centroid ``x_b``, and
      ``p_b = (density * volume_b * gravity, 0)`` (weight at the centroid);
    - the linearised Coulomb cone, Eq. (5) and App. B: ``d_k . (f_u, f_v) <= m f_n``
      for ``sides`` directions ``d_k = (cos 2 pi k / sides, sin 2 pi k / sides)``,
      with ``m = mu`` for ``cone="paper"`` (faces tangent to the cone, App. B's
      ``G`` for eight sides) and ``m = mu cos(pi / sides)`` for ``cone="inner"``
      (vertices on the cone: never admits more friction than Coulomb).

    ``A_eq`` restricted to the normal components is the transpose of the
    interlocking matrix (before merging rows), with force and moment rows in
    the other order.  Frame blocks take any load.  The assembly is stable when
    the LP is feasible (Whiting et al.: a solution without tension).  Among
    feasible forces, HiGHS returns one minimising the total normal force
    ``sum f_n`` (any feasible one if that LP stalls).  The forces then sit on
    the cone's faces wherever friction helps, so :attr:`StabilityResult.friction_utilisation`
    (measured against the round Coulomb cone) reaches ``1 / cos(pi / sides)``
    (1.082 for eight sides) with the "paper" cone.

    Parameters
    ----------
    assembly : Assembly
    mu : float
        Friction coefficient: 0, or between :data:`~interlock.verify.statics.equilibrium.MU_MIN` (1e-6) and
        :data:`~interlock.verify.statics.equilibrium.MU_MAX` (1e15), the range the solvers represent.
    density : float or array (n,)
        Weight per volume, ``> 0``; one value, or one per block (loads carried by heavier blocks,
        e.g. the bridge's 3.51 on nodes 11-15).
    gravity : array (3,)
        Gravity direction and magnitude, not zero.
    frame : iterable of int, optional
        Fixed blocks; default ``assembly.frame``; at least one.
    cone : {"paper", "inner"}
    sides : int
        Sides of the friction pyramid, ``>= 3`` (``>= 4`` for "paper", which is unbounded with 3).
    contacts : None, "interfaces", "exact", Interfaces or sequence of Contact
        The contact model (:func:`~interlock.verify.statics.interfaces.statics_contacts`).  Default
        (``None`` or ``"interfaces"``): :func:`~interlock.verify.statics.interfaces.interfaces`, faces
        facing each other within a quarter of the thinner block's thickness, as real structures' joints
        meet (the armadillo vault's); ``"exact"``: :func:`~interlock.verify.contacts.contacts`, only
        faces that touch (what :func:`~interlock.verify.check` uses); or contacts given, e.g. from
        :func:`~interlock.verify.statics.interfaces.compas_interfaces`.  ``parameters["contacts"]``
        records which, with the tolerances.
    time_limit : float, optional
        Seconds for the whole call (contacts and solves; default: no limit).  When they run out the answer is
        "inconclusive" (``stable`` is ``None``, ``message`` "time limit reached in <stage>").  The clock never
        changes a verdict otherwise: each solver also has an iteration limit.

    Returns
    -------
    StabilityResult

    Raises
    ------
    StabilityError
        Bad ``mu`` (outside the solvers' range too), ``density``, ``gravity``, ``cone`` or ``sides``; no frame;
        not an assembly.
    InterlockError
        ``time_limit`` not a number of seconds > 0.

    Notes
    -----
    One sparse LP with ``3 s`` unknowns, ``6 (free blocks)`` equalities and
    ``sides * s`` inequalities for ``s`` contact vertices.  Clarabel decides it;
    on models up to :data:`~interlock.verify.statics.equilibrium.LARGE_LP` unknowns HiGHS' simplex then finds
    the forces of least ``sum f_n``.  A solver that does not decide hands over to the next (HiGHS' interior
    point, then its simplex); when none does, the answer is "inconclusive (solver: ...)", never "unstable".
    Lengths are divided by the model size and loads by the total weight.

    Examples
    --------
    >>> import trimesh
    >>> from interlock.verify.statics import tilted_gravity
    >>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    >>> stack = Assembly.from_meshes(cubes, frame=[0])
    >>> rbe(stack, mu=0.5).stable, rbe(stack, mu=0.5, gravity=tilted_gravity("x", 30)).stable
    (True, False)
    """
    budget = Budget.start(time_limit)
    gravity = gravity_vector(gravity)
    system = EquilibriumSystem.build(assembly, mu, density, frame, cone, sides, contacts, budget)
    return system.solve(gravity, budget)
