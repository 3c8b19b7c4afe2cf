"""Second-order blocking (prestress stability of the gap functions) and ``check(..., order=2)``."""

import math

import numpy as np
import pytest
import trimesh
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from interlock import InterlockError
from interlock.blocks import Assembly, presets
from interlock.verify import check
from interlock.verify.contacts import Contact, ContactError, contacts
from interlock.verify.second_order import SecondOrderError, gap_expansion, prestress_stability, second_order


# --- the gap functions' expansion ----------------------------------------------------------------


def _exact_gap(z, point, normal, c_p, c_q, L):
    """The gap of the module docstring, evaluated exactly (rotation vectors through scipy)."""
    w_p, t_p, w_q, t_q = z[:3], z[3:6], z[6:9], z[9:]
    R_p, R_q = Rotation.from_rotvec(w_p).as_matrix(), Rotation.from_rotvec(w_q).as_matrix()
    x_p = c_p + R_p @ (point - c_p) + L * t_p
    x_q = c_q + R_q @ (point - c_q) + L * t_q
    return (R_q @ normal) @ (x_p - x_q) / L


vectors = st.lists(st.floats(-2, 2), min_size=3, max_size=3).map(np.array)


@settings(max_examples=40, deadline=None)
@given(point=vectors, normal=vectors.filter(lambda v: np.linalg.norm(v) > 0.1), c_p=vectors, c_q=vectors,
       z=st.lists(st.floats(-1, 1), min_size=12, max_size=12).map(np.array), L=st.floats(0.5, 4))
def test_gradient_and_hessian_are_the_taylor_coefficients_of_the_exact_gap(point, normal, c_p, c_q, z, L):
    normal = normal / np.linalg.norm(normal)
    g, H = gap_expansion(point, normal, c_p, c_q, L)
    assert np.allclose(H[0], H[0].T)
    s = 1e-3
    plus, minus = _exact_gap(s * z, point, normal, c_p, c_q, L), _exact_gap(-s * z, point, normal, c_p, c_q, L)
    assert (plus - minus) / (2 * s) == pytest.approx(g[0] @ z, abs=1e-5 * (1 + np.abs(z).sum() * 10))
    # second difference: g(s z) + g(-s z) = s^2 z^T H z + O(s^4)
    assert (plus + minus) / s**2 == pytest.approx(z @ H[0] @ z, abs=1e-4 * (1 + 100 * np.abs(z).sum() ** 2))


def test_gradient_rows_are_the_interlocking_matrix_rows():
    """Block j's point on block i's face (normal n, i -> j) gives exactly the row of Def. 3.3."""
    boxes = [trimesh.creation.box(bounds=[[-2, -2, -1], [2, 2, 0]]), trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]),
             trimesh.creation.box(bounds=[[-2, -2, 1], [2, 2, 2]])]
    pair = Assembly.from_meshes(boxes[:2])
    from interlock.verify import interlocking_matrix

    matrix = interlocking_matrix(pair, frame=[])
    A = matrix.matrix.toarray()
    (contact,) = check.__globals__["find_contacts"](pair)
    L = matrix.length_scale
    g, _ = gap_expansion(contact.vertices, np.broadcast_to(contact.normal, (4, 3)), pair.centroids[[1] * 4],
                         pair.centroids[[0] * 4], L)
    expected = np.hstack([g[:, 6:], g[:, :6]])  # columns of block 0 (the face), then block 1 (the points)
    assert np.allclose(np.sort(A, axis=0), np.sort(expected, axis=0))


# --- prestress stability: the cup on three pins ------------------------------------------------------


def _cup_constraints(h, c, swap=False):
    """Block 0 with upper faces (normals meeting at (0, 0, h)) on pins at x = +-1, a pin under it at
    (0, 0, -c) and end pins in y; ``swap``: the block's corners on fixed faces instead (same lines)."""
    a = math.hypot(1, h)
    pins, faces = [], []
    for y in (-0.5, 0.5):
        pins += [[-1, y, 0], [1, y, 0], [0, y, -c]]
        faces += [[1 / a, 0, h / a], [-1 / a, 0, h / a], [0, 0, -1]]
    for x in (-0.5, 0.5):
        pins += [[x, -1, -c / 2], [x, 1, -c / 2]]
        faces += [[0, -1, 0], [0, 1, 0]]
    k = len(pins)
    if swap:  # the block's points on the frame's faces: normals point into the block
        return np.array(pins, float), -np.array(faces, float), np.zeros(k, int), np.arange(1, k + 1)
    return np.array(pins, float), np.array(faces, float), np.arange(1, k + 1), np.zeros(k, int)


@pytest.mark.parametrize("h, c", [(1, 2), (1, 1.2), (2, 0.6), (0.5, 3)])
def test_a_block_turning_on_pins_is_blocked_at_second_order_when_h_c_exceeds_one(h, c):
    """The stressed form on the turn about O = (0, 0, h) is 2 lambda (1 - h c) / sqrt(1 + h^2) (by hand)."""
    points, normals, p, q = _cup_constraints(h, c)
    r = prestress_stability(points, normals, p, q, np.zeros((11, 3)), free=[0])
    assert r.blocked is True and r.kernel_dimension == 1 and r.support == 10
    assert r.largest_eigenvalue < 0 and r.stress.min() > 0 and r.stress.sum() == pytest.approx(1)


@pytest.mark.parametrize("h, c", [(1, 0.5), (2, 0.4), (1, 1)])
def test_the_same_turn_is_not_blocked_when_h_c_is_at_most_one(h, c):
    points, normals, p, q = _cup_constraints(h, c)
    r = prestress_stability(points, normals, p, q, np.zeros((11, 3)), free=[0])
    assert r.blocked is False and r.kernel_dimension == 1 and r.bound >= -1e-9


@pytest.mark.parametrize("h, c, blocked", [(1, 0.5, True), (1, 2, False)])
def test_which_body_carries_the_corner_flips_the_second_order_answer(h, c, blocked):
    """Corners of the block on fixed faces (the inverse relative motion): blocked iff h c < 1."""
    points, normals, p, q = _cup_constraints(h, c, swap=True)
    assert prestress_stability(points, normals, p, q, np.zeros((11, 3)), free=[0]).blocked is blocked


@settings(max_examples=25, deadline=None)
@given(rotation=st.lists(st.floats(-3, 3), min_size=3, max_size=3), shift=vectors, scale=st.floats(0.2, 20),
       h=st.sampled_from([1.0, 2.0]), c=st.sampled_from([0.4, 0.5, 1.2, 2.0]))
# found by hypothesis: entries of 5e-10 in A, dropped by HiGHS, and its presolve then saw a support of 4
@example(rotation=[1.192092896e-07, 0.0, 0.015625], shift=np.zeros(3), scale=1.0, h=1.0, c=0.4)
def test_the_verdict_is_invariant_under_rigid_motion_and_scaling(rotation, shift, scale, h, c):
    points, normals, p, q = _cup_constraints(h, c)
    R = Rotation.from_rotvec(rotation).as_matrix()
    reference = prestress_stability(points, normals, p, q, np.zeros((11, 3)), free=[0])
    moved = prestress_stability(scale * points @ R.T + shift, normals @ R.T, p, q,
                                np.tile(shift, (11, 1)), free=[0], length_scale=scale)
    assert (moved.blocked, moved.kernel_dimension, moved.support) == (reference.blocked, 1, 10)
    assert (moved.largest_eigenvalue < 0) if reference.blocked else (moved.bound >= -1e-9)


def test_bad_constraints_are_refused_with_a_clear_message():
    points, normals, p, q = _cup_constraints(1, 2)
    with pytest.raises(SecondOrderError, match="one entry per constraint"):
        prestress_stability(points, normals[:3], p, q, np.zeros((11, 3)), free=[0])
    with pytest.raises(SecondOrderError, match="finite"):
        prestress_stability(points * np.nan, normals, p, q, np.zeros((11, 3)), free=[0])
    with pytest.raises(SecondOrderError, match="two different blocks"):
        prestress_stability(points, normals, q, q, np.zeros((11, 3)), free=[0])
    with pytest.raises(SecondOrderError, match="index the 11 centroids"):
        prestress_stability(points, normals, p + 5, q, np.zeros((11, 3)), free=[0])
    with pytest.raises(InterlockError, match="non-zero"):
        prestress_stability(points, normals * 0, p, q, np.zeros((11, 3)), free=[0])


# --- assemblies ------------------------------------------------------------------------------------


@pytest.mark.parametrize("h, c", [(1, 2), (2, 0.6)])
def test_check_order_2_proves_the_cup_interlocked_at_second_order(h, c):
    cup = presets.block_on_pins(h, c)
    first = check(cup)  # the pins' point and line contacts travel with the assembly
    assert first.interlocked is False and first.rank == 5 and first.motion_kind == "sliding"
    assert "first-order motion" in first.status and first.order == 1 and first.second_order is None
    v = check(cup, order=2)
    assert v.interlocked is True and v.order == 2 and v.second_order.blocked is True
    assert str(v).startswith("interlocked (second order)") and "first order:" in v.status
    assert v.to_dict()["second_order"]["blocked"] is True and v.finite_motion is None


def test_face_contacts_slide_so_second_order_does_not_block():
    floor = trimesh.creation.box(bounds=[[-2, -2, -1], [2, 2, 0]])
    ceiling = trimesh.creation.box(bounds=[[-2, -2, 1], [2, 2, 2]])
    cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    r = second_order(Assembly.from_meshes([floor, ceiling, cube]), frame=[0, 1])
    assert r.blocked is False and r.constraints == 8 and r.skipped == 0 and r.kernel_dimension == 3
    assert abs(r.largest_eigenvalue) < 1e-12  # planar slides keep every gap at zero, to every order


def test_coinciding_corners_have_no_smooth_gap_function():
    r = second_order(presets.cube_grid())  # the middle cube's contacts: squares on squares
    # 16 polygon vertices, and the 8 corners the middle cube shares with its diagonal neighbours (vertex-vertex
    # contacts, a cone of normals each: no gap function of a point on a face)
    assert r.constraints == 0 and r.skipped == 16 + 8 and r.blocked is False
    faces_only = second_order(presets.cube_grid(), contacts=contacts(presets.cube_grid()))
    assert faces_only.constraints == 0 and faces_only.skipped == 16


def test_check_order_2_shows_the_grid_cube_sliding_out():
    v = check(presets.cube_grid(), order=2)
    assert v.interlocked is False and v.finite_motion.shown and v.moving == (4,)
    assert str(v).startswith("not interlocked (finite motion shown)")
    assert v.to_dict()["finite_motion"]["shown"] is True


def test_block_on_pins_needs_its_valley_above_its_bottom():
    with pytest.raises(InterlockError, match="h c > 1"):
        presets.block_on_pins(1.0, 0.5)


def test_translational_verdicts_skip_second_order_and_still_show_the_motion():
    v = check(presets.cube_grid(), translational=True, order=2)
    assert v.second_order is None and v.finite_motion.shown and v.interlocked is False


def test_check_refuses_other_orders():
    with pytest.raises(InterlockError, match="order must be 1"):
        check(presets.cube_grid(), order=3)


def test_hand_made_contacts_are_checked():
    with pytest.raises(ContactError, match="0 <= i < j"):
        Contact.at_points(1, 0, [0, 0, 1], [[0, 0, 0]])
    with pytest.raises(ContactError, match="non-zero"):
        Contact.at_points(0, 1, [0, 0, 0], [[0, 0, 0]])
    with pytest.raises(ContactError, match="one or more"):
        Contact.at_points(0, 1, [0, 0, 1], [])


def test_example_3_7_the_versatile_blocks_move_apart_at_order_2():
    pair = presets.versatile_blocks()
    first = check(pair)
    assert first.interlocked is False and "can move" not in first.status and "first-order motion" in first.status
    v = check(pair, order=2)
    assert v.interlocked is False and v.finite_motion.shown and v.moving == (1,)
    assert v.second_order.blocked is False  # one triangle contact: its planar slides keep every gap at zero


@pytest.mark.parametrize("name, frame", [("cube_grid", None), ("versatile_blocks", None),
                                         ("interlocking_cubes", [0]), ("modified_cube_assembly", [])])
def test_a_first_order_status_never_claims_that_blocks_can_move(name, frame):
    v = check(getattr(presets, name)(), frame=frame)
    assert v.interlocked is False and v.order == 1 and v.finite_motion is None
    assert "can move" not in v.status and "first-order motion" in v.status


def test_without_cutting_planes_an_unblocked_turn_is_undecided(monkeypatch):
    import sys

    module = sys.modules["interlock.verify.second_order"]
    monkeypatch.setattr(module, "CUTTING_PLANES", 0)
    points, normals, p, q = _cup_constraints(1, 0.5)
    r = prestress_stability(points, normals, p, q, np.zeros((11, 3)), free=[0])
    assert r.blocked is None and "undecided" in r.status and r.bound is None


def test_a_spent_budget_stops_second_order():
    from interlock.verify.budget import Budget, TimeLimitReached

    with pytest.raises(TimeLimitReached, match="beyond"):
        second_order(presets.cube_grid(), budget=Budget(limit=1e-9, started=0.0))
