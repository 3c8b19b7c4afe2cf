"""Finite motions: the paper's Ex. 3.7, the cube grid, second-order penetration, invariance, bad input."""

import json
import math

import numpy as np
import pytest
import scipy.linalg
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from interlock import InterlockError
from interlock.blocks import Assembly, presets
from interlock.verify import check, interlocking_matrix
from interlock.gallery.motion import export_motion
from interlock.verify.motion import OVERLAP_RTOL, FiniteMotion, MotionError, finite_motion, moved, twist_exponential

GRID_FRAME = [0, 1, 2, 3, 5, 6, 7, 8]


def _grid(side: float = 1.0) -> Assembly:
    """The 3x3 grid of cubes of the check() doctest: block 3x + y at (x, y), the middle one (4) free."""
    cubes = [trimesh.creation.box(bounds=[[x * side, y * side, 0], [(x + 1) * side, (y + 1) * side, side]])
             for x in range(3) for y in range(3)]
    return Assembly.from_meshes(cubes, frame=GRID_FRAME)


def _about_centroid(assembly: Assembly, block: int, omega, v, origin=(0, 0, 0)) -> np.ndarray:
    """The twist (omega, v) about ``origin`` (velocity of x: omega x (x - origin) + v) in the centroid format."""
    out = np.zeros((len(assembly), 6))
    omega = np.asarray(omega, dtype=float)
    out[block, :3] = omega
    out[block, 3:] = np.asarray(v, dtype=float) + np.cross(omega, assembly.centroids[block] - np.asarray(origin))
    return out


def _gamma(t: float) -> np.ndarray:
    """Ex. 3.7: gamma(t) on the right block (1), the left one (0) fixed."""
    c, s = math.cos(t), math.sin(t)
    g = np.array([[c, 0, -s, -s * (t - 1)], [0, 1, 0, 0], [s, 0, c, c * (t - 1) + 1], [0, 0, 0, 1]])
    return np.stack([np.eye(4), g])


# --- the SE(3) exponential ---------------------------------------------------------------------------


def test_twist_exponential_is_a_one_parameter_group_with_the_twist_as_velocity():
    rng = np.random.default_rng(1)
    twists, centres = rng.normal(size=(5, 6)), rng.normal(size=(5, 3))
    T = lambda s: twist_exponential(twists, centres, s)  # noqa: E731
    np.testing.assert_allclose(T(0.3) @ T(0.9), T(1.2), atol=1e-12)  # exp((a + b) xi) = exp(a xi) exp(b xi)
    np.testing.assert_allclose(T(0.0), np.tile(np.eye(4), (5, 1, 1)), atol=0)
    x = rng.normal(size=3)
    h = 1e-6
    velocity = (T(h)[:, :3] @ np.r_[x, 1] - T(-h)[:, :3] @ np.r_[x, 1]) / (2 * h)
    np.testing.assert_allclose(velocity, np.cross(twists[:, :3], x - centres) + twists[:, 3:], atol=1e-8)
    np.testing.assert_allclose(T(0.7)[:, :3, :3], Rotation.from_rotvec(0.7 * twists[:, :3]).as_matrix(), atol=1e-12)
    # the translation is V s t, not s t: a turn about the centre c moves no point of the axis
    turn = twist_exponential([[0, 0, 2.0, 0, 0, 0]], [[1.0, 2.0, 0]], 1.3)[0]
    np.testing.assert_allclose(turn @ [1.0, 2.0, 5.0, 1.0], [1.0, 2.0, 5.0, 1.0], atol=1e-12)
    # the matrix exponential of the se(3) element about each centre, for a finite and a tiny (Taylor) angle
    for s in (1.3, 0.5e-4 / np.linalg.norm(twists[:, :3], axis=1).max()):
        for k in range(5):
            xi = np.zeros((4, 4))
            xi[:3, :3] = np.cross(twists[k, :3], np.eye(3)).T  # [omega]_x: column j is omega x e_j
            xi[:3, 3] = twists[k, 3:]
            shift = np.eye(4)
            shift[:3, 3] = centres[k]
            expected = shift @ scipy.linalg.expm(s * xi) @ np.linalg.inv(shift)
            np.testing.assert_allclose(T(s)[k], expected, atol=1e-13)


# --- Ex. 3.7: two Versatile Blocks ---------------------------------------------------------------------


def test_example_3_7_gamma_is_a_finite_motion():
    pair = presets.versatile_blocks()
    result = finite_motion(pair, _gamma, span=(0, 1))
    assert result.shown and result.kind == "path" and result.moving == (1,) and result.frame == (0,)
    assert result.first_collision is None and result.ending == "end of the path"
    assert result.parameters[-1] == pytest.approx(1.0) and len(result.parameters) == 16 + 3
    assert max(result.overlap_fractions) <= OVERLAP_RTOL
    # the small steps: displacements 1e-4, 1e-3, 1e-2 of the model size
    np.testing.assert_allclose(result.displacements[:3], np.array([1e-4, 1e-3, 1e-2]) * pair.scale, rtol=1e-9)
    assert result.displacements[-1] > 0.5 * pair.scale
    # gamma(1) leaves the image of (0, 0, 0) on the left block's top edge: touching, not separated
    assert not result.separated
    np.testing.assert_allclose(result.at_step(-1).transforms[1], _gamma(1.0)[1], atol=1e-12)


def test_example_3_7_pushing_into_the_left_block_is_not_shown():
    pair = presets.versatile_blocks()
    push = lambda t: np.stack([np.eye(4), trimesh.transformations.translation_matrix((-t, 0, 0))])  # noqa: E731
    result = finite_motion(pair, push)
    assert not result.shown and result.first_collision.step == 0 and result.first_collision.pair == (1, 0)
    assert "block 1 hits block 0" in str(result)


@pytest.mark.parametrize("v", [(1, 0, 2), (1, 0, 1)])
def test_example_3_7_exponential_of_the_first_order_motion_is_finite(v):
    # The paper states gamma'(0) = (omega, v) = ((0, -1, 0), (1, 0, 2)) about the origin; differentiating its
    # gamma gives v = (1, 0, 1) (the z-entry of d/dt [cos t (t - 1) + 1] at 0 is 1): both are tested.
    # omega . v = 0, so exp(s xi) is a pure rotation about the line x = -2, z = 1 (v = (1, 0, 2)) or
    # x = -1, z = 1 (v = (1, 0, 1)), parallel to y.  The contact points (0, +-1, 1) have velocity (0, 0, v_z)
    # and acceleration omega x (omega x p + v) = (-v_z, 0, 0), towards the left block -- but they rise above
    # its top (z = 1) first: every point of the right block has x + a >= a and z <= 1 relative to the axis
    # (-a, 1), and a rotation that brings it to x < 0 takes it above z = 1, where the left block is not.  The
    # gap opens like s^2 (the contact plane turns about a line at the height of the triangle's top edge), so
    # the blocks separate within the small steps.
    pair = presets.versatile_blocks()
    twists = _about_centroid(pair, 1, (0, -1, 0), v)
    p = np.array([0, 1, 1.0])
    assert np.cross([0, -1, 0], np.cross([0, -1, 0], p) + v) == pytest.approx([-v[2], 0, 0])
    result = finite_motion(pair, twists)
    assert result.shown and result.separated and result.ending == "separated"
    assert max(result.overlaps) <= OVERLAP_RTOL * 2.0
    assert result.displacements[-1] <= 1e-2 * pair.scale * (1 + 1e-9)
    # against the paper's gamma: the same velocity (v = (1, 0, 1) only) but another second-order term
    if v == (1, 0, 1):
        h = 1e-6
        derivative = (_gamma(h)[1] - _gamma(-h)[1]) / (2 * h)
        np.testing.assert_allclose(derivative[:3, 3], v, atol=1e-9)


# --- the 3x3 grid of cubes ---------------------------------------------------------------------------


def test_cube_grid_motion_of_check_is_finite_and_separates_after_displacement_1():
    grid = _grid()
    verdict = check(grid)
    assert verdict.interlocked is False and verdict.moving == (4,)
    result = finite_motion(grid, verdict.motion, frame=verdict.frame)
    assert result.shown and result.separated and result.ending == "separated" and result.moving == (4,)
    assert 1.0 < result.displacements[-1] <= 1.0 + grid.scale / 16 + 1e-9
    assert all(d <= 1.0 + 1e-9 for d in result.displacements[:-1])  # not separated while still touching
    assert max(result.overlaps) <= 1e-12
    assert json.loads(json.dumps(result.to_dict()))["shown"] is True
    assert str(result).startswith("block 4 moves 1.09 (model size 4.36)")
    np.testing.assert_allclose(result.assembly_at(0.5).bounds[4], [[1, 1, 0.5], [2, 2, 1.5]], atol=1e-12)
    np.testing.assert_allclose(moved(grid, verdict.motion, 0.5).bounds[4], [[1, 1, 0.5], [2, 2, 1.5]], atol=1e-12)


def test_cube_grid_pushed_sideways_collides_at_the_first_step():
    grid = _grid()
    sideways = np.zeros((9, 6))
    sideways[4, 3] = 1.0
    result = finite_motion(grid, sideways)
    assert not result.shown and result.ending == "collision" and not result.separated
    c = result.first_collision
    assert c.step == 0 and c.pair == (4, 7) and len(result.parameters) == 1
    assert c.displacement == pytest.approx(1e-4 * grid.scale)
    assert c.volume == pytest.approx(c.displacement, rel=1e-6)  # a 1 x 1 x d slab
    assert "block 4 hits block 7" in str(result)
    assert json.loads(json.dumps(result.to_dict()))["first_collision"]["pair"] == [4, 7]


def test_moving_blocks_are_measured_against_each_other():
    row = Assembly.from_meshes([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)], frame=[2])
    towards = np.zeros((3, 6))
    towards[0, 3], towards[1, 3] = 1.0, -1.0
    result = finite_motion(row, towards)
    assert not result.shown and result.moving == (0, 1) and result.first_collision.pair == (0, 1)
    assert "block 0 hits block 1" in str(result)
    # moved as one (the same rigid motion, twists about their own centroids): their overlap is not recomputed
    together = _about_centroid(row, 0, (0, 0, 1), (0, 0, 0), origin=(0, 0, 0)) \
        + _about_centroid(row, 1, (0, 0, 1), (0, 0, 0), origin=(0, 0, 0))
    apart = finite_motion(row, together)  # a counterclockwise turn about the z-axis: away from block 2
    assert apart.shown and apart.moving == (0, 1)
    assert str(apart).startswith("blocks 0, 1 move")
    assert apart.timings["booleans"] <= len(apart.parameters)  # at most block 1 against block 2 per step


# --- first order is not enough ---------------------------------------------------------------------------


def _cube_on(base_bounds) -> Assembly:
    """A unit cube on a fixed base (block 0, the frame)."""
    base = trimesh.creation.box(bounds=base_bounds)
    return Assembly.from_meshes([base, trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])], frame=[0])


def _first_order(assembly: Assembly, twists) -> np.ndarray:
    """A x for the twist of block 1 (A x >= 0: first-order admissible, main paper Def. 3.3)."""
    A = interlocking_matrix(assembly, frame=[0])
    return A.matrix @ np.r_[twists[1, :3], twists[1, 3:] / A.length_scale]


def test_rotation_about_a_contact_edge_is_a_genuine_opening():
    # a cube on a cube, turned about its bottom edge x = 1, z = 0 so that the side x = 0 lifts: the two contact
    # vertices on the axis stand still, the two others rise; the cube rolls over the edge without collision
    pair = _cube_on([[0, 0, -1], [1, 1, 0]])
    twists = _about_centroid(pair, 1, (0, 1, 0), (0, 0, 0), origin=(1, 0.5, 0))
    opening = _first_order(pair, twists)
    assert opening.min() >= -1e-12 and opening.max() > 0
    result = finite_motion(pair, twists)
    assert result.shown and result.ending == "reach" and not result.separated
    assert result.displacements[-1] == pytest.approx(pair.scale)
    assert max(result.overlap_fractions) <= 1e-12
    # on a wider base the same roll lands on it after a quarter turn, and then penetrates: the reach matters
    slab = _cube_on([[-1, 0, -1], [2, 1, 0]])
    rolled = finite_motion(slab, _about_centroid(slab, 1, (0, 1, 0), (0, 0, 0), origin=(1, 0.5, 0)))
    assert not rolled.shown and rolled.first_collision.parameter > math.pi / 2


def test_first_order_tangent_motion_that_penetrates_at_second_order_is_not_shown():
    # A cube on a wide fixed slab turned about the line x = 0, z = -h (parallel to y, BELOW the contact plane):
    # the contact vertices at x = 0 move horizontally (velocity (-h, 0, 0)), those at x = 1 rise, so A x >= 0;
    # but the acceleration of the edge x = 0 is (0, 0, -h): it dips into the slab, by h (1 - cos s) ~ h s^2 / 2,
    # over a length ~ h s / 2, so the overlap volume grows like s^3.  (An axis above the plane lifts that edge
    # at second order instead; and on a base no wider than the cube the edge dips where no block is.)
    h = 2.0
    slab = _cube_on([[-1, 0, -1], [2, 1, 0]])
    twists = _about_centroid(slab, 1, (0, -1, 0), (0, 0, 0), origin=(0, 0.5, -h))
    first_order = _first_order(slab, twists)
    assert first_order.min() >= -1e-12 and first_order.max() > 0
    assert check(slab).interlocked is False  # not infinitesimally interlocked, yet this motion is not real
    result = finite_motion(slab, twists)
    assert not result.shown and result.first_collision.pair == (1, 0)
    c = result.first_collision
    assert c.displacement <= 0.1 * slab.scale  # found at a small step
    s, volume = np.array(result.parameters), np.array(result.overlaps)
    assert (volume[:c.step + 1] > 0).all()  # the overlap is there from the first step, below the tolerance
    order = np.log(volume[1:c.step + 1] / volume[:c.step]) / np.log(s[1:c.step + 1] / s[:c.step])
    np.testing.assert_allclose(order, 3.0, atol=0.1)
    assert volume[0] == pytest.approx(h**2 * s[0] ** 3 / 8, rel=1e-3)  # (1/2) (h s / 2) (h s^2 / 2) x width 1


# --- invariance ---------------------------------------------------------------------------------------


@settings(max_examples=12, deadline=None)
@given(rotation=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
       shift=st.lists(st.floats(-50, 50), min_size=3, max_size=3), scale=st.floats(0.01, 100))
def test_grid_verdicts_do_not_depend_on_placement_or_scale(rotation, shift, scale):
    R = Rotation.from_quat(rotation).as_matrix()
    g = np.eye(4)
    g[:3, :3], g[:3, 3] = R, shift
    base = _grid(scale)
    placed = Assembly(base.meshes, base.types, g @ base.transforms, frame=GRID_FRAME)
    for axis, shown in ((5, True), (3, False)):
        twists = np.zeros((9, 6))
        twists[4, axis] = scale  # the same motion in units of the side
        twists[:, 3:] = twists[:, 3:] @ R.T  # velocities turn with the assembly
        result = finite_motion(placed, twists)
        assert result.shown is shown
        assert result.separated is shown
        if not shown:
            assert result.first_collision.step == 0 and result.first_collision.pair == (4, 7)
        else:
            # apart after a displacement of one side, within one uniform step (the model size is the diagonal
            # of the bounding box, which depends on the placement)
            assert scale < result.displacements[-1] <= scale + result.model_size / 16 * (1 + 1e-9)


# --- frames --------------------------------------------------------------------------------------------


def test_export_motion_writes_stl_frames_that_load_back(tmp_path):
    grid = _grid()
    result = finite_motion(grid, check(grid).motion)
    paths = export_motion(grid, result, tmp_path / "frames", frames=3)
    assert [p.name for p in paths] == ["frame_000.stl", "frame_001.stl", "frame_002.stl"]
    first, last = Assembly.load(paths[0]), Assembly.load(paths[-1])
    assert len(first) == len(last) == 9
    assert first.bounds[:, 1, 2].max() == pytest.approx(1.0, abs=1e-6)
    assert last.bounds[:, 1, 2].max() == pytest.approx(1.0 + result.displacements[-1], abs=1e-5)


def test_export_motion_draws_png_frames(tmp_path):
    pytest.importorskip("matplotlib")
    pair = presets.versatile_blocks()
    paths = export_motion(pair, finite_motion(pair, _gamma), tmp_path, frames=2, format="png")
    assert [p.suffix for p in paths] == [".png", ".png"] and all(p.stat().st_size > 0 for p in paths)


# --- bad input --------------------------------------------------------------------------------------


def _twists(**rows):
    out = np.zeros((9, 6))
    for block, row in rows.items():
        out[int(block[1:])] = row
    return out


def _scaled(t):
    out = np.tile(np.eye(4), (9, 1, 1))
    out[4, :3, :3] *= 1 + t
    return out


def _moves_frame(t):
    out = np.tile(np.eye(4), (9, 1, 1))
    out[0, 2, 3] = t
    return out


def _late_start(t):
    out = np.tile(np.eye(4), (9, 1, 1))
    out[4, 2, 3] = t + 1
    return out


BAD = [
    (lambda g: finite_motion(g, np.zeros((9, 5))), r"shape \(9, 6\)"),
    (lambda g: finite_motion(g, np.zeros((8, 6))), r"shape \(9, 6\)"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, np.nan])), "not finite"),
    (lambda g: finite_motion(g, np.zeros((9, 6))), "moves no block"),
    (lambda g: finite_motion(g, _twists(b0=[0, 0, 0, 0, 0, 1])), "moves frame block"),
    (lambda g: finite_motion(g, "up"), "array of twists or a callable"),
    (lambda g: finite_motion(g, lambda t: np.eye(4)), r"\(9, 4, 4\)"),
    (lambda g: finite_motion(g, lambda t: "x"), r"not an \(9, 4, 4\) array"),
    (lambda g: finite_motion(g, lambda t: np.full((9, 4, 4), np.nan)), "not finite"),
    (lambda g: finite_motion(g, _scaled), "not a rigid motion"),
    (lambda g: finite_motion(g, _moves_frame), "moves frame block"),
    (lambda g: finite_motion(g, _late_start), "must start at the identity"),
    (lambda g: finite_motion(g, lambda t: np.tile(np.eye(4), (9, 1, 1))), "moves no block"),
    (lambda g: finite_motion(g, _late_start, span=(1, 0)), "stop > start"),
    (lambda g: finite_motion(g, _late_start, span=(0, np.inf)), "finite"),
    (lambda g: finite_motion(g, _late_start, span=3), "two numbers"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), span=(0, 1)), "span applies to a callable"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), steps=0), "steps must be an integer >= 1"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), steps=2.5), "steps must be an integer >= 1"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), reach_rtol=0), "reach_rtol must be a finite num"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), overlap_rtol=-1), "overlap_rtol must be a finite"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), small_steps=(1e-3, 0)), "small_steps must be a finite"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), frame=[9]), "out of range"),
    (lambda g: finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1]), frame=["a"]), "block indices"),
    (lambda g: finite_motion(g.meshes, _twists(b4=[0, 0, 0, 0, 0, 1])), "needs an Assembly"),
    (lambda g: export_motion(g, g, "out"), "needs the FiniteMotion"),
    (lambda g: export_motion(g.meshes, finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1])), "out"), "the Assembly"),
    (lambda g: export_motion(presets.versatile_blocks(), finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1])), "out"),
     r"\(9 blocks\)"),
    (lambda g: export_motion(g, finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1])), "out", frames=0), "frames must be"),
    (lambda g: export_motion(g, finite_motion(g, _twists(b4=[0, 0, 0, 0, 0, 1])), "out", format="gif"),
     "unknown frame"),
]


@pytest.mark.parametrize("call, words", BAD)
def test_bad_input_raises_motion_error(call, words):
    with pytest.raises(MotionError, match=words) as error:
        call(_grid())
    assert isinstance(error.value, InterlockError)


def test_result_is_a_frozen_value():
    result = finite_motion(_grid(), _twists(b4=[0, 0, 0, 0, 0, 1]))
    assert isinstance(result, FiniteMotion)
    with pytest.raises(AttributeError):
        result.shown = False


def test_a_spent_budget_stops_the_finite_motion():
    import trimesh as _trimesh

    from interlock.verify.budget import Budget, TimeLimitReached

    grid = [_trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    grid = Assembly.from_meshes(grid, frame=[0, 1, 2, 3, 5, 6, 7, 8])
    up = np.zeros((9, 6))
    up[4, 5] = 1.0
    with pytest.raises(TimeLimitReached, match="beyond"):
        finite_motion(grid, up, budget=Budget(limit=1e-9, started=0.0))
