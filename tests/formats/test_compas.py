"""interlock/formats/compas.py with today's COMPAS: files dumped by the installed compas and compas_cra are read
(geometry, supports, interfaces in COMPAS 2's object form), and what interlock writes loads in COMPAS."""

import json

import numpy as np
import pytest

import interlock
from interlock.cli import main
from interlock.formats.compas import load_compas
from interlock.verify.statics import rbe
from interlock.verify.statics.interfaces import compas_interfaces

compas = pytest.importorskip("compas")
pytest.importorskip("compas_assembly")
compas_cra = pytest.importorskip("compas_cra")


@pytest.fixture(scope="module")
def dumped(tmp_path_factory):
    """A stack of three boxes, block 0 the support, with interfaces, as compas_cra dumps it today."""
    from compas.geometry import Box, Frame
    from compas_assembly.algorithms import assembly_interfaces
    from compas_assembly.datastructures import Block
    from compas_cra.datastructures import CRA_Assembly

    assembly = CRA_Assembly()
    for z in (0.5, 1.5, 2.5):
        assembly.add_block(Block.from_shape(Box(1, 1, 1, frame=Frame([0, 0, z], [1, 0, 0], [0, 1, 0]))))
    assembly.set_boundary_conditions([0])
    assembly_interfaces(assembly, amin=1e-6, tmax=1e-4)
    path = tmp_path_factory.mktemp("compas") / "stack.json"
    compas.json_dump(assembly, str(path))
    return path


def test_the_fixture_is_compas_2_object_form(dumped):
    edge = json.loads(dumped.read_text())["data"]["graph"]["data"]["edge"]
    interface = next(v for neighbours in edge.values() for v in neighbours.values() if v)["interfaces"][0]
    assert interface["data"]["points"][0]["dtype"] == "compas.geometry/Point"


def test_geometry_and_supports_of_a_dumped_file_are_read(dumped):
    stack = interlock.read(dumped)
    assert len(stack) == 3 and stack.frame == (0,) and stack.info["frame_from"] == "file"
    np.testing.assert_allclose(stack.volumes, 1.0)


def test_interfaces_dumped_by_compas_cra_are_read(dumped):
    stack = load_compas(dumped)
    found = compas_interfaces(dumped, stack)
    assert [(c.i, c.j) for c in found] == [(0, 1), (1, 2)]
    np.testing.assert_allclose([c.area for c in found], 1.0)
    np.testing.assert_allclose([c.normal for c in found], [[0, 0, 1], [0, 0, 1]])
    assert rbe(stack, mu=0.84, contacts=found).stable is True


def test_stability_with_interfaces_of_today_s_compas_cra_exits_0(dumped, capsys):
    assert main(["stability", str(dumped), "--mu", "0.84", "--interfaces", str(dumped)]) == 0
    out = capsys.readouterr()
    assert "stable" in out.out and out.err == ""


def test_compas_loads_what_interlock_writes(tmp_path):
    from interlock.blocks import presets

    path = interlock.write(presets.cube_grid(), tmp_path / "grid.json")
    loaded = compas.json_load(str(path))
    assert type(loaded).__name__ == "Assembly" and len(list(loaded.graph.nodes())) == 9
    supports = [key for key in loaded.graph.nodes() if loaded.graph.node_attribute(key, "is_support")]
    assert len(supports) == 8


def test_old_plain_list_interfaces_still_read(dumped, tmp_path):
    document = json.loads(dumped.read_text())
    for neighbours in document["data"]["graph"]["data"]["edge"].values():
        for attributes in neighbours.values():
            for interface in (attributes or {}).get("interfaces", []):
                interface["data"]["points"] = [p["data"] for p in interface["data"]["points"]]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(document))
    stack = load_compas(old)
    assert [(c.i, c.j) for c in compas_interfaces(old, stack)] == [(0, 1), (1, 2)]


def test_a_vertex_at_infinity_is_one_message_without_warnings(dumped, tmp_path, capsys):
    document = json.loads(dumped.read_text())
    block = document["data"]["graph"]["data"]["node"]["1"]["block"]["data"]
    first = next(iter(block["vertex"]))
    block["vertex"][first]["z"] = float("inf")
    path = tmp_path / "infinite.json"
    path.write_text(json.dumps(document))  # json writes Infinity
    assert "Infinity" in path.read_text()
    for command in (["verify", str(path)], ["convert", str(path), str(tmp_path / "x.stl")],
                    ["stability", str(path), "--mu", "0.5"]):
        assert main(command) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "not a finite number" in err and "Warning" not in err
