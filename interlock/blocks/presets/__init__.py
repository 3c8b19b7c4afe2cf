"""The example assemblies of the main paper (Ex. 3.5-3.7, Fig. 1, 4-7, 9-11), a block on pins, a honeycomb layer."""

from interlock.blocks.presets.common import PresetError
from interlock.blocks.presets.cubes import (CUBE_FACES, CUBE_VERTICES, INTERLOCKING_CUBE_SIDE,
                                            INTERLOCKING_CUBES_TRANSLATIONS, PYRAMID_HEIGHT, cube_grid, cube_grid_cell,
                                            interlocking_cubes, interlocking_cubes_cell, modified_cube,
                                            modified_cube_assembly)
from interlock.blocks.presets.fig1 import FIG1_DEFORMATION, fig1_p6_block
from interlock.blocks.presets.honeycomb import HONEYCOMB_HEIGHT, honeycomb_layer
from interlock.blocks.presets.pins import block_on_pins
from interlock.blocks.presets.tetrahedral import TETRAHEDRA_SYMMETRIES, tetrahedra
from interlock.blocks.presets.versatile import VERSATILE_BLOCK_DATA, VERSATILE_TO_PAPER, versatile_blocks

__all__ = [
    "PresetError", "cube_grid", "cube_grid_cell", "interlocking_cubes", "interlocking_cubes_cell", "tetrahedra",
    "modified_cube", "modified_cube_assembly", "versatile_blocks", "fig1_p6_block", "block_on_pins", "honeycomb_layer",
    "CUBE_VERTICES", "CUBE_FACES", "INTERLOCKING_CUBES_TRANSLATIONS", "INTERLOCKING_CUBE_SIDE", "TETRAHEDRA_SYMMETRIES",
    "PYRAMID_HEIGHT", "VERSATILE_BLOCK_DATA", "VERSATILE_TO_PAPER", "FIG1_DEFORMATION", "HONEYCOMB_HEIGHT",
]
