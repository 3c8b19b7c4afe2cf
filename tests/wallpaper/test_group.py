"""The public API of interlock.wallpaper: names, lattices, validation, elements."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock import GroupError, InterlockError, LatticeError, wallpaper
from interlock.wallpaper import parse_symop

ORDERS = {"p1": 1, "p2": 2, "pm": 2, "pg": 2, "cm": 2, "pmm": 4, "pmg": 4, "pgg": 4, "cmm": 4,
          "p4": 4, "p4m": 8, "p4g": 8, "p3": 3, "p3m1": 6, "p31m": 6, "p6": 6, "p6m": 12}


def test_the_17_groups():
    assert wallpaper.GROUPS == tuple(ORDERS)
    for name, order in ORDERS.items():
        g = wallpaper.group(name)
        assert g.name == name and g.point_group_order == order
        reps = g.coset_representatives()
        assert reps.shape == (order, 3, 3)
        np.testing.assert_allclose(reps[0], np.eye(3), atol=1e-15)


@pytest.mark.parametrize("name,a,b,gamma", [
    ("p1", 1.0, 1.0, 75.0), ("p2", 1.0, 1.0, 75.0), ("pm", 1.0, 1.0, 90.0), ("cmm", 1.0, 1.0, 90.0),
    ("p4", 1.0, 1.0, 90.0), ("p4g", 1.0, 1.0, 90.0), ("p3", 1.0, 1.0, 120.0), ("p6m", 1.0, 1.0, 120.0),
])
def test_default_lattices_follow_crystal_system(name, a, b, gamma):
    p = wallpaper.group(name).parameters
    assert (p.a, p.b, p.gamma) == (a, b, gamma)


def test_lattice_rows_are_basis_vectors():
    np.testing.assert_allclose(wallpaper.group("p4", a=2).lattice, [[2, 0], [0, 2]])
    np.testing.assert_allclose(wallpaper.group("p6").lattice, [[1, 0], [-0.5, math.sqrt(3) / 2]], atol=1e-15)
    # centred groups: a and b are the conventional cell, the lattice is primitive
    np.testing.assert_allclose(wallpaper.group("cm", a=2, b=4).lattice, [[1, -2], [1, 2]])
    assert wallpaper.group("cm", a=2, b=4).cell_area == pytest.approx(4.0)


@pytest.mark.parametrize("kwargs,match", [
    (dict(name="p5"), "unknown wallpaper group 'p5'; choose one of: p1 p2"),
    (dict(name="P4"), "unknown wallpaper group"),
    (dict(name=4), "unknown wallpaper group 4"),
    (dict(name="p4", gamma=100), "gamma must be 90 degrees"),
    (dict(name="p4", a=1, b=2), "b must equal a"),
    (dict(name="p6", gamma=90), "gamma must be 120 degrees"),
    (dict(name="pmm", gamma=80), "gamma must be 90 degrees"),
    (dict(name="p1", a=-1), "must be positive"),
    (dict(name="p2", b=0), "must be positive"),
    (dict(name="p1", gamma=0), "degenerate lattice"),
    (dict(name="p1", gamma=180), "degenerate lattice"),
    (dict(name="p1", a=float("nan")), "not finite"),
    (dict(name="p3", a=float("inf")), "not finite"),
    (dict(name="p1", gamma="wide"), "must be a real number"),
])
def test_bad_input_is_a_clear_interlock_error(kwargs, match):
    with pytest.raises(InterlockError, match=match) as info:
        wallpaper.group(**kwargs)
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, (GroupError, LatticeError))


def test_bad_radius_and_centre():
    g = wallpaper.group("p4")
    for radius in (-1, float("nan"), "far"):
        with pytest.raises(InterlockError, match="radius"):
            g.elements_within(radius)
    with pytest.raises(InterlockError, match="center"):
        g.elements_within(1.0, center=(0, 0, 0))


def test_elements_within_starts_with_identity_and_grows():
    g = wallpaper.group("p6")
    small, large = g.elements_within(0.2), g.elements_within(2.0)
    assert small[0].is_identity and large[0].is_identity
    assert set(small) < set(large)
    assert len(set(large)) == len(large)
    assert g.elements_within(0.0) == (g.identity,)


def test_to_3d_and_orientation():
    g = wallpaper.group("p4m")
    for element in g.cosets:
        m4 = g.to_3d(element)
        np.testing.assert_array_equal(m4[2], [0, 0, 1, 0])
        np.testing.assert_array_equal(m4[:, 2], [0, 0, 1, 0])
        np.testing.assert_allclose(m4[:2, :2], g.matrix(element)[:2, :2])
        assert g.is_orientation_preserving(element) == (element.kind in ("identity", "rotation"))
        assert g.is_orientation_preserving(g.matrix(element)) == g.is_orientation_preserving(element)
    assert sum(g.is_orientation_preserving(e) for e in g.cosets) == 4


def test_element_algebra_and_printing():
    r = parse_symop("-y,x-y")
    assert r.kind == "rotation" and r.order_of_linear_part == 3
    assert str(r) == "-y,x-y" and str(r.inverse()) == "-x+y,-x"
    assert (r @ r.inverse()).is_identity
    assert r.rotation_centre() == (0, 0)
    assert parse_symop("-x+1/2,y").kind == "reflection"
    assert parse_symop("-x,y+1/2").kind == "glide reflection"
    assert parse_symop("x+1,y-2").kind == "translation"
    assert parse_symop("-x+1,-y").rotation_centre() == (0.5, 0)
    for bad in ("x", "x,y,z", "2x+q,y", "x/2,y"):
        with pytest.raises(GroupError):
            parse_symop(bad)
    with pytest.raises(GroupError, match="determinant"):
        parse_symop("x+y,x-y")


@given(
    name=st.sampled_from(wallpaper.GROUPS),
    scale=st.floats(1e-3, 1e3),
    b_ratio=st.floats(0.2, 5.0),
    gamma=st.floats(20.0, 160.0),
)
@settings(max_examples=60, deadline=None)
def test_geometry_scales_with_the_lattice(name, scale, b_ratio, gamma):
    system = wallpaper.group(name).crystal_system
    kwargs = dict(a=1.0)
    if system in ("oblique", "rectangular", "centred rectangular"):
        kwargs["b"] = b_ratio
    if system == "oblique":
        kwargs["gamma"] = gamma
    unit = wallpaper.group(name, **kwargs)
    scaled = wallpaper.group(name, **{k: (v * scale if k in "ab" else v) for k, v in kwargs.items()})
    F1 = np.asarray(unit.fundamental_domain().exterior.coords)
    F2 = np.asarray(scaled.fundamental_domain().exterior.coords)
    np.testing.assert_allclose(F2, scale * F1, rtol=1e-12, atol=1e-12 * scale)
    assert len(scaled.elements_within(2 * scale)) == len(unit.elements_within(2.0))
    # side pairings map the partner edge onto the edge in Cartesian coordinates
    for s in scaled.side_pairings():
        m = scaled.matrix(s.element)
        ends = F2[[s.partner, s.partner + 1]] @ m[:2, :2].T + m[:2, 2]
        target = F2[[s.edge, s.edge + 1]]
        err = min(np.abs(ends - target).max(), np.abs(ends[::-1] - target).max())
        assert err <= 1e-9 * scale


def test_elements_within_a_huge_radius_is_refused_before_anything_is_made():
    # issue 36: p4 within 1e6 asked numpy for 29 TiB of translations
    with pytest.raises(InterlockError, match=r"about 1\.6e\+13 candidates, more than max_elements=10,000,000"):
        wallpaper.group("p4").elements_within(1e6)
    with pytest.raises(InterlockError, match="max_elements"):
        wallpaper.group("p6").elements_within(1e308)
    with pytest.raises(InterlockError, match="beyond 2\\*\\*53"):
        wallpaper.group("p4").elements_within(1.0, center=(1e20, 0.0))
    assert len(wallpaper.group("p4").elements_within(3.0, max_elements=1000)) > 0
    with pytest.raises(InterlockError, match="max_elements"):
        wallpaper.group("p4").elements_within(3.0, max_elements=10)


@pytest.mark.parametrize("bad", ["x,y", b"x,y", [[1.0], [2.0, 3.0]], None, np.eye(2)])
def test_to_3d_of_something_that_is_no_element_or_matrix_is_a_clear_error(bad):
    with pytest.raises(InterlockError, match="expected a GroupElement or a finite 3x3 affine matrix"):
        wallpaper.group("p4").to_3d(bad)


@pytest.mark.parametrize("a", [1e200, 1e31, 1e-31, 1e-300])
def test_cell_lengths_whose_areas_would_overflow_are_refused(a):
    with pytest.raises(InterlockError, match="outside 1e-30..1e\\+30"):
        wallpaper.group("p1", a=a)
    with pytest.raises(InterlockError, match="outside"):
        wallpaper.group("pm", b=a)


@pytest.mark.parametrize("gamma", [1e-300, 5e-4, 180 - 5e-4])
def test_a_cell_too_flat_for_its_blocks_is_refused(gamma):
    with pytest.raises(LatticeError, match="too flat"):
        wallpaper.group("p1", gamma=gamma)
    assert wallpaper.group("p1", gamma=1e-3).parameters.gamma == 1e-3
