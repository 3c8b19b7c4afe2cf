"""Deciding whether an assembly interlocks: contacts, interlocking matrix, verdicts; statics and n-pods below.

- kinematic interlocking (this package): :func:`contacts`, :func:`interlocking_matrix`,
  :func:`check` (Def. 3.3, ``docs/interlocking.md``), :func:`criterion_4_3`,
  :func:`periodic_check`, :func:`second_order` and :func:`finite_motion`;
- statics (:mod:`interlock.verify.statics`): :func:`rbe`, :func:`cra`, :func:`critical_tilt`;
- n-pods (:mod:`interlock.verify.npod`): :func:`npod`, :func:`mobility`, :func:`self_motion`, bonds.

>>> import trimesh
>>> from interlock.blocks import Assembly
>>> from interlock.verify import check
>>> grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
>>> print(check(Assembly.from_meshes(grid), frame=[0, 1, 2, 3, 5, 6, 7, 8]))
not infinitesimally interlocked: block 4 has a first-order motion that keeps every contact (A x = 0, kernel dimension 1) (A 16x6, rank 5)
"""

from interlock import deprecation
# The deprecated module paths (interlock.verify.cra, .stability, ...) are loaded first, so that the names
# bound below (the function ``cra``) are not replaced by those modules when someone imports them later.
from interlock.verify import cra, cra_compas, cra_ipopt, cra_local, npod_bonds, stability  # noqa: F401, F811
from interlock.verify.check import Verdict, check
from interlock.verify.contacts import Contact, contacts
from interlock.verify.criterion import CriterionResult, criterion_4_3
from interlock.verify.matrix import InterlockingMatrix, interlocking_matrix
from interlock.verify.motion import FiniteMotion, MotionError, finite_motion, moved, twist_exponential
from interlock.verify.npod import (BondConditions, BondSearch, Mobility, NPod, NPodError, ProjectionBond, SelfMotion,
                                   bond_conditions, leg_rows, mobility, npod, projection_bonds, self_motion)
from interlock.verify.periodic import PeriodicVerdict, edge_quadruples, periodic_check, symbol
from interlock.verify.second_order import SecondOrder, prestress_stability, second_order
from interlock.verify.statics import CRAResult, StabilityResult, cra, critical_tilt, rbe  # noqa: F811

__all__ = ["Contact", "contacts", "CriterionResult", "criterion_4_3", "InterlockingMatrix", "interlocking_matrix",
           "Verdict", "check", "PeriodicVerdict", "edge_quadruples", "periodic_check", "symbol",
           "StabilityResult", "rbe", "critical_tilt", "CRAResult", "cra",
           "SecondOrder", "prestress_stability", "second_order",
           "FiniteMotion", "MotionError", "finite_motion", "moved", "twist_exponential",
           "NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "SelfMotion", "self_motion",
           "BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds"]

# Deprecated: pictures of a motion are made in the gallery (interlock.gallery.motion); removed in interlock 0.3.
__getattr__ = deprecation.moved(__name__, {"export_motion": "interlock.gallery.motion"})
