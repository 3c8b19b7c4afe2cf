"""Lozenge tilings: hexagons and plane partitions (MacMahon), uniform sampling, height functions, periodic tilings."""

import math
from fractions import Fraction
from itertools import combinations_with_replacement, product

import numpy as np
import pytest
import shapely
from scipy.stats import chisquare

from interlock import InterlockError
from interlock.blocks import lozenge, trilattice
from interlock.blocks.lozenge import (
    DOWN,
    LATTICE_BASIS,
    UP,
    UP_OFFSETS,
    Lozenge,
    LozengeTiling,
    TilingError,
    hexagon_triangles,
    random_hexagon,
    staircase,
)

#: Significance level of the chi-square tests: a uniform sampler passes, a biased one fails.
ALPHA = 1e-3
#: Samples drawn for the chi-square test (about 50 per tiling of the 2 x 2 x 2 hexagon).
SAMPLES = 1000
#: Areas in the plane agree to this.
AREA_TOL = 1e-9
LOZENGE_AREA = math.sqrt(3) / 2


def plane_partitions(a, b, c):
    """Every plane partition in an a x b box with entries <= c, row by row (rows non-increasing)."""
    rows = [np.array(r[::-1]) for r in combinations_with_replacement(range(c + 1), b)]

    def extend(done):
        if len(done) == a:
            yield np.array(done, dtype=int).reshape(a, b)
            return
        for row in rows:
            if not done or np.all(row <= done[-1]):
                yield from extend(done + [row])

    yield from extend([])


def macmahon(a, b, c):
    """prod_{i,j,k} (i + j + k - 1) / (i + j + k - 2), exactly."""
    total = Fraction(1)
    for i, j, k in product(range(1, a + 1), range(1, b + 1), range(1, c + 1)):
        total *= Fraction(i + j + k - 1, i + j + k - 2)
    return int(total)


def count_tilings(triangles):
    """Lozenge tilings of a set of triangles, by backtracking (independent of plane partitions)."""
    todo = set(map(tuple, np.asarray(triangles).tolist()))

    def partners(i, j, kind):
        if kind == DOWN:
            return [(i + di, j + dj, UP) for di, dj in UP_OFFSETS.tolist()]
        return [(i - di, j - dj, DOWN) for di, dj in UP_OFFSETS.tolist()]

    def count(left):
        if not left:
            return 1
        first = min(left)
        return sum(count(left - {first, other}) for other in partners(*first) if other in left)

    return count(frozenset(todo))


def key(tiling):
    return tiling.lozenges.tobytes()


def forward_coupling(a, b, c, rng):
    """A classic biased sampler: run the monotone chain forward until the extreme chains meet."""
    low, high = np.zeros((a, b), dtype=int), np.full((a, b), c)
    while not np.array_equal(low, high):
        r, s, u = rng.integers(a), rng.integers(b), rng.random()
        for x in (low, high):
            top = min(x[r - 1, s] if r else c, x[r, s - 1] if s else c)
            bottom = max(x[r + 1, s] if r + 1 < a else 0, x[r, s + 1] if s + 1 < b else 0)
            x[r, s] = bottom + int(u * (top - bottom + 1))
    return LozengeTiling.from_plane_partition(low, c)


# --- hexagons and plane partitions (Sec. 4.4) -------------------------------------------------------------

@pytest.mark.parametrize("a, b, c", [(1, 1, 1), (2, 3, 4), (5, 2, 3), (3, 0, 2), (0, 0, 3), (4, 4, 0)])
def test_hexagon_has_ab_plus_bc_plus_ca_lozenges(a, b, c):
    tiling = random_hexagon(a, b, c, seed=a + 10 * b + 100 * c)
    assert len(tiling) == a * b + b * c + c * a
    assert tiling.orientation_counts == (b * c, c * a, a * b)
    assert len(hexagon_triangles(a, b, c)) == 2 * len(tiling)
    region = shapely.Polygon(np.array([(a, 0), (a - b, b), (-b, b), (-b, b - c), (0, -c), (a, -c)]) @ LATTICE_BASIS)
    union = shapely.union_all(shapely.polygons(tiling.polygons()))
    assert region.area == pytest.approx(len(tiling) * LOZENGE_AREA, abs=AREA_TOL)
    assert shapely.symmetric_difference(union, region).area == pytest.approx(0, abs=AREA_TOL)


@pytest.mark.parametrize("a, b, c", [(1, 1, 1), (2, 2, 2), (3, 3, 3), (2, 3, 4), (1, 4, 2)])
def test_tiling_counts_match_macmahon(a, b, c):
    tilings = {key(LozengeTiling.from_plane_partition(pp, c)) for pp in plane_partitions(a, b, c)}
    assert len(tilings) == macmahon(a, b, c)
    assert macmahon(2, 2, 2) == 20 and macmahon(3, 3, 3) == 980


@pytest.mark.parametrize("a, b, c, count", [(2, 2, 2, 20), (3, 3, 3, 980), (2, 3, 1, 10)])
def test_hexagon_tilings_found_by_search_are_macmahons(a, b, c, count):
    assert count_tilings(hexagon_triangles(a, b, c)) == macmahon(a, b, c) == count


def test_random_hexagon_is_uniform_and_a_biased_sampler_is_rejected():
    index = {key(LozengeTiling.from_plane_partition(pp, 2)): k for k, pp in enumerate(plane_partitions(2, 2, 2))}
    rng = np.random.default_rng(7)
    fair, biased = np.zeros(len(index), dtype=int), np.zeros(len(index), dtype=int)
    for _ in range(SAMPLES):
        fair[index[key(random_hexagon(2, 2, 2, seed=rng))]] += 1
        biased[index[key(forward_coupling(2, 2, 2, rng))]] += 1
    assert fair.sum() == biased.sum() == SAMPLES  # every sample is one of the 20 tilings
    assert chisquare(fair).pvalue > ALPHA
    assert chisquare(biased).pvalue < ALPHA


def test_random_hexagon_is_reproducible_and_varies_with_the_seed():
    first, again, other = (random_hexagon(6, 5, 4, seed=s) for s in (3, 3, 4))
    assert np.array_equal(first.lozenges, again.lozenges)
    assert not np.array_equal(first.lozenges, other.lozenges)
    rng = np.random.default_rng(0)
    assert len({key(random_hexagon(3, 3, 3, seed=rng)) for _ in range(20)}) > 10


# --- height functions ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("a, b, c", [(2, 3, 2), (1, 1, 3)])
def test_round_trip_through_height_functions(a, b, c):
    for pp in plane_partitions(a, b, c):
        tiling = LozengeTiling.from_plane_partition(pp, c)
        heights = tiling.height_function()
        back = LozengeTiling.from_height_function(heights)
        assert np.array_equal(back.lozenges, tiling.lozenges)
        assert np.array_equal(back.to_plane_partition(), pp)


def test_heights_are_x_plus_y_plus_z_of_the_cube_stack():
    tiling = random_hexagon(7, 6, 5, seed=11)
    pp, heights = tiling.to_plane_partition(), tiling.height_function()
    assert len(heights) == 7 * 6 + 6 * 5 + 5 * 7 + 7 + 6 + 5 + 1  # vertices of the hexagon (Euler)
    for x, y in np.ndindex(pp.shape):
        z = pp[x, y]
        assert heights[x - y, y - z] == x + y + z
    for (i, j), h in heights.items():  # each lattice edge changes the height by +1 or -2
        for di, dj in ((1, 0), (-1, 1), (0, -1)):
            if (i + di, j + dj) in heights:
                assert heights[i + di, j + dj] - h in (1, -2)


def test_large_round_trip():
    tiling = random_hexagon(15, 12, 9, seed=5)
    pp = tiling.to_plane_partition()
    assert pp.shape == (15, 12) and pp.max() <= 9
    assert np.all(np.diff(pp, axis=0) <= 0) and np.all(np.diff(pp, axis=1) <= 0)
    back = LozengeTiling.from_height_function(tiling.height_function())
    assert np.array_equal(back.lozenges, tiling.lozenges)


# --- boundary and neighbours ------------------------------------------------------------------------------------

def test_boundary_is_the_lozenges_touching_the_outline():
    a, b, c = 5, 4, 3
    tiling = random_hexagon(a, b, c, seed=2)
    outline = shapely.LinearRing(np.array([(a, 0), (a - b, b), (-b, b), (-b, b - c), (0, -c), (a, -c)]) @ LATTICE_BASIS)
    touching = [k for k, poly in enumerate(tiling.polygons()) if shapely.Polygon(poly).distance(outline) < AREA_TOL]
    assert list(tiling.boundary()) == touching
    assert 0 < len(touching) < len(tiling)


def test_adjacency_counts_shared_edges():
    a, b, c = 4, 5, 3
    tiling = random_hexagon(a, b, c, seed=9)
    pairs = tiling.adjacency()
    assert len(pairs) == 2 * len(tiling) - (a + b + c)  # 4 edges per lozenge, 2 (a + b + c) on the outline
    polygons = shapely.polygons(tiling.polygons())
    for p, q in pairs.tolist():
        assert shapely.intersection(polygons[p], polygons[q]).length == pytest.approx(1.0)


# --- periodic tilings -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("counts", [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (0, 2, 1), (3, 1, 0), (1, 1, 1),
                                    (1, 2, 3), (2, 2, 2), (4, 1, 2)])
def test_staircases_tile_the_plane(counts):
    tiling = staircase(counts)
    g = math.gcd(*counts)
    assert tiling.orientation_counts == tuple(n // g for n in counts)
    assert len(tiling) == tiling.cell_size == sum(counts) // g
    reps = range(-3, 4)
    big = np.concatenate([tiling.lozenges + (*(m * tiling.periods[0] + n * tiling.periods[1]), 0)
                          for m, n in product(reps, reps)])
    patch = LozengeTiling(big)  # no two copies overlap
    covered = set(map(tuple, patch.triangles().tolist()))
    # every triangle near the origin is covered (no gaps)
    assert all((i, j, kind) in covered for i, j, kind in product(range(-2, 3), range(-2, 3), (UP, DOWN)))


def test_periodic_tilings_reject_gaps_and_overlaps():
    tiling = staircase((1, 1, 1))
    with pytest.raises(TilingError, match="needs exactly 3 lozenges per period"):
        LozengeTiling.periodic(tiling.lozenges[:2], tiling.periods)
    moved = tiling.lozenges.copy()
    moved[0, :2] += tiling.periods[0]  # the same lozenge in another period: still a fundamental patch
    assert np.array_equal(LozengeTiling.periodic(moved, tiling.periods).orientation_counts, (1, 1, 1))
    with pytest.raises(TilingError, match="overlap.*modulo the periods"):
        LozengeTiling.periodic(np.vstack([tiling.lozenges, moved[:1]]), tiling.periods)
    with pytest.raises(TilingError, match="linearly independent"):
        LozengeTiling.periodic([(0, 0, 0)], [(1, 0), (2, 0)])
    with pytest.raises(TilingError, match="finite tilings"):
        tiling.height_function()


# --- invalid input -----------------------------------------------------------------------------------------------

@pytest.mark.parametrize("partition, c, message", [
    ([[1, 2], [0, 0]], 2, "non-increasing along rows and columns.*along its row"),
    ([[1, 1], [2, 0]], 2, "non-increasing along rows and columns.*down its column"),
    ([[3, 1], [1, 0]], 2, r"entries must lie in 0\.\.c = 0\.\.2"),
    ([[1, -1]], 2, r"entries must lie in 0\.\.c"),
    ([[1.5, 0]], 2, "must be integers"),
    ([1, 0], 2, "a x b matrix"),
    ([[1, 0]], -1, "side c must be an integer >= 0"),
])
def test_invalid_plane_partitions_are_rejected(partition, c, message):
    with pytest.raises(TilingError, match=message):
        LozengeTiling.from_plane_partition(partition, c)


@pytest.mark.parametrize("sizes", [(-1, 2, 2), (2, -3, 1), (1, 1, 2.5), (True, 1, 1)])
def test_invalid_hexagon_sizes_are_rejected(sizes):
    with pytest.raises(TilingError, match="must be an integer >= 0"):
        random_hexagon(*sizes, seed=0)
    with pytest.raises(InterlockError):
        hexagon_triangles(*sizes)


def test_overlaps_and_gaps_are_rejected():
    with pytest.raises(TilingError, match=r"lozenges overlap: D\(0, 0\)\+U\(0, 1\) and D\(0, 0\)\+U\(1, 0\) both cover "
                                          r"D\(0, 0\); each triangle may lie in one lozenge only"):
        LozengeTiling([(0, 0, 0), (0, 0, 2)])
    with pytest.raises(TilingError, match=r"both cover U\(1, 0\)"):
        LozengeTiling([Lozenge(0, 0, 2), Lozenge(1, -1, 0)])
    tiling = random_hexagon(3, 2, 2, seed=1)
    region = hexagon_triangles(3, 2, 2)
    with pytest.raises(TilingError, match=r"leave 2 triangle\(s\) of the region uncovered.*cover its region exactly"):
        LozengeTiling.from_lozenges(tiling.lozenges[1:], region)
    with pytest.raises(TilingError, match=r"2 triangle\(s\) of the lozenges lie outside the region"):
        LozengeTiling.from_lozenges(np.vstack([tiling.lozenges, [(10, 10, 1)]]), region)
    with pytest.raises(TilingError, match="orientation must be 0, 1 or 2"):
        LozengeTiling([(0, 0, 3)])
    with pytest.raises(TilingError, match=r"rows \(i, j, orientation\)"):
        LozengeTiling([(0, 0)])


def test_invalid_height_functions_are_rejected():
    heights = random_hexagon(2, 2, 2, seed=0).height_function()
    flat = dict.fromkeys(heights, 0)
    with pytest.raises(TilingError, match=r"change by \+1 \(tile edge\) or -2 \(across a lozenge\)"):
        LozengeTiling.from_height_function(flat)
    lone = {(0, 0): 0, (1, 0): -2, (0, 1): -1}  # one up-triangle whose bottom edge is a diagonal
    with pytest.raises(TilingError, match="across the region's boundary.*boundary edges must be tile edges"):
        LozengeTiling.from_height_function(lone)
    with pytest.raises(TilingError, match="non-empty mapping"):
        LozengeTiling.from_height_function({})


def test_only_hexagons_have_plane_partitions():
    with pytest.raises(TilingError, match="not an a x b x c hexagon"):
        LozengeTiling([(0, 0, 0), (5, 5, 1)]).to_plane_partition()
    with pytest.raises(TilingError, match="falls apart"):
        LozengeTiling([(0, 0, 0), (5, 5, 1)]).height_function()


def test_lattice_names_are_exported_from_lozenge():
    for name in ("LATTICE_BASIS", "UP", "DOWN", "UP_OFFSETS", "LOZENGE_CORNERS", "Lozenge", "TilingError",
                 "hexagon_triangles"):
        assert name in lozenge.__all__ and getattr(lozenge, name) is getattr(trilattice, name)
