"""Block classes, colours and exploded positions."""

import numpy as np
import pytest

from interlock import GalleryError, wallpaper
from interlock.blocks import (cell_patch, escher_block, patch, periodic_cell, presets, random_hexagon,
                              rhomblock_assembly, staircase)
from interlock.gallery import as_assembly, block_classes, block_colours, exploded
from interlock.gallery.appearance import PALETTE


def test_rhomblocks_are_classed_by_lozenge_orientation():
    tiling = random_hexagon(3, 2, 4, seed=1)
    classes, kind = block_classes(rhomblock_assembly(tiling))
    assert kind == "orientation"
    assert np.bincount(classes, minlength=3).tolist() == list(tiling.orientation_counts)


def test_escher_blocks_are_classed_by_coset_with_the_identity_first():
    block = escher_block(wallpaper.group("p6"), {0: [(0.25, 0.08)]})
    p = patch(block, 1.5)
    classes, kind = block_classes(p)
    assert kind == "coset" and classes[0] == 0 and sorted(set(classes.tolist())) == list(range(6))
    # blocks in the same coset differ by a translation: equal linear parts of their transforms
    for k in range(6):
        linear = p.transforms[classes == k][:, :3, :3]
        assert np.allclose(linear, linear[0])


def test_cell_patches_keep_the_cells_classes():
    cell = rhomblock_assembly(staircase((2, 1, 1)), 1)
    around = cell_patch(cell, 1)
    classes, kind = block_classes(around)
    cell_classes, _ = block_classes(cell)
    assert kind == "orientation"
    assert classes.tolist() == [cell_classes[i] for _, _, i in around.labels]
    escher = cell_patch(periodic_cell(escher_block(wallpaper.group("p3"), {})), 1)
    assert block_classes(escher)[1] == "coset"
    assert block_classes(cell_patch(presets.cube_grid_cell(), 1))[1] == "cell block"


def test_colours_follow_the_classes():
    a = rhomblock_assembly(random_hexagon(2, 2, 2, seed=0))
    classes, _ = block_classes(a)
    colours = block_colours(a)
    assert colours.dtype == np.uint8 and colours.shape == (len(a), 4)
    assert (colours == PALETTE[classes]).all()


@pytest.mark.parametrize("factor", [0.0, 0.25, 1.0])
def test_exploded_scales_the_spread_of_centroids_and_keeps_everything_else(factor):
    a = presets.interlocking_cubes()
    b = exploded(a, factor)
    spread = lambda x: x.centroids - x.centroids.mean(axis=0)
    np.testing.assert_allclose(spread(b), (1 + factor) * spread(a), atol=1e-12)
    np.testing.assert_allclose(b.volumes, a.volumes)
    assert b.frame == a.frame and b.labels == a.labels
    np.testing.assert_allclose(b.transforms[:, :3, :3], a.transforms[:, :3, :3])


@pytest.mark.parametrize("factor", [-0.1, float("nan"), float("inf")])
def test_bad_exploded_factors_are_refused(factor):
    with pytest.raises(GalleryError, match="finite factor >= 0"):
        exploded(presets.cube_grid(), factor)


def test_as_assembly_takes_blocks_meshes_and_assemblies():
    block = escher_block(wallpaper.group("p2"), {})
    assert len(as_assembly(block)) == 1 and as_assembly(block).volumes[0] == pytest.approx(block.volume)
    grid = presets.cube_grid()
    assert as_assembly(grid) is grid and len(as_assembly(grid.mesh(0))) == 1
    with pytest.raises(GalleryError, match="expected a Block, an Assembly or a trimesh.Trimesh, got str"):
        as_assembly("cube.stl")
