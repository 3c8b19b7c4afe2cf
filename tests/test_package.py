"""Packaging facts: the error hierarchy, the version, and README/CI agreement."""

import re

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
