"""One STL holding many closed bodies that touch (issue 38): read as its bodies, not refused."""

import numpy as np
import pytest
import trimesh

import interlock
from interlock.blocks import presets
from interlock.formats.common import FormatError


def test_a_soup_of_touching_closed_bodies_reads_as_its_bodies(tmp_path):
    layer = presets.honeycomb_layer(1.5)  # tetrahedra and octahedra sharing faces and edges
    path = tmp_path / "layer.stl"
    trimesh.util.concatenate(layer.world_meshes()).export(path)  # a plain STL: no block index, one soup
    read = interlock.read(path)
    assert len(read) == len(layer)
    assert np.allclose(np.sort(read.volumes), np.sort(layer.volumes), rtol=1e-5)  # STL: float32 coordinates


def test_an_open_surface_among_touching_bodies_is_still_refused(tmp_path):
    cubes = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 1)]
    soup = trimesh.util.concatenate(cubes)
    soup = trimesh.Trimesh(soup.vertices, soup.faces[1:], process=False)  # one triangle of a cube missing
    path = tmp_path / "open.stl"
    soup.export(path)
    with pytest.raises(FormatError, match="touch"):
        interlock.read(path)
