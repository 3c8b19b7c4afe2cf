"""One triangle soup of closed bodies that touch, split into its bodies: interlock/blocks/bodies.py."""

import numpy as np
import pytest
import trimesh

from interlock.blocks import presets
from interlock.blocks.bodies import BodiesError, closed_bodies


def _soup(meshes):
    return trimesh.util.concatenate([m.copy() for m in meshes])


def _boxes(nx, ny, nz):
    return [trimesh.creation.box(bounds=[[x, y, z], [x + 1, y + 1, z + 1]])
            for x in range(nx) for y in range(ny) for z in range(nz)]


def test_cubes_sharing_faces_edges_and_corners_come_apart():
    boxes = _boxes(3, 3, 2)
    bodies = closed_bodies(*_pieces(_soup(boxes)))
    assert len(bodies) == 18
    assert all(b.is_watertight and b.is_winding_consistent and b.volume == pytest.approx(1.0) for b in bodies)
    assert sorted(np.round([b.centroid for b in bodies], 9).tolist()) == \
        sorted(np.round([b.centroid for b in boxes], 9).tolist())


def _pieces(mesh):
    return mesh.vertices, mesh.faces


def test_cubes_touching_along_an_edge_only():
    pair = [trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]), trimesh.creation.box(bounds=[[1, 1, 0], [2, 2, 1]])]
    assert len(closed_bodies(*_pieces(_soup(pair)))) == 2


def test_a_multi_body_stl_written_with_trimesh_splits_into_its_blocks(tmp_path):
    layer = presets.honeycomb_layer(2.0)
    path = tmp_path / "honeycomb.stl"
    _soup(layer.world_meshes()).export(path)
    read = trimesh.load(path, force="mesh")  # an STL reader merges coincident vertices: the bodies are welded
    assert len(read.split(only_watertight=True)) < len(layer)  # connected components cannot tell them apart
    bodies = closed_bodies(read.vertices, read.faces)
    assert len(bodies) == len(layer)
    volumes = sorted(round(float(b.volume), 6) for b in bodies)
    assert volumes == sorted(round(float(m.volume), 6) for m in layer.world_meshes())


def test_a_soup_wound_inwards_throughout_is_turned():
    soup = _soup(_boxes(2, 2, 1))
    soup.invert()
    bodies = closed_bodies(*_pieces(soup))
    assert len(bodies) == 4 and all(b.volume > 0 for b in bodies)


def test_an_open_surface_is_still_refused():
    soup = _soup(_boxes(2, 1, 1))
    with pytest.raises(BodiesError, match="open"):
        closed_bodies(soup.vertices, soup.faces[:-1])
    sheet = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    with pytest.raises(BodiesError, match="triangle on one side only"):
        closed_bodies(sheet.vertices, sheet.faces)


def test_a_body_turned_inside_out_among_others_is_refused():
    boxes = _boxes(3, 1, 1)
    boxes[1].invert()
    with pytest.raises(BodiesError, match="inside out|do not pair|turned against"):
        closed_bodies(*_pieces(_soup(boxes)))


def test_nothing_in_nothing_out():
    assert closed_bodies(np.zeros((0, 3)), np.zeros((0, 3), dtype=int)) == []
