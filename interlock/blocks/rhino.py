"""Rhino ``.3dm`` files through rhino3dm: one mesh object per block, layers by class, a ``frame`` layer."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.classes import block_classes
from interlock.blocks.info import plain, restored
from interlock.blocks.labels import label_from_text, label_text
from interlock.blocks.lozenge import Lozenge
from interlock.blocks.repair import merge_vertices, split_t_junctions, triangulate_polygons, unmatched_edges
from interlock.errors import AssemblyError
from interlock.files import atomic_write, unwritable
from interlock.wallpaper.elements import GroupElement

__all__ = ["write_3dm", "read_3dm_blocks", "RhinoError", "FRAME_LAYER", "MARKER_KEY", "INFO_KEY", "MISSING_MESSAGE",
           "RHINO_VERSION", "LAYER_COLOURS"]

#: The layer whose objects are the fixed blocks (the frame), on writing and on reading (any case).
FRAME_LAYER = "frame"
#: Document user text key announcing an interlock file: ``"interlock blocks=N fixed=K classes=KIND"``.
MARKER_KEY = "interlock"
#: Document user text key of ``Assembly.info``, written as a Python literal (``repr``) so that
#: integer keys, tuples and floats read back exactly.
INFO_KEY = "interlock.info"
#: The Rhino version of written files: 7, which Rhino 7 and 8 open (double-precision mesh
#: vertices are kept in both).
RHINO_VERSION = 7
#: The error when rhino3dm does not import.
MISSING_MESSAGE = 'reading and writing .3dm files needs rhino3dm: pip install "interlock[rhino]"'
#: Layer colours (RGBA) of classes 0, 1, 2, ... (cycled): the gallery's Okabe-Ito palette.
LAYER_COLOURS = ((0, 114, 178, 255), (230, 159, 0, 255), (0, 158, 115, 255), (204, 121, 167, 255),
                 (86, 180, 233, 255), (213, 94, 0, 255), (240, 228, 66, 255), (120, 120, 120, 255))
_FRAME_COLOUR = (40, 40, 40, 255)


class RhinoError(AssemblyError):
    """A ``.3dm`` file that cannot be read as blocks or written, or rhino3dm missing."""


def write_3dm(assembly, path, *, classes=None, version: int = RHINO_VERSION, progress=None) -> Path:
    """Write an assembly to a Rhino ``.3dm`` file, one closed mesh object per block.

    - Objects are named ``block_0007 <label>`` (block index, then the label: a group
      element such as ``-y+1/2,x``, a lozenge ``D(0, 0)+U(1, 0)``, ...).
    - Each class (coset of the translation subgroup for Escher blocks, orientation
      for RhomBlocks, else the mesh type) is a layer (``coset 0``, ``orientation 2``);
      the fixed blocks are on the layer :data:`FRAME_LAYER` instead.
    - Object user strings: ``block``, ``label``, ``label_type``, ``class``,
      ``class_kind``, ``fixed``, ``mirrored``, ``type`` (mesh index), ``transform``
      (16 numbers, row by row), ``volume``; for group elements also ``element`` and
      ``coset`` (the linear part, e.g. ``-y,x``), for lozenges ``orientation``.
    - Document user text: :data:`MARKER_KEY`, :data:`INFO_KEY` and each key of
      ``assembly.info`` (``group``, ``deformation``, ``seed``, ...) as JSON.

    Vertices are double precision, so :func:`~interlock.blocks.load_3dm` gives back every block's
    world vertices bit for bit.  The file is written next to ``path`` under a
    temporary name and then moved into place, so a reader never sees half a file.

    Parameters
    ----------
    assembly : Assembly
    path : str or path-like
        The file to write (any suffix; ``.3dm`` by convention).
    classes : (array of int, str), optional
        Each block's class and what classes mean, e.g. the result of
        :func:`interlock.blocks.classes.block_classes`; by default the same rules
        are applied here.
    version : int
        The Rhino file version (6, 7 or 8); :data:`RHINO_VERSION` by default.
    progress : callable, optional
        Called as ``progress(done, total)`` after each block (a progress bar).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    RhinoError
        If rhino3dm is missing (:data:`MISSING_MESSAGE`), the assembly has no blocks,
        ``classes`` does not give one class per block, or the file cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import Assembly, presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = Assembly.load(write_3dm(grid, Path(folder) / "grid.3dm"))
    >>> len(back), back.frame == grid.frame, back.info["preset"], back.labels[:3]
    (9, True, 'cube_grid', ((0, 0), (0, 1), (0, 2)))
    """
    rhino = _rhino3dm()
    path = Path(path)
    if not all(hasattr(assembly, name) for name in ("types", "transforms", "labels", "frame", "world_meshes")):
        raise RhinoError(f"write_3dm needs an Assembly (interlock.blocks.Assembly), got {type(assembly).__name__}")
    if not len(assembly):
        raise RhinoError(f"nothing to write to {path.name}: the assembly has no blocks")
    values, kind = block_classes(assembly) if classes is None else classes
    values = np.asarray(values, dtype=int).reshape(-1)
    if len(values) != len(assembly):
        raise RhinoError(f"classes must give one class per block: got {len(values)} for {len(assembly)} blocks")
    document = rhino.File3dm()
    layers = {}
    for value in sorted(set(values.tolist())):
        layers[value] = _add_layer(rhino, document, f"{kind} {value}", LAYER_COLOURS[value % len(LAYER_COLOURS)])
    fixed = set(assembly.frame)
    if fixed:
        layers["frame"] = _add_layer(rhino, document, FRAME_LAYER, _FRAME_COLOUR)
    for i in range(len(assembly)):
        if progress is not None:
            progress(i, len(assembly))
        world = assembly.mesh(i)
        mesh = rhino.Mesh()
        for x, y, z in world.vertices.tolist():
            mesh.Vertices.AddPoint3d(x, y, z)  # double precision
        for a, b, c in world.faces.tolist():
            mesh.Faces.AddFace(a, b, c)
        mesh.Normals.ComputeNormals()
        attributes = rhino.ObjectAttributes()
        attributes.Name = f"block_{i:04d} {assembly.labels[i]}"
        attributes.LayerIndex = layers["frame" if i in fixed else int(values[i])]
        for key, value in _block_strings(assembly, i, int(values[i]), kind, world).items():
            attributes.SetUserString(key, value)
        document.Objects.AddMesh(mesh, attributes)
    document.Strings[MARKER_KEY] = f"interlock blocks={len(assembly)} fixed={len(fixed)} classes={kind}"
    info = plain(assembly.info, json=False)
    document.Strings[INFO_KEY] = repr(info)
    for key, value in info.items():
        if isinstance(key, str) and key not in (MARKER_KEY, INFO_KEY):
            document.Strings[key] = value if isinstance(value, str) else json.dumps(value, default=str)
    _write_atomically(document, path, version)
    return path


def read_3dm_blocks(path, *, frame_layer: str = FRAME_LAYER,
                    progress=None) -> tuple[list[trimesh.Trimesh], list, tuple | None, dict]:
    """The blocks of a ``.3dm`` file: ``(meshes, labels, frame, info)``, read for :func:`~interlock.blocks.load_3dm`.

    See :func:`~interlock.blocks.assembly.load_3dm` for what is read;
    ``frame`` holds the indices of the blocks on the layer ``frame_layer``
    (None when the file has no such layer and is not an interlock file).
    """
    rhino = _rhino3dm()
    path = Path(path)
    document = _read_document(rhino, path)
    marker = _string(document, MARKER_KEY)
    ours = marker.startswith("interlock ")
    objects = [document.Objects[k] for k in range(len(document.Objects))]
    if not objects:
        raise RhinoError(f"{path.name} holds no objects; a block is a closed mesh or a closed polysurface")
    on_frame = _frame_layers(document, frame_layer)
    blocks = []  # (order key, mesh, label, fixed)
    for k, item in enumerate(objects):
        if progress is not None:
            progress(k, len(objects))
        name = _object_name(document, item, k)
        mesh = _object_mesh(rhino, item.Geometry, name, path)
        strings = dict(item.Attributes.GetUserStrings())
        fixed = item.Attributes.LayerIndex in on_frame
        if ours and "block" in strings:
            blocks.append((int(strings["block"]), mesh, _label(strings), fixed))
        else:
            label = item.Attributes.Name or str(item.Attributes.Id)
            blocks.append((k, mesh, f"{path.name}:{label}", fixed))
    blocks.sort(key=lambda block: block[0])
    expected = _marker_count(marker)
    if ours and expected is not None and expected != len(blocks):
        raise RhinoError(f"{path.name} announces {expected} blocks but holds {len(blocks)}; the file is cut short "
                         "or objects were deleted")
    stored = tuple(k for k, block in enumerate(blocks) if block[3]) if (on_frame or ours) else None
    info = restored(_info(_string(document, INFO_KEY))) if ours else {}
    info.update({"source": [str(path)], "format": "3dm"})
    return [b[1] for b in blocks], [b[2] for b in blocks], stored, info


def _rhino3dm():
    try:
        import rhino3dm
    except ImportError:
        raise RhinoError(MISSING_MESSAGE) from None
    return rhino3dm


def _add_layer(rhino, document, name: str, colour) -> int:
    layer = rhino.Layer()
    layer.Name = name
    layer.Color = tuple(int(c) for c in colour)
    return document.Layers.Add(layer)


def _block_strings(assembly, i: int, value: int, kind: str, world: trimesh.Trimesh) -> dict[str, str]:
    label = assembly.labels[i]
    label_type, text = label_text(label)
    strings = {"block": str(i), "label": text, "label_type": label_type, "class": str(value), "class_kind": kind,
               "fixed": str(i in assembly.frame).lower(), "mirrored": str(bool(assembly.mirrored[i])).lower(),
               "type": str(int(assembly.types[i])),
               "transform": ",".join(repr(v) for v in assembly.transforms[i].ravel().tolist()),
               "volume": repr(float(world.volume))}
    if isinstance(label, GroupElement):
        strings["element"] = str(label)
        strings["coset"] = str(GroupElement(label.linear, (0, 0)))
    elif isinstance(label, Lozenge):
        strings["orientation"] = str(label.orientation)
    return strings


def _write_atomically(document, path: Path, version: int):
    problem = unwritable(path, hint="ending in .3dm")
    if problem:
        raise RhinoError(f"cannot write {path}: {problem}")
    try:
        with atomic_write(path) as temporary:
            if not document.Write(str(temporary), int(version)):
                raise RhinoError(f"cannot write {path}: rhino3dm failed to write a version {version} file "
                                 "(versions 6, 7 and 8 are supported)")
    except OSError as error:
        raise RhinoError(f"cannot write {path}: {error.strerror or error}") from None


# --- reading ---------------------------------------------------------------------------------------

def _read_document(rhino, path: Path):
    if not path.is_file():
        raise RhinoError(f"3dm file {path} does not exist")
    if path.stat().st_size == 0:
        raise RhinoError(f"{path.name} is empty, not a Rhino .3dm file")
    document = rhino.File3dm.Read(str(path))
    if document is None:
        raise RhinoError(f"{path.name} is not a Rhino .3dm file that rhino3dm can read")
    return document


def _string(document, key: str) -> str:
    try:
        return document.Strings[key] or ""
    except (KeyError, IndexError, TypeError):
        return ""


def _marker_count(marker: str) -> int | None:
    for word in marker.split():
        if word.startswith("blocks="):
            try:
                return int(word[len("blocks="):])
            except ValueError:
                return None
    return None


def _info(text: str) -> dict:
    try:
        info = ast.literal_eval(text) if text else {}
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return {"info_text": text}
    return info if isinstance(info, dict) else {"info_text": text}


def _frame_layers(document, frame_layer: str) -> set[int]:
    """Indices of the layers named ``frame_layer`` and of their sublayers (any case)."""
    wanted = frame_layer.casefold()
    layers = [document.Layers[k] for k in range(len(document.Layers))]
    return {k for k, layer in enumerate(layers)
            if any(part.casefold() == wanted for part in (layer.FullPath or layer.Name or "").split("::"))}


def _object_name(document, item, k: int) -> str:
    attributes = item.Attributes
    layer = attributes.LayerIndex
    layer_name = document.Layers[layer].FullPath if 0 <= layer < len(document.Layers) else "?"
    name = f" {attributes.Name!r}" if attributes.Name else ""
    return f"object {k}{name} (id {attributes.Id}, layer {layer_name!r})"


def _object_mesh(rhino, geometry, name: str, path: Path) -> trimesh.Trimesh:
    """The object as a closed triangle mesh, or a one-line error naming it."""
    what = type(geometry).__name__
    if isinstance(geometry, rhino.Mesh):
        vertices, faces = _mesh_arrays(geometry)
    elif isinstance(geometry, rhino.Extrusion):
        cached = geometry.GetMesh(rhino.MeshType.Any)
        if cached is not None:
            vertices, faces = _mesh_arrays(cached)
        else:
            brep = geometry.ToBrep(True)
            if brep is None:
                raise RhinoError(f"{name} of {path.name}: an extrusion rhino3dm cannot turn into a polysurface")
            vertices, faces = _brep_arrays(rhino, brep, name, path)
    elif isinstance(geometry, rhino.Brep):
        vertices, faces = _brep_arrays(rhino, geometry, name, path)
    else:
        raise RhinoError(f"{name} of {path.name} is a {what}, not a closed solid; a block is a closed mesh or a "
                         "closed polysurface (delete the object or move it to another file)")
    if not len(faces):
        raise RhinoError(f"{name} of {path.name} is a {what} without faces, not a closed solid")
    vertices, faces = _closed_faces(vertices, faces, f"{name} of {path.name}", what)
    return trimesh.Trimesh(vertices, faces, process=False)


def _mesh_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    vertices = np.array([(p.X, p.Y, p.Z) for p in mesh.Vertices.ToPoint3dArray()], dtype=float).reshape(-1, 3)
    corners = np.array([mesh.Faces[k] for k in range(len(mesh.Faces))], dtype=np.int64).reshape(-1, 4)
    triangles = corners[corners[:, 2] == corners[:, 3], :3]
    quads = corners[corners[:, 2] != corners[:, 3]]
    if len(quads):
        cut, _ = triangulate_polygons(vertices, quads.ravel(), np.full(len(quads), 4))
        triangles = np.vstack([triangles, cut])
    return vertices, triangles


def _brep_arrays(rhino, brep, name: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of a polysurface: from its render meshes if saved, else from planar faces with straight edges."""
    where = f"{name} of {path.name}"
    faces = [brep.Faces[k] for k in range(len(brep.Faces))]
    if not brep.IsSolid:
        raise RhinoError(f"{where} is an open polysurface, not a closed solid; close it (Cap, Join) in Rhino")
    cached = [face.GetMesh(rhino.MeshType.Any) for face in faces]
    if all(mesh is not None for mesh in cached):
        parts = [_mesh_arrays(mesh) for mesh in cached]
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


def _closed_faces(vertices: np.ndarray, faces: np.ndarray, where: str, what: str) -> tuple[np.ndarray, np.ndarray]:
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


def _label(strings: dict[str, str]):
    """The label written by :func:`write_3dm`, rebuilt from its text."""
    return label_from_text(strings.get("label_type", "text"), strings.get("label", ""))
