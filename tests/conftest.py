"""Shared fixtures: lattice parameters per crystal system and the reference data of other projects."""

from pathlib import Path

import pytest
from hypothesis import settings

from interlock import wallpaper

#: Property tests draw the same examples on every run and machine (derandomised: each test's seed is fixed by
#: its name), so CI cannot draw a case no earlier run saw; no deadline, since shared machines are noisy.
settings.register_profile("interlock", derandomize=True, deadline=None, print_blob=True)
settings.load_profile("interlock")


HYPOTHESIS_HEADER = "hypothesis: profile 'interlock', derandomised (each test's seed fixed by its name), deadline none"


def pytest_report_header(config):
    return HYPOTHESIS_HEADER


def pytest_sessionstart(session):
    # `pytest -q` (the README's command, so CI's) prints no header: say how hypothesis draws there too
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None and session.config.option.verbose < 0 and not hasattr(session.config, "workerinput"):
        reporter.write_line(HYPOTHESIS_HEADER)


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


#: The suite runs on two processes (pytest-xdist's ``-n 2`` in pyproject.toml).  Each module's tests go to one
#: worker, in order, so that a module-scoped fixture is built once (a custom scope, below); the tests of
#: ``SPLIT_MODULES`` are dealt out one by one (they share no costly fixture).  The slow tests and modules of
#: ``SLOW_FIRST`` (measured seconds on one core, largest first) start first, so that neither worker is left
#: with a long test at the end while the other idles.  With ``-n 0`` the order is the collection's.
SPLIT_MODULES = ("tests/verify/test_cra.py", "tests/verify/test_interfaces.py")
SLOW_FIRST = (
    "tests/verify/test_interfaces.py::test_armadillo_cra_is_stable_by_holding_block_238_out",  # 175-200 s
    "tests/test_benchmarks.py",  # 175 s: the quick run of every benchmark, one module-scoped fixture
    "tests/verify/test_interfaces.py::test_armadillo_cra_without_holding_out_names_block_238",  # 140 s
    "tests/verify/test_margin.py",  # 140-180 s, module-scoped float32 bunnies
    "tests/verify/test_cra.py::test_shelf_rbe_holds_it_and_cra_does_not_claim_it_stands",  # 50 s, at times 170-210
    "tests/verify/test_interfaces.py::test_armadillo_without_its_edge_block_238_is_proved_stable_by_cra",  # 70 s
    "tests/verify/test_cra.py::test_table_2_cra_critical_tilt",  # 24 cases, up to 40 s each
)


def _scope(nodeid: str) -> str:
    module = nodeid.split("::", 1)[0]
    return nodeid if module in SPLIT_MODULES else module


def pytest_xdist_make_scheduler(config, log):
    """Scopes of work: a module, or a test of ``SPLIT_MODULES``; handed out in the workers' collection order."""
    from xdist.scheduler import LoadScopeScheduling

    class ModuleScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return _scope(nodeid)

    config.option.loadscopereorder = False  # not by number of tests: pytest_collection_modifyitems orders them
    return ModuleScheduling(config, log)


def pytest_collection_modifyitems(config, items):
    if not hasattr(config, "workerinput"):  # not an xdist worker
        return

    def rank(item):
        return next((k for k, prefix in enumerate(SLOW_FIRST) if item.nodeid.startswith(prefix)), len(SLOW_FIRST))

    items.sort(key=rank)  # stable: the collection's order within each rank
