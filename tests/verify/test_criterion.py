"""Criterion 4.3 (main paper Sec. 4): exact subgroup closure and the witness H."""

import numpy as np
import pytest

from interlock import InterlockError, wallpaper
from interlock.blocks import escher_block
from interlock.verify.criterion import criterion_4_3
from tests.blocks.deformations import random_block


@pytest.mark.parametrize("name,edges,holds,order", [
    ("p1", [], False, 1),
    ("p1", [0], True, None),          # one translation pair: an infinite column of tiles
    ("p1", [0, 1], True, None),
    ("p2", [1], False, 2),            # the two half-edges paired by one half-turn: F and its image
    ("p2", [0, 1, 4], True, None),
    ("p3", [0], False, 3),            # the 3-fold pair at the origin: three rhombi make a hexagon
    ("p3", [0, 1], True, None),
    ("p4", [0], False, 4),            # the 4-fold pair at the origin: a square of four tiles
    ("p4", [1], False, 4),
    ("p4", [0, 1], True, None),
    ("p6", [0], False, 6),
    ("p6", [1], False, 3),
    ("p6", [0, 1], True, None),
    ("pmm", [], False, 1),            # nothing deformable
    ("pgg", [0], True, None),         # glides generate infinite groups
])
def test_subgroup_of_deformed_side_pairings(name, edges, holds, order):
    result = criterion_4_3(wallpaper.group(name), edges)
    assert result.holds is holds
    if not holds:
        assert len(result.witness) == order and result.witness[0].is_identity
        group = wallpaper.group(name)
        members = set(result.witness)
        assert all(g @ h in members for g in result.witness for h in result.witness)  # a subgroup
        assert all(group.contains(h) for h in result.witness)


@pytest.mark.parametrize("name,edges", [("p2", [1]), ("p3", [0]), ("p4", [1]), ("p6", [0]), ("p6", [1])])
def test_failing_blocks_lift_together(name, edges):
    group = wallpaper.group(name)
    corners = np.asarray(group.fundamental_domain().exterior.coords)
    rng = np.random.default_rng(1)
    deformation = {}
    for e in edges:
        p, q = corners[e], corners[e + 1]
        normal = np.array([q[1] - p[1], p[0] - q[0]])
        deformation[e] = [p + 0.5 * (q - p) + rng.uniform(0.05, 0.15) * normal]
    result = criterion_4_3(escher_block(group, deformation))
    assert not result.holds
    assert result.union_difference < 1e-9 * group.cell_area  # U h(F) = U h(F'): H can be lifted
    assert "can be lifted together" in str(result)


@pytest.mark.parametrize("name", ["p1", "p2", "p3", "p4", "p6"])
def test_fully_deformed_blocks_satisfy_the_criterion(name):
    block = random_block(wallpaper.group(name), np.random.default_rng(5))
    assert criterion_4_3(block).holds


def test_points_on_the_edge_do_not_deform_it():
    group = wallpaper.group("p1", gamma=90)
    flat = escher_block(group, {0: [(0.5, 0.0)], 1: [(1.0, 0.5)]})  # F' = F
    result = criterion_4_3(flat)
    assert not result.holds and result.deformed_edges == () and result.union_difference == 0.0
    bent = escher_block(group, {0: [(0.5, 1e-6)], 1: [(1.0, 0.5)]})
    assert criterion_4_3(bent).holds


def test_bad_input():
    with pytest.raises(InterlockError, match="edge 9 does not exist"):
        criterion_4_3(wallpaper.group("p4"), [9])
    with pytest.raises(InterlockError, match="needs an Escher Block or a WallpaperGroup"):
        criterion_4_3("p4")
    block = escher_block(wallpaper.group("p4"), {})
    with pytest.raises(InterlockError, match="give deformed_edges only with a group"):
        criterion_4_3(block, [0])


def _p1_block_near_its_line(delta):
    group = wallpaper.group("p1")
    p, q = np.asarray(group.fundamental_domain().exterior.coords)[:2]
    along = (q - p) / np.linalg.norm(q - p)
    return escher_block(group, {0: [p + 0.4 * (q - p) + delta * np.array([along[1], -along[0]])]})


@pytest.mark.parametrize("delta,holds", [(1e-3, True), (1e-9, True), (1e-10, None), (1e-13, None), (0.0, False)])
def test_points_within_the_tolerance_of_their_line_make_the_criterion_inconclusive(delta, holds):
    # between rounding and the generator's tolerance floating point cannot say whether the edge is deformed
    result = criterion_4_3(_p1_block_near_its_line(delta))
    assert result.holds is holds
    if holds is None:
        assert result.uncertain_edges == (0, 2) and "inconclusive" in str(result)
        assert result.to_dict()["uncertain_edges"] == [0, 2]
