"""Packaging facts: the error hierarchy, the version, and README/CI agreement."""

import re

import pytest

import interlock
from tests.conftest import ROOT


def test_error_hierarchy():
    assert issubclass(interlock.InterlockError, ValueError)
    assert issubclass(interlock.GroupError, interlock.InterlockError)
    assert issubclass(interlock.LatticeError, interlock.InterlockError)


def test_version_is_semantic():
    assert re.fullmatch(r"\d+\.\d+\.\d+", interlock.__version__)


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    commands = re.findall(r"```bash\n(.+?)\n```", readme)
    assert len(commands) == 2, "the Quickstart is exactly two commands"
    install_and_run, test = commands
    assert "pytest" in test and "pip install" in install_and_run
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert test in ci


def _loaded(code: str) -> set:
    """The modules a fresh interpreter holds after running ``code``."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code + "\nimport sys\nprint(' '.join(sys.modules))"],
                         capture_output=True, text=True, check=True).stdout
    return set(out.split())


HEAVY = {"trimesh", "scipy.optimize", "scipy.linalg", "manifold3d", "clarabel", "matplotlib", "networkx", "meshio",
         "casadi", "dask", "h5py", "lxml", "rhino3dm"}


def test_packages_import_only_what_is_asked_for():
    # issue 40: importing interlock.verify took 2-4 s; a package's names are now imported on first use
    for code in ("import interlock.verify", "import interlock.blocks", "import interlock.gallery",
                 "from interlock.sweep import MAX_POINTS, SweepError, check_size, load_spec, run"):
        assert _loaded(code) & HEAVY == set(), code
    assert {"interlock.verify.check", "scipy.optimize"} <= _loaded("from interlock.verify import check")
    assert "interlock.verify.statics" not in _loaded("from interlock.verify import check")


def test_a_submodule_loaded_by_name_leaves_the_function_of_that_name():
    import importlib

    import interlock.blocks
    import interlock.verify
    from interlock.verify.statics import cra

    importlib.import_module("interlock.verify.contacts")
    importlib.import_module("interlock.verify.cra")  # a deprecated module path
    importlib.import_module("interlock.gallery.render")
    from interlock.gallery import render
    from interlock.verify import check, contacts, npod

    assert all(callable(f) for f in (check, contacts, npod, render)) and interlock.verify.cra is cra
    assert "check" in dir(interlock.verify) and "Assembly" in dir(interlock.blocks)
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        interlock.verify.nothing
