"""Patches of a periodic cell with a fixed ring (the finite fallback of the periodic verdict)."""

import numpy as np
import pytest

from interlock import InterlockError, wallpaper
from interlock.blocks import cell_patch, cell_reach, escher_block, periodic_cell, presets, rhomblock_assembly, staircase


@pytest.mark.parametrize("radius", [0, 1, 2])
def test_cell_patch_frees_the_inner_square_and_fixes_a_ring_of_the_reach(radius):
    cell = presets.cube_grid_cell()
    p = cell_patch(cell, radius)
    outer = radius + cell_reach(cell)
    assert len(p) == (2 * outer + 1) ** 2
    free = [p.labels[b] for b in range(len(p)) if b not in set(p.frame)]
    assert sorted(free) == sorted((a, b, 0) for a in range(-radius, radius + 1) for b in range(-radius, radius + 1))
    assert p.labels[0] == (0, 0, 0) and np.allclose(p.transforms[0], cell.transforms[0])
    # the translate (a, b) of block i sits at the cell's block moved by a v1 + b v2
    for index, (a, b, i) in enumerate(p.labels):
        shift = a * cell.lattice[0] + b * cell.lattice[1]
        assert np.allclose(p.transforms[index][:3, 3], cell.transforms[i][:3, 3] + shift)


def test_every_block_touching_a_free_one_is_in_the_ring():
    block = escher_block(wallpaper.group("p3"), {0: [(0.3, 0.1)]})
    cell = periodic_cell(block)
    p = cell_patch(cell, 1)
    # in a larger patch, every neighbour of a free block of p is a block of p
    larger = cell_patch(cell, 1 + cell_reach(cell))
    inner = {larger.labels[b] for b in range(len(larger)) if max(map(abs, larger.labels[b][:2])) <= 1}
    needed = {larger.labels[j] for i in range(len(larger)) if larger.labels[i] in inner for j in larger.neighbours[i]}
    assert needed <= set(p.labels)


def test_reach_of_rhomblock_cells_and_tall_blocks():
    assert cell_reach(rhomblock_assembly(staircase((1, 0, 0)), 0)) >= 1
    assert cell_reach(presets.interlocking_cubes_cell()) >= 1


def test_cell_patch_rejects_bad_input():
    with pytest.raises(InterlockError, match="two lattice vectors"):
        cell_patch(presets.cube_grid(), 1)
    with pytest.raises(InterlockError, match="whole number"):
        cell_patch(presets.cube_grid_cell(), 1.5)
    with pytest.raises(InterlockError, match="whole number"):
        cell_patch(presets.cube_grid_cell(), -1)


@pytest.mark.parametrize("counts", [(2, 2, 1), (0, 1, 1), (3, 3, 2), (1, 0, 3)])
@pytest.mark.parametrize("variant", [0, 1])
def test_no_translate_beyond_the_reach_touches_the_cell(counts, variant):
    # under a skew lattice any corner of a block's box may be the extreme one (2,2,1 once lost 4 contacts)
    from interlock.verify import contacts

    cell = rhomblock_assembly(staircase(counts), variant)
    reach = cell_reach(cell)
    wider = cell_patch(cell, reach + 1)  # everything within reach + 1 + reach of the centre
    k = len(cell)
    touching = {wider.labels[c.j if c.i < k else c.i][:2] for c in contacts(wider, involving=range(k))}
    assert max(max(abs(a), abs(b)) for a, b in touching) <= reach
