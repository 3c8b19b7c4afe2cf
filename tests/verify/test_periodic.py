"""Verdicts for infinite periodic assemblies from one cell (main paper Sec. 4, DESIGN.md "Periodic reduction")."""

import numpy as np
import pytest

from interlock import InterlockError, wallpaper
from interlock.blocks import (Assembly, cell_patch, escher_block, patch, periodic_cell, presets, rhomblock_assembly,
                              staircase)
from interlock.verify import check, criterion_4_3, edge_quadruples, interlocking_matrix, periodic_check, symbol
from interlock.verify import periodic
from tests.blocks.deformations import random_block


def test_example_3_6_infinite_layer_is_interlocked():
    v = periodic_check(presets.interlocking_cubes_cell())
    assert v.status == "interlocked" and v.generic_rank == 6 and v.rounds == 1


def test_example_3_5_infinite_cube_grid_slides_vertically():
    v = periodic_check(presets.cube_grid_cell())
    assert v.status == "not interlocked" and v.generic_rank == 5
    np.testing.assert_allclose(v.motion, [[0, 0, 0, 0, 0, 1]], atol=1e-9)  # one cube lifts: finite support
    assert v.moving == (0,)


@pytest.mark.parametrize("counts", [(1, 0, 0), (1, 1, 0), (2, 1, 0), (1, 1, 1), (2, 2, 1), (1, 2, 2), (0, 1, 2)])
@pytest.mark.parametrize("variant", [0, 1])
def test_theorem_4_9_periodic_rhomblock_assemblies_interlock(counts, variant):
    v = periodic_check(rhomblock_assembly(staircase(counts), variant))
    assert v.status == "interlocked" and v.generic_rank == v.columns


def test_one_orientation_rhomblocks_need_two_rounds():
    # DESIGN.md: the vertical walls are forced first and leave a vertical translation; the tilted rows end it
    assert periodic_check(rhomblock_assembly(staircase((1, 0, 0)), 0)).rounds == 2


@pytest.mark.parametrize("seed", range(40))
def test_theorem_4_7_translational_verdict_equals_criterion_4_3_in_p1(seed):
    rng = np.random.default_rng(seed)
    group = wallpaper.group("p1", b=float(rng.uniform(0.7, 1.3)), gamma=float(rng.uniform(60, 120)))
    block = random_block(group, rng, max_points=2, skip=0.4)
    v = periodic_check(periodic_cell(block), translational=True)
    assert (v.status == "interlocked") == criterion_4_3(block).holds
    assert v.status != "inconclusive"


@pytest.mark.parametrize("name", ["p2", "p3", "p4", "p6"])
@pytest.mark.parametrize("seed", range(10))
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


def _cells():
    """Cells of every kind the verifier accepts, with a seeded random Escher block per rotation group."""
    cells = {"cube grid": presets.cube_grid_cell(), "tilted cubes": presets.interlocking_cubes_cell(),
             "rhomblock (1,0,0)": rhomblock_assembly(staircase((1, 0, 0)), 0),
             "rhomblock (1,1,0) v1": rhomblock_assembly(staircase((1, 1, 0)), 1)}
    for name, seed in [("p1", 0), ("p1", 3), ("p2", 1), ("p2", 5), ("p3", 2), ("p4", 0), ("p4", 4), ("p6", 1)]:
        cells[f"{name} seed {seed}"] = periodic_cell(random_block(wallpaper.group(name), np.random.default_rng(seed),
                                                                  max_points=2, skip=0.4))
    return cells


CELLS = _cells()


def _world_vector(matrix, twists_by_block):
    """The column vector of ``interlocking_matrix`` for world twists given per block (zero elsewhere)."""
    x = np.zeros((len(matrix.free), 6))
    for k, b in enumerate(matrix.free):
        omega, t = twists_by_block.get(int(b), np.zeros(6)).reshape(2, 3)
        x[k] = np.concatenate([omega, t / matrix.length_scale])
    return x.ravel()


@pytest.mark.parametrize("name", sorted(CELLS))
def test_patches_with_a_fixed_ring_never_contradict_the_periodic_verdict(name):
    cell = CELLS[name]
    v = periodic_check(cell)
    assert v.status != "inconclusive"
    for radius in (0, 1):
        finite = check(cell_patch(cell, radius), validate=False)
        # a motion of a patch with its ring fixed is a finite-support motion of the infinite assembly
        assert not (v.status == "interlocked" and finite.interlocked is False), radius
    if v.status == "not interlocked" and v.patch_radius is None:
        assert check(cell_patch(cell, 0), validate=False).interlocked is False  # one cell moving is found at once


def _assert_motion_keeps_every_contact(cell, v, sliding):
    """Apply the verdict's motion to a patch holding the moving blocks and all they touch: A x >= 0 (= 0 if sliding)."""
    assert v.moving and len(v.motion) == len(v.motion_blocks)
    reach = max(max(abs(a), abs(b)) for a, b, _ in v.motion_blocks)
    around = cell_patch(cell, reach)
    where = {label: index for index, label in enumerate(around.labels)}
    M = interlocking_matrix(around, frame=())
    Ax = M.matrix @ _world_vector(M, {where[v.motion_blocks[k]]: v.motion[k] for k in v.moving})
    assert Ax.min() > -1e-7
    if sliding:
        assert np.abs(Ax).max() < 1e-7


@pytest.mark.parametrize("name", [n for n in sorted(CELLS) if periodic_check(CELLS[n]).status == "not interlocked"])
def test_the_reported_motion_keeps_every_contact_of_the_infinite_assembly(name):
    _assert_motion_keeps_every_contact(CELLS[name], periodic_check(CELLS[name]), sliding=True)


def test_lp_values_report_each_positive_z_tried():
    v = periodic_check(rhomblock_assembly(staircase((1, 0, 0)), 0))
    assert v.lp_values[0][:3] == (1, 1.0, 1.0)
    assert {r for r, *_ in v.lp_values} == {1, 2}
    # round 1 forces the vertical walls only (DESIGN.md), round 2 the tilted rows as well
    assert 0 < v.lp_values[0][3] < v.rows and v.lp_values[-1][3] == pytest.approx(v.rows, abs=1e-6)
    assert all(z1 > 0 and z2 > 0 for _, z1, z2, _ in v.lp_values)
    assert v.to_dict()["lp_values"][0] == {"round": 1, "z": [1.0, 1.0], "value": v.lp_values[0][3]}


def _undecided(A, at_points):
    return periodic._Reduction("inconclusive", "forced undecided for the test", 1, 0, (), (), "undecided")


def test_an_undecided_reduction_falls_back_to_patches_that_find_a_motion(monkeypatch):
    monkeypatch.setattr(periodic, "_reduce", _undecided)
    v = periodic_check(presets.cube_grid_cell())
    assert v.status == "not interlocked" and v.patch_radius == 1 and "patch of radius 1" in v.reason
    assert all(max(abs(a), abs(b)) <= 1 for a, b, _ in v.motion_blocks)  # finite support, ring fixed
    assert "patches" in v.timings
    _assert_motion_keeps_every_contact(presets.cube_grid_cell(), v, sliding=False)


def test_an_undecided_reduction_stays_inconclusive_when_no_patch_moves(monkeypatch):
    monkeypatch.setattr(periodic, "_reduce", _undecided)
    v = periodic_check(presets.interlocking_cubes_cell(), patch_radii=(0, 1))
    assert v.status == "inconclusive" and v.motion is None and "radius 0, 1" in v.reason
    assert v.tolerances["patch_radii"] == [0, 1]


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


@pytest.mark.parametrize("name,status", [("cube grid", "not interlocked"), ("tilted cubes", "interlocked"),
                                         ("p4 seed 0", "interlocked"), ("p6 seed 1", "interlocked"),
                                         ("rhomblock (1,0,0)", "interlocked"), ("p1 seed 3", "not interlocked")])
def test_certified_periodic_verdicts_replay_the_reduction_exactly(name, status):
    v = periodic_check(CELLS[name], certify=True)
    assert v.status == status and v.certified and "; certified: " in v.reason and "not certified" not in v.reason
    assert v.to_dict()["certified"] is True


def test_certification_refuses_a_wrong_ending():
    from interlock.verify.certify import certify_reduction

    cell = presets.cube_grid_cell()
    A = symbol(cell)
    rng = np.random.default_rng(0)
    reduction = periodic._reduce(A, [A(np.exp(2j * np.pi * rng.random(2))) for _ in range(2)])
    assert reduction.ending == "cell motion"
    # the grid's forced rows keep the vertical lift: claiming "no kernel" must not be certified
    ok, note = certify_reduction(A, reduction.steps, "no kernel")
    assert not ok and "not of full exact rank" in note
    # a stress step with a weight vector that is not a stress is refused too
    _, z, rows, w = reduction.steps[0]
    ok, note = certify_reduction(A, [("stress", z, rows, -w)], "no kernel")
    assert not ok and "no exact positive stress" in note
    # a cell motion needs no step: the exact common kernel of every A_delta is the proof
    ok, note = certify_reduction(A, (), "cell motion")
    assert ok and "exact rational cell motion" in note


def test_float_data_that_breaks_exact_dependencies_is_reported_not_certified():
    # rounding sqrt(3) geometry to floats makes some stress rows exactly independent: say so, claim nothing
    v = periodic_check(CELLS["rhomblock (1,1,0) v1"], certify=True)
    assert v.status == "interlocked" and not v.certified and "not certified: no exact positive stress" in v.reason


def _p1_cell_near_its_line(delta):
    group = wallpaper.group("p1")
    p, q = np.asarray(group.fundamental_domain().exterior.coords)[:2]
    along = (q - p) / np.linalg.norm(q - p)
    return periodic_cell(escher_block(group, {0: [p + 0.4 * (q - p) + delta * np.array([along[1], -along[0]])]}))


@pytest.mark.parametrize("delta,status", [(1e-2, "interlocked"), (1e-4, "interlocked"), (1e-6, "inconclusive"),
                                          (1e-11, "inconclusive"), (0.0, "not interlocked")])
def test_a_slide_across_faces_bent_below_the_tolerance_is_inconclusive_not_a_motion(delta, status):
    # Thm. 4.7: interlocked for every delta > 0; below the contact tolerance the bent side face is merged into
    # one plane and a cell seems to slide across it: the verdict must say so instead of answering wrongly
    v = periodic_check(_p1_cell_near_its_line(delta), translational=True, certify=True)
    assert v.status == status
    if status == "inconclusive":
        assert "planar only within the contact tolerances" in v.reason and v.motion is None and not v.certified
    else:
        assert v.certified


def test_a_sliding_motion_the_exact_matrix_does_not_have_is_not_certified():
    from interlock.verify.contacts import contacts as find

    block = _p1_cell_near_its_line(1e-10)
    finite = patch(escher_block(wallpaper.group("p1"), {0: [block.info["deformation"][0][0]]}), 1.0,
                   frame="boundary")
    tight = find(finite, rtol=1e-12, angle_tol=1e-12)  # contacts that keep the bend: the slide is rounding only
    v = check(finite, translational=True, contacts=tight, certify=True)
    # rank_rtol 1e-9 calls the bend's value zero, but the slide crosses a face the default contacts see bent
    assert v.interlocked is None and v.motion_kind == "sliding"
    assert not v.certified and "planar only within the contact tolerances" in v.status


@pytest.mark.parametrize("name", sorted(CELLS))
def test_a_cell_turned_by_a_tiny_rotation_keeps_its_verdict(name):
    # turning "p2 seed 5" by (1.2e-7, 0, 0.0156) rad gave M columns of 1e-10 entries, HiGHS failed on the
    # widest-stress LP, no row was forced, and "interlocked" became "inconclusive"
    from scipy.spatial.transform import Rotation

    cell = CELLS[name]
    turn = Rotation.from_rotvec([1.192092896e-07, 0.0, 0.015625]).as_matrix()
    transform = np.eye(4)
    transform[:3, :3] = turn
    turned = Assembly(cell.meshes, cell.types, [transform @ t for t in cell.transforms], cell.labels, cell.frame,
                      cell.lattice @ turn.T, None, cell.info)
    assert periodic_check(turned).status == periodic_check(cell).status
