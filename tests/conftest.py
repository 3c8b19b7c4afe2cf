"""Shared fixtures: lattice parameters per crystal system and the reference data of other projects."""

from pathlib import Path

import pytest
from hypothesis import settings

from interlock import wallpaper

#: Property tests draw the same examples on every run and machine (derandomised: each test's seed is fixed by
#: its name), so CI cannot draw a case no earlier run saw; no deadline, since shared machines are noisy.
settings.register_profile("interlock", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("interlock")


def pytest_report_header(config):
    return "hypothesis: profile 'interlock', derandomised (each test's seed fixed by its name), deadline none"

ROOT = Path(__file__).resolve().parents[1]
#: TopoLite and compas_cra files with their licences; ``tests/data/README.md`` gives provenance and verdicts.
REFERENCE_DATA = ROOT / "tests" / "data"

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
def reference_data():
    """The reference data folder ``tests/data`` (part of the repository: a missing file is a failure, not a skip)."""
    assert REFERENCE_DATA.is_dir(), f"the reference data folder {REFERENCE_DATA} is missing from the checkout"
    return REFERENCE_DATA
