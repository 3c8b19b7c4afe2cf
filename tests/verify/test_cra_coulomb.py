"""The Coulomb fixed point for CRA's problem (11) (interlock.verify.statics.cra_coulomb)."""

import math
from functools import partial

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from interlock.blocks import Assembly, load_compas
from interlock.verify import contacts
from interlock.verify.statics import cra, cra_coulomb, cra_ipopt, cra_local, tilted_gravity
from interlock.verify.statics.cra import CRAProblem
from tests.verify.test_stability import _stack


def _problem(assembly, mu, gravity):
    problem = CRAProblem.build(assembly, mu)
    b_eq, _ = problem._right_hand_side(np.asarray(gravity, dtype=float))
    return problem, b_eq


def _fixed_point(problem, b_eq):
    frugal = cra_local.least_friction(problem, b_eq)
    return cra_coulomb.coulomb_fixed_point(problem, b_eq, frugal[:, 0], lambda m: problem.exact(b_eq, m))


def test_tresca_solution_is_an_equilibrium_with_friction_against_the_slide():
    # A cube on a fixed cube, gravity tilted by 20 degrees (needs friction tan 20 = 0.36 < mu = 0.5): the
    # optimality conditions of (T) are (7b), (9) and (10), whatever the thresholds, when eta is inactive.
    problem, b_eq = _problem(_stack(), 0.5, tilted_gravity("x", 20))
    solved = cra_coulomb.tresca(problem, b_eq, np.full(4, 0.2), 0.25)
    assert solved is not None and solved.eta_active == 0
    f = solved.forces
    assert problem.system.a_eq @ f.ravel() == pytest.approx(b_eq, abs=1e-7)  # Eq. (7b)
    dd = (problem.kinematic @ solved.motion).reshape(-1, 3)
    assert np.all(dd[:, 0] >= -1 - 1e-7) and np.all(f[:, 0] >= -1e-9)
    assert np.abs(f[:, 0] * (dd[:, 0] + 1)).max() < 1e-7  # Eq. (10)
    slide, friction = dd[:, 1:], f[:, 1:]
    assert np.abs(slide[:, 0] * friction[:, 1] - slide[:, 1] * friction[:, 0]).max() < 1e-7  # Eq. (9): parallel
    assert np.all(np.einsum("ij,ij->i", slide, friction) < 0)  # and against the slide
    assert np.all(np.hypot(*friction.T) <= 0.2 + 1e-7)  # |f_t| <= s_v


def test_tresca_leans_on_eta_when_the_thresholds_cannot_hold_the_load():
    # Tilted by 30 degrees the cube needs friction tan 30 = 0.58 of its normal force; thresholds of 0.5 cannot
    # hold it, so it slides until the bound eta stops it (100 eps down the slope), whose multipliers carry the rest
    problem, b_eq = _problem(_stack(), 0.5, tilted_gravity("x", 30))
    normal, tangential = b_eq[2], b_eq[1]  # the load's components across and along the contact
    assert tangential / normal == pytest.approx(math.tan(math.radians(30)))
    solved = cra_coulomb.tresca(problem, b_eq, np.full(4, 0.5 * normal / 4), 0.25)
    assert solved.eta_active > 0 and solved.motion[1] == pytest.approx(-problem.ratio)
    held = cra_coulomb.tresca(problem, b_eq, np.full(4, 0.6 * normal / 4), 0.25)  # mu = 0.6 > tan 30 holds it
    assert held is not None and held.eta_active == 0


def test_tresca_vertex_with_threshold_zero_has_no_friction_and_the_others_hold_the_load():
    # Thresholds 0.2 at two corners, 0 at the other two (no friction unknowns or cone there): tilted by 10
    # degrees the two corners hold the cube (0.4 > tan 10 of the load), and the frictionless ones carry none.
    problem, b_eq = _problem(_stack(), 0.5, tilted_gravity("x", 10))
    solved = cra_coulomb.tresca(problem, b_eq, np.array([0.2, 0.0, 0.2, 0.0]), 0.25)
    assert solved is not None and solved.eta_active == 0
    assert np.all(solved.forces[[1, 3], 1:] == 0.0) and np.abs(solved.forces[[0, 2], 1:]).max() > 1e-3
    assert problem.system.a_eq @ solved.forces.ravel() == pytest.approx(b_eq, abs=1e-7)  # Eq. (7b)


def test_thresholds_below_the_floor_are_zero():
    floored = cra_coulomb._floored(np.array([-1.0, 0.0, 1e-7, 2e-6, 1.0]))
    assert floored.tolist() == [0.0, 0.0, 0.0, 2e-6, 1.0]  # THRESHOLD_RTOL = 1e-6 of the largest
    assert cra_coulomb._floored(np.zeros(3)).tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("angle", [0.0, 10.0, 20.0, 26.0])
def test_fixed_point_proves_a_cube_on_a_slope_stable(angle):
    # friction angle of mu = 0.5: 26.57 degrees; the exact LP accepts the motion, which slides down the slope
    problem, b_eq = _problem(_stack(), 0.5, tilted_gravity("x", angle))
    fixed_point = _fixed_point(problem, b_eq)
    assert fixed_point.found is not None and fixed_point.rounds >= 1
    motion, forces = fixed_point.found
    assert np.array_equal(motion, fixed_point.closest) and fixed_point.residual == 0.0
    assert problem.system.a_eq @ forces.ravel() == pytest.approx(b_eq, abs=1e-7)
    down = tilted_gravity("x", angle)
    down[2] = 0.0
    assert motion[:3] @ down >= 0.0  # the cube moves with the tangential load, never against it
    assert cra_coulomb.unbalanced(problem, b_eq, motion) == (pytest.approx(0.0, abs=1e-7), ())


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.floats(0.01, 100.0))
def test_fixed_point_invariant_under_rigid_motion_and_scale(seed, scale):
    # the same stack and load, turned, moved and scaled together: the fixed point still proves it stable and
    # closes the same 4 vertices (motions are in units of eps, a fraction of the model's size)
    turn = Rotation.random(random_state=seed)
    shift = np.random.default_rng(seed).normal(size=3) * 10
    meshes = [m.copy().apply_scale(scale).apply_transform(_affine(turn.as_matrix(), shift))
              for m in _stack().meshes]
    problem, b_eq = _problem(Assembly.from_meshes(meshes, frame=[0]), 0.5, turn.apply(tilted_gravity("x", 20)))
    found = _fixed_point(problem, b_eq).found
    assert found is not None
    dd = (problem.kinematic @ found[0]).reshape(-1, 3)
    assert int((dd[:, 0] + 1 <= 1e-7).sum()) == 4


def _affine(rotation, shift):
    matrix = np.eye(4)
    matrix[:3, :3], matrix[:3, 3] = rotation, shift
    return matrix


def test_shelf_stable_is_proved_without_ipopt(reference_data, monkeypatch):
    # Fig. 12's repaired shelf: IPOPT used to be the only route that found its motion (the MILP's 300
    # binaries are undecided in 10 min); the fixed point finds one the exact LP accepts, with CasADi absent
    monkeypatch.setattr(cra_ipopt, "available", lambda: False)
    assembly = load_compas(reference_data / "compas_cra" / "shelf-stable.json")
    result = cra(assembly, 0.9, contacts=contacts(assembly))
    assert result.status == "stable" and "Coulomb fixed point" in result.message
    assert result.timings["milp"] == 0.0 and "ipopt" not in result.timings


def test_shelf_fixed_point_names_the_blocks_it_cannot_balance(reference_data):
    # Fig. 7's shelf (3DEC and the paper: its blocks 9 and 10 slide): no fixed point is reached, and the closest
    # motion leaves load unbalanced at exactly those two blocks; which proves nothing ("inconclusive" stays)
    assembly = load_compas(reference_data / "compas_cra" / "shelf.json")
    problem = CRAProblem.build(assembly, 0.9, contacts=contacts(assembly))
    b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    fixed_point = _fixed_point(problem, b_eq)
    assert fixed_point.found is None and fixed_point.rounds == cra_coulomb.COULOMB_ITERATIONS
    residual, blocks = cra_coulomb.unbalanced(problem, b_eq, fixed_point.closest)  # measured again: the same
    assert residual > 1e-3 and blocks == (9, 10) == fixed_point.unbalanced_blocks
    assert fixed_point.residual == pytest.approx(residual, rel=1e-6)
    words = cra_coulomb.describe(fixed_point)
    assert f"ran {fixed_point.rounds} rounds" in words and "at its closest motion" in words
    assert "at 2 blocks (9, 10)" in words


def test_progress_names_each_stage_and_round(reference_data):
    # the CLI shows these words on its progress bar: RBE, the quick answers, then one entry per round
    assembly = load_compas(reference_data / "compas_cra" / "shelf-stable.json")
    stages = []
    result = cra(assembly, 0.9, contacts=contacts(assembly), progress=stages.append)
    rounds = int(result.message.split("Coulomb fixed point (")[1].split()[0])
    assert stages[:2] == ["RBE", "quick answers"]
    assert stages[2:] == [f"Coulomb fixed point, round {k}" for k in range(1, rounds + 1)]


def test_continuing_from_history_is_the_same_iteration(reference_data):
    # Stopped after 5 rounds and continued from its Anderson memory (FixedPoint.history), the fixed point on
    # shelf-stable takes the rounds the uninterrupted run takes after its fifth, to the same motion
    assembly = load_compas(reference_data / "compas_cra" / "shelf-stable.json")
    problem = CRAProblem.build(assembly, 0.9, contacts=contacts(assembly))
    b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    whole = _fixed_point(problem, b_eq)
    frugal = cra_local.least_friction(problem, b_eq)
    check = partial(problem.exact, b_eq)
    stopped = cra_coulomb.coulomb_fixed_point(problem, b_eq, frugal[:, 0], check, iterations=5)
    assert whole.found is not None and whole.rounds > 5 and stopped.found is None
    assert len(stopped.history) == cra_coulomb.COULOMB_MEMORY + 1
    continued = cra_coulomb.coulomb_fixed_point(problem, b_eq, None, check, history=stopped.history)
    assert continued.found is not None and continued.rounds == whole.rounds - 5
    assert np.allclose(continued.found[0], whole.found[0], atol=1e-9)


def test_least_unbalanced_leaves_an_unsupported_block_unbalanced_and_its_dual_says_so():
    # Four cubes, three free; the lower two settle by eps each, the top one moves with the second: its
    # contact stays open, nothing carries its weight (a third of the load), and the dual prices exactly that
    problem, b_eq = _problem(_stack((1.0,) * 4), 0.5, (0.0, 0.0, -1.0))
    motion = np.zeros(18)
    motion[2], motion[8], motion[14] = -1.0, -2.0, -2.0
    least = cra_coulomb.least_unbalanced(problem, b_eq, motion, tolerance=1e-10)
    assert least.residual == pytest.approx(1 / 3, abs=1e-8)
    assert np.abs(least.slack[:12]).max() < 1e-8 and abs(least.slack[14]) == pytest.approx(1 / 3, abs=1e-8)
    assert least.dual @ b_eq == pytest.approx(least.residual, abs=1e-8) and np.abs(least.dual).max() <= 1 + 1e-8
    assert cra_coulomb.unbalanced(problem, b_eq, motion) == (pytest.approx(1.0 / 3, abs=1e-6), (3,))


def test_shut_nearly_closed_adds_the_bounds_its_step_would_break(monkeypatch):
    # Two twists, two vertices: vertex 0's normal row is 2 q_1 + q_2, 5e-6 eps from closed; vertex 1 slides by
    # q_1, 1e-8 eps inside the bound eta / eps = 0.5.  The cheapest shut (q_1 alone) breaks that bound; with no
    # row but the shut one to start from, the loop adds it and shuts through q_2, as the LP with every row does
    from types import SimpleNamespace

    import scipy.sparse as sp

    kinematic = sp.csr_matrix(np.array([[2.0, 1.0], [0, 0], [0, 0], [0, 0], [1.0, 0], [0, 0]]))
    from interlock.verify.budget import Budget

    problem = SimpleNamespace(kinematic=kinematic, ratio=0.5, budget=Budget())
    motion = np.array([-0.5 + 1e-8, 5e-6])
    assert cra_coulomb.shut_nearly_closed(problem, motion) == pytest.approx([-0.5, 0.0], abs=1e-12)
    monkeypatch.setattr(cra_coulomb, "SHUT_MARGIN", -1.0)
    assert cra_coulomb.shut_nearly_closed(problem, motion) == pytest.approx([-0.5, 0.0], abs=1e-12)
