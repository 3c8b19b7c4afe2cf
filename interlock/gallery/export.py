"""Files of assemblies that keep the blocks apart: STL, OBJ, PLY, GLB, 3MF, VTU, XDMF, Rhino 3dm and COMPAS JSON."""

from __future__ import annotations

import io
import json
import math
import zipfile
from xml.sax.saxutils import escape
from numbers import Real
from pathlib import Path

import meshio
import numpy as np
import trimesh
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

from interlock.blocks.assembly import Assembly
from interlock.blocks.compas import write_compas
from interlock.blocks.info import plain
from interlock.blocks.labels import label_text
from interlock.blocks.rhino import write_3dm
from interlock.blocks.meshformat import (BLOCK_DATA, FIXED_DATA, FIXED_WORD, GLTF_TO_Z_UP, INFO_KEY, LABELS_KEY,
                                        OBJ_INFO, OBJ_LABEL, OBJ_SECOND_LINE, STL_FIXED_BIT, STL_MAX_FRAMED,
                                        STL_RECORD, file_header)
from interlock.errors import GalleryError
from interlock.files import atomic_write, unwritable, write_atomically
from interlock.gallery import appearance

__all__ = ["export", "FORMATS", "LABELLED_FORMATS"]

#: The file formats :func:`export` writes, by suffix, and how each keeps the blocks apart and stores the frame.
FORMATS = {
    ".stl": "binary STL; block index in each triangle's attribute bytes, its top bit set for fixed blocks; "
            "'interlock blocks=N fixed=K' in the header",
    ".obj": "Wavefront OBJ; one object per block, 'block_0007' or 'block_0007 fixed', its label in a comment "
            "'# interlock label [kind, text]'; '# interlock blocks=N fixed=K triangles=T' and '# interlock info "
            "{...}'; class colours in a .mtl file beside it",
    ".ply": "binary PLY; one mesh, per-face 'block' index, 'fixed' flag and class colour; "
            "'comment interlock blocks=N fixed=K', the labels and the info as JSON comments",
    ".glb": "binary glTF, +Y up as glTF says (interlock's z is glTF's y); one node per block, 'block_0007' or "
            "'block_0007 fixed', one mesh per block type and class, class colours; 'interlock blocks=N fixed=K', "
            "the labels and the info in the scene extras",
    ".3mf": "3MF; one build item per block (part number 'block_0007' or 'block_0007 fixed'), one object per block "
            "type and class, class colours; 'interlock blocks=N fixed=K', the labels and the info in the model "
            "metadata",
    ".vtu": "VTK unstructured grid; triangles with cell data block, class, mirrored, fixed",
    ".xdmf": "XDMF with inline XML data; triangles with cell data block, class, mirrored, fixed",
    ".3dm": "Rhino 3dm (rhino3dm, the 'rhino' extra); one mesh object per block named 'block_0007 <label>', "
            "layers by class and a 'frame' layer, label, class and transform as user strings, info as document "
            "user text",
    ".json": "COMPAS assembly JSON (compas_assembly / compas_cra); one node per block with is_support from the "
             "frame, names and labels as node attributes, info as an assembly attribute",
}

#: The formats that keep the blocks' labels and ``Assembly.info`` (:mod:`interlock.blocks.labels`); the others
#: keep the blocks and the frame, and the labels come back as ``"<file name>:block_0007"``.
LABELLED_FORMATS = (".obj", ".ply", ".glb", ".3mf", ".3dm", ".json")

#: The most blocks an STL file can tell apart: block indices in the triangles' 2-byte attribute.  Up to
#: :data:`~interlock.blocks.meshfiles.STL_MAX_FRAMED` blocks the top bit of the attribute carries the
#: frame; beyond, the indices take all 16 bits and the file stores no frame.
STL_MAX_BLOCKS = np.iinfo(np.uint16).max
# Turns a mirror-image placement T into the proper one T @ _MIRROR of the mirrored mesh _MIRROR(mesh).
_MIRROR = np.diag([-1.0, 1.0, 1.0, 1.0])


def export(obj, path, exploded=0.0, progress=None) -> Path:
    """Write a block, a mesh or an assembly to a mesh file whose blocks load back apart.

    Every format carries the blocks in world coordinates, each outward-oriented
    (mirror-image blocks included), a way to tell them apart where they
    touch, and the frame (:data:`FORMATS` says where);
    :meth:`Assembly.load <interlock.blocks.Assembly.load>` reads each one
    back into the same blocks with the same frame.  Formats with colour
    colour the blocks by :func:`~interlock.gallery.appearance.block_classes`.
    GLB is written +Y up, as glTF specifies, so that viewers show interlock's
    +Z up as up: each node is placed by the inverse of
    :data:`~interlock.blocks.meshfiles.GLTF_TO_Z_UP`, which reading applies,
    so the coordinates read back are the same to the last bit.

    Parameters
    ----------
    obj : Block, Assembly or trimesh.Trimesh
        What to write (see :func:`~interlock.gallery.appearance.as_assembly`).
    path : str or path-like
        The file; its suffix (any case) picks the format from :data:`FORMATS`.
    exploded : float
        Move the blocks apart by this factor first
        (:func:`~interlock.gallery.appearance.exploded`); 0 keeps them in place.
    progress : callable, optional
        Called as ``progress(done, total)`` per block while a ``.3dm`` or ``.json``
        file is written (the slow formats; a progress bar).

    Returns
    -------
    pathlib.Path
        The file written.  OBJ also writes the materials next to it (same stem, ``.mtl``).

    Raises
    ------
    GalleryError
        For an unknown suffix, a folder that does not exist or cannot be
        written, an object that is not a block, mesh or assembly (or an
        assembly without blocks), or an ``exploded`` factor that is negative
        or not a number.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import Assembly, presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = export(grid, Path(folder) / "grid.stl")
    ...     back = Assembly.load(path)
    >>> path.name, len(back) == len(grid), bool(np.allclose(back.volumes, grid.volumes))
    ('grid.stl', True, True)
    >>> back.frame == grid.frame, back.info["frame_from"]
    (True, 'file')

    Notes
    -----
    Every file is written whole or not at all (:func:`interlock.files.atomic_write`): a
    temporary file beside the target, synced and then renamed over it, so an interrupted
    export leaves the old file (or none), never a part of the new one.

    World triangles come from one ``einsum`` per block type over all its
    blocks, so the cost is linear in the number of triangles: a 4,800-block
    RhomBlock assembly writes as STL in a fraction of a second.  GLB and 3MF
    share one mesh per block type and class (mirror images stored mirrored),
    placed by proper rigid motions, so viewers need no winding conventions
    for reflections.
    """
    path = _target(path)
    factor = _factor(exploded)
    assembly = appearance.exploded(appearance.as_assembly(obj), factor)
    if not len(assembly):
        raise GalleryError(f"nothing to write to {path.name}: the assembly has no blocks")
    try:
        if path.suffix.lower() in _WITH_PROGRESS:
            _WRITERS[path.suffix.lower()](assembly, path, progress=progress)
        else:
            _WRITERS[path.suffix.lower()](assembly, path)
    except OSError as error:
        raise GalleryError(f"cannot write {path}: {error.strerror or error}") from None
    except ImportError as error:  # meshio writes XDMF only with h5py installed
        raise GalleryError(f"writing {path.suffix} files needs the package {error.name}: "
                           f"pip install {error.name}") from None
    return path


# --- checks ----------------------------------------------------------------------
def _target(path) -> Path:
    try:
        path = Path(path)
    except TypeError:
        raise GalleryError(f"path must be a file name or path, got {type(path).__name__}") from None
    supported = ", ".join(FORMATS)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise GalleryError(f"cannot export to {path.name!r}: unknown format {suffix or '(no suffix)'}; "
                           f"use one of {supported}")
    problem = unwritable(path, hint=f"ending in one of {supported}")
    if problem:
        raise GalleryError(f"cannot write {path}: {problem}")
    return path


def _factor(exploded) -> float:
    if isinstance(exploded, bool) or not isinstance(exploded, Real) or not math.isfinite(exploded) or exploded < 0:
        raise GalleryError(f"exploded must be a finite number >= 0 (0 keeps the blocks in place), got {exploded!r}")
    return float(exploded)


# --- world triangles -----------------------------------------------------------
def _world(assembly: Assembly) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every block's vertices and outward faces in world coordinates, blocks in order.

    Returns ``vertices (V, 3)``, ``faces (F, 3)`` (indices into ``vertices``)
    and the offsets ``vertex_start (n + 1,)``, ``face_start (n + 1,)``: block
    ``i`` owns ``vertices[vertex_start[i]:vertex_start[i + 1]]`` and likewise faces.
    """
    n_vertices = np.array([len(m.vertices) for m in assembly.meshes], dtype=int)[assembly.types]
    n_faces = np.array([len(m.faces) for m in assembly.meshes], dtype=int)[assembly.types]
    vertex_start = np.concatenate([[0], np.cumsum(n_vertices)])
    face_start = np.concatenate([[0], np.cumsum(n_faces)])
    vertices = np.empty((vertex_start[-1], 3))
    faces = np.empty((face_start[-1], 3), dtype=np.int64)
    for t, mesh in enumerate(assembly.meshes):
        blocks = np.flatnonzero(assembly.types == t)
        if not blocks.size:
            continue
        placed = np.einsum("nij,vj->nvi", assembly.transforms[blocks, :3, :3], mesh.vertices)
        placed += assembly.transforms[blocks, None, :3, 3]
        vertices[vertex_start[blocks, None] + np.arange(len(mesh.vertices))] = placed
        own = mesh.faces[None] + vertex_start[blocks, None, None]
        mirrored = assembly.mirrored[blocks]
        own[mirrored] = own[mirrored][:, :, ::-1]  # a reflection turns the winding inside out
        faces[face_start[blocks, None] + np.arange(len(mesh.faces))] = own
    return vertices, faces, vertex_start, face_start


def _face_blocks(face_start: np.ndarray) -> np.ndarray:
    return np.repeat(np.arange(len(face_start) - 1), np.diff(face_start))


def _parts(assembly: Assembly) -> tuple[list[trimesh.Trimesh], np.ndarray, np.ndarray, np.ndarray]:
    """Shared meshes for instancing: one per block type, mirroring and class.

    Returns the part meshes (mirror images stored mirrored, outward), each
    part's RGBA colour, each block's part and each block's placement of its
    part, a proper rigid motion.
    """
    classes, _ = appearance.block_classes(assembly)
    colours = appearance.block_colours(assembly)
    mirrored = assembly.mirrored
    keys = np.column_stack([assembly.types, mirrored, classes])
    unique, first, part_of = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    meshes = [assembly.meshes[t].copy().apply_transform(_MIRROR) if m else assembly.meshes[t]
              for t, m, _ in unique]
    placements = assembly.transforms.copy()
    placements[mirrored] = placements[mirrored] @ _MIRROR
    return meshes, colours[first], part_of.ravel(), placements


def _block_name(i: int, fixed=()) -> str:
    """The name of block ``i`` in OBJ objects, GLB nodes and 3MF items: ``block_0007``, ``block_0007 fixed``."""
    return f"block_{i:04d} {FIXED_WORD}" if i in fixed else f"block_{i:04d}"


def _fixed(assembly: Assembly) -> np.ndarray:
    """Whether each block is in the frame."""
    fixed = np.zeros(len(assembly), dtype=bool)
    fixed[list(assembly.frame)] = True
    return fixed


def _header(assembly: Assembly, triangles: int | None = None) -> str:
    return file_header(len(assembly), len(assembly.frame), triangles)


def _labels(assembly: Assembly) -> dict[str, list[str]]:
    """``{block name: [kind, text]}`` (:func:`~interlock.blocks.labels.label_text`), the names without ``fixed``."""
    return {_block_name(i): list(label_text(label)) for i, label in enumerate(assembly.labels)}


def _json(value) -> str:
    """``value`` as one line of JSON (``Assembly.info`` through :func:`~interlock.blocks.info.plain`)."""
    return json.dumps(value, allow_nan=False, separators=(",", ":"))


# --- writers -------------------------------------------------------------------
def _write_stl(assembly: Assembly, path: Path):
    vertices, faces, _, face_start = _world(assembly)
    records = np.zeros(len(faces), dtype=STL_RECORD)
    triangles = vertices[faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    records["normal"] = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    records["vertices"] = triangles
    blocks = _face_blocks(face_start)
    if len(assembly) <= STL_MAX_FRAMED:
        records["block"] = blocks | np.where(_fixed(assembly)[blocks], STL_FIXED_BIT, 0)
        header = _header(assembly).encode()
    elif len(assembly) <= STL_MAX_BLOCKS:  # the block indices take every bit: no frame
        records["block"] = blocks
        header = file_header(len(assembly)).encode()
    else:
        header = b"interlock: too many blocks to index in the triangle attributes"
    with atomic_write(path) as temporary, open(temporary, "wb") as file:
        file.write(header.ljust(80, b" ")[:80])
        file.write(np.uint32(len(records)).tobytes())
        file.write(records.tobytes())


def _write_obj(assembly: Assembly, path: Path):
    vertices, faces, vertex_start, face_start = _world(assembly)
    classes, kind = appearance.block_classes(assembly)
    colours = appearance.block_colours(assembly)
    materials = path.with_suffix(".mtl")
    write_atomically(materials, "".join(
        f"newmtl class_{c}\nKd {rgba[0]:.6f} {rgba[1]:.6f} {rgba[2]:.6f}\nd {rgba[3]:.6f}\n\n"
        for c, rgba in ((c, colours[np.argmax(classes == c)] / 255) for c in np.unique(classes))))
    frame = set(assembly.frame)
    with atomic_write(path) as temporary, open(temporary, "w") as file:
        file.write(f"# {_header(assembly, len(faces))}\n")
        file.write(f"{OBJ_SECOND_LINE}; materials by {kind}\n")
        file.write(f"{OBJ_INFO}{_json(plain(assembly.info))}\n")
        file.write(f"mtllib {materials.name}\n")
        labels = _labels(assembly)
        for i in range(len(assembly)):
            block_vertices = vertices[vertex_start[i]:vertex_start[i + 1]]
            block_faces = faces[face_start[i]:face_start[i + 1]] + 1
            file.write(f"o {_block_name(i, frame)}\n{OBJ_LABEL}{_json(labels[_block_name(i)])}\n"
                       f"usemtl class_{classes[i]}\n")
            file.write("v %r %r %r\n" * len(block_vertices) % tuple(block_vertices.ravel().tolist()))
            file.write("f %d %d %d\n" * len(block_faces) % tuple(block_faces.ravel().tolist()))


def _write_ply(assembly: Assembly, path: Path):
    vertices, faces, _, face_start = _world(assembly)
    blocks = _face_blocks(face_start)
    colours = appearance.block_colours(assembly)[blocks]
    face_records = np.zeros(len(faces), dtype=[("count", "u1"), ("vertex_indices", "<i4", 3), (BLOCK_DATA, "<i4"),
                                               (FIXED_DATA, "u1"), ("red", "u1"), ("green", "u1"), ("blue", "u1"),
                                               ("alpha", "u1")])
    face_records["count"] = 3
    face_records["vertex_indices"] = faces
    face_records[BLOCK_DATA] = blocks
    face_records[FIXED_DATA] = _fixed(assembly)[blocks]
    for k, channel in enumerate(("red", "green", "blue", "alpha")):
        face_records[channel] = colours[:, k]
    header = "\n".join([
        "ply", "format binary_little_endian 1.0", f"comment {_header(assembly)}",
        f"comment {LABELS_KEY} {_json(_labels(assembly))}", f"comment {INFO_KEY} {_json(plain(assembly.info))}",
        f"element vertex {len(vertices)}", "property double x", "property double y", "property double z",
        f"element face {len(faces)}", "property list uchar int vertex_indices", f"property int {BLOCK_DATA}",
        f"property uchar {FIXED_DATA}",
        "property uchar red", "property uchar green", "property uchar blue", "property uchar alpha",
        "end_header", ""])
    with atomic_write(path) as temporary, open(temporary, "wb") as file:
        file.write(header.encode("ascii"))
        file.write(vertices.astype("<f8").tobytes())
        file.write(face_records.tobytes())


def _write_glb(assembly: Assembly, path: Path):
    meshes, colours, part_of, placements = _parts(assembly)
    placements = GLTF_TO_Z_UP.T @ placements  # +Z up to glTF's +Y up; exact, read back by GLTF_TO_Z_UP
    scene = trimesh.Scene()
    for k, (mesh, rgba) in enumerate(zip(meshes, colours)):
        part = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
        part.visual = TextureVisuals(material=PBRMaterial(name=f"part_{k}", baseColorFactor=rgba,
                                                          metallicFactor=0.0, roughnessFactor=0.8))
        scene.geometry[f"part_{k}"] = part
    frame = set(assembly.frame)
    for i, (k, placement) in enumerate(zip(part_of, placements)):
        scene.graph.update(frame_from=scene.graph.base_frame, frame_to=_block_name(i, frame), matrix=placement,
                           geometry=f"part_{k}")
    scene.metadata["interlock"] = _header(assembly)  # the scene's extras
    scene.metadata[LABELS_KEY] = _labels(assembly)
    scene.metadata[INFO_KEY] = plain(assembly.info)
    write_atomically(path, scene.export(file_type="glb"))


def _write_3mf(assembly: Assembly, path: Path):
    meshes, colours, part_of, placements = _parts(assembly)
    model = io.StringIO()
    model.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                '<model unit="millimeter" xml:lang="en-US" '
                'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
                f'xmlns:interlock="{_3MF_NAMESPACE}">\n'
                f'<metadata name="interlock:header">{_header(assembly)}</metadata>\n'
                f'<metadata name="interlock:{LABELS_KEY}">{escape(_json(_labels(assembly)))}</metadata>\n'
                f'<metadata name="interlock:{INFO_KEY}">{escape(_json(plain(assembly.info)))}</metadata>\n'
                '<resources>\n<basematerials id="1">\n')
    for k, rgba in enumerate(colours):
        model.write(f'<base name="part_{k}" displaycolor="#{bytes(rgba.tolist()).hex().upper()}"/>\n')
    model.write("</basematerials>\n")
    for k, mesh in enumerate(meshes):
        model.write(f'<object id="{k + 2}" type="model" name="part_{k}" pid="1" pindex="{k}">\n<mesh>\n<vertices>\n')
        model.write('<vertex x="%r" y="%r" z="%r"/>\n' * len(mesh.vertices) % tuple(mesh.vertices.ravel().tolist()))
        model.write("</vertices>\n<triangles>\n")
        model.write('<triangle v1="%d" v2="%d" v3="%d"/>\n' * len(mesh.faces) % tuple(mesh.faces.ravel().tolist()))
        model.write("</triangles>\n</mesh>\n</object>\n")
    model.write("</resources>\n<build>\n")
    frame = set(assembly.frame)
    for i, (k, placement) in enumerate(zip(part_of, placements)):
        # 3MF multiplies row vectors: the 4x3 matrix is the transpose of the top 3x4 of ours
        transform = " ".join(map(repr, placement[:3, :4].T.ravel().tolist()))
        model.write(f'<item objectid="{k + 2}" transform="{transform}" partnumber="{_block_name(i, frame)}"/>\n')
    model.write("</build>\n</model>\n")
    with atomic_write(path) as temporary, zipfile.ZipFile(temporary, "w", compression=zipfile.ZIP_DEFLATED) as package:
        package.writestr("[Content_Types].xml", _3MF_CONTENT_TYPES)
        package.writestr("_rels/.rels", _3MF_RELATIONSHIPS)
        package.writestr("3D/3dmodel.model", model.getvalue())


# Custom 3MF metadata names need a namespace of their own.
_3MF_NAMESPACE = "urn:interlock:3mf"
_3MF_CONTENT_TYPES = """<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"""
_3MF_RELATIONSHIPS = """<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
<Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"""


def _write_meshio(assembly: Assembly, path: Path):
    vertices, faces, _, face_start = _world(assembly)
    blocks = _face_blocks(face_start)
    classes, _ = appearance.block_classes(assembly)
    cell_data = {BLOCK_DATA: [blocks], "class": [classes[blocks].astype(np.int64)],
                 "mirrored": [assembly.mirrored[blocks].astype(np.int64)],
                 FIXED_DATA: [_fixed(assembly)[blocks].astype(np.int64)]}
    mesh = meshio.Mesh(vertices, [("triangle", faces)], cell_data=cell_data)
    with atomic_write(path) as temporary:
        if path.suffix.lower() == ".xdmf":
            meshio.write(temporary, mesh, file_format="xdmf", data_format="XML")
        else:
            meshio.write(temporary, mesh, file_format="vtu")


def _write_3dm(assembly: Assembly, path: Path, progress=None):
    write_3dm(assembly, path, classes=appearance.block_classes(assembly), progress=progress)


def _write_compas(assembly: Assembly, path: Path, progress=None):
    write_compas(assembly, path, progress=progress)


#: Formats slow enough to report progress per block.
_WITH_PROGRESS = (".3dm", ".json")
_WRITERS = {".stl": _write_stl, ".obj": _write_obj, ".ply": _write_ply, ".glb": _write_glb, ".3mf": _write_3mf,
            ".vtu": _write_meshio, ".xdmf": _write_meshio, ".3dm": _write_3dm, ".json": _write_compas}
