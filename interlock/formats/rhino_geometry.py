"""The geometry of ``.3dm`` objects as closed triangle meshes: meshes, extrusions and polysurfaces (rhino3dm)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.repair import merge_vertices, split_t_junctions, triangulate_polygons, unmatched_edges
from interlock.formats.common import FormatError

__all__ = ["RhinoError", "object_mesh", "mesh_arrays", "brep_arrays", "closed_faces"]


class RhinoError(FormatError):
    """A ``.3dm`` file that cannot be read as blocks or written, or rhino3dm missing."""


def object_mesh(rhino, geometry, name: str, path: Path) -> trimesh.Trimesh:
    """The object as a closed triangle mesh, or a one-line error naming it."""
    what = type(geometry).__name__
    if isinstance(geometry, rhino.Mesh):
        vertices, faces = mesh_arrays(geometry)
    elif isinstance(geometry, rhino.Extrusion):
        cached = geometry.GetMesh(rhino.MeshType.Any)
        if cached is not None:
            vertices, faces = mesh_arrays(cached)
        else:
            brep = geometry.ToBrep(True)
            if brep is None:
                raise RhinoError(f"{name} of {path.name}: an extrusion rhino3dm cannot turn into a polysurface")
            vertices, faces = brep_arrays(rhino, brep, name, path)
    elif isinstance(geometry, rhino.Brep):
        vertices, faces = brep_arrays(rhino, geometry, name, path)
    else:
        raise RhinoError(f"{name} of {path.name} is a {what}, not a closed solid; a block is a closed mesh or a "
                         "closed polysurface (delete the object or move it to another file)")
    if not len(faces):
        raise RhinoError(f"{name} of {path.name} is a {what} without faces, not a closed solid")
    vertices, faces = closed_faces(vertices, faces, f"{name} of {path.name}", what)
    return trimesh.Trimesh(vertices, faces, process=False)


def mesh_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    vertices = np.array([(p.X, p.Y, p.Z) for p in mesh.Vertices.ToPoint3dArray()], dtype=float).reshape(-1, 3)
    corners = np.array([mesh.Faces[k] for k in range(len(mesh.Faces))], dtype=np.int64).reshape(-1, 4)
    triangles = corners[corners[:, 2] == corners[:, 3], :3]
    quads = corners[corners[:, 2] != corners[:, 3]]
    if len(quads):
        cut, _ = triangulate_polygons(vertices, quads.ravel(), np.full(len(quads), 4))
        triangles = np.vstack([triangles, cut])
    return vertices, triangles


def brep_arrays(rhino, brep, name: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of a polysurface: from its render meshes if saved, else from planar faces with straight edges."""
    where = f"{name} of {path.name}"
    faces = [brep.Faces[k] for k in range(len(brep.Faces))]
    if not brep.IsSolid:
        raise RhinoError(f"{where} is an open polysurface, not a closed solid; close it (Cap, Join) in Rhino")
    cached = [face.GetMesh(rhino.MeshType.Any) for face in faces]
    if all(mesh is not None for mesh in cached):
        parts = [mesh_arrays(mesh) for mesh in cached]
        offsets = np.cumsum([0] + [len(v) for v, _ in parts])
        return (np.vstack([v for v, _ in parts]), np.vstack([f + o for (_, f), o in zip(parts, offsets)]))
    edges = [brep.Edges[k] for k in range(len(brep.Edges))]
    if not all(face.IsPlanar() for face in faces) or not all(edge.IsLinear() for edge in edges):
        raise RhinoError(f"{where} is a polysurface with curved faces or edges and no render mesh; rhino3dm cannot "
                         "mesh it outside Rhino: mesh it in Rhino (_Mesh) or save the file with render meshes")
    vertices = np.array([(p.X, p.Y, p.Z) for p in (brep.Vertices[k].Location for k in range(len(brep.Vertices)))],
                        dtype=float).reshape(-1, 3)
    polygons = []
    for face in faces:
        if len(face.Loops) != 1:
            raise RhinoError(f"{where} has a face with a hole; mesh it in Rhino (_Mesh) and read the mesh")
        polygon = [trim.StartVertexIndex for trim in face.OuterLoop.Trims]
        polygons.append(polygon[::-1] if face.OrientationIsReversed else polygon)
    triangles, _ = triangulate_polygons(vertices, [v for p in polygons for v in p], [len(p) for p in polygons])
    return vertices, triangles


def closed_faces(vertices: np.ndarray, faces: np.ndarray, where: str, what: str) -> tuple[np.ndarray, np.ndarray]:
    """The mesh, its vertices welded where they coincide if needed; an error unless it closes up."""
    if not unmatched_edges(faces).size:
        return vertices, faces
    merged, welded = merge_vertices(vertices, faces)
    welded = welded[(welded[:, 0] != welded[:, 1]) & (welded[:, 1] != welded[:, 2]) & (welded[:, 0] != welded[:, 2])]
    if welded.size and not unmatched_edges(split_t_junctions(merged, welded)).size:
        return merged, welded
    open_edges = unmatched_edges(welded).shape[0] if welded.size else 0
    raise RhinoError(f"{where} is a {what} that is not a closed solid ({open_edges} edges without a matching "
                     "opposite edge); a block must be a closed, consistently oriented surface")
