"""The order of the margin's lower bounds in interlock/verify/margin.py ``assess``: the one-stress bound first where
it is cheap and its sample predicts a proof, the load paths otherwise; never more than the exact margin."""

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from interlock import wallpaper
from interlock.blocks import Assembly, escher_block, patch
from interlock.formats import read, write
from interlock.verify import check, contacts, interlocking_matrix
from interlock.verify.margin import (ONE_STRESS_PROBE, assess, margin_lower_bound, one_stress_bounds,
                                     rounding_tolerance, row_tolerances)


@pytest.fixture(scope="module")
def escher_float32(tmp_path_factory):
    """The p4 Escher patch of radius 2 (ring fixed) of the scaling benchmark, turned, as binary STL read back."""
    made = patch(escher_block(wallpaper.group("p4"), {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}), 2, frame="boundary")
    turn = Rotation.random(random_state=20).as_matrix()
    turned = Assembly.from_meshes([trimesh.Trimesh(m.vertices @ turn.T, m.faces, process=False)
                                   for m in made.world_meshes()], frame=made.frame)
    path = tmp_path_factory.mktemp("escher") / "escher.stl"
    write(turned, path)
    assembly = read(path)
    found = contacts(assembly)
    A = interlocking_matrix(assembly, assembly.frame, contacts=found)
    stress = check(assembly, validate=False, contacts=found).stress
    return assembly, found, A, stress


def _margin_at_most(A, eps, columns):
    """An upper bound on the exact margin ``rho = 1 / max {||x||_inf : A x >= -eps}``: the coordinate LPs of
    ``columns`` (both signs) reach at most that far."""
    import scipy.optimize

    n = A.shape[1]
    reach = 0.0
    for j in columns:
        for sign in (1.0, -1.0):
            objective = np.zeros(n)
            objective[j] = -sign
            result = scipy.optimize.linprog(objective, A_ub=-A, b_ub=eps, bounds=(None, None), method="highs")
            assert result.status == 0
            reach = max(reach, -result.fun)
    return 1.0 / reach


@pytest.mark.parametrize("times, route", [(1, "one stress"), (200, "demand stress"), (200, "load paths")])
def test_the_margin_never_exceeds_the_exact_one(escher_float32, times, route, monkeypatch):
    """At the float32 tolerance (the one-stress bound goes first and proves) and 200 times it (its sample is above
    ONE_STRESS_PROBE: with at most DEMAND_FIRST_COLUMNS coordinates the stress built for their loads goes first,
    else the load paths), the proved margin is at most the exact margin (bounded above by the coordinate LPs of the
    ten coordinates the one-stress bound finds worst), and at least the one-stress bound's."""
    from interlock.verify import margin as margins

    assembly, found, A, stress = escher_float32
    assert A.shape[1] <= margins.DEMAND_FIRST_COLUMNS
    if route == "load paths":
        monkeypatch.setattr(margins, "DEMAND_FIRST_COLUMNS", 0)
    tolerance, source = rounding_tolerance(assembly)
    assert source == "float32 input"
    eps = row_tolerances(A, found, times * tolerance)
    margin = assess(A, found, assembly.scale, stress, times * tolerance, "given")
    one_stress = margin_lower_bound(A.matrix, eps, stress)
    worst = np.argsort(one_stress_bounds(A.matrix, eps, stress)[0])[-10:]
    exact = _margin_at_most(A.matrix.tocsr(), eps, worst)
    assert margin.lower > 1 and margin.upper_status == "not needed"
    assert one_stress * (1 - 1e-9) <= margin.lower <= exact * (1 + 1e-9)
    sample, _ = one_stress_bounds(A.matrix, eps, stress,
                                  np.sort(np.random.default_rng(0).permutation(A.shape[1])[:64]))
    if times == 1:  # the sample predicts a proof: the one-stress bound is the margin proved
        assert sample.max() <= ONE_STRESS_PROBE and margin.lower == pytest.approx(one_stress, rel=1e-12)
    elif route == "demand stress":  # the stress built for the loads proves more than the float verdict's
        assert sample.max() > ONE_STRESS_PROBE and margin.lower > 1.5 * one_stress
    else:  # the load paths went first and prove more than one stress does
        assert sample.max() > ONE_STRESS_PROBE and margin.lower > 2 * one_stress
