"""Reading COMPAS assembly JSON (compas_assembly / compas_cra) without COMPAS."""

import json

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly, load_compas
from interlock.blocks.compas import COMPAS_DTYPES, UPSTREAM_SUPPORTS
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


def _write(tmp_path, meshes, support=(), name="model.json", drop_face=False):
    nodes = {}
    for k, mesh in enumerate(meshes):
        faces = mesh.faces.tolist()[1:] if drop_face and k == 0 else mesh.faces.tolist()
        vertex = {str(n): dict(zip("xyz", p)) for n, p in enumerate(mesh.vertices.tolist())}
        nodes[str(k)] = {"block": {"dtype": "compas_assembly.datastructures/Block",
                                   "data": {"vertex": vertex, "face": {str(f): face for f, face in enumerate(faces)}}},
                         "is_support": k in support}
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
    a = Assembly.load(reference_data / "compas_cra" / "cubes.json")
    assert len(a) == 3 and a.frame == (0,) and a.info["format"] == "compas"
    assert Assembly.load(reference_data / "compas_cra" / "cubes.json", frame=[2]).frame == (2,)
