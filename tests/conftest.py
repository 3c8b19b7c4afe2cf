"""Shared fixtures: lattice parameters per crystal system and the reference data folder."""

import os
from pathlib import Path

import pytest

from interlock import wallpaper

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("INTERLOCK_SHARED_DATA", ROOT.parent / "shared" / "data"))

#: Several lattices per crystal system (a, b, gamma); None means the default.
LATTICES = {
    "oblique": [(1.0, None, None), (1.3, 0.7, 110.0), (2.0, 1.5, 60.5)],
    "rectangular": [(1.0, None, None), (1.7, 0.6, None)],
    "centred rectangular": [(1.0, None, None), (0.8, 1.9, None)],
    "square": [(1.0, None, None), (2.5, None, None)],
    "hexagonal": [(1.0, None, None), (0.3, None, None)],
}


def all_groups_and_lattices():
    """(name, a, b, gamma) for every group and several lattices of its system."""
    cases = []
    for name in wallpaper.GROUPS:
        system = wallpaper.group(name).crystal_system
        cases += [pytest.param(name, a, b, gamma, id=f"{name}-{a}-{b}-{gamma}") for a, b, gamma in LATTICES[system]]
    return cases


@pytest.fixture(scope="session")
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.skip(f"reference data folder {SHARED_DATA} is absent (it lives beside the project, in ../shared/data)")
    return SHARED_DATA
