"""What the command line imports (issue 40: every answer in bounded time).

``--time-limit`` counts from the start of :func:`interlock.cli.main`, imports included, and
imports cannot be interrupted: a command imports only what it uses, and ``import interlock.cli``
(before the clock starts) imports no numpy.  These tests state facts about ``sys.modules`` in a
fresh interpreter, never a wall-clock time.
"""

import json
import subprocess
import sys

import pytest
import trimesh

from interlock.blocks import Assembly
from interlock.formats import write

#: Runs ``main`` on the arguments in a fresh interpreter and prints the modules held before and after.
DRIVER = """
import contextlib, gc, io, json, sys
from interlock.cli import main
before = sorted(sys.modules)
program = sys.argv[1] == "program"
arguments = sys.argv[2:]
if program:
    sys.argv = ["interlock", *arguments]
with contextlib.redirect_stdout(io.StringIO()) as out:
    status = main() if program else main(arguments)
print(json.dumps({"status": status, "before": before, "after": sorted(sys.modules), "output": out.getvalue(),
                  "frozen": gc.get_freeze_count()}))
"""

#: Never needed by verify or stability on a mesh file: other commands' and other formats' modules, and the
#: optional heavy packages (plots, IPOPT, Dask, HDF5, Rhino).
NOT_FOR_MESH_COMMANDS = {"matplotlib", "casadi", "dask", "h5py", "rhino3dm", "interlock.gallery", "interlock.sweep",
                         "interlock.formats.rhino", "interlock.formats.gltf", "interlock.formats.threemf",
                         "interlock.formats.vtu", "interlock.formats.ply", "interlock.formats.stl",
                         "interlock.verify.periodic", "interlock.verify.criterion", "interlock.verify.npod"}
#: CRA's modules, and the tilt scan's (which imports CRA's): RBE without --tilt-axis needs none of them.
CRA = {"interlock.verify.statics.cra", "interlock.verify.statics.cra_coulomb", "interlock.verify.statics.cra_large",
       "interlock.verify.statics.cra_local", "interlock.verify.statics.cra_milp", "interlock.verify.statics.cra_ipopt",
       "interlock.verify.statics.cra_split", "interlock.verify.statics.cra_compas", "interlock.verify.statics.tilt"}


def _run(*arguments, program=False) -> dict:
    finished = subprocess.run([sys.executable, "-c", DRIVER, "program" if program else "call", *map(str, arguments)],
                              capture_output=True, text=True, check=True)
    record = json.loads(finished.stdout.strip().splitlines()[-1])
    record["before"], record["after"] = set(record["before"]), set(record["after"])
    return record


@pytest.fixture(scope="module")
def stack_obj(tmp_path_factory):
    """Two unit cubes, one on the other, block 0 the frame, as OBJ."""
    path = tmp_path_factory.mktemp("stack") / "stack.obj"
    cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    write(Assembly.from_meshes(cubes, frame=[0]), path)
    return path


def test_the_command_line_starts_without_numpy(stack_obj):
    # imported before main's clock starts: the parser only (generate, groups and periodic import
    # interlock.wallpaper, with numpy and shapely, when they run)
    record = _run("verify", stack_obj, "--fixed", "0")
    assert record["before"] & {"numpy", "scipy", "shapely", "trimesh", "networkx", "interlock.wallpaper",
                               "interlock.blocks", "interlock.formats", "interlock.verify"} == set()


def test_verify_imports_what_it_uses(stack_obj):
    record = _run("verify", stack_obj, "--fixed", "0", "--time-limit", "600")
    assert record["status"] == 1 and record["output"].startswith("not infinitesimally interlocked")  # block 1 lifts
    assert "interlock.verify.check" in record["after"]
    assert record["after"] & NOT_FOR_MESH_COMMANDS == set()
    assert "interlock.verify.statics" not in record["after"]  # verify decides kinematics only


def test_stability_rbe_imports_no_cra(stack_obj):
    record = _run("stability", stack_obj, "--fixed", "0", "--mu", "0.5", "--time-limit", "600")
    assert record["output"].startswith("RBE stable")
    assert "interlock.verify.statics.rbe" in record["after"]
    assert record["after"] & (NOT_FOR_MESH_COMMANDS | CRA) == set()


def test_stability_cra_imports_no_plots_and_no_other_formats(stack_obj):
    record = _run("stability", stack_obj, "--fixed", "0", "--mu", "0.5", "--method", "cra", "--time-limit", "600")
    assert record["output"].startswith("CRA")
    assert "interlock.verify.statics.cra" in record["after"]
    assert record["after"] & (NOT_FOR_MESH_COMMANDS - {"casadi"}) == set()  # IPOPT's casadi: only if CRA gets there


def test_only_the_program_freezes_the_garbage_collector_at_its_end(stack_obj):
    # the interpreter's last collection took 0.2 s after every answer; a caller of main(argv) keeps its collector
    assert _run("verify", stack_obj, "--fixed", "0")["frozen"] == 0
    assert _run("verify", stack_obj, "--fixed", "0", program=True)["frozen"] > 0
