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


def test_import_interlock_loads_no_numpy_and_offers_the_main_names_lazily():
    loaded = _loaded("import interlock")
    assert "numpy" not in loaded and not any(name.startswith("interlock.") and name != "interlock.errors"
                                             for name in loaded)
    names = _loaded("import interlock\nassert callable(interlock.read) and callable(interlock.write)\n"
                    "assert callable(interlock.check) and interlock.Assembly.__name__ == 'Assembly'\n"
                    "assert interlock.formats.read is interlock.read and interlock.wallpaper.group('p4')")
    assert {"interlock.formats.readwrite", "interlock.verify.check", "interlock.blocks.assembly"} <= names
    assert {"read", "write", "check", "Assembly", "formats", "verify", "blocks"} <= set(dir(interlock))


def test_the_package_ships_py_typed():
    assert (ROOT / "interlock" / "py.typed").is_file()


def test_results_refuse_a_truth_value_and_point_to_their_answer():
    from interlock.blocks import presets
    from interlock.verify import check
    from interlock.verify.statics import rbe

    with pytest.raises(TypeError, match=r"\.interlocked"):
        bool(check(presets.cube_grid()))
    result = rbe(presets.cube_grid(), mu=0.5)
    with pytest.raises(TypeError, match=r"result\.stable, which is True, False or None"):
        bool(result)
    assert result.parameters["force_unit"] == "density x model unit^3"


def test_stability_forces_are_stated_in_the_model_s_units(tmp_path):
    from interlock.blocks import presets
    from interlock.formats.units import with_unit
    from interlock.verify.statics import rbe

    result = rbe(with_unit(presets.cube_grid(), "m"), mu=0.5, density=24.0)
    assert result.parameters["unit"] == "m" and result.parameters["force_unit"] == "density x m^3"
    assert "kN/m^3" in result.parameters["density_unit"]
    if result.stable:
        assert "forces in density x m^3" in str(result)


# --- the command line's exit status, as its help says ---------------------------------------------
def _status(argv, capsys):
    from interlock.cli import main

    try:
        code = main(argv)
    except SystemExit as error:
        code = error.code
    capsys.readouterr()
    return code


@pytest.mark.parametrize("command", ["verify", "periodic"])
def test_the_help_of_verify_and_periodic_documents_the_exit_status(command, capsys):
    from interlock.cli import parser

    text = " ".join(parser()._subparsers._group_actions[0].choices[command].format_help().split())
    assert "exit status: 0 interlocked, 1 not interlocked, 3 inconclusive (time limit, undecided solver), " \
           "2 bad input" in text


def test_verify_exits_by_its_answer(tmp_path, capsys):
    from interlock.blocks import presets
    from interlock.formats import write

    grid = write(presets.cube_grid(), tmp_path / "grid.stl")  # Ex. 3.5: the middle cube slides
    assert _status(["verify", str(grid)], capsys) == 1
    assert _status(["verify", str(grid), "--json"], capsys) == 1
    assert _status(["verify", str(grid), "--fixed", "0-8"], capsys) == 0  # every block fixed: nothing moves
    assert _status(["verify", str(grid), "--time-limit", "1e-9"], capsys) == 3
    assert _status(["verify", str(tmp_path / "missing.stl")], capsys) == 2
    assert _status(["verify", str(grid), "--order", "7"], capsys) == 2
    p4 = tmp_path / "p4.obj"
    assert _status(["generate", "wallpaper", "p4", "--deform", "0:0.25,0.1", "--deform", "1:0.4,0.25", "--radius",
                    "1.5", "-o", str(p4)], capsys) == 0
    assert _status(["verify", str(p4)], capsys) == 0


def test_periodic_exits_by_its_answer(capsys):
    assert _status(["periodic", "p4", "--deform", "0:0.25,0.1", "--deform", "1:0.4,0.25"], capsys) == 0
    assert _status(["periodic", "p1"], capsys) == 1  # undeformed p1 blocks slide
    assert _status(["periodic", "p4", "--staircase", "1,1,0"], capsys) == 2


def test_shell_completion_is_generated_for_every_command(capsys):
    pytest.importorskip("shtab")
    from interlock.cli import main

    assert main(["completion", "bash"]) == 0
    script = capsys.readouterr().out
    assert "interlock" in script and all(name in script for name in ("verify", "convert", "--unit", "--up"))
