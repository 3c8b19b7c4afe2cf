"""Verdicts that know the precision of their input (interlock/verify/margin.py; docs/interlocking.md)."""

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from interlock.blocks import Assembly
from interlock.gallery import export
from interlock.verify import check, contacts, finite_motion
from interlock.verify.precision import coordinate_precision

BUNNY_PARTS = 80


@pytest.fixture(scope="module")
def bunny(reference_data):
    paths = [reference_data / "topolite" / "bunny" / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)]
    return Assembly.load(paths)


def _rotated(assembly, seed):
    turn = Rotation.random(random_state=seed).as_matrix()
    return Assembly.from_meshes([trimesh.Trimesh(m.vertices @ turn.T, m.faces) for m in assembly.world_meshes()])


def _noisy(assembly, amplitude, seed):
    rng = np.random.default_rng(seed)
    return Assembly.from_meshes([trimesh.Trimesh(m.vertices + rng.normal(scale=amplitude * assembly.scale,
                                                                         size=m.vertices.shape), m.faces)
                                 for m in assembly.world_meshes()])


@pytest.fixture(scope="module", params=[3, 4])
def bunny_float32(bunny, tmp_path_factory, request):
    """The bunny turned by a random rotation, written as binary STL (float32) and read back."""
    path = tmp_path_factory.mktemp("float32") / "bunny.stl"
    export(_rotated(bunny, request.param), path)
    assembly = Assembly.load(path)
    return assembly, contacts(assembly)


def test_precision_is_read_off_the_coordinates(bunny, bunny_float32):
    assert coordinate_precision(np.vstack([m.vertices for m in bunny.meshes]))[1] == "grid"  # multiples of 1/16
    assembly, _ = bunny_float32
    delta, source = coordinate_precision(np.vstack([m.vertices for m in assembly.meshes]))
    assert source == "float32" and delta <= 2.0**-24 * assembly.scale


@pytest.mark.parametrize("frame", [[1], [0]])
def test_float32_bunny_with_one_fixed_part_is_not_interlocked(bunny_float32, frame):
    assembly, found = bunny_float32
    verdict = check(assembly, frame=frame, contacts=found)
    assert verdict.interlocked is False and verdict.motion_kind == "within tolerance"
    assert verdict.margin.upper <= 1.0 and verdict.tolerances["tolerance_from"] == "float32 input"
    shown = verdict.finite_motion
    if shown is not None and shown.shown:  # the part came out, its blocks reaching into others within the rounding
        assert str(verdict).startswith("not interlocked (finite motion shown)")
        assert 0 <= shown.tolerances["interference"] <= 2 * shown.tolerances["depth"]
        assert "within the input's precision" in str(verdict)
    else:
        assert "not interlocked within tolerance" in str(verdict)


@pytest.mark.parametrize("frame", [[0, 1], [0, 79]])
def test_float32_bunny_with_its_frame_is_interlocked_or_says_its_margin(bunny_float32, frame):
    assembly, found = bunny_float32
    verdict = check(assembly, frame=frame, contacts=found)
    assert verdict.interlocked in (True, None) and verdict.margin is not None
    assert "margin at least" in verdict.status
    if verdict.interlocked:
        assert verdict.margin.lower > 1
    # the tolerance stated is the largest contact's, whichever bound proved the margin (a float32 rounding:
    # 2^-24 of the coordinates, times the precision factor and the faces' bends, far below a part's size)
    assert verdict.margin.tolerance == verdict.tolerances["tolerance"] < 1e-4 * assembly.block_size


def test_certify_does_not_certify_what_the_margin_does_not_support(bunny_float32):
    assembly, found = bunny_float32
    moving = check(assembly, frame=[0], contacts=found, certify=True)
    assert moving.interlocked is not True and "certified" not in str(moving).split(":")[0]
    held = check(assembly, frame=[0, 1], contacts=found, certify=True)
    if held.certified:
        assert "certified for the exact input only" in str(held)


def test_exact_input_keeps_its_verdicts_and_computes_no_margin(bunny):
    found = contacts(bunny)
    held = check(bunny, frame=[0, 1], contacts=found)
    assert held.interlocked is True and np.isinf(held.margin.lower) and str(held).startswith("interlocked:")
    assert check(bunny, frame=[1], contacts=found).interlocked is False


@pytest.mark.parametrize("frame, allowed", [([1], (False, None)), ([0, 1], (True, None))])
def test_bunny_with_vertex_noise_of_1e_7(bunny, frame, allowed):
    noisy = _noisy(bunny, 1e-7, seed=1)
    verdict = check(noisy, frame=frame)
    assert verdict.interlocked in allowed and "faces bent by up to" in verdict.tolerances["tolerance_from"]


@pytest.mark.parametrize("amplitude", [1e-12, 1e-9, 1e-7])
@pytest.mark.parametrize("certify", [False, True])
def test_contacts_tighter_than_the_noise_give_no_wrong_verdict(bunny, amplitude, certify):
    """Contacts found below the input's noise miss touching faces: frame {0, 1} is then never "not interlocked"."""
    noisy = _noisy(bunny, amplitude, seed=2)
    verdict = check(noisy, frame=[0, 1], contacts=contacts(noisy, 1e-12, 1e-12), certify=certify)
    assert verdict.interlocked is not False and not verdict.certified
    assert verdict.interlocked is True or "the given contacts lack" in verdict.status


def test_a_given_tolerance_is_used_and_reported(bunny):
    verdict = check(bunny, frame=[0, 1], tolerance=1e-3 * bunny.scale)
    assert verdict.tolerances["tolerance_from"] == "given" and verdict.interlocked is not True


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(amplitude=st.sampled_from([1e-8, 1e-7, 3e-7]), seed=st.integers(0, 2**16))
def test_a_motion_shown_within_tolerance_is_never_called_interlocked(bunny, amplitude, seed):
    """Consistency: when finite_motion moves block 0 clear on a perturbed bunny, check does not say interlocked."""
    exact = check(bunny, frame=[1])
    noisy = _noisy(bunny, amplitude, seed)
    shown = finite_motion(noisy, exact.motion, frame=[1])
    if shown.shown:
        assert check(noisy, frame=[1]).interlocked is not True


def _scaled(assembly, factor, frame):
    return Assembly.from_meshes([m.copy().apply_scale(factor) for m in assembly.world_meshes()], frame=frame)


@pytest.mark.parametrize("factor", [1e-9, 1e-4, 1e6, 1e12])
def test_verdicts_identical_from_1e_minus_9_to_1e12(factor):
    """Tolerances are relative everywhere: contacts, vertex merging, precision and margin."""
    from interlock.blocks import presets, random_hexagon, rhomblock_assembly

    patch = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0))
    cases = [(patch, patch.boundary()), (presets.cube_grid(), presets.cube_grid().frame),
             (presets.interlocking_cubes(), presets.interlocking_cubes().frame)]
    for assembly, frame in cases:
        reference = check(_scaled(assembly, 1.0, frame))
        scaled = check(_scaled(assembly, factor, frame))
        assert (scaled.interlocked, scaled.contacts, scaled.rank, scaled.moving) == \
            (reference.interlocked, reference.contacts, reference.rank, reference.moving)
    assert reference.interlocked is True and reference.contacts == 16


@pytest.mark.parametrize("bad", [-1e-6, float("nan"), float("inf"), "1e-6", True])
def test_a_bad_tolerance_is_a_clear_error(bad):
    from interlock import InterlockError
    from interlock.blocks import presets

    with pytest.raises(InterlockError, match="tolerance must be a finite length >= 0"):
        check(presets.cube_grid(), tolerance=bad)


# --- the load-path bound (interlock/verify/load_paths.py) and assess ------------------------------


def _exact_reach(A, eps):
    """``R = max {||x||_inf : A x >= -eps}`` by the 2n coordinate LPs (inf when P is unbounded)."""
    import scipy.optimize

    n = A.shape[1]
    reach = 0.0
    for j in range(n):
        for sign in (1.0, -1.0):
            objective = np.zeros(n)
            objective[j] = -sign
            result = scipy.optimize.linprog(objective, A_ub=-A, b_ub=eps, bounds=(None, None), method="highs")
            if result.status == 3:
                return np.inf
            assert result.status == 0
            reach = max(reach, -result.fun)
    return reach


def _random_blocks(seed, blocks, size, rows):
    """Rows between random pairs of blocks (or a block and the frame): ``v`` on one, ``-v`` moved on the other."""
    import scipy.sparse as sp

    rng = np.random.default_rng(seed)
    dense = np.zeros((rows, blocks * size))
    for r in range(rows):
        g = rng.integers(blocks)
        h = rng.integers(-1, blocks)  # -1: the frame
        v = rng.normal(size=size)
        dense[r, g * size:(g + 1) * size] = v
        if h >= 0 and h != g:
            dense[r, h * size:(h + 1) * size] = -v + 0.3 * rng.normal(size=size)
    return sp.csr_matrix(dense), rng.uniform(0.5, 2.0, rows) * 10.0 ** rng.uniform(-4, -2)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**16), blocks=st.integers(1, 4), size=st.sampled_from([1, 3]),
       extra=st.integers(0, 12))
def test_load_path_bound_is_sound(seed, blocks, size, extra):
    """The proved bound never undercuts the exact LPs: lower bound on the margin <= 1 / R."""
    from interlock.verify.load_paths import load_path_bound

    A, eps = _random_blocks(seed, blocks, size, rows=blocks * (2 * size + 2) + extra)
    exact = _exact_reach(A.toarray(), eps)
    found = load_path_bound(A, eps, block_size=size)
    assert found.bound >= exact * (1 - 1e-9)
    assert np.all(found.coordinates.max(axis=1) <= found.bound)
    # with a target, coordinates above it are bounded again by exact LPs over their neighbourhoods
    targeted = load_path_bound(A, eps, block_size=size, target=0.5 * exact if np.isfinite(exact) else 1.0)
    assert targeted.bound >= exact * (1 - 1e-9)
    if np.isfinite(found.bound):
        assert found.margin == pytest.approx(1 / found.bound)


def test_load_path_bound_is_close_to_exact_on_a_chain():
    """A chain of three blocks between two walls: the load paths are the exact LPs' duals."""
    import scipy.sparse as sp

    from interlock.verify.load_paths import load_path_bound

    # blocks 0, 1, 2 on a line, walls at both ends; rows x_g - x_{g-1} >= -eps (a push to the right)...
    A = sp.csr_matrix(np.array([[1.0, 0, 0], [-1, 1, 0], [0, -1, 1], [0, 0, -1]]))
    eps = np.array([1e-3, 2e-3, 3e-3, 4e-3])
    found = load_path_bound(A, eps, block_size=1)
    assert found.bound == pytest.approx(_exact_reach(A.toarray(), eps), rel=1e-5)


@settings(max_examples=20, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**16), n=st.integers(1, 8), extra=st.integers(1, 10))
def test_one_stress_bounds_never_undercut_the_coordinate_lps(seed, n, extra):
    """``B_j >= max |x_j|`` on ``{A x >= -eps}`` for a matrix with a positive self-stress (``w^T A = 0``)."""
    import scipy.optimize
    import scipy.sparse as sp

    from interlock.verify.margin import closed_bounds, one_stress_bounds

    rng = np.random.default_rng(seed)
    dense = rng.normal(size=(n + extra, n))
    w = rng.uniform(0.1, 2.0, n + extra)
    dense -= np.outer(w, w @ dense) / (w @ w)  # now w^T A = 0: every motion opens some row and closes another
    if np.linalg.matrix_rank(dense) < n:
        return
    eps = rng.uniform(0.5, 2.0, n + extra) * 1e-3
    bounds = closed_bounds(*one_stress_bounds(sp.csr_matrix(dense), eps, w, chunk=3))
    for j in range(n):
        for sign in (1.0, -1.0):
            objective = np.zeros(n)
            objective[j] = -sign
            result = scipy.optimize.linprog(objective, A_ub=-dense, b_ub=eps, bounds=(None, None), method="highs")
            assert result.status == 0
            assert bounds[j] >= -result.fun * (1 - 1e-9) - 1e-12


@settings(max_examples=20, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # set the same way in every example
@given(seed=st.integers(0, 2**16), n=st.sampled_from([1, 3, 6]), extra=st.integers(1, 10), route=st.booleans())
def test_motion_bound_never_undercuts_the_exact_reach(seed, n, extra, route, monkeypatch):
    """``motion_bound`` (the play of gaps): through the stresses (the given one, then the one built for the loads)
    or, when the one-stress bound may not go first, the load paths, ``R >= max ||x||_inf`` on ``{A x >= -eps}``."""
    import scipy.sparse as sp

    from interlock.verify import margin as margins

    monkeypatch.setattr(margins, "ONE_STRESS_COLUMNS", 20000 if route else 0)
    rng = np.random.default_rng(seed)
    dense = rng.normal(size=(n + extra, n))
    w = rng.uniform(0.1, 2.0, n + extra)
    dense -= np.outer(w, w @ dense) / (w @ w)
    if np.linalg.matrix_rank(dense) < n:
        return
    eps = rng.uniform(0.5, 2.0, n + extra) * 1e-3  # well above HiGHS' feasibility tolerance: the LPs are exact
    bound = margins.motion_bound(sp.csr_matrix(dense), eps, w, block_size=n)  # one block and the frame
    exact = _exact_reach(dense, eps)
    assert bound >= exact * (1 - 1e-9)
    if route:
        assert np.isfinite(bound)


def test_load_paths_stop_once_their_values_keep_doubling():
    """The passes give up (nothing proved, the one-stress bound follows) once the median value has doubled from one
    try to the next (the p4 patch of radius 9 in float32); values that settle (hexagons, p4 radius 6) go on."""
    from interlock.verify.load_paths import _diverging

    medians, growing = [], [1.65e-3, 3.87e-3, 8.84e-3]
    assert [_diverging(medians, np.full(4, value)) for value in growing] == [False, True, True]
    for settling in ([4.25e-4, 4.75e-4, 6.67e-4], [3.87e-3, 2.22e-3, 1.45e-3, 1.35e-3, 9.1e-4]):
        medians = []
        assert not any(_diverging(medians, np.array([value, np.inf])) for value in settling)


@pytest.fixture(scope="module")
def small_hexagon(tmp_path_factory):
    """A RhomBlock 6 x 6 x 6 hexagon (108 blocks, ring fixed), turned, written as binary STL and read back."""
    from interlock.blocks import random_hexagon, rhomblock_assembly
    from interlock.verify import interlocking_matrix

    made = rhomblock_assembly(random_hexagon(6, 6, 6, seed=0), 0, frame="boundary")
    turn = Rotation.random(random_state=0).as_matrix()
    turned = Assembly.from_meshes([trimesh.Trimesh(m.vertices @ turn.T, m.faces) for m in made.world_meshes()],
                                  frame=made.frame)
    path = tmp_path_factory.mktemp("hexagon") / "hexagon.stl"
    export(turned, path)
    assembly = Assembly.load(path)
    found = contacts(assembly)
    return assembly, found, interlocking_matrix(assembly, assembly.frame, contacts=found)


def test_load_paths_decide_where_one_stress_did_not(small_hexagon):
    """At 300 times the float32 tolerance the old bound (one stress) is below 1; the load paths prove > 1."""
    from interlock.verify.margin import assess, margin_lower_bound, rounding_tolerance, row_tolerances

    assembly, found, A = small_hexagon
    tolerance, source = rounding_tolerance(assembly)
    assert source == "float32 input"
    stress = np.ones(A.shape[0])  # assess needs only that an exact verdict had a stress
    margin = assess(A, found, assembly.scale, stress, 300 * tolerance, "given")
    assert margin.lower > 1 and margin.upper_status == "not needed"
    from interlock.verify.check import check as full_check

    w = full_check(assembly, validate=False, contacts=found).stress
    old = margin_lower_bound(A.matrix, row_tolerances(A, found, 300 * tolerance), w)
    assert old < 1 < margin.lower


def test_float32_hexagon_is_interlocked_with_a_margin(small_hexagon):
    assembly, found, _ = small_hexagon
    verdict = check(assembly, contacts=found)
    assert verdict.interlocked is True and verdict.margin.lower > 10
    assert verdict.tolerances["tolerance_from"] == "float32 input"


def test_per_contact_tolerances_are_used_as_given(small_hexagon):
    from interlock.verify.margin import assess

    assembly, found, A = small_hexagon
    stress = np.ones(A.shape[0])
    one = assess(A, found, assembly.scale, stress, 1e-6 * assembly.scale, "given")
    each = assess(A, found, assembly.scale, stress, np.full(len(found), 1e-6 * assembly.scale), "per contact")
    assert each.per_contact and not one.per_contact and each.source == "per contact"
    assert each.lower == pytest.approx(one.lower, rel=1e-6)
    # per contact: a bent face does not replace the tolerance by the global "faces bent by up to"
    bent = [dataclasses_replace(c, deviation=1e-3 * assembly.scale) for c in found]
    kept = assess(A, bent, assembly.scale, stress, np.full(len(found), 1e-6 * assembly.scale), "per contact")
    assert kept.source == "per contact" and kept.tolerance == pytest.approx(1e-6 * assembly.scale)
    replaced = assess(A, bent, assembly.scale, stress, 1e-6 * assembly.scale, "float32 input")
    assert replaced.source.startswith("faces bent by up to")


def dataclasses_replace(contact, **changes):
    import dataclasses

    return dataclasses.replace(contact, **changes)


@pytest.mark.parametrize("name, kwargs", [
    ("tolerance", {"tolerance": float("nan")}), ("tolerance", {"tolerance": -1e-6}),
    ("tolerance", {"tolerance": float("inf")}), ("tolerance", {"tolerance": [1e-6, 2e-6]}),
    ("scale", {"scale": float("nan")}), ("scale", {"scale": -1.0}), ("scale", {"scale": float("inf")}),
    ("stress", {"stress": "nan"}), ("per_contact", {"per_contact": "yes"})])
def test_assess_names_a_bad_number(small_hexagon, name, kwargs):
    from interlock.verify.margin import MarginError, assess

    assembly, found, A = small_hexagon
    arguments = {"scale": assembly.scale, "stress": np.ones(A.shape[0]), "tolerance": 1e-6 * assembly.scale}
    if kwargs.get("stress") == "nan":
        kwargs = {"stress": np.full(A.shape[0], np.nan)}
    arguments.update(kwargs)
    with pytest.raises(MarginError, match=name):
        assess(A, found, arguments["scale"], arguments["stress"], arguments["tolerance"], "given",
               **({"per_contact": kwargs["per_contact"]} if "per_contact" in kwargs else {}))


@pytest.mark.parametrize("bad", [float("nan"), -1.0, 0.0, float("inf")])
def test_load_path_bound_refuses_bad_tolerances(bad):
    import scipy.sparse as sp

    from interlock.verify.load_paths import LoadPathError, load_path_bound

    with pytest.raises(LoadPathError, match="eps"):
        load_path_bound(sp.csr_matrix(np.array([[1.0], [-1.0]])), np.array([1e-3, bad]), block_size=1)


def test_a_failed_upper_bound_is_reported(small_hexagon, monkeypatch):
    """When the tolerance is too coarse to prove a margin and the motion LPs fail, the verdict says so."""
    import scipy.optimize

    from interlock.verify import margin as module

    assembly, found, A = small_hexagon

    class Failed:
        status, x, message = 4, None, "numerical difficulties (test)"

    monkeypatch.setattr(scipy.optimize, "linprog", lambda *args, **kwargs: Failed())
    result = module.assess(A, found, assembly.scale, np.ones(A.shape[0]), 1e-2 * assembly.scale, "given")
    assert result.lower <= 1 and np.isinf(result.upper)
    assert result.upper_status.startswith("solver failed") and "upper bound: solver failed" in str(result)


# --- a part that slides out of a rounded file ------------------------------------------------------------


@pytest.mark.parametrize("family", ["float32 STL", "7 digits"])
def test_a_part_of_a_rounded_file_slides_out_through_interference_within_its_precision(family):
    """The TopoLite cube with part 9 fixed is not interlocked: part 1 slides out (float64, an exact motion).  Placed
    far away and rounded, the faces it slides along tilt by the rounding and jam at first order ("within
    tolerance"); moved as a rigid body it comes out with the blocks reaching into each other by less than each
    block's rounding allows, so the answer is the plain "not interlocked (finite motion shown)"."""
    from benchmarks.real_files import perturbed
    from interlock.verify.precision import block_precision
    from interlock.verify.tolerances import block_depths

    rounded = perturbed("TopoLite cube", 0, family)
    verdict = check(rounded, frame=[8])
    assert verdict.interlocked is False and verdict.motion_kind == "within tolerance"
    shown = verdict.finite_motion
    assert shown.shown and shown.separated and shown.moving == (0,)
    assert str(verdict).startswith("not interlocked (finite motion shown): block 0 moves")
    assert "within the input's precision" in str(verdict)
    depths = block_depths(contacts(rounded), block_precision(rounded), len(rounded))
    assert 0 < shown.tolerances["interference"] <= depths[0] + depths.max()
    # the same motion with no interference allowed collides: the rounding, not the motion, was in the way
    assert not finite_motion(rounded, verdict.motion, frame=[8]).shown
    exact = check(perturbed("TopoLite cube", 0, "float64"), frame=[8])
    assert exact.interlocked is False and exact.motion_kind == "opening" and exact.moving == (0,)


def test_finite_motion_lets_blocks_interfere_only_as_deep_as_allowed():
    """A unit cube lifted out of a slot whose walls lean in by 1e-5 (per unit height): it scrapes 1e-5 deep, an
    overlap of 5e-6 of its volume, above the volume tolerance 1e-6."""
    from interlock.verify.motion import MotionError

    lean = 1e-5
    left = trimesh.Trimesh([[-1, 0, 0], [0, 0, 0], [-1, 1, 0], [0, 1, 0], [-1, 0, 1], [lean, 0, 1], [-1, 1, 1],
                            [lean, 1, 1]], process=False)
    wall = trimesh.convex.convex_hull(left.vertices)
    other = trimesh.convex.convex_hull(left.vertices * [-1, 1, 1] + [1, 0, 0])
    floor = trimesh.creation.box(bounds=[[-1, 0, -1], [2, 1, 0]])
    cube = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    slot = Assembly.from_meshes([wall, other, floor, cube], frame=[0, 1, 2])
    lift = np.zeros((4, 6))
    lift[3, 5] = 1.0
    assert not finite_motion(slot, lift).shown
    assert not finite_motion(slot, lift, depth=1e-8).shown
    scraped = finite_motion(slot, lift, depth=1e-5)
    assert scraped.shown and scraped.separated
    assert scraped.tolerances["interference"] == pytest.approx(lean, rel=0.05) and scraped.tolerances["depth"] == 1e-5
    with pytest.raises(MotionError, match="depth must be"):
        finite_motion(slot, lift, depth=-1.0)
    with pytest.raises(MotionError, match="depth must be"):
        finite_motion(slot, lift, depth=[1e-5, 1e-5])


def test_a_given_tolerance_widens_the_search_and_the_overlaps_too():
    """A caged unit cube whose +x neighbour reaches 5e-5 into it is refused as an overlap (its grid coordinates are
    exact); told that the faces are only within 1e-4, the overlap test and the search use that, and the cube is
    interlocked, the tolerance stated as given."""
    from interlock.verify.validate import OverlapError

    cage = [(0, 0, 0)] + [tuple(s * (k == axis) for k in range(3)) for axis in range(3) for s in (-1, 1)]
    lows = np.array(cage, dtype=float)
    lows[2, 0] -= 5e-5  # the +x neighbour pressed in
    pressed = Assembly.from_meshes([trimesh.creation.box(bounds=[lo, lo + 1]) for lo in lows], frame=range(1, 7))
    with pytest.raises(OverlapError, match="overlap 5e-05 deep"):
        check(pressed)
    verdict = check(pressed, tolerance=1e-4)
    assert verdict.interlocked is True and verdict.margin.lower > 1
    assert verdict.tolerances["tolerance_from"] == "given" and "(given)" in str(verdict)


def test_vertex_noise_is_read_off_the_faces():
    """A GeoCombSurfX patch with Gaussian vertex noise of 1e-5 of its size (its triangles tilted by up to 1e-3):
    the noise is read off the strays of nearly coplanar triangles, every contact of the original is found, the
    overlaps of the noise pass, and the patch is interlocked as its original (frame: blocks 1-8)."""
    from benchmarks.real_files import perturbed

    noisy = perturbed("GeoComb [-05,05]", 1, "noise 1e-5")
    original = perturbed("GeoComb [-05,05]", 1, "float64")
    assert len(contacts(noisy)) == len(contacts(original)) == 120
    verdict = check(noisy, frame=list(range(1, 9)))
    assert verdict.interlocked is True and verdict.margin.lower > 1


def test_a_stress_built_for_the_loads_proves_more_and_still_bounds_the_motions(bunny_float32):
    """The float32 bunny, frame {0, 1}, against 20 times its tolerances: the float verdict's stress proves a margin
    of 0.26 to 0.33 (6.6 and 5.1 at the real tolerances); the stress that covers the least-squares loads of every
    coordinate (demand_stress) proves 8 to 9 times more, and each bound it gives is above what the exact LP of
    that coordinate reaches."""
    from interlock.verify import interlocking_matrix
    from interlock.verify.margin import (closed_bounds, coordinate_motion, demand_stress, one_stress_bounds,
                                         row_tolerances)
    from interlock.verify.precision import block_precision
    from interlock.verify.tolerances import contact_tolerances

    assembly, found = bunny_float32
    verdict = check(assembly, frame=[0, 1], contacts=found)
    A = interlocking_matrix(assembly, frame=[0, 1], contacts=found)
    eps = 20 * row_tolerances(A, found, contact_tolerances(found, block_precision(assembly)))
    M = A.matrix.toarray()
    loads = np.abs(M @ np.linalg.solve(M.T @ M, np.eye(M.shape[1]))).max(axis=1)
    before = closed_bounds(*one_stress_bounds(A.matrix, eps, verdict.stress))
    w = demand_stress(A.matrix, eps, loads)
    after = closed_bounds(*one_stress_bounds(A.matrix, eps, w))
    assert after.max() < 1 < before.max() and after.max() < before.max() / 5
    for column in np.argsort(after)[-2:]:
        for sign in (1.0, -1.0):
            x, _, status = coordinate_motion(A.matrix, eps, int(column), sign)
            assert x is None or sign * x[column] <= after[column]


def test_demand_must_be_loads():
    from interlock.verify.margin import MarginError, demand_stress

    A = np.array([[1.0], [-1.0]])
    for demand in ([0.0, 0.0], [1.0, np.nan], [1.0, -1.0], [1.0]):
        with pytest.raises(MarginError, match="demand"):
            demand_stress(A, np.full(2, 1e-3), np.asarray(demand))


def test_one_stress_bounds_on_threads_are_the_serial_ones(monkeypatch, bunny):
    """Chunks solved two at a time give the very numbers of one at a time."""
    import interlock.verify.margin as margin_module
    from interlock.verify import interlocking_matrix
    from interlock.verify.margin import one_stress_bounds, row_tolerances

    found = contacts(bunny)
    A = interlocking_matrix(bunny, frame=[0, 1], contacts=found)
    eps = row_tolerances(A, found, 1e-6 * bunny.scale)
    stress = check(bunny, frame=[0, 1], contacts=found).stress
    results = []
    for threads in (1, 2):
        monkeypatch.setattr(margin_module, "MARGIN_THREADS", threads)
        results.append(one_stress_bounds(A.matrix, eps, stress, chunk=7))
    assert all(np.array_equal(a, b) for a, b in zip(*results))
