"""Stability under self-weight: rigid-block equilibrium (RBE), coupled rigid-block analysis (CRA), the tilt test.

The contact model (interfaces of faces that meet approximately) is in
:mod:`~interlock.verify.statics.interfaces` (``interfaces(assembly)``; the module keeps its name, so
the function is not re-exported here); the shared equilibrium problem is in
:mod:`~interlock.verify.statics.equilibrium`;
the theory, with the CRA paper's numbering, is in ``docs/statics.md``.

>>> import trimesh
>>> from interlock.blocks import Assembly
>>> from interlock.verify.statics import rbe
>>> cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
>>> rbe(Assembly.from_meshes(cubes, frame=[0]), mu=0.5).stable
True
"""

from interlock.verify.statics.cra import (DEFAULT_FORCE_BOUND, DEFAULT_MIN_SLIDE, DEFAULT_SECTORS, REFINED_SECTORS,
                                          CRAResult, cra)
from interlock.verify.statics.equilibrium import (CONES, DEFAULT_EPS, DEFAULT_ETA, DEFAULT_SIDES, FRICTION_RTOL,
                                                  StabilityError, StabilityResult)
from interlock.verify.statics.interfaces import (DEFAULT_AREA_THICKNESS, DEFAULT_GAP_THICKNESS, Interfaces,
                                                 compas_interfaces, thickness)
from interlock.verify.statics.rbe import rbe
from interlock.verify.statics.tilt import (DEFAULT_TILT_STEP, DEFAULT_TILT_TOL, TILT_AXES, TiltScan, critical_tilt,
                                          tilt_scan, tilted_gravity)

__all__ = ["rbe", "StabilityResult", "StabilityError", "cra", "CRAResult", "critical_tilt", "tilt_scan", "TiltScan",
           "tilted_gravity",
           "TILT_AXES", "CONES", "DEFAULT_SIDES", "DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL", "DEFAULT_EPS", "DEFAULT_ETA",
           "DEFAULT_SECTORS", "DEFAULT_FORCE_BOUND", "DEFAULT_MIN_SLIDE", "REFINED_SECTORS", "FRICTION_RTOL",
           "Interfaces", "compas_interfaces", "thickness", "DEFAULT_GAP_THICKNESS", "DEFAULT_AREA_THICKNESS"]
