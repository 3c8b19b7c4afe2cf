"""Deciding whether an assembly interlocks: contacts, interlocking matrix, verdicts.

>>> import trimesh
>>> from interlock.blocks import Assembly
>>> from interlock.verify import check
>>> grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
>>> print(check(Assembly.from_meshes(grid), frame=[0, 1, 2, 3, 5, 6, 7, 8]))
not infinitesimally interlocked: block 4 has a first-order motion that keeps every contact (A x = 0, kernel dimension 1) (A 16x6, rank 5)
"""

from interlock.verify.check import Verdict, check
from interlock.verify.contacts import Contact, contacts
from interlock.verify.criterion import CriterionResult, criterion_4_3
from interlock.verify.matrix import InterlockingMatrix, interlocking_matrix
from interlock.verify.stability import StabilityResult, critical_tilt, rbe
from interlock.verify.cra import CRAResult, cra
from interlock.verify.periodic import PeriodicVerdict, edge_quadruples, periodic_check, symbol
from interlock.verify.second_order import SecondOrder, prestress_stability, second_order
from interlock.verify.motion import FiniteMotion, MotionError, export_motion, finite_motion, moved, twist_exponential
from interlock.verify.npod import Mobility, NPod, NPodError, SelfMotion, leg_rows, mobility, npod, self_motion
from interlock.verify.npod_bonds import BondConditions, BondSearch, ProjectionBond, bond_conditions, projection_bonds

__all__ = ["Contact", "contacts", "CriterionResult", "criterion_4_3", "InterlockingMatrix", "interlocking_matrix",
           "Verdict", "check", "PeriodicVerdict", "edge_quadruples", "periodic_check", "symbol",
           "StabilityResult", "rbe", "critical_tilt", "CRAResult", "cra",
           "SecondOrder", "prestress_stability", "second_order",
           "FiniteMotion", "MotionError", "export_motion", "finite_motion", "moved", "twist_exponential",
           "NPod", "NPodError", "npod", "leg_rows", "Mobility", "mobility", "SelfMotion", "self_motion",
           "BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds"]
