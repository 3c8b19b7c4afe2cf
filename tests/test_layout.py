"""The package's layout: one-way imports, no circles, no private names across modules, old paths that warn."""

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "interlock"
#: Data flows one way (docs/architecture.md): a module may import its own layer and the layers below.
LAYERS = {"interlock.errors": 0, "interlock.deprecation": 0, "interlock.wallpaper": 1, "interlock.blocks": 2,
          "interlock.formats": 3, "interlock.verify": 4, "interlock.gallery": 5, "interlock.sweep": 5,
          "interlock.cli": 6, "interlock.__main__": 7, "interlock": 1}


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = ("interlock",) + path.relative_to(PACKAGE).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        found[name] = path
    return found


MODULES = _modules()


def _imports(name: str, path: Path):
    """(imported module, imported names) for every import statement of a module, at any depth."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            yield base, tuple(alias.name for alias in node.names)


def _graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for name, path in MODULES.items():
        graph.add_node(name)
        for module, names in _imports(name, path):
            targets = [f"{module}.{n}" for n in names if f"{module}.{n}" in MODULES] or [module]
            for target in targets:
                if target in MODULES and target != name:
                    graph.add_edge(name, target)
    return graph


def _layer(name: str) -> int:
    return next(LAYERS[prefix] for prefix in sorted(LAYERS, key=len, reverse=True)
                if name == prefix or name.startswith(prefix + "."))


def test_no_module_imports_through_a_circle():
    cycles = list(nx.simple_cycles(_graph()))
    assert cycles == []


def test_importing_the_verifier_imports_no_module_twice():
    code = ("import sys, importlib.abc\n"
            "seen = []\n"
            "class Watch(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path, target=None):\n"
            "        if name.startswith('interlock') and name in seen: print('again', name)\n"
            "        seen.append(name)\n"
            "sys.meta_path.insert(0, Watch())\n"
            "from interlock.verify import check\n"
            "print(len(seen))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "again" not in out and int(out.split()[-1]) > 20


def test_nothing_imports_upward():
    upward = [(a, b) for a, b in _graph().edges if _layer(b) > _layer(a)]
    assert upward == []


def test_no_module_imports_a_private_name_of_another():
    private = [(name, module, n) for name, path in MODULES.items() for module, names in _imports(name, path)
               for n in names if n.startswith("_") and n != "__version__" and module.startswith("interlock")]
    assert private == []


def test_docstrings_point_into_the_repository():
    outside = [str(p) for p in PACKAGE.rglob("*.py") if "DESIGN.md" in p.read_text()]
    assert outside == []


def test_every_docs_page_a_docstring_names_exists():
    import re

    named = {m for p in PACKAGE.rglob("*.py") for m in re.findall(r"docs/[\w./-]+\.md", p.read_text())}
    missing = sorted(m for m in named if not (PACKAGE.parent / m).is_file())
    assert named and missing == []


#: Every public name of the old module paths (0.1), and its new home.
OLD_PATHS = [
    *[("interlock.verify.stability", n, "interlock.verify.statics")
      for n in ("StabilityResult", "StabilityError", "rbe", "critical_tilt", "tilted_gravity", "TILT_AXES", "CONES",
                "DEFAULT_SIDES", "DEFAULT_TILT_STEP", "DEFAULT_TILT_TOL")],
    *[("interlock.verify.cra", n, "interlock.verify.statics.cra")
      for n in ("CRAResult", "cra", "DEFAULT_EPS", "DEFAULT_ETA", "DEFAULT_SECTORS", "DEFAULT_FORCE_BOUND",
                "DEFAULT_MIN_SLIDE", "REFINED_SECTORS")],
    *[("interlock.verify.cra_local", n, "interlock.verify.statics.cra_local")
      for n in ("least_friction", "realise", "realise_least_friction", "settled_motion", "snap", "polish",
                "verify_local", "last_resort")],
    *[("interlock.verify.cra_compas", n, "interlock.verify.statics.cra_compas")
      for n in ("upstream_motion", "upstream_solution", "MISSING_MESSAGE", "UPSTREAM_VERSION")],
    *[("interlock.verify.cra_ipopt", n, "interlock.verify.statics.cra_ipopt")
      for n in ("MISSING_MESSAGE", "IPOPT_ITERATIONS", "available", "local_solutions")],
    *[("interlock.verify.npod_bonds", n, "interlock.verify.npod")
      for n in ("BondConditions", "bond_conditions", "ProjectionBond", "BondSearch", "projection_bonds",
                "COLLINEAR_RTOL", "BOND_TOL", "DEGENERATE_TOL", "SIMILARITY_TOL", "SEARCH_SAMPLES", "SEARCH_STARTS",
                "REFINE_EVALUATIONS")],
    ("interlock.verify", "export_motion", "interlock.gallery.motion"),
    ("interlock.verify.motion", "export_motion", "interlock.gallery.motion"),
    ("interlock.verify.motion", "FRAME_FORMATS", "interlock.gallery.motion"),
    # issue 37: one module per format under interlock.formats
    *[("interlock.blocks.compas", n, "interlock.formats.compas")
      for n in ("load_compas", "read_compas", "write_compas", "fingerprint", "UPSTREAM_SUPPORTS",
                "UPSTREAM_FINGERPRINTS", "FINGERPRINT_ROUNDING", "COMPAS_DTYPES", "BLOCK_DTYPE", "GRAPH_DTYPE",
                "INFO_ATTRIBUTE")],
    *[("interlock.blocks.rhino", n, "interlock.formats.rhino")
      for n in ("write_3dm", "read_3dm_blocks", "RhinoError", "FRAME_LAYER", "MARKER_KEY", "INFO_KEY",
                "MISSING_MESSAGE", "RHINO_VERSION", "LAYER_COLOURS")],
    *[(old, n, "interlock.formats.common") for old in ("interlock.blocks.meshformat", "interlock.blocks.meshfiles")
      for n in ("MeshFile", "file_header", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA", "FIXED_DATA", "FIXED_WORD",
                "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE", "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY",
                "INFO_KEY", "GLTF_TO_Z_UP", "GLTF_SUFFIXES")],
    *[("interlock.blocks.meshformat", n, "interlock.formats.common")
      for n in ("header_counts", "flagged_name", "named_frame", "touching_bodies", "json_value", "is_label_pair",
                "stored_meaning")],
    ("interlock.blocks.meshfiles", "read_mesh_file", "interlock.formats"),
    ("interlock.gallery.export", "FORMATS", "interlock.formats"),
    ("interlock.gallery.export", "LABELLED_FORMATS", "interlock.formats"),
    ("interlock.gallery.export", "STL_MAX_BLOCKS", "interlock.formats.stl"),
]


@pytest.mark.parametrize("call", ["Assembly.load", "interlock.blocks.load_compas", "interlock.blocks.load_3dm",
                                  "interlock.gallery.export"])
def test_the_old_ways_in_and_out_warn_and_forward(call, tmp_path):
    import interlock
    from interlock.blocks import presets

    grid = presets.cube_grid()
    suffix = {"interlock.blocks.load_compas": ".json", "interlock.blocks.load_3dm": ".3dm"}.get(call, ".obj")
    path = interlock.write(grid, tmp_path / f"grid{suffix}")
    old = {"Assembly.load": interlock.blocks.Assembly.load,
           "interlock.blocks.load_compas": interlock.blocks.load_compas, "interlock.blocks.load_3dm": interlock.blocks.load_3dm,
           "interlock.gallery.export": lambda p: interlock.gallery.export(grid, p)}[call]
    with pytest.warns(DeprecationWarning, match=f"{call} moved to .*interlock.formats.*removed in interlock 0.3"):
        result = old(path)
    back = interlock.read(result) if call == "interlock.gallery.export" else result
    assert len(back) == len(grid) and back.frame == grid.frame


@pytest.mark.parametrize("old, name, new", OLD_PATHS, ids=[f"{o}.{n}" for o, n, _ in OLD_PATHS])
def test_old_import_paths_still_work_with_a_warning(old, name, new):
    module = importlib.import_module(old)
    with pytest.warns(DeprecationWarning, match=f"{old}.{name} moved to .*removed in interlock 0.3"):
        value = getattr(module, name)
    assert value is getattr(importlib.import_module(new), name)


def test_the_names_of_the_packages_are_not_shadowed_by_the_old_modules():
    import interlock.verify as verify
    from interlock.verify.statics import cra

    importlib.import_module("interlock.verify.cra")  # the deprecated module, loaded again
    assert verify.cra is cra and callable(verify.npod)
