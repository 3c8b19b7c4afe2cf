"""The margin's lower bounds (interlock/verify/margin.py, load_paths.py) are proofs: what a float stress or a float
solve misses of its load is counted (docs/interlocking.md, "Margin and tolerance"), so no proved bound on a
coordinate lies below the exact LP's value of that coordinate."""

import numpy as np
import pytest
import scipy.optimize
import scipy.sparse as sp
import trimesh
from scipy.spatial.transform import Rotation

from interlock import wallpaper
from interlock.blocks import Assembly, escher_block, patch, random_hexagon, rhomblock_assembly
from interlock.formats import read, write
from interlock.verify import check, contacts, interlocking_matrix
from interlock.verify.load_paths import closed_bounds, load_path_bound
from interlock.verify import margin
from interlock.verify.margin import (SINGLE_MISS, assess, margin_lower_bound, one_stress_bounds, rounding_tolerance,
                                     row_tolerances)


def _reach(A, eps, column, sign):
    """The exact LP of one coordinate: ``max sign * x_j`` subject to ``A x >= -eps`` (HiGHS)."""
    objective = np.zeros(A.shape[1])
    objective[column] = -sign
    result = scipy.optimize.linprog(objective, A_ub=-A, b_ub=eps, bounds=(None, None), method="highs")
    assert result.status == 0
    return -result.fun


def _naive(A, eps, w):
    """The one-stress bounds as computed before they were proved: ``A^T w`` and the solves' residuals taken as zero."""
    dense = A.toarray()
    U = dense @ np.linalg.solve(dense.T @ dense, np.eye(dense.shape[1]))
    ratios = U / w[:, None]
    plus, minus = np.maximum(0.0, ratios.max(axis=0)), np.maximum(0.0, -ratios.min(axis=0))
    return plus * (eps @ w) - eps @ U, minus * (eps @ w) + eps @ U, U


def test_a_stress_that_is_none_no_longer_overstates_the_margin():
    """Three cubes in a row, the outer ones fixed: the middle one reaches 0.002 along the row.  With the "stress"
    w = (1.5, 1) (A^T w = 0.5, not 0) the old bound claimed 1/600 (a margin of 600 against the exact 500); the
    miss is now counted and the margin proved is below the exact one."""
    A = sp.csr_matrix(np.array([[1.0], [-1.0]]))
    eps = np.array([1e-3, 2e-3])
    w = np.array([1.5, 1.0])
    plus, minus, _ = _naive(A, eps, w)
    exact = 1.0 / max(_reach(A.toarray(), eps, 0, 1.0), _reach(A.toarray(), eps, 0, -1.0))
    assert exact == pytest.approx(500.0)
    assert 1.0 / max(plus.max(), minus.max()) == pytest.approx(600.0)  # the old claim: wrong
    assert margin_lower_bound(A, eps, w) <= exact
    assert margin_lower_bound(A, eps, np.ones(2)) == pytest.approx(exact, rel=1e-9)  # a true stress loses nothing


@pytest.fixture(scope="module")
def cage():
    """A unit cube held by six fixed neighbours, with its float64 verdict's stress."""
    cubes = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]])
             for x, y in [(1, 1), (0, 1), (2, 1), (1, 0), (1, 2)]]
    made = Assembly.from_meshes(cubes + [trimesh.creation.box(bounds=[[1, 1, z], [2, 2, z + 1]]) for z in (-1, 1)])
    frame = [1, 2, 3, 4, 5, 6]
    found = contacts(made)
    A = interlocking_matrix(made, frame=frame, contacts=found)
    verdict = check(made, frame=frame, validate=False, contacts=found)
    assert verdict.interlocked
    return made, found, A, verdict.stress


@pytest.mark.parametrize("column", range(6))
def test_a_perturbed_stress_is_paid_for_on_every_coordinate(cage, column):
    """A positive ``w`` shaped after the least-squares load of one coordinate (``A^T w`` far from 0): the old
    formula bounded that coordinate at about half its exact reach (a wrong proof); the proved bound is not below
    the exact LP (here: nothing is proved, the miss exceeds the load)."""
    _, found, A, _ = cage
    eps = row_tolerances(A, found, 1e-3)
    U = _naive(A.matrix, eps, np.ones(A.shape[0]))[2]
    w = np.maximum(U[:, column], 0.0) + 1e-3
    exact = _reach(A.matrix.toarray(), eps, column, 1.0)
    old = _naive(A.matrix, eps, w)[0][column]
    assert old < 0.6 * exact
    bounds = closed_bounds(*one_stress_bounds(A.matrix, eps, w))
    assert bounds[column] >= exact


def test_the_true_stress_keeps_its_bound(cage):
    """With the float verdict's stress (``|A^T w|_1`` ~ 1e-15) the proved bound equals the old one to 1e-9."""
    _, found, A, stress = cage
    eps = row_tolerances(A, found, 1e-3)
    plus, minus, _ = _naive(A.matrix, eps, stress)
    assert margin_lower_bound(A.matrix, eps, stress) == pytest.approx(1.0 / np.maximum(plus, minus).max(), rel=1e-9)


def _escher():
    made = patch(escher_block(wallpaper.group("p4"), {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}), 2, frame="boundary")
    return made, 20


def _hexagon():
    return rhomblock_assembly(random_hexagon(4, 4, 4, seed=0), 0, frame="boundary"), 40


@pytest.fixture(scope="module", params=["escher", "hexagon"])
def float32_case(request, tmp_path_factory):
    """A p4 Escher patch of radius 2 and a RhomBlock hexagon 4 x 4 x 4 (ring fixed), turned and written as binary
    STL (float32) as the scaling benchmark does, read back, with the contacts, matrix and float verdict's stress."""
    made, seed = _escher() if request.param == "escher" else _hexagon()
    turn = Rotation.random(random_state=seed).as_matrix()
    turned = Assembly.from_meshes([trimesh.Trimesh(m.vertices @ turn.T, m.faces, process=False)
                                   for m in made.world_meshes()], frame=made.frame)
    path = tmp_path_factory.mktemp(request.param) / "float32.stl"
    write(turned, path)
    assembly = read(path)
    found = contacts(assembly)
    A = interlocking_matrix(assembly, assembly.frame, contacts=found)
    verdict = check(assembly, validate=False, contacts=found)
    assert verdict.interlocked
    return assembly, found, A, verdict.stress


@pytest.mark.parametrize("times", [1, 100])
def test_no_proved_bound_lies_below_the_exact_lp(float32_case, times):
    """For 12 coordinates (the six the one-stress bound finds worst, six at random) and both signs: the one-stress
    bound, the load-path bound, and the margin ``assess`` proves are on the safe side of the exact coordinate LPs."""
    assembly, found, A, stress = float32_case
    tolerance, source = rounding_tolerance(assembly)
    assert source == "float32 input"
    eps = row_tolerances(A, found, times * tolerance)
    dense = A.matrix.toarray()
    n = A.shape[1]
    raw, slack = one_stress_bounds(A.matrix, eps, stress)
    assert 0 < slack.max() <= SINGLE_MISS  # a float stress and float32 solves: small misses, counted
    stressed = closed_bounds(raw, slack)
    paths = load_path_bound(A.matrix, eps, A.block_size)
    chosen = np.union1d(np.argsort(raw)[-6:], np.random.default_rng(0).permutation(n)[:6])
    reach = 0.0
    for column in chosen:
        for side, sign in enumerate((1.0, -1.0)):
            exact = _reach(dense, eps, int(column), sign)
            reach = max(reach, exact)
            assert stressed[column] >= exact
            assert paths.coordinates[column, side] >= exact
    margin = assess(A, found, assembly.scale, stress, times * tolerance, "given")
    assert margin.lower <= 1.0 / reach


def test_float32_solves_lose_little_and_are_redone_where_they_miss(float32_case, monkeypatch):
    """The one-stress bound solves with a float32 factor and pays for the residual in ``delta``: the bounds it
    proves are within 1e-3 of those from float64 solves; where a chunk misses by more than SINGLE_MISS (here: any
    miss at all) it is solved again in float64, and its misses are float64's."""
    assembly, found, A, stress = float32_case
    eps = row_tolerances(A, found, rounding_tolerance(assembly)[0])
    single = closed_bounds(*one_stress_bounds(A.matrix, eps, stress))
    monkeypatch.setattr(margin, "SINGLE_MISS", 0.0)
    raw, slack = one_stress_bounds(A.matrix, eps, stress)
    assert slack.max() < 1e-6
    double = closed_bounds(raw, slack)
    np.testing.assert_allclose(single, double, rtol=1e-3)


@pytest.mark.parametrize("perturbation", [1e-10, 0.2])
def test_the_local_solutions_count_what_they_miss(monkeypatch, perturbation):
    """The load paths' local LPs (6 x 30, random) return forces whose miss of the load, computed in exact rational
    arithmetic on the real columns (a slack left in the basis is no row of A), is at most the miss they report;
    with the loads perturbed by 20 % while pivoting the forces solved with the true loads come out negative and are
    dropped, and the reported misses grow with them."""
    from fractions import Fraction

    from interlock.verify import load_paths

    monkeypatch.setattr(load_paths, "LOAD_PATH_PERTURBATION", perturbation)
    rng = np.random.default_rng(1)
    count, s, rows = 40, 6, 30
    M = np.concatenate([rng.normal(size=(count, s, rows)), np.broadcast_to(-np.eye(s), (count, s, s)),
                        np.broadcast_to(np.eye(s), (count, s, s))], axis=2)
    c = np.concatenate([rng.uniform(1e-3, 2e-3, (count, rows)), np.full((count, 2 * s), np.inf)], axis=1)
    b = rng.normal(size=(count, s))
    values, _, _, basis, forces, misses = load_paths._simplex(M, c, np.where(np.isfinite(c), c, 0.0), b, 200)
    assert np.isfinite(values).any()
    largest = 0.0
    for k in range(count):
        miss = Fraction(0)
        for i in range(s):
            total = -Fraction(float(b[k, i]))
            for column, force in zip(basis[k], forces[k]):
                if column < rows:
                    total += Fraction(float(M[k, i, column])) * Fraction(float(force))
            miss += abs(total)
        assert miss <= Fraction(float(misses[k]))
        largest = max(largest, float(miss))
    assert (largest > 1e-6) == (perturbation > 1e-3)
