"""One way in and one way out: :func:`read` a file into an :class:`~interlock.blocks.Assembly`, :func:`write` one
to a file; the suffix picks the format's module (meshio's ``read`` and ``write``)."""

from __future__ import annotations

import contextlib
import importlib
import os
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.assembly import MAX_COORDINATE, Assembly
from interlock.blocks.info import restored
from interlock.files import unwritable
from interlock.formats.bodies import split_bodies
from interlock.formats.common import GLTF_TO_Z_UP, FormatError, MeshFile, as_assembly
from interlock.formats.scene import quiet_trimesh, read_scene
from interlock.formats.units import converted, turned, unit_name, up_axis

__all__ = ["read", "write", "read_mesh_file", "writable_target", "FORMATS", "READ_FORMATS", "LABELLED_FORMATS",
           "UP_CONVENTIONS",
           "MAX_COORDINATE"]

#: The formats :func:`write` writes, by suffix, and how each keeps the blocks apart, the frame and the unit
#: (``docs/formats.md`` says more).
FORMATS = {
    ".stl": "binary STL; block index in each triangle's attribute bytes, its top bit set for fixed blocks; "
            "'interlock blocks=N fixed=K unit=U up=A' in the header",
    ".obj": "Wavefront OBJ; one object per block, 'block_0007' or 'block_0007 fixed', its label in a comment; "
            "'# interlock blocks=N fixed=K triangles=T unit=U up=A' and the info as comments; class materials in "
            "a .mtl file beside it",
    ".ply": "binary PLY; one mesh, per-vertex block index, fixed flag and class colour (the layout meshio, "
            "plyfile and trimesh read); the header, labels and info as comments",
    ".glb": "binary glTF, +Y up and metres as glTF says; one node per block with extras (block, label, class, "
            "fixed), one mesh per block type and class; the header, labels and info in the scene extras",
    ".3mf": "3MF in the assembly's unit; one build item per block with metadata (block, label, class, fixed), "
            "one object per block type and class; the header, labels and info in the model metadata",
    ".vtu": "VTK unstructured grid; triangles with cell data block, class, mirrored, fixed; the header as an XML "
            "comment",
    ".xdmf": "XDMF with inline XML data; triangles with cell data block, class, mirrored, fixed; the header as an "
             "XML comment",
    ".3dm": "Rhino 3dm (rhino3dm, the 'rhino' extra) in the assembly's unit; one mesh object per block with the "
            "designer's names, layers and user text where read from a 3dm (else 'block_0007 <label>', a layer "
            "per class), a 'frame' layer, info as document user text",
    ".off": "OFF; one mesh whose blocks share no vertex (a block per set of faces sharing vertices); the header, the "
            "frame, labels and info as comments",
    ".json": "COMPAS assembly JSON (compas_assembly / compas_cra); one node per block with is_support from the "
             "frame, names and labels as node attributes, info (and the unit) as an assembly attribute",
}
#: The suffixes :func:`read` reads: those of :data:`FORMATS` and ``.gltf``; any other mesh format trimesh reads
#: is read too, one block per body.
READ_FORMATS = (*FORMATS, ".gltf")
#: The formats that keep the blocks' labels and ``Assembly.info``; the others keep the blocks, the frame and
#: the unit, and the labels come back as ``"<file name>:block_0007"``.
LABELLED_FORMATS = (".obj", ".ply", ".off", ".glb", ".3mf", ".3dm", ".json")
#: The up-axis of the formats that have a convention of their own; the others are written +Z up unless
#: ``up="y"`` is asked for, and say which in their header.
UP_CONVENTIONS = {".glb": "y", ".gltf": "y", ".3mf": "z", ".3dm": "z", ".json": "z"}
# the readers of mesh files, as (module of interlock.formats, function), imported by _format when a file of that
# format is read or written (reading an OBJ imports no Rhino, COMPAS, glTF or 3MF code); a suffix not here: every
# body of the trimesh scene (plain STL, plain PLY, OFF, ...)
_MESH_READERS = {".stl": ("stl", "read_stl"), ".ply": ("ply", "read_ply"), ".obj": ("obj", "read_obj"),
                 ".off": ("off", "read_off"), ".vtu": ("vtu", "read_vtu"), ".xdmf": ("vtu", "read_vtu"),
                 ".glb": ("gltf", "read_gltf"), ".gltf": ("gltf", "read_gltf"), ".3mf": ("threemf", "read_3mf")}
_WRITERS = {".stl": ("stl", "write_stl"), ".obj": ("obj", "write_obj"), ".ply": ("ply", "write_ply"),
            ".off": ("off", "write_off"), ".vtu": ("vtu", "write_vtu"), ".xdmf": ("vtu", "write_vtu")}


def _format(module: str, function: str):
    """``interlock.formats.<module>.<function>``, the module imported on first use."""
    return getattr(importlib.import_module(f"interlock.formats.{module}"), function)


def read(paths, frame=None, *, unit=None, up=None, progress=None) -> Assembly:
    """An assembly from a file (or from a list of files, one block each), in the format of its suffix.

    In one file the blocks are, in this order of preference: the stored block indices of interlock's files
    (STL, PLY, VTU, XDMF); the file's objects (OBJ ``o``, else ``g`` groups; GLB nodes; 3MF items; ``.3dm``
    objects; COMPAS nodes); for an OBJ file without objects the sets of faces that share vertex indices or the
    runs of ``v`` lines, if each is a closed surface; else its connected bodies.  A file that announces its
    blocks (``interlock blocks=N``) and holds fewer is cut short: an error.

    Parameters
    ----------
    paths : str, Path or sequence of them
    frame : iterable of int, optional
        Indices of the fixed blocks (for COMPAS JSON: node keys).  Default: the frame the file stores (STL
        attribute bits, PLY/VTU/XDMF ``fixed`` data, OBJ/GLB/3MF names ending in ``fixed``, the ``.3dm``
        ``frame`` layer, COMPAS ``is_support``); for a list of files, the blocks whose file marks them fixed.
    unit : str, optional
        The unit to read into (``"mm"``, ``"m"``, ``"in"``, ...): a file that states its unit is converted to
        it, every size kept; a file that states none is taken to be in it.  Default: the file's unit (None if
        it states none).
    up : {"z", "y"}, optional
        The up-axis of a file of a format without a convention of its own (OBJ, STL, PLY, OFF, VTU, XDMF):
        ``"y"`` turns it to interlock's +Z up.  Default: what the file's interlock header says, else ``"z"``.
    progress : callable, optional
        Called as ``progress(done, total)`` per block while a ``.3dm`` or ``.json`` file is read.

    Returns
    -------
    Assembly
        ``assembly.unit`` the unit; ``info["source"]`` the files; ``info["frame_from"]`` where the frame came
        from (``"argument"``, ``"file"``, ``"none"``, for COMPAS also ``"upstream examples"``).  Labels are
        those the file stores, else ``"<file name>:<object name>"``.

    Raises
    ------
    FormatError
        For a missing, unreadable or cut-short file, coordinates that are not finite or beyond
        :data:`MAX_COORDINATE`, a block that is not a closed surface, touching bodies in one plain STL or PLY
        file, or a frame index out of range.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import presets
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = read(write(presets.cube_grid(), Path(folder) / "grid.3mf", unit="mm"))
    >>> len(back), back.frame, back.unit
    (9, (0, 1, 2, 3, 5, 6, 7, 8), 'mm')
    """
    unit = unit_name(unit)
    if up is not None:
        up = up_axis(up)
    paths = _paths(paths)
    with _quiet():
        try:
            assembly = _read(paths, frame, up, progress)
        except RecursionError:
            raise FormatError(f"{paths} nests too deep to be read") from None
    return assembly if unit is None else converted(assembly, unit)


def write(obj, path, *, unit=None, up=None, progress=None) -> Path:
    """Write a block, a mesh or an assembly to a file whose blocks read back apart, in the format of its suffix.

    Every format carries the blocks in world coordinates, each outward-oriented (mirror images included), a
    way to tell them apart where they touch, the frame and the unit (:data:`FORMATS`; ``docs/formats.md``).
    Formats with colour colour the blocks by class.  Every file is written whole or not at all
    (:func:`interlock.files.atomic_write`).

    Parameters
    ----------
    obj : Block, Assembly or trimesh.Trimesh
    path : str or path-like
        The file; its suffix (any case) picks the format from :data:`FORMATS`.
    unit : str, optional
        The unit to write in: an assembly with a unit is converted to it (every size kept), one without is
        declared in it.  Default: the assembly's unit.
    up : {"z", "y"}, optional
        The up-axis of a format without a convention of its own (OBJ, STL, PLY, OFF, VTU, XDMF); default ``"z"``.
        ``"y"`` suits Blender's and three.js' importers; the header says so and reading turns it back.
    progress : callable, optional
        Called as ``progress(done, total)`` per block while a ``.3dm`` or ``.json`` file is written.

    Returns
    -------
    pathlib.Path
        The file written.  OBJ also writes the materials next to it (same stem, ``.mtl``).

    Raises
    ------
    FormatError
        For an unknown suffix, a folder or device as target, a folder that does not exist or cannot be
        written, an object that is not a block, mesh or assembly (or has no blocks), an unknown unit, or an
        up-axis against the format's convention.

    Examples
    --------
    >>> import tempfile
    >>> from interlock.blocks import presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = read(write(grid, Path(folder) / "grid.obj", up="y"))
    >>> bool(np.allclose(back.bounds, grid.bounds)), back.info["frame_from"]
    (True, 'file')
    """
    path = writable_target(path)
    suffix = path.suffix.lower()
    assembly = as_assembly(obj)
    if not len(assembly):
        raise FormatError(f"nothing to write to {path.name}: the assembly has no blocks")
    up = _file_up(suffix, up)
    if unit is not None:
        assembly = converted(assembly, unit)
    with _quiet():
        try:
            if suffix in _WRITERS:
                _format(*_WRITERS[suffix])(turned(assembly, up), path, up=up)
            elif suffix == ".glb":
                _format("gltf", "write_gltf")(assembly, path)
            elif suffix == ".3mf":
                _format("threemf", "write_3mf")(assembly, path)
            elif suffix == ".3dm":
                _format("rhino", "write_3dm")(assembly, path, progress=progress)
            else:
                _format("compas", "write_compas")(assembly, path, progress=progress)
        except OSError as error:
            raise FormatError(f"cannot write {path}: {error.strerror or error}") from None
        except ImportError as error:  # meshio writes XDMF only with h5py installed
            raise FormatError(f"writing {path.suffix} files needs the package {error.name}: "
                              f"pip install {error.name}") from None
    return path


def read_mesh_file(path, split: bool = True, up=None) -> MeshFile:
    """The blocks and the frame of one mesh file (not ``.3dm`` or COMPAS ``.json``), in file coordinates turned
    +Z up (:func:`read` builds the assembly from it).

    ``split``: split a file holding one body-less object into its connected bodies; without, the file is to be
    one block, so a file announcing several is refused.  Warnings of the readers are silenced: a file is
    read, or a :class:`FormatError` says in one line why not.

    Examples
    --------
    >>> import tempfile
    >>> def tetrahedron(name, x):
    ...     corners = "".join(f"v {x + a} {b} {c}\\n" for a, b, c in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)])
    ...     return f"o {name}\\n{corners}f -4 -2 -3\\nf -4 -3 -1\\nf -3 -2 -1\\nf -4 -1 -2\\n"
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "two.obj"
    ...     _ = path.write_text(tetrahedron("left", 0) + tetrahedron("right fixed", 2))
    ...     found = read_mesh_file(path)
    >>> found.names, found.frame, [round(float(m.volume), 6) for m in found.meshes]
    (('left', 'right'), (1,), [0.166667, 0.166667])
    """
    path = _mesh_path(path)
    with _quiet():
        return _mesh_file(path, split, up)


# --- reading ----------------------------------------------------------------------------------------
def _read(paths, frame, up, progress) -> Assembly:
    if isinstance(paths, Path):
        suffix = paths.suffix.lower()
        if suffix in (".3dm", ".json"):
            _mesh_path(paths)
            if up is not None and up != UP_CONVENTIONS[suffix]:
                raise FormatError(_convention(suffix, up))
            if suffix == ".3dm":
                assembly = _format("rhino", "read_3dm")(paths, frame, progress=progress)
            else:  # COMPAS; frame: node keys
                assembly = _format("compas", "load_compas")(paths, supports=None if frame is None else list(frame),
                                                            progress=progress)
                assembly.info["frame_from"] = assembly.info["supports_from"]
            _check_coordinates(paths, assembly.meshes)
            return assembly
        found = _mesh_file(_mesh_path(paths), True, up)
        labels = [found.labels.get(name, f"{paths.name}:{name}") for name in found.names]
        stored, sources, kept = found.frame, [str(paths)], restored(found.info or {})
        kept.pop("unit", None)
        kept.update(found.extra)
        if found.unit is not None:
            kept["unit"] = found.unit
        meshes = found.meshes
    else:
        if not paths:
            raise FormatError("no mesh files given; pass one path or a list of paths")
        files = [_mesh_file(_mesh_path(p), False, up) for p in paths]
        meshes = [trimesh.util.concatenate(list(f.meshes)) if len(f.meshes) > 1 else f.meshes[0] for f in files]
        labels, sources, kept = [p.name for p in paths], [str(p) for p in paths], {}
        units = {f.unit for f in files}
        if len(units) > 1:
            raise FormatError(f"the files state different units ({', '.join(sorted(map(str, units)))}); convert "
                              "them to one unit first (interlock convert --unit)")
        if units != {None}:
            kept["unit"] = units.pop()
        marked = [f.frame is not None for f in files]
        stored = tuple(k for k, f in enumerate(files) if f.frame) if any(marked) else None
    frame_from = "argument" if frame is not None else "none" if stored is None else "file"
    chosen = frame if frame is not None else stored or ()
    return Assembly.from_meshes(meshes, frame=chosen, labels=labels,
                                info={**kept, "source": sources, "frame_from": frame_from})


def _mesh_file(path: Path, split: bool, up) -> MeshFile:
    """The checked :class:`MeshFile` of ``path`` (:func:`read_mesh_file`)."""
    suffix = path.suffix.lower()
    if suffix in (".3dm", ".json"):
        raise FormatError(f"{path.name} is not a mesh file; read it with interlock.read")
    if up is not None and suffix in UP_CONVENTIONS and up != UP_CONVENTIONS[suffix] and suffix != ".3mf":
        raise FormatError(_convention(suffix, up))
    reader = _format(*_MESH_READERS[suffix]) if suffix in _MESH_READERS else None
    try:
        found = reader(path) if reader is not None else None
        if found is None:  # a plain STL or PLY file, OFF, another format trimesh reads
            found = read_scene(path)
    except FormatError:
        raise
    except RecursionError:
        raise FormatError(f"cannot read {path}: it nests too deep") from None
    except Exception as error:  # the readers raise many types for unreadable files
        raise FormatError(f"cannot read {path} as a mesh ({type(error).__name__}: {error})") from None
    if not found.meshes:
        raise FormatError(f"{path} holds no triangle mesh")
    _check_coordinates(path, found.meshes)
    if found.announced is not None and found.announced != len(found.meshes):
        raise FormatError(f"{path} is cut short or damaged: it announces {found.announced} blocks, "
                          f"it holds {len(found.meshes)}")
    if not split and len(found.meshes) > 1 and found.announced is not None:
        raise FormatError(f"{path} holds {len(found.meshes)} blocks, which would merge into one in a list of "
                          f"one file per block; load it on its own: interlock.read({str(path)!r})")
    if split and found.announced is None and len(found.meshes) == 1:
        found = split_bodies(path, found)
    turn = up if up is not None and suffix not in UP_CONVENTIONS else found.up
    if turn == "y":
        meshes = tuple(trimesh.Trimesh(trimesh.transform_points(m.vertices, GLTF_TO_Z_UP), m.faces, process=False)
                       for m in found.meshes)
        found = MeshFile(found.names, meshes, found.frame, found.announced, found.labels, found.info, found.unit,
                         found.extra)
    return found


def _check_coordinates(path: Path, meshes) -> None:
    """An error naming the first coordinate that is not finite or beyond :data:`MAX_COORDINATE`."""
    if not len(meshes):
        return
    every = np.vstack([np.asarray(mesh.vertices) for mesh in meshes])
    if np.isfinite(every).all() and not (np.abs(every) > MAX_COORDINATE).any():
        return
    for k, mesh in enumerate(meshes):
        vertices = np.asarray(mesh.vertices)
        bad = ~np.isfinite(vertices) | (np.abs(np.nan_to_num(vertices)) > MAX_COORDINATE)
        if bad.any():
            value = float(vertices[bad][0])
            what = "not a finite number" if not np.isfinite(value) else (
                f"beyond {MAX_COORDINATE:g}, where volumes and normals overflow double precision; scale the model "
                "down (interlock convert --scale, or another --unit)")
            where = f"block {k} of {path}" if len(meshes) > 1 else str(path)
            raise FormatError(f"{where} has a vertex coordinate {value:g} that is {what}")


def _mesh_path(path) -> Path:
    """``path`` as a Path to an existing regular file; a :class:`FormatError` that says what it is otherwise."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise FormatError(f"a file is given by its path (str or path-like), got {type(path).__name__}")
    path = Path(os.fsdecode(path))
    try:
        if path.is_symlink() and not path.exists():
            raise FormatError(f"{path} is a symbolic link that leads nowhere (to a missing file, or round a loop "
                              "of links); give the file itself")
        if path.is_dir():
            raise FormatError(f"{path} is a folder, not a mesh file; give the files in it, e.g. {path}/*.obj")
        if not path.exists():
            raise FormatError(f"file {path} does not exist")
        if not path.is_file():
            raise FormatError(f"{path} is not a regular file (a pipe, socket or device); save the assembly to a "
                              "file and give that")
        if path.stat().st_size == 0:
            raise FormatError(f"{path} is empty (0 bytes): it holds no mesh")
    except OSError as error:
        raise FormatError(f"cannot read {path}: {error.strerror or error}") from None
    return path


def _paths(paths):
    """One path (a Path), or a list of them; a :class:`FormatError` for anything else (None, 42, ...)."""
    if isinstance(paths, (str, os.PathLike)):
        return Path(paths)
    if isinstance(paths, Sequence) and not isinstance(paths, bytes) and all(
            isinstance(p, (str, os.PathLike)) for p in paths):
        return [Path(p) for p in paths]
    got = type(paths).__name__ if not isinstance(paths, Sequence) else f"a {type(paths).__name__} holding " + \
        ", ".join(sorted({type(p).__name__ for p in paths if not isinstance(p, (str, os.PathLike))}))
    raise FormatError(f"interlock.read needs a file path (str or Path) or a list of them, got {got}")


# --- writing ----------------------------------------------------------------------------------------
def writable_target(path) -> Path:
    """``path`` checked as a file :func:`write` can write: not a folder or device, a known suffix, in a folder that
    exists and is writable; a :class:`FormatError` saying what is wrong otherwise."""
    if not isinstance(path, (str, os.PathLike)):
        raise FormatError(f"path must be a file name or path, got {type(path).__name__}")
    path = Path(path)
    supported = ", ".join(FORMATS)
    suffix = path.suffix.lower()
    try:
        folder, device = path.is_dir(), path.exists() and not path.is_file()
    except OSError:
        folder = device = False
    if folder:
        raise FormatError(f"cannot write {path}: it is a folder; give a file name ending in one of {supported}")
    if device:
        raise FormatError(f"cannot write {path}: it is not a regular file (a device, pipe or socket); give a file "
                          f"name ending in one of {supported}")
    if suffix not in FORMATS:
        raise FormatError(f"cannot write {path}: unknown format {suffix or '(no suffix)'}; use one of {supported}")
    problem = unwritable(path, hint=f"ending in one of {supported}")
    if problem:
        raise FormatError(f"cannot write {path}: {problem}")
    return path


def _file_up(suffix: str, up) -> str:
    """The up-axis to write a file of ``suffix`` with: its convention, else ``up`` (default ``"z"``)."""
    if suffix in UP_CONVENTIONS:
        if up is not None and up_axis(up) != UP_CONVENTIONS[suffix]:
            raise FormatError(_convention(suffix, up_axis(up)))
        return "z"  # the writer turns the coordinates itself (glTF) or the format is +Z up
    return "z" if up is None else up_axis(up, suffix)


def _convention(suffix: str, up: str) -> str:
    free = ", ".join(s for s in READ_FORMATS if s not in UP_CONVENTIONS)
    return (f"{suffix} files are +{UP_CONVENTIONS[suffix].upper()} up by their format's convention, so up={up!r} "
            f"cannot be chosen for them; up='y' or 'z' is for {free}")


@contextlib.contextmanager
def _quiet():
    """numpy's, scipy's and trimesh's warnings and log messages kept off stderr: a file is read or written, or a
    :class:`FormatError` says in one line why not."""
    with warnings.catch_warnings(), np.errstate(all="ignore"), quiet_trimesh():
        warnings.simplefilter("ignore")
        yield

