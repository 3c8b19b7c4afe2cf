"""Deciding whether an assembly interlocks: contacts, interlocking matrix, verdicts; statics and n-pods below.

- kinematic interlocking (this package): :func:`contacts`, :func:`interlocking_matrix`,
  :func:`check` (Def. 3.3, ``docs/interlocking.md``), :func:`criterion_4_3`,
  :func:`periodic_check`, :func:`second_order` and :func:`finite_motion`;
- statics (:mod:`interlock.verify.statics`): :func:`rbe`, :func:`cra`, :func:`critical_tilt`;
- n-pods (:mod:`interlock.verify.npod`): :func:`npod`, :func:`mobility`, :func:`self_motion`, bonds.

Each name is imported on first use (:func:`interlock.lazy_exports`), so a
command loads only the modules it needs.

>>> import trimesh
>>> from interlock.blocks import Assembly
>>> from interlock.verify import check
>>> grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
>>> print(check(Assembly.from_meshes(grid), frame=[0, 1, 2, 3, 5, 6, 7, 8]))
not infinitesimally interlocked: block 4 has a first-order motion that keeps every contact (A x = 0, kernel dimension 1) (A 16x6, rank 5)
"""

from interlock import deprecation, lazy_exports

# where each exported name lives
_HOMES = {
    **dict.fromkeys(["Verdict", "check"], "interlock.verify.check"),
    **dict.fromkeys(["Contact", "contacts"], "interlock.verify.contacts"),
    **dict.fromkeys(["CriterionResult", "criterion_4_3"], "interlock.verify.criterion"),
    **dict.fromkeys(["InterlockingMatrix", "interlocking_matrix"], "interlock.verify.matrix"),
    **dict.fromkeys(["FiniteMotion", "MotionError", "finite_motion", "moved", "twist_exponential"],
                    "interlock.verify.motion"),
    **dict.fromkeys(["BondConditions", "BondSearch", "Mobility", "NPod", "NPodError", "ProjectionBond", "SelfMotion",
                     "bond_conditions", "leg_rows", "mobility", "npod", "projection_bonds", "self_motion"],
                    "interlock.verify.npod"),
    **dict.fromkeys(["PeriodicVerdict", "edge_quadruples", "periodic_check", "symbol"], "interlock.verify.periodic"),
    **dict.fromkeys(["SecondOrder", "prestress_stability", "second_order"], "interlock.verify.second_order"),
    **dict.fromkeys(["CRAResult", "StabilityResult", "cra", "critical_tilt", "rbe"], "interlock.verify.statics"),
}

__all__ = ["Contact", "contacts", "CriterionResult", "criterion_4_3", "InterlockingMatrix", "interlocking_matrix",
           "Verdict", "check", "PeriodicVerdict", "edge_quadruples", "periodic_check", "symbol",
           "StabilityResult", "rbe", "critical_tilt", "CRAResult", "cra",
           "SecondOrder", "prestress_stability", "second_order",
           "FiniteMotion", "MotionError", "finite_motion", "moved", "twist_exponential",
           "NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "SelfMotion", "self_motion",
           "BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds"]

# Deprecated: pictures of a motion are made in the gallery (interlock.gallery.motion); removed in interlock 0.3.
# The old module paths (interlock.verify.cra, .stability, ...) are submodules; loading interlock.verify.cra
# leaves the function cra bound here (interlock.LazyPackage).
__getattr__, __dir__ = lazy_exports(__name__, _HOMES,
                                    deprecation.moved(__name__, {"export_motion": "interlock.gallery.motion"}))
