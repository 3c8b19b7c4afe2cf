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
from interlock.verify.margin import input_precision

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
    assert input_precision(np.vstack([m.vertices for m in bunny.meshes]))[1] == "grid"  # multiples of 1/16
    assembly, _ = bunny_float32
    delta, source = input_precision(np.vstack([m.vertices for m in assembly.meshes]))
    assert source == "float32" and delta <= 2.0**-24 * assembly.scale


@pytest.mark.parametrize("frame", [[1], [0]])
def test_float32_bunny_with_one_fixed_part_is_not_interlocked(bunny_float32, frame):
    assembly, found = bunny_float32
    verdict = check(assembly, frame=frame, contacts=found)
    assert verdict.interlocked is False and verdict.motion_kind == "within tolerance"
    assert verdict.margin.upper <= 1.0 and "not interlocked within tolerance" in str(verdict)
    assert verdict.tolerances["tolerance_from"] == "float32 input"


@pytest.mark.parametrize("frame", [[0, 1], [0, 79]])
def test_float32_bunny_with_its_frame_is_interlocked_or_says_its_margin(bunny_float32, frame):
    assembly, found = bunny_float32
    verdict = check(assembly, frame=frame, contacts=found)
    assert verdict.interlocked in (True, None) and verdict.margin is not None
    assert "margin at least" in verdict.status
    if verdict.interlocked:
        assert verdict.margin.lower > 1


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
