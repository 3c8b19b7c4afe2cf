"""Verdicts for infinite periodic assemblies from one cell (main paper Sec. 4, DESIGN.md "Periodic reduction")."""

import numpy as np
import pytest

from interlock import InterlockError, wallpaper
from interlock.blocks import Assembly, escher_block, patch, periodic_cell, presets, rhomblock_assembly, staircase
from interlock.verify import check, criterion_4_3, edge_quadruples, periodic_check, symbol
from tests.blocks.deformations import random_block


def test_example_3_6_infinite_layer_is_interlocked():
    v = periodic_check(presets.interlocking_cubes_cell())
    assert v.status == "interlocked" and v.generic_rank == 6 and v.rounds == 1


def test_example_3_5_infinite_cube_grid_slides_vertically():
    v = periodic_check(presets.cube_grid_cell())
    assert v.status == "not interlocked" and v.generic_rank == 5
    np.testing.assert_allclose(v.motion, [[0, 0, 0, 0, 0, 1]], atol=1e-9)  # one cube lifts: finite support
    assert v.moving == (0,)


@pytest.mark.parametrize("counts", [(1, 0, 0), (1, 1, 0), (2, 1, 0), (1, 1, 1)])
@pytest.mark.parametrize("variant", [0, 1])
def test_theorem_4_9_periodic_rhomblock_assemblies_interlock(counts, variant):
    v = periodic_check(rhomblock_assembly(staircase(counts), variant))
    assert v.status == "interlocked" and v.generic_rank == v.columns


def test_one_orientation_rhomblocks_need_two_rounds():
    # DESIGN.md: the vertical walls are forced first and leave a vertical translation; the tilted rows end it
    assert periodic_check(rhomblock_assembly(staircase((1, 0, 0)), 0)).rounds == 2


@pytest.mark.parametrize("seed", range(12))
def test_theorem_4_7_translational_verdict_equals_criterion_4_3_in_p1(seed):
    rng = np.random.default_rng(seed)
    group = wallpaper.group("p1", b=float(rng.uniform(0.7, 1.3)), gamma=float(rng.uniform(60, 120)))
    block = random_block(group, rng, max_points=2, skip=0.4)
    v = periodic_check(periodic_cell(block), translational=True)
    assert (v.status == "interlocked") == criterion_4_3(block).holds
    assert v.status != "inconclusive"


@pytest.mark.parametrize("name", ["p2", "p3", "p4", "p6"])
@pytest.mark.parametrize("seed", range(4))
def test_proposition_4_6_full_generic_rank_exactly_when_criterion_holds(name, seed):
    block = random_block(wallpaper.group(name), np.random.default_rng(100 + seed), max_points=2, skip=0.4)
    v = periodic_check(periodic_cell(block))
    holds = criterion_4_3(block).holds
    assert (v.generic_rank == v.columns) == holds
    assert (v.status == "interlocked") == holds


@pytest.mark.parametrize("deformation", [{0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}, {0: [(0.25, 0.1)]}])
def test_patches_never_contradict_the_periodic_verdict(deformation):
    # a patch motion with the outside fixed exists only when the periodic verdict is not "interlocked"
    block = escher_block(wallpaper.group("p4"), deformation)
    periodic = periodic_check(periodic_cell(block)).status
    for radius in (1.0, 1.5, 2.0):
        finite = check(patch(block, radius, frame="boundary")).interlocked
        assert not (periodic == "interlocked" and finite is False)


def test_symbol_and_quadruples():
    cell = presets.cube_grid_cell()
    quadruples = edge_quadruples(cell)
    assert sorted(q.offset for q in quadruples) == [(0, 1), (1, 0)]  # each contact of the grid once
    A = symbol(cell, quadruples=quadruples)
    assert A.rows == 8 and A.columns == 6
    z = (np.exp(0.7j), np.exp(-1.3j))
    assert np.allclose(A(z) @ [0, 0, 0, 0, 0, 1], 0)  # the vertical lift is in the kernel at every z
    assert np.linalg.matrix_rank(A(z)) == 5


def test_a_cell_needs_a_lattice():
    with pytest.raises(InterlockError, match="needs a periodic cell"):
        periodic_check(Assembly.from_meshes(presets.cube_grid().world_meshes()))
