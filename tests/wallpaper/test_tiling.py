"""The tiling by g(F): cover without overlap, side pairings, rotation centres, closure."""

import numpy as np
import pytest
import shapely

from interlock import GroupError, wallpaper
from tests.conftest import all_groups_and_lattices

CASES = all_groups_and_lattices()


def _window(g, cells=2.5):
    return cells * np.sqrt(g.cell_area)


@pytest.mark.parametrize("name,a,b,gamma", CASES)
def test_tiles_cover_disc_without_overlap(name, a, b, gamma):
    g = wallpaper.group(name, a, b, gamma)
    r = _window(g)
    elements = g.elements_within(r)
    tiles = g.tiles(elements)
    center = shapely.Point(g.fundamental_domain().centroid)
    disc = center.buffer(r / 2, quad_segs=64)
    scale = g.cell_area

    # no two tiles overlap
    left, right = shapely.STRtree(tiles).query(tiles, predicate="intersects")
    pairs = left < right
    overlap = shapely.area(shapely.intersection(tiles[left[pairs]], tiles[right[pairs]])).sum()
    touching = np.unique(np.concatenate([left[pairs], right[pairs]]))
    assert touching.size == len(tiles)  # every tile has a neighbour in the window
    assert overlap < 1e-9 * scale

    # they cover the disc of radius r/2
    inside = shapely.area(shapely.intersection(tiles, disc)).sum()
    assert inside == pytest.approx(disc.area, rel=1e-9)
    assert shapely.difference(disc, shapely.union_all(tiles)).area < 1e-9 * scale

    # every tile returned meets the disc of radius r, and no other tile does
    assert shapely.distance(tiles, center).max() <= r * (1 + 1e-9)
    more = set(g.elements_within(1.5 * r)) - set(elements)
    assert more and shapely.distance(g.tiles(list(more)), center).min() > r


@pytest.mark.parametrize("name,a,b,gamma", CASES)
def test_domain_area_and_orientation(name, a, b, gamma):
    g = wallpaper.group(name, a, b, gamma)
    F = g.fundamental_domain()
    assert F.is_valid and F.exterior.is_ccw
    assert F.area == pytest.approx(g.cell_area / g.point_group_order, rel=1e-12)


@pytest.mark.parametrize("name,a,b,gamma", CASES)
def test_side_pairings_are_consistent(name, a, b, gamma):
    g = wallpaper.group(name, a, b, gamma)
    F = g.fundamental_domain()
    V = g.domain_vertices
    n = len(V)
    pairings = g.side_pairings()
    assert [s.edge for s in pairings] == list(range(n))
    coords = np.asarray(F.exterior.coords)
    for s in pairings:
        # exact: g_e maps the partner edge onto edge e (as a set)
        image = {s.element.apply_exact(V[s.partner]), s.element.apply_exact(V[(s.partner + 1) % n])}
        assert image == {V[s.edge], V[(s.edge + 1) % n]}
        # involution
        back = pairings[s.partner]
        assert back.partner == s.edge and back.element == s.element.inverse()
        assert g.contains(s.element) and not s.element.is_identity
        # geometry: the tile across e touches F exactly along e, on the outside
        tile = g.tiles([s.element])[0]
        assert shapely.area(shapely.intersection(F, tile)) < 1e-12 * g.cell_area
        p, q = coords[s.edge], coords[s.edge + 1]
        outward = np.array([q[1] - p[1], p[0] - q[0]]) / np.linalg.norm(q - p)
        probe = (p + q) / 2 + 1e-6 * np.sqrt(g.cell_area) * outward
        assert tile.contains(shapely.Point(probe))
        # mirror edges are exactly the self-paired ones
        assert s.self_paired == (s.kind == "reflection")


@pytest.mark.parametrize("name", wallpaper.GROUPS)
def test_rotation_centres_on_boundary_are_vertices(name):
    g = wallpaper.group(name)
    V = g.domain_vertices
    n = len(V)
    centres = {
        c for e in g.elements_within(_window(g)) if (c := e.rotation_centre()) is not None
    }
    on_boundary = [c for c in centres if any(_on_segment(c, V[i], V[(i + 1) % n]) for i in range(n))]
    assert bool(on_boundary) == (name not in {"p1", "pm", "pg", "cm"})  # the groups without rotations
    for c in on_boundary:
        assert c in V, f"{name}: rotation centre {c} lies on an edge but is not a vertex"


def _on_segment(c, p, q):
    cross = (q[0] - p[0]) * (c[1] - p[1]) - (q[1] - p[1]) * (c[0] - p[0])
    dot = (c[0] - p[0]) * (q[0] - p[0]) + (c[1] - p[1]) * (q[1] - p[1])
    return cross == 0 and 0 <= dot <= (q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2


@pytest.mark.parametrize("name,a,b,gamma", CASES)
def test_group_closed_on_window(name, a, b, gamma):
    g = wallpaper.group(name, a, b, gamma)
    window = g.elements_within(_window(g, 1.0))
    for x in window:
        assert g.contains(x.inverse())
        assert (x @ x.inverse()).is_identity
        for y in window:
            assert g.contains(x @ y)
    # the Cartesian matrices are isometries and respect composition
    mats = g.matrices(window)
    linear = mats[:, :2, :2]
    np.testing.assert_allclose(linear @ linear.transpose(0, 2, 1), np.broadcast_to(np.eye(2), linear.shape), atol=1e-12)
    x, y = window[1], window[-1]
    np.testing.assert_allclose(g.matrix(x @ y), g.matrix(x) @ g.matrix(y), atol=1e-12)


def test_non_members_are_rejected():
    p4 = wallpaper.group("p4")
    assert not p4.contains(wallpaper.parse_symop("-x,y"))  # a reflection
    assert not p4.contains(wallpaper.parse_symop("x+1/2,y"))  # not a lattice translation
    assert p4.contains(wallpaper.parse_symop("-y+3,x-2"))
    with pytest.raises(GroupError, match="not an element of p4"):
        p4.decompose(wallpaper.parse_symop("-x,y"))
