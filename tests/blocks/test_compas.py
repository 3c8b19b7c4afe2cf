"""COMPAS assembly JSON (compas_assembly / compas_cra): read and written without COMPAS, loaded in COMPAS."""

import json

import numpy as np
import pytest
import trimesh

from interlock.formats import read
from interlock.blocks import Assembly
from interlock.formats.compas import load_compas
from interlock.formats.compas import (COMPAS_DTYPES, UPSTREAM_FINGERPRINTS, UPSTREAM_SUPPORTS, fingerprint,
                                     write_compas)
from interlock.errors import InterlockError


def _polygon_volume(path) -> float:
    """Total volume from the file's own polygon faces (divergence theorem, Newell area vectors)."""
    nodes = json.loads(path.read_text())["data"]["graph"]["data"]["node"]
    total = 0.0
    for node in nodes.values():
        mesh = node["block"]["data"]
        xyz = {k: np.array([v.get(a, 0.0) for a in "xyz"]) for k, v in mesh["vertex"].items()}
        for face in mesh["face"].values():
            points = np.array([xyz[str(k)] for k in face])
            area = 0.5 * np.cross(points, np.roll(points, -1, axis=0)).sum(axis=0)
            total += points.mean(axis=0) @ area / 3.0
    return abs(total)


def _write(tmp_path, meshes, support=(), name="model.json", drop_face=False, keys=None, labels=None):
    """A COMPAS file of ``meshes``, keyed by ``keys`` (default 0, 1, ...); ``support`` and ``labels`` by key."""
    nodes = {}
    for k, (key, mesh) in enumerate(zip(keys or range(len(meshes)), meshes)):
        faces = mesh.faces.tolist()[1:] if drop_face and k == 0 else mesh.faces.tolist()
        vertex = {str(n): dict(zip("xyz", p)) for n, p in enumerate(mesh.vertices.tolist())}
        face = {str(f): face for f, face in enumerate(faces)}
        nodes[str(key)] = {"block": {"dtype": "compas_assembly.datastructures/Block",
                                     "data": {"vertex": vertex, "face": face}},
                           "is_support": key in support}
        if labels is not None and key in labels:
            nodes[str(key)]["label"] = labels[key]
    path = tmp_path / name
    path.write_text(json.dumps({"dtype": COMPAS_DTYPES[0], "data": {"graph": {"data": {"node": nodes}}}}))
    return path


def _stack(count=3):
    return [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in range(count)]


# rtol: the shelf, cube-curve and armadillo files have slightly non-planar quads, whose volume depends on
# how they are cut into triangles
@pytest.mark.parametrize("stem, blocks, frame, rtol", [
    ("type-a", 3, (0, 1), 1e-12), ("type-d", 3, (0, 1), 1e-12), ("H", 3, (0, 1), 1e-12),
    ("bridge", 16, (0, 1), 1e-12), ("cubes", 3, (0,), 1e-12), ("shelf", 11, (0,), 1e-6), ("snake", 4, (0,), 1e-12),
    ("concave-short", 2, (0,), 1e-12), ("cube-curve-short", 2, (0,), 1e-3),
    ("armadillo", 399, UPSTREAM_SUPPORTS["armadillo"], 1e-3)])
def test_sample_files_blocks_volumes_and_upstream_supports(reference_data, stem, blocks, frame, rtol):
    path = reference_data / "compas_cra" / f"{stem}.json"
    assembly = load_compas(path)
    assert len(assembly) == blocks
    assert assembly.labels == tuple(range(blocks))
    assert assembly.frame == tuple(sorted(frame))
    assert assembly.info["supports_from"] == "upstream examples"
    assert np.all(assembly.volumes > 0)
    assert assembly.volumes.sum() == pytest.approx(_polygon_volume(path), rel=rtol)


@pytest.mark.parametrize("stem", sorted(UPSTREAM_SUPPORTS))
def test_every_upstream_example_is_recognised_by_its_blocks(reference_data, tmp_path, stem):
    path = reference_data / "compas_cra" / f"{stem}.json"
    copy = tmp_path / "my-own-name.json"  # the example under another name is still the example
    copy.write_bytes(path.read_bytes())
    for loaded in (load_compas(path), load_compas(copy)):
        assert loaded.frame == tuple(sorted(UPSTREAM_SUPPORTS[stem]))
        assert loaded.info["supports_from"] == "upstream examples" and loaded.info["upstream_example"] == stem
        blocks = [loaded.mesh(i) for i in range(len(loaded))]
        assert fingerprint(loaded.labels, blocks) == UPSTREAM_FINGERPRINTS[stem][1]


def test_fingerprints_cover_the_upstream_supports_and_differ():
    assert set(UPSTREAM_FINGERPRINTS) == set(UPSTREAM_SUPPORTS)
    assert len({digest for _, digest in UPSTREAM_FINGERPRINTS.values()}) == len(UPSTREAM_FINGERPRINTS)


@pytest.mark.parametrize("name", ["bridge.json", "shelf.json", "cubes.json", "type-a.json", "armadillo.json"])
def test_user_file_named_like_an_example_gets_no_upstream_supports(tmp_path, name):
    # three unmarked boxes (as many nodes as cubes.json and type-a.json): not those examples
    path = _write(tmp_path, _stack(3), name=name)
    assembly = load_compas(path)
    assert assembly.frame == () and assembly.info["supports_from"] == "none"
    assert "upstream_example" not in assembly.info


def test_moved_or_rekeyed_example_is_not_the_example(reference_data, tmp_path):
    document = json.loads((reference_data / "compas_cra" / "bridge.json").read_text())
    graph = document["data"]["graph"]["data"]
    rekeyed = dict(document, data=dict(document["data"], graph={"data": dict(
        graph, node={str(int(k) * 10 + 100): v for k, v in graph["node"].items()}, edge={}, adjacency={})}))
    (tmp_path / "rekeyed").mkdir()
    (tmp_path / "rekeyed" / "bridge.json").write_text(json.dumps(rekeyed))
    vertex = next(iter(graph["node"]["5"]["block"]["data"]["vertex"].values()))
    vertex["z"] += 1e-3  # one vertex of one block moved by a millimetre
    (tmp_path / "bridge.json").write_text(json.dumps(document))
    for path in (tmp_path / "rekeyed" / "bridge.json", tmp_path / "bridge.json"):
        assert load_compas(path).frame == () and load_compas(path).info["supports_from"] == "none"


def test_armadillo_first_course_is_33_supports():
    assert len(UPSTREAM_SUPPORTS["armadillo"]) == 33


def test_is_support_marks_the_frame(tmp_path):
    a = load_compas(_write(tmp_path, _stack(), support=(0, 2)))
    assert a.frame == (0, 2) and a.info["supports_from"] == "file"


def test_supports_argument_overrides_file_and_table(tmp_path, reference_data):
    assert load_compas(_write(tmp_path, _stack(), support=(0,)), supports=[1]).frame == (1,)
    assert load_compas(reference_data / "compas_cra" / "type-a.json", supports=[2]).frame == (2,)


def test_unmarked_unknown_file_has_no_frame(tmp_path):
    assert load_compas(_write(tmp_path, _stack())).frame == ()


def test_unknown_support_key_raises(tmp_path):
    with pytest.raises(InterlockError, match="support keys \\[7\\] are not nodes"):
        load_compas(_write(tmp_path, _stack()), supports=[7])


def test_open_mesh_raises(tmp_path):
    with pytest.raises(InterlockError, match="block 0 .* not a closed mesh"):
        load_compas(_write(tmp_path, _stack(), drop_face=True))


@pytest.mark.parametrize("text", ["not json at all", json.dumps([1, 2]), json.dumps({"dtype": "compas.geometry/Box"}),
                                  json.dumps({"data": {"graph": {"data": {"node": {}}}}})])
def test_not_a_compas_assembly_raises(tmp_path, text):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(InterlockError, match="not JSON|not a COMPAS assembly|without blocks"):
        load_compas(path)


def test_missing_file_raises(tmp_path):
    with pytest.raises(InterlockError, match="does not exist"):
        load_compas(tmp_path / "nothing.json")


def test_non_convex_polygon_faces_are_triangulated(tmp_path):
    # an L-shaped prism whose two L faces are single non-convex hexagons
    outline = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    vertex = {str(k): {"x": x, "y": y, "z": z} for k, (x, y, z) in
              enumerate([(x, y, 0.0) for x, y in outline] + [(x, y, 1.0) for x, y in outline])}
    faces = [list(range(5, -1, -1)), list(range(6, 12))] + [[k, (k + 1) % 6, (k + 1) % 6 + 6, k + 6] for k in range(6)]
    node = {"block": {"data": {"vertex": vertex, "face": {str(f): face for f, face in enumerate(faces)}}}}
    path = tmp_path / "ell.json"
    path.write_text(json.dumps({"dtype": COMPAS_DTYPES[1], "data": {"graph": {"data": {"node": {"0": node}}}}}))
    assert load_compas(path).volumes[0] == pytest.approx(3.0)


def test_assembly_load_dispatches_json(reference_data):
    a = read(reference_data / "compas_cra" / "cubes.json")
    assert len(a) == 3 and a.frame == (0,) and a.info["format"] == "compas"
    assert read(reference_data / "compas_cra" / "cubes.json", frame=[2]).frame == (2,)


# --- writing -------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def generated():
    """A p4 Escher patch of radius 2 cells and RhomBlocks on a 4x4x4 hexagon, outer rings fixed."""
    import math

    from interlock import wallpaper
    from interlock.blocks import escher_block, patch, random_hexagon, rhomblock_assembly

    group = wallpaper.group("p4")
    p4 = patch(escher_block(group, {0: [(0.25, 0.1)], 1: [(0.4, 0.25)]}), 2 * math.sqrt(group.cell_area),
               frame="boundary")
    return {"p4": p4, "rhomblock": rhomblock_assembly(random_hexagon(4, 4, 4, seed=3), variant=1, frame="boundary")}


@pytest.mark.parametrize("name", ["p4", "rhomblock"])
def test_write_compas_round_trips_through_load_compas(tmp_path, generated, name):
    assembly = generated[name]
    back = load_compas(write_compas(assembly, tmp_path / f"{name}.json"))
    assert len(back) == len(assembly) and back.labels == assembly.labels  # group elements, lozenges: not their text
    np.testing.assert_allclose(back.volumes, assembly.volumes, rtol=1e-12)
    np.testing.assert_allclose(back.centroids, assembly.centroids, rtol=0, atol=1e-12 * assembly.scale)
    assert back.frame == assembly.frame and back.info["supports_from"] == "file"
    assert back.info["names"] == [f"block_{i:04d}" for i in range(len(assembly))]
    assert {k: v for k, v in back.info.items() if k in ("group", "block", "variant")} == \
        {k: v for k, v in assembly.info.items() if k in ("group", "block", "variant")}


def test_written_nodes_hold_names_labels_supports_and_polygon_faces(tmp_path, generated):
    assembly = generated["p4"]
    document = json.loads(write_compas(assembly, tmp_path / "p4.json").read_text())
    assert document["dtype"] == COMPAS_DTYPES[0]
    nodes = document["data"]["graph"]["data"]["node"]
    assert list(nodes) == [str(i) for i in range(len(assembly))]
    for i, node in nodes.items():
        assert node["name"] == f"block_{int(i):04d}" and node["label"] == str(assembly.labels[int(i)])
        assert node["is_support"] == (int(i) in assembly.frame)
    # coplanar triangles are merged: the bottom and the top of an Escher block are one face each
    faces = nodes["0"]["block"]["data"]["face"].values()
    assert len(faces) < len(assembly.mesh(0).faces) and max(len(f) for f in faces) > 4


def test_cubes_are_written_as_quadrilaterals_exactly(tmp_path):
    cubes = Assembly.from_meshes(_stack(2), frame=[0])
    document = json.loads(write_compas(cubes, tmp_path / "stack.json").read_text())
    block = document["data"]["graph"]["data"]["node"]["1"]["block"]["data"]
    assert sorted(len(f) for f in block["face"].values()) == [4] * 6
    assert sorted(tuple(v.values()) for v in block["vertex"].values()) == \
        sorted(map(tuple, _stack(2)[1].vertices.tolist()))


def test_reference_files_round_trip_with_their_supports(tmp_path, reference_data):
    original = load_compas(reference_data / "compas_cra" / "type-a.json")
    back = load_compas(write_compas(original, tmp_path / "type-a-copy.json"))
    assert len(back) == 3 and back.frame == (0, 1) and back.info["supports_from"] == "file"
    np.testing.assert_allclose(back.volumes, original.volumes, rtol=1e-12)


def test_written_file_loads_in_compas(tmp_path, generated):
    compas = pytest.importorskip("compas")
    pytest.importorskip("compas_assembly")
    assembly = generated["rhomblock"]
    loaded = compas.json_load(str(write_compas(assembly, tmp_path / "hexagon.json")))
    assert type(loaded).__name__ == "Assembly" and loaded.graph.number_of_nodes() == len(assembly)
    assert sorted(n for n in loaded.graph.nodes() if loaded.graph.node_attribute(n, "is_support")) == \
        list(assembly.frame)
    volumes = [loaded.graph.node_attribute(n, "block").volume() for n in sorted(loaded.graph.nodes())]
    np.testing.assert_allclose(volumes, assembly.volumes, rtol=1e-9)
    assert loaded.graph.node_attribute(0, "name") == "block_0000"


def test_info_with_a_dtype_key_does_not_confuse_compas(tmp_path, reference_data):
    compas = pytest.importorskip("compas")
    pytest.importorskip("compas_assembly")
    original = load_compas(reference_data / "compas_cra" / "cubes.json")  # its info holds "dtype"
    loaded = compas.json_load(str(write_compas(original, tmp_path / "cubes-copy.json")))
    assert loaded.graph.number_of_nodes() == 3


def test_write_compas_errors(tmp_path):
    with pytest.raises(InterlockError, match="has no blocks"):
        write_compas(Assembly.from_meshes([]), tmp_path / "empty.json")
    with pytest.raises(InterlockError, match="does not exist"):
        write_compas(Assembly.from_meshes(_stack(1)), tmp_path / "no" / "x.json")
    path = write_compas(Assembly.from_meshes(_stack(1)), tmp_path / "one.json")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.json"]  # no temporary file left
    assert len(load_compas(path)) == 1


# --- labels and node keys ------------------------------------------------------------------------

def test_labels_written_come_back(tmp_path):
    named = Assembly.from_meshes(_stack(3), frame=[0], labels=["named.obj:base", "named.obj:keystone", "top"])
    path = write_compas(named, tmp_path / "named.json")
    back = load_compas(path)
    assert back.labels == ("named.obj:base", "named.obj:keystone", "top") and back.frame == (0,)
    assert back.info["node_keys"] == [0, 1, 2]
    assert load_compas(write_compas(back, tmp_path / "again.json")).labels == back.labels


def test_label_texts_of_a_foreign_file_are_labels_and_supports_stay_node_keys(tmp_path):
    path = _write(tmp_path, _stack(3), keys=[5, 9, 12], labels={5: "base", 9: "9", 12: "cap"})
    assembly = load_compas(path, supports=[9])
    assert assembly.labels == ("base", 9, "cap")  # a label that is its key's text stays the key
    assert assembly.frame == (1,) and assembly.info["node_keys"] == [5, 9, 12]
    document = json.loads(write_compas(assembly, tmp_path / "copy.json").read_text())
    assert list(document["data"]["graph"]["data"]["node"]) == ["5", "9", "12"]


def test_node_keys_survive_json_to_json(tmp_path):
    keys = [100, 110, 120, 250]
    original = load_compas(_write(tmp_path, _stack(4), support=(100, 120), keys=keys))
    assert original.labels == tuple(keys) and original.frame == (0, 2) and "node_keys" not in original.info
    document = json.loads(write_compas(original, tmp_path / "copy.json").read_text())
    graph = document["data"]["graph"]["data"]
    assert list(graph["node"]) == ["100", "110", "120", "250"] and graph["max_node"] == 250
    assert [node["block"]["data"]["attributes"]["node"] for node in graph["node"].values()] == keys
    back = load_compas(tmp_path / "copy.json")
    assert back.labels == tuple(keys) and back.frame == (0, 2)
    np.testing.assert_array_equal(back.volumes, original.volumes)


def test_labels_that_are_not_node_keys_give_index_keys(tmp_path):
    for labels in (["a", "b"], [3, 3], [-1, 4], [True, False]):
        document = json.loads(write_compas(Assembly.from_meshes(_stack(2), labels=labels), tmp_path / "x.json")
                              .read_text())
        assert list(document["data"]["graph"]["data"]["node"]) == ["0", "1"]
