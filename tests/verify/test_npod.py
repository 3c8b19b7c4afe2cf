"""n-pods (seed 003, Gallet–Nawratil–Schicho): mobility at a pose, bond conditions of Cor. 3.17, self-motions."""

import re
from fractions import Fraction as F

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock import InterlockError
from interlock.verify.npod import NPodError, leg_rows, mobility, npod, self_motion
from interlock.verify.npod import bond_conditions, projection_bonds

I = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]

# Bricard-type hexapod (seed 003, Example ad (i)): P_i = (q_i / |q_i|^2, c_i) for p_i = (q_i, c_i).
BRICARD_p = [(2, 0, 0), (0, 1, 1), (1, 1, 0), (-1, 2, 1), (3, -1, 2), (-2, -2, -1)]
BRICARD_P = [(F(1, 2), 0, 0), (0, 1, 1), (F(1, 2), F(1, 2), 0), (F(-1, 5), F(2, 5), 1), (F(3, 10), F(-1, 10), 2),
             (F(-1, 4), F(-1, 4), -1)]
BRICARD_D2 = [F(25, 4), 4, F(9, 2), F(36, 5), F(121, 10), F(81, 8)]
BRICARD_POSE = (I, [0, 0, 2])
SEVENTH_p, SEVENTH_P, SEVENTH_D2 = (2, 1, 0), (F(2, 5), F(1, 5), 1), F(21, 5)

BUTTERFLY_p = [(-1, 0, 0), (0, 0, 0), (1, 0, 0), (0, 1, 1), (1, -1, 2), (-1, 2, 0)]
BUTTERFLY_P = [(0, 2, -1), (1, -2, -1), (-1, 0, -2), (-2, 0, 0), (F(1, 2), 0, 0), (3, 0, 0)]
BUTTERFLY_POSE = (I, [0, 0, 0])


def bricard():
    return npod(BRICARD_P, BRICARD_p, squared_lengths=BRICARD_D2)


def seven_legs():
    return npod(BRICARD_P + [SEVENTH_P], BRICARD_p + [SEVENTH_p], squared_lengths=BRICARD_D2 + [SEVENTH_D2])


def butterfly():
    return npod(BUTTERFLY_P, BUTTERFLY_p, pose=BUTTERFLY_POSE)


def rotation_z(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rotation_x(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def squared_legs(pod, M, y):
    x = np.array(pod.platform, dtype=float) @ np.asarray(M, float).T + np.asarray(y, float)
    return np.sum((x - np.array(pod.base, dtype=float)) ** 2, axis=1)


def rational_rotation(a, b, c, d):
    """The rotation of the quaternion (a, b, c, d), exactly: rational entries, M^T M = I."""
    n = F(a * a + b * b + c * c + d * d)
    return [[(a * a + b * b - c * c - d * d) / n, 2 * (b * c - a * d) / n, 2 * (b * d + a * c) / n],
            [2 * (b * c + a * d) / n, (a * a - b * b + c * c - d * d) / n, 2 * (c * d - a * b) / n],
            [2 * (b * d - a * c) / n, 2 * (c * d + a * b) / n, (a * a - b * b - c * c + d * d) / n]]


def apply(M, v):
    return [sum(M[r][k] * v[k] for k in range(3)) for r in range(3)]


# --- the Bricard hexapod ---------------------------------------------------------------------------------------


def test_bricard_data_match_the_stated_squared_lengths_exactly():
    from_pose = npod(BRICARD_P, BRICARD_p, pose=BRICARD_POSE)
    assert from_pose.exact and list(from_pose.squared_lengths) == BRICARD_D2


@pytest.mark.parametrize("phi", [F(1, 3), 1.0, 2.5, -2.0, np.pi / 2])
def test_bricard_motion_keeps_every_leg_length(phi):
    """R_z(phi), y = (0, 0, 2 cos(phi / 2)): |R p_i + y - P_i|^2 = |p_i|^2 + |P_i|^2 + 2 - 2 c_i^2, constant."""
    phi = float(phi)
    lengths = squared_legs(bricard(), rotation_z(phi), [0, 0, 2 * np.cos(phi / 2)])
    assert np.allclose(lengths, [float(d) for d in BRICARD_D2], rtol=0, atol=1e-12)
    # exactly, at a rational point of the motion: cos(phi) = 7/25, sin(phi) = 24/25, cos(phi/2) = 4/5
    c, s = F(7, 25), F(24, 25)
    M = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    assert list(npod(BRICARD_P, BRICARD_p, pose=(M, [0, 0, F(8, 5)])).squared_lengths) == BRICARD_D2


def test_bricard_rank_5_with_rotation_about_z_as_kernel():
    result = mobility(bricard(), BRICARD_POSE)
    assert (result.rank, result.exact_rank, result.mobility) == (5, 5, 1)
    assert result.singular_values[4] > 1e-2 and result.singular_values[5] < 1e-12  # a clear gap
    omega, v = result.kernel[0][:3], result.kernel[0][3:]
    assert np.allclose(np.abs(omega), [0, 0, 1], atol=1e-12) and np.allclose(v, 0, atol=1e-12)
    rows = leg_rows(bricard(), BRICARD_POSE)
    assert np.allclose(rows @ result.kernel[0], 0, atol=1e-12)
    assert "infinitesimally mobile (1 first-order motion)" in str(result)
    assert result.to_dict()["tolerances"]["rank_rtol"] == 1e-9


def test_leg_rows_give_half_the_derivative_of_the_squared_lengths():
    pod, twist, t = bricard(), np.array([0.3, -0.2, 0.5, 0.1, 0.7, -0.4]), 1e-6
    M, y = np.eye(3), np.array([0.0, 0.0, 2.0])
    hat = np.array([[0, -twist[2], twist[1]], [twist[2], 0, -twist[0]], [-twist[1], twist[0], 0]])
    moved = [(M + s * t * hat @ M, y + s * t * (hat @ y + twist[3:])) for s in (1, -1)]
    derivative = (squared_legs(pod, *moved[0]) - squared_legs(pod, *moved[1])) / (2 * t)
    assert np.allclose(leg_rows(pod, (M, y)) @ twist, derivative / 2, atol=1e-6)


def test_bricard_continuation_finds_the_self_motion():
    pod = bricard()
    motion = self_motion(pod, BRICARD_POSE, arc_length=3.0)
    assert motion.found is True and "self-motion found" in str(motion)
    assert motion.reached == (3.0, 3.0) and motion.max_residual < 1e-11
    assert motion.max_angle > 1.5  # the platform really turns
    for M, y in motion.poses:
        assert np.allclose(squared_legs(pod, M, y), [float(d) for d in BRICARD_D2], rtol=0, atol=1e-9)
        phi = np.arctan2(M[1, 0], M[0, 0])  # the closed form, parametrised by the rotation angle
        assert np.allclose(M, rotation_z(phi), atol=1e-9)
        assert np.allclose(y, [0, 0, 2 * np.cos(phi / 2)], atol=1e-9)
    angles = [np.arctan2(M[1, 0], M[0, 0]) for M, _ in motion.poses]
    assert min(angles) < -1.5 and max(angles) > 1.5 and np.all(np.diff(angles) * np.sign(angles[-1]) > 0)


def test_bricard_has_the_inversion_bond_of_the_paper():
    """Cor. 3.12: projections along z are coupled by the inversion q -> q / |q|^2 (L = -R with our orientation)."""
    search = projection_bonds(bricard())
    assert search.found and len(search.bonds) == 1
    bond = search.bonds[0]
    assert bond.kind == "inversion" and bond.residual < 1e-12
    assert np.allclose(bond.left, [0, 0, 1], atol=1e-8) and np.allclose(bond.right, [0, 0, -1], atol=1e-8)
    assert bond_conditions(bricard()).cases == ()  # no collinearity, no butterfly (exact)


# --- seven legs: infinitesimally mobile, finitely rigid --------------------------------------------------------


def test_seven_legs_rank_5_but_no_self_motion():
    pod = seven_legs()
    first = mobility(pod, BRICARD_POSE)
    assert (first.rank, first.exact_rank, first.mobility) == (5, 5, 1)
    # the seventh leg changes along the Bricard motion: 41/5 - 4 cos(phi/2), second order at phi = 0
    phi = 0.2
    assert squared_legs(pod, rotation_z(phi), [0, 0, 2 * np.cos(phi / 2)])[6] == pytest.approx(41 / 5 - 4 * np.cos(phi / 2))
    motion = self_motion(pod, BRICARD_POSE)
    assert motion.found is False and "no self-motion found" in motion.status
    assert motion.reached == (0.0, 0.0) and motion.smallest_step < 1e-3 and len(motion.poses) == 1
    # with tiny steps the second-order error h^2 drops below residual_tol for a while, but the branch still stalls
    motion = self_motion(pod, BRICARD_POSE, min_step=1e-6)
    assert motion.found is False and max(motion.reached) < 1e-3 and motion.smallest_step < 1e-6
    # the projection condition of Cor. 3.17 (i) still holds: necessary, not sufficient
    assert projection_bonds(pod).found


# --- butterfly --------------------------------------------------------------------------------------------------


def test_butterfly_detected_exactly_with_the_right_split():
    pod = butterfly()
    conditions = bond_conditions(pod)
    assert conditions.exact and conditions.method.startswith("exact")
    assert conditions.butterflies == (((0, 1, 2), (3, 4, 5)),)
    assert conditions.cases == ("butterfly",)
    assert not conditions.platform_collinear and not conditions.base_collinear
    floats = bond_conditions(npod(np.array(BUTTERFLY_P, dtype=float), BUTTERFLY_p, pose=BUTTERFLY_POSE))
    assert not floats.exact and floats.butterflies == conditions.butterflies
    assert floats.to_dict()["tolerances"] == {"collinear_rtol": 1e-9}


def test_butterfly_rank_5_and_rotation_about_x_keeps_lengths():
    pod = butterfly()
    result = mobility(pod)
    assert (result.rank, result.exact_rank) == (5, 5)
    assert np.allclose(np.abs(result.kernel[0]), [1, 0, 0, 0, 0, 0], atol=1e-12)
    for phi in (0.3, 1.7, -2.9):
        assert np.allclose(squared_legs(pod, rotation_x(phi), [0, 0, 0]), [float(d) for d in pod.squared_lengths])
    motion = self_motion(pod)
    assert motion.found is True
    for M, y in motion.poses:
        assert np.allclose(M, rotation_x(np.arctan2(M[2, 1], M[1, 1])), atol=1e-9) and np.allclose(y, 0, atol=1e-9)


def test_collinear_anchors_detected():
    line = [(0, 0, 0), (1, 1, 1), (F(1, 3), F(1, 3), F(1, 3)), (-2, -2, -2), (5, 5, 5)]
    other = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]
    assert bond_conditions(npod(other, line, lengths=[1] * 5)).cases == ("platform collinear",)
    assert bond_conditions(npod(line, other, lengths=[1] * 5)).cases == ("base collinear",)
    off = line[:4] + [(5, 5, F(50000001, 10000000))]  # off the line by 1e-7: exact says no
    exact = bond_conditions(npod(off, other, lengths=[1] * 5))
    # ... but P_1..P_4 are collinear and a single platform point is: a butterfly with m = 1 (Cor. 3.14)
    assert exact.cases == ("butterfly",) and exact.butterflies == (((4,), (0, 1, 2, 3)),)
    floats = np.array(off, dtype=float)
    assert bond_conditions(npod(floats, other, lengths=[1] * 5)).butterflies == exact.butterflies
    assert bond_conditions(npod(floats, other, lengths=[1] * 5), collinear_rtol=1e-6).cases == ("base collinear",)


# --- planar and generic -----------------------------------------------------------------------------------------


def test_planar_hexapod_rank_at_most_3():
    base = [(0, 0, 0), (4, 0, 0), (0, 4, 0), (4, 4, 0), (1, 3, 0), (3, 1, 0)]
    platform = [(0, 0, 0), (2, 0, 0), (0, 2, 0), (2, 2, 0), (1, 0, 0), (0, 1, 0)]
    result = mobility(npod(base, platform, pose=(I, [1, 1, 0])))
    assert result.rank <= 3 and result.exact_rank <= 3 and result.mobility >= 3


def test_generic_hexapod_is_rigid_and_pentapod_moves():
    base = [(0, 0, 0), (3, 0, 0), (0, 3, 0), (3, 3, 1), (1, 2, 2), (2, 1, 0)]
    platform = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1)]
    six = npod(base, platform, pose=(I, [0, 0, 2]))
    assert mobility(six).mobility == 0
    assert self_motion(six).found is False and "infinitesimally rigid" in self_motion(six).status
    assert not projection_bonds(six).found  # no condition (i) found: a generic hexapod has no bonds (Rem. 3.18)
    five = npod(base[:5], platform[:5], pose=(I, [0, 0, 2]))
    assert self_motion(five).found is True
    assert projection_bonds(five).found  # a pentapod is mobile over C, so it has bonds (Rem. 3.8, Cor. 3.17)


def test_kernel_of_dimension_two_is_inconclusive():
    four = npod(BRICARD_P[:4], BRICARD_p[:4], pose=BRICARD_POSE)
    motion = self_motion(four)
    assert motion.found is None and motion.kernel_dimension == 2 and "inconclusive" in motion.status


# --- invariance -------------------------------------------------------------------------------------------------

CONFIGURATIONS = {"bricard": (BRICARD_P, BRICARD_p, BRICARD_POSE),
                  "seven": (BRICARD_P + [SEVENTH_P], BRICARD_p + [SEVENTH_p], BRICARD_POSE),
                  "butterfly": (BUTTERFLY_P, BUTTERFLY_p, BUTTERFLY_POSE)}


def verdicts(pod, pose):
    m, b = mobility(pod, pose), bond_conditions(pod)
    return m.rank, m.exact_rank, b.cases, b.butterflies, self_motion(pod, pose, arc_length=0.3).found


quaternions = st.tuples(*[st.integers(-4, 4)] * 4).filter(lambda q: any(q))
rationals = st.fractions(min_value=-10, max_value=10, max_denominator=7)


@settings(max_examples=25, deadline=None)
@given(name=st.sampled_from(sorted(CONFIGURATIONS)), q=quaternions, t=st.tuples(rationals, rationals, rationals),
       scale=st.builds(F, st.integers(1, 50), st.integers(1, 50)), floats=st.booleans())
def test_verdicts_invariant_under_rigid_motion_and_scaling(name, q, t, scale, floats):
    base, platform, (M, y) = CONFIGURATIONS[name]
    expected = verdicts(npod(base, platform, pose=(M, y)), (M, y))
    Q = rational_rotation(*q)
    moved_base = [[scale * (a + b) for a, b in zip(apply(Q, P), t)] for P in base]
    moved_M = [[sum(Q[r][k] * M[k][c] for k in range(3)) for c in range(3)] for r in range(3)]
    moved_y = [scale * (a + b) for a, b in zip(apply(Q, y), t)]
    moved_platform = [[scale * c for c in p] for p in platform]
    if floats:
        moved_base = np.array(moved_base, dtype=float)
        moved_M, moved_y = np.array(moved_M, dtype=float), np.array(moved_y, dtype=float)
    pod = npod(moved_base, moved_platform, pose=(moved_M, moved_y))
    assert pod.exact is not floats
    got = verdicts(pod, (moved_M, moved_y))
    assert got[0] == expected[0] and got[2:] == expected[2:]
    assert got[1] == (None if floats else expected[1])


def test_projection_bond_moves_with_the_base():
    """A rigid motion Q of the base keeps L (platform frame) and turns R into Q R."""
    Q = rational_rotation(1, 2, -1, 3)
    base = [apply(Q, P) for P in BRICARD_P]
    bond = projection_bonds(npod(base, BRICARD_p, squared_lengths=BRICARD_D2)).bonds[0]
    assert bond.kind == "inversion"
    assert np.allclose(bond.left, [0, 0, 1], atol=1e-8)
    assert np.allclose(bond.right, np.array(Q, dtype=float) @ [0, 0, -1], atol=1e-8)


# --- bad input --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs,message", [
    ({"base": [], "platform": [], "lengths": []}, "at least one leg"),
    ({"base": [(0, 0)], "platform": [(0, 0, 0)], "lengths": [1]}, "shape (n, 3)"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0), (1, 0, 0)], "lengths": [1]}, "one base and one platform point"),
    ({"base": [(0, 0, float("nan"))], "platform": [(0, 0, 0)], "lengths": [1]}, "finite"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "lengths": [float("inf")]}, "finite"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "lengths": [-1]}, "positive"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "lengths": [0]}, "spherical joint"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "lengths": [1, 2]}, "shape (1,)"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)]}, "exactly one of"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "lengths": [1], "pose": (I, [0, 0, 1])}, "exactly one of"),
    ({"base": [(0, 0, "a")], "platform": [(0, 0, 0)], "lengths": [1]}, "real numbers"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "pose": ([[2, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 1])}, "M^T M = I"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "pose": ([[1, 0, 0], [0, 1, 0], [0, 0, -1]], [0, 0, 1])}, "det M = 1"),
    ({"base": [(0, 0, 0)], "platform": [(0, 0, 0)], "pose": (I,)}, "pair (M, y)"),
])
def test_bad_input_raises(kwargs, message):
    with pytest.raises(NPodError, match=re.escape(message)) as error:
        npod(**kwargs)
    assert isinstance(error.value, InterlockError)


def test_pose_off_the_pod_or_missing_raises():
    with pytest.raises(NPodError, match="not on the n-pod"):
        mobility(bricard(), (I, [0, 0, 3]))
    with pytest.raises(NPodError, match="no pose"):
        self_motion(bricard())


def test_projection_search_skipped_for_three_legs():
    search = projection_bonds(npod(BRICARD_P[:3], BRICARD_p[:3], pose=BRICARD_POSE))
    assert search.found is None and "not searched" in str(search) and search.to_dict()["searched"] is False
