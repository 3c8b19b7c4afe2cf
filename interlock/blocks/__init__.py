"""Blocks from deformed fundamental domains, RhomBlocks, and assemblies of them.

>>> from interlock import wallpaper
>>> from interlock.blocks import escher_block, patch
>>> X = escher_block(wallpaper.group("p6"), {0: [(0.25, 0.08)], 1: [(0.55, 0.15)]})
>>> len(patch(X, 1.0))
31
"""

from interlock.blocks.arch import semicircular_arch
from interlock.blocks.assembly import Assembly, AssemblyError, load_3dm, load_compas
from interlock.blocks.escher import Block, DeformationError, escher_block
from interlock.blocks import presets
from interlock.blocks.lozenge import Lozenge, LozengeTiling, TilingError, random_hexagon, staircase
from interlock.blocks.orbits import cell_patch, cell_reach, patch, periodic_cell
from interlock.blocks.rhomblock import rhomblock, rhomblock_assembly

__all__ = ["Assembly", "AssemblyError", "Block", "DeformationError", "escher_block", "patch", "periodic_cell",
           "cell_patch", "cell_reach",
           "presets", "Lozenge", "LozengeTiling", "TilingError", "random_hexagon", "staircase", "rhomblock",
           "rhomblock_assembly", "load_compas", "load_3dm", "semicircular_arch"]
