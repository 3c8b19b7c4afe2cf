"""Holding out the blocks the Coulomb fixed point cannot hold (interlock.verify.statics.cra_split)."""

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly
from interlock.verify.statics import cra_coulomb, cra_ipopt, cra_large, cra_split
from interlock.verify.statics.cra import CRAProblem


def _tower(count=4, mu=0.5):
    cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in range(count)]
    assembly = Assembly.from_meshes(cubes, frame=[0])
    problem = CRAProblem.build(assembly, mu)
    b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    return assembly, problem, b_eq


def test_without_blocks_is_the_problem_of_the_assembly_without_them():
    # Holding out the top cube of four: the rest's equilibrium rows are those of the three-cube tower (force rows
    # alike; moment rows over the model size, which is the same up to the ratio of sizes), its load the whole's
    # rows of the kept blocks, and the held-out block's contact goes with it
    assembly, problem, b_eq = _tower()
    rest, rows, vertices = cra_split.without_blocks(problem, (3,))
    smaller = CRAProblem.build(Assembly.from_meshes(assembly.world_meshes()[:3], frame=[0]), 0.5)
    force_rows = np.tile([True] * 3 + [False] * 3, 2)
    assert rest.system.a_eq.shape == smaller.system.a_eq.shape == (12, 24)
    assert np.allclose(rest.system.a_eq.toarray()[force_rows], smaller.system.a_eq.toarray()[force_rows])
    assert np.allclose(rest.system.a_ub.toarray(), smaller.system.a_ub.toarray())
    assert rest.system.free.tolist() == [1, 2] and int(vertices.sum()) == 8 and rows.sum() == 12
    assert [(c.i, c.j) for c in rest.system.contacts] == [(0, 1), (1, 2)]
    assert (rest.kinematic != rest.system.a_eq.T).nnz == 0
    assert np.allclose(b_eq[rows], b_eq[:12])


def test_bound_blocks_names_the_block_that_slid_to_eta():
    # The third cube slides by eta (in units of eps, the bound of (11)) against both its neighbours; the fourth
    # rides along. Contacts 1-2 and 2-3 are at the bound, and cube 2 is in both
    _, problem, _ = _tower()
    motion = np.zeros(18)
    motion[6:9] = [problem.ratio, 0.0, -1.0]
    assert cra_coulomb.bound_blocks(problem, motion) == (2,)
    motion[12:15] = motion[6:9]  # the top cube moves with it: only contact 1-2 is at the bound
    assert cra_coulomb.bound_blocks(problem, motion) == (2,)
    motion[6:9] = 0.0  # the top cube alone: contact 2-3, the block that moved
    assert cra_coulomb.bound_blocks(problem, motion) == (3,)
    assert cra_coulomb.bound_blocks(problem, np.zeros(18)) == ()


@pytest.mark.skipif(not cra_ipopt.available(), reason="IPOPT (CasADi) is optional")
def test_split_route_places_the_held_out_block_and_the_exact_lp_accepts_the_whole():
    # The top cube held out: the rest settles (Coulomb fixed point), the top cube is placed on it by IPOPT, and
    # the exact LP of the whole accepts the motion: a solution of (11) for all four cubes
    _, problem, b_eq = _tower()
    found, how = cra_split.split_route(problem, b_eq, (3,), cra_large.exact, seed=1)
    assert found is not None, how
    motion, forces = found
    assert "holding out block 3" in how and "placed by IPOPT" in how
    assert np.abs(problem.system.a_eq @ forces.ravel() - b_eq).max() < 1e-7
    dd = (problem.kinematic @ motion).reshape(-1, 3)
    assert np.all(dd[:, 0] >= -1 - 1e-9) and np.all(np.abs(forces[dd[:, 0] > -1 + 1e-6]) == 0)  # Eq. (10)
    assert cra_large.exact(problem, b_eq, motion) is not None


def test_split_route_without_ipopt_says_what_it_needs(monkeypatch):
    _, problem, b_eq = _tower()
    monkeypatch.setattr(cra_ipopt, "available", lambda: False)
    found, why = cra_split.split_route(problem, b_eq, (3,), cra_large.exact)
    assert found is None and "interlock[nlp]" in why and "block 3" in why
