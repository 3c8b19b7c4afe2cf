"""spglib recognises the groups: a decorated motif copied by the cosets has the expected symmetry."""

import numpy as np
import pytest
import spglib
import spglib.error

from interlock import wallpaper
from interlock.wallpaper.tables import SPACE_GROUP_NUMBERS
from tests.conftest import all_groups_and_lattices

VACUUM = 10.0  # cell height along z, in units of the in-plane cell size


@pytest.fixture(autouse=True)
def _spglib_raises_errors(monkeypatch):
    monkeypatch.setattr(spglib.error, "OLD_ERROR_HANDLING", False)


def _layer(g):
    """A cell with vacuum along z holding the orbit of three generic points of F at distinct heights."""
    corners = np.asarray(g.fundamental_domain().exterior.coords)[:-1]
    weights = np.array([[5, 2, 1], [1, 6, 2], [2, 1, 7]], dtype=float)
    weights = np.hstack([weights, np.ones((3, len(corners) - 3))]) if len(corners) > 3 else weights
    motif = (weights / weights.sum(axis=1, keepdims=True)) @ corners
    heights = np.array([0.11, 0.37, 0.58])
    c = VACUUM * np.sqrt(g.cell_area)
    lattice = np.zeros((3, 3))
    lattice[:2, :2] = g.lattice
    lattice[2, 2] = c
    positions = []
    for m in g.coset_representatives():
        xy = motif @ m[:2, :2].T + m[:2, 2]
        positions.append(np.column_stack([g.to_lattice(xy) % 1.0, heights]))
    return lattice, np.vstack(positions), [1] * (3 * g.point_group_order)


@pytest.mark.parametrize("name,a,b,gamma", all_groups_and_lattices())
def test_spglib_finds_the_point_group_and_type(name, a, b, gamma):
    g = wallpaper.group(name, a, b, gamma)
    dataset = spglib.get_symmetry_dataset(_layer(g), symprec=1e-6 * np.sqrt(g.cell_area))
    assert dataset is not None
    assert len(dataset.rotations) == g.point_group_order
    assert dataset.number == SPACE_GROUP_NUMBERS[name]


@pytest.mark.parametrize("name,symbol", [("p1", "P1"), ("p2", "P2"), ("p3", "P3"), ("p4", "P4"), ("p6", "P6")])
def test_rotation_groups_have_expected_space_group_symbols(name, symbol):
    dataset = spglib.get_symmetry_dataset(_layer(wallpaper.group(name)), symprec=1e-6)
    assert dataset.international == symbol
