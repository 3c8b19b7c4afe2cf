"""Rhino ``.3dm`` files through rhino3dm: one mesh object per block, layers by class, a ``frame`` layer.

What a designer drew comes back as it was: the model unit system (``assembly.unit``), the objects' names,
layers (with their colours) and user text, and the document's user text are read into ``Assembly.info``
(``names``, ``layers``, ``layer_colours``, ``user_text``, ``document_text``) and written back from there, so a
``.3dm`` -> ``.3dm`` conversion keeps them.  An assembly interlock made gets object names ``block_0007 <label>``
and a layer per class (``coset_1``, ...).  Rhino is +Z up.
"""

from __future__ import annotations

import ast
import json
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain, restored
from interlock.blocks.labels import label_from_text, label_text
from interlock.blocks.lozenge import Lozenge
from interlock.files import atomic_write, unwritable
from interlock.formats.common import PALETTE, class_name, classes
from interlock.formats.rhino_geometry import RhinoError, object_mesh
from interlock.formats.units import METRES
from interlock.wallpaper.elements import GroupElement

__all__ = ["write_3dm", "read_3dm", "read_3dm_blocks", "RhinoError", "FRAME_LAYER", "MARKER_KEY", "INFO_KEY",
           "MISSING_MESSAGE", "RHINO_VERSION", "LAYER_COLOURS", "DESIGNER_KEYS", "RHINO_UNITS"]

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
LAYER_COLOURS = tuple(tuple(int(c) for c in colour) for colour in PALETTE.tolist())
#: The keys of ``Assembly.info`` that hold what a designer drew in a ``.3dm`` file, one entry per block where a
#: list: object names, layer full paths, object user text (dicts); and the layer colours (by full path) and the
#: document user text (a dict).
DESIGNER_KEYS = ("names", "layers", "layer_colours", "user_text", "document_text")
#: Rhino's unit systems by name, in metres, for those interlock has no short name of (read in metres).
RHINO_UNITS = {"Angstroms": 1e-10, "Nanometers": 1e-9, "Microinches": 2.54e-8, "Mils": 2.54e-5,
               "Decimeters": 0.1, "Yards": 0.9144, "Dekameters": 10.0, "Hectometers": 100.0, "Kilometers": 1e3,
               "Miles": 1609.344, "NauticalMiles": 1852.0, "Megameters": 1e6, "Gigameters": 1e9}
_RHINO_NAMES = {"um": "Microns", "mm": "Millimeters", "cm": "Centimeters", "m": "Meters", "in": "Inches",
                "ft": "Feet"}
# the object user strings interlock writes
_OUR_STRINGS = ("block", "label", "label_type", "class", "class_kind", "fixed", "mirrored", "type", "transform",
                "volume", "element", "coset", "orientation")
_FRAME_COLOUR = (40, 40, 40, 255)


def write_3dm(assembly, path, *, classes=None, version: int = RHINO_VERSION, progress=None) -> Path:
    """Write an assembly to a Rhino ``.3dm`` file, one closed mesh object per block, in the assembly's unit.

    - The model unit system is ``assembly.unit`` (millimetres, metres, inches, ...; "None" for a model
      without unit).
    - Objects are named as the designer named them (``info["names"]``, read from a ``.3dm``), else
      ``block_0007 <label>`` (block index, then the label: a group element such as ``-y+1/2,x``, ...).
    - Objects are on the designer's layers (``info["layers"]``, full paths, with ``info["layer_colours"]``),
      else on a layer per class (``coset_0``, ``orientation_2``, :func:`~interlock.formats.common.class_name`);
      fixed blocks are on the layer :data:`FRAME_LAYER` (a designer's layer under it: ``frame::blocks``).
    - Object user strings: the designer's (``info["user_text"]``), then ``block``, ``label``, ``label_type``,
      ``class``, ``class_kind``, ``fixed``, ``mirrored``, ``type`` (mesh index), ``transform`` (16 numbers, row
      by row), ``volume``; for group elements also ``element`` and ``coset``, for lozenges ``orientation``.
    - Document user text: the designer's (``info["document_text"]``), :data:`MARKER_KEY`, :data:`INFO_KEY`
      and each other key of ``assembly.info`` (``group``, ``deformation``, ``seed``, ...) as JSON.

    Vertices are double precision, so reading gives back every block's world vertices bit for bit.  The file
    is written next to ``path`` under a temporary name and then moved into place.

    Parameters
    ----------
    assembly : Assembly
    path : str or path-like
        The file to write (any suffix; ``.3dm`` by convention).
    classes : (array of int, str), optional
        Each block's class and what classes mean; by default :func:`interlock.formats.common.classes`.
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
    >>> from interlock.blocks import presets
    >>> grid = presets.cube_grid()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     back = read_3dm(write_3dm(grid, Path(folder) / "grid.3dm"))
    >>> len(back), back.frame == grid.frame, back.info["preset"], back.labels[:3]
    (9, True, 'cube_grid', ((0, 0), (0, 1), (0, 2)))
    """
    rhino = _rhino3dm()
    path = Path(path)
    if not all(hasattr(assembly, name) for name in ("types", "transforms", "labels", "frame", "world_meshes")):
        raise RhinoError(f"write_3dm needs an Assembly (interlock.blocks.Assembly), got {type(assembly).__name__}")
    if not len(assembly):
        raise RhinoError(f"nothing to write to {path.name}: the assembly has no blocks")
    values, kind = _classes(assembly) if classes is None else classes
    values = np.asarray(values, dtype=int).reshape(-1)
    if len(values) != len(assembly):
        raise RhinoError(f"classes must give one class per block: got {len(values)} for {len(assembly)} blocks")
    document = rhino.File3dm()
    unit = assembly.unit
    document.Settings.ModelUnitSystem = getattr(rhino.UnitSystem, _RHINO_NAMES[unit] if unit else "None")
    names, paths = _per_block(assembly, "names", str), _per_block(assembly, "layers", str)
    user_text = _per_block(assembly, "user_text", dict)
    colours = assembly.info.get("layer_colours") if isinstance(assembly.info.get("layer_colours"), dict) else {}
    fixed = set(assembly.frame)
    layers = {}  # full path -> layer index

    def layer(full_path: str, colour) -> int:
        if full_path not in layers:
            parent, _, name = full_path.rpartition("::")
            made = rhino.Layer()
            made.Name = name
            stored = colours.get(full_path)
            made.Color = tuple(int(c) for c in (stored if _is_colour(stored) else colour))
            if parent:
                made.ParentLayerId = document.Layers[layer(parent, colour)].Id
            layers[full_path] = document.Layers.Add(made)
        return layers[full_path]

    if paths is None:  # a layer per class, in order, then the frame's
        for value in sorted(set(values.tolist())):
            layer(class_name(kind, value), LAYER_COLOURS[value % len(LAYER_COLOURS)])
        if fixed:
            layer(FRAME_LAYER, _FRAME_COLOUR)
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
        name = names[i] if names is not None else None
        attributes.Name = name if name is not None else f"block_{i:04d} {assembly.labels[i]}"
        colour = LAYER_COLOURS[int(values[i]) % len(LAYER_COLOURS)]
        own = paths[i] if paths is not None and paths[i] else class_name(kind, int(values[i]))
        framed = _on_frame_layer(own)
        if i in fixed and not framed:
            own = FRAME_LAYER if paths is None or not paths[i] else f"{FRAME_LAYER}::{own}"
        elif i not in fixed and framed:
            own = class_name(kind, int(values[i]))
        attributes.LayerIndex = layer(own, _FRAME_COLOUR if own == FRAME_LAYER else colour)
        designer = user_text[i] if user_text is not None and user_text[i] is not None else {}
        for key, value in designer.items():
            attributes.SetUserString(str(key), str(value))
        for key, value in _block_strings(assembly, i, int(values[i]), kind, world).items():
            if key not in designer:
                attributes.SetUserString(key, value)
        document.Objects.AddMesh(mesh, attributes)
    stored_text = assembly.info.get("document_text")
    for key, value in (stored_text.items() if isinstance(stored_text, dict) else ()):
        document.Strings[str(key)] = str(value)
    document.Strings[MARKER_KEY] = f"interlock blocks={len(assembly)} fixed={len(fixed)} classes={kind}"
    info = plain(assembly.info, json=False)
    document.Strings[INFO_KEY] = repr({k: v for k, v in info.items() if k not in DESIGNER_KEYS})
    for key, value in info.items():
        if isinstance(key, str) and key not in (MARKER_KEY, INFO_KEY, *DESIGNER_KEYS):
            document.Strings[key] = value if isinstance(value, str) else json.dumps(value, default=str)
    _write_atomically(document, path, version)
    return path


def read_3dm(path, frame=None, *, frame_layer: str = FRAME_LAYER, progress=None) -> Assembly:
    """An assembly from a Rhino ``.3dm`` file: every closed mesh or closed polysurface is a block.

    A file of :func:`write_3dm` comes back exactly: the blocks in their order with bit-identical vertices,
    their labels (group elements, lozenges, ...), the frame and ``info``.  A file drawn by a person gives one
    block per object, in file order, labelled ``<file name>:<object name>`` (else its id); the objects on the
    layer ``frame_layer`` (or a sublayer of it; any case) are the frame.  Its unit, object names, layers and
    user text go into ``assembly.unit`` and ``info`` (:data:`DESIGNER_KEYS`), which :func:`write_3dm` writes back.

    Objects may be meshes (vertices welded where they coincide), or polysurfaces and extrusions: those Rhino
    saved with render meshes are read through them; others with planar faces and straight edges (boxes,
    prisms, anything faceted) are cut into polygons here.  rhino3dm cannot mesh curved surfaces outside
    Rhino, so a curved polysurface saved without render meshes is an error saying so.

    Parameters
    ----------
    path : str or path-like
    frame : iterable of int, optional
        Indices of the fixed blocks, instead of the frame layer.
    frame_layer : str
        The name of the layer of fixed blocks.
    progress : callable, optional
        Called as ``progress(done, total)`` per object.

    Returns
    -------
    Assembly
        ``info`` holds the written ``info`` (for files of :func:`write_3dm`), ``source``, ``format``
        (``"3dm"``), ``frame_from`` (``"argument"``, ``"file"`` or ``"none"``), ``unit`` and
        :data:`DESIGNER_KEYS`.

    Raises
    ------
    RhinoError
        (one line) if rhino3dm is missing, the file is missing, empty or not a ``.3dm`` file, holds no
        objects, or an object is not a closed solid (the message names the object).

    Examples
    --------
    Two boxes drawn as a person would, in metres, the lower one on the ``frame`` layer:

    >>> import rhino3dm, tempfile
    >>> model = rhino3dm.File3dm()
    >>> model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Meters
    >>> def box(z, layer_name):
    ...     layer, attributes = rhino3dm.Layer(), rhino3dm.ObjectAttributes()
    ...     layer.Name = layer_name
    ...     attributes.LayerIndex = model.Layers.Add(layer)
    ...     corners = rhino3dm.BoundingBox(0, 0, z, 1, 1, z + 1)
    ...     return model.Objects.AddBrep(rhino3dm.Brep.CreateFromBox(rhino3dm.Box(corners)), attributes)
    >>> _, _ = box(0, "frame"), box(1, "blocks")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     _ = model.Write(str(Path(folder) / "stack.3dm"), 7)
    ...     stack = read_3dm(Path(folder) / "stack.3dm")
    >>> len(stack), stack.frame, stack.volumes.tolist(), stack.info["frame_from"], stack.unit, stack.info["layers"]
    (2, (0,), [1.0, 1.0], 'file', 'm', ['frame', 'blocks'])
    """
    meshes, labels, stored, info = read_3dm_blocks(path, frame_layer=frame_layer, progress=progress)
    info["frame_from"] = "argument" if frame is not None else "none" if stored is None else "file"
    return Assembly.from_meshes(meshes, frame=frame if frame is not None else stored or (), labels=labels, info=info)


def read_3dm_blocks(path, *, frame_layer: str = FRAME_LAYER,
                    progress=None) -> tuple[list[trimesh.Trimesh], list, tuple | None, dict]:
    """The blocks of a ``.3dm`` file: ``(meshes, labels, frame, info)``, as :func:`read_3dm` uses them.

    ``frame`` holds the indices of the blocks on the layer ``frame_layer`` (None when the file has no such
    layer and is not an interlock file).
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
    all_layers = [document.Layers[k] for k in range(len(document.Layers))]
    blocks = []  # (order key, mesh, label, fixed, name, layer path, user strings)
    for k, item in enumerate(objects):
        if progress is not None:
            progress(k, len(objects))
        name = _object_name(document, item, k)
        mesh = object_mesh(rhino, item.Geometry, name, path)
        strings = dict(item.Attributes.GetUserStrings())
        index = item.Attributes.LayerIndex
        layer_path = (all_layers[index].FullPath or all_layers[index].Name) if 0 <= index < len(all_layers) else ""
        fixed = index in on_frame
        designer = {key: value for key, value in strings.items() if not (ours and key in _OUR_STRINGS)}
        order = int(strings["block"]) if ours and strings.get("block", "").isdecimal() else k
        label = _label(strings) if ours and "block" in strings else \
            f"{path.name}:{item.Attributes.Name or item.Attributes.Id}"
        blocks.append((order, mesh, label, fixed, item.Attributes.Name or None, layer_path, designer))
    blocks.sort(key=lambda block: block[0])
    expected = _marker_count(marker)
    if ours and expected is not None and expected != len(blocks):
        raise RhinoError(f"{path.name} announces {expected} blocks but holds {len(blocks)}; the file is cut short "
                         "or objects were deleted")
    stored = tuple(k for k, block in enumerate(blocks) if block[3]) if (on_frame or ours) else None
    info = restored(_info(_string(document, INFO_KEY))) if ours else {}
    info.update({"source": [str(path)], "format": "3dm"})
    unit, factor = _unit(document)
    info.pop("unit", None)
    if unit is not None:
        info["unit"] = unit
    info["names"] = [b[4] for b in blocks]
    info["layers"] = [b[5] for b in blocks]
    info["layer_colours"] = {layer.FullPath or layer.Name: list(layer.Color) for layer in all_layers}
    if any(b[6] for b in blocks):
        info["user_text"] = [b[6] for b in blocks]
    ours_keys = set(restored(_info(_string(document, INFO_KEY)))) if ours else set()
    text = {key: value for key, value in _strings(document) if key not in (MARKER_KEY, INFO_KEY)
            and key not in ours_keys}
    if text:
        info["document_text"] = text
    meshes = [b[1] for b in blocks]
    if factor != 1.0:  # a unit interlock has no short name of: read in metres, every size kept
        meshes = [trimesh.Trimesh(np.asarray(m.vertices) * factor, m.faces, process=False) for m in meshes]
    return meshes, [b[2] for b in blocks], stored, info


def _classes(assembly):
    return classes(assembly)


def _per_block(assembly, key: str, kind):
    """``info[key]`` if it lists one entry (of type ``kind`` or None) per block, else None."""
    value = assembly.info.get(key)
    if isinstance(value, (list, tuple)) and len(value) == len(assembly) and all(
            v is None or isinstance(v, kind) for v in value):
        return list(value)
    return None


def _is_colour(value) -> bool:
    return isinstance(value, (list, tuple)) and len(value) in (3, 4) and all(
        isinstance(c, int) and 0 <= c <= 255 for c in value)


def _on_frame_layer(full_path: str) -> bool:
    return any(part.casefold() == FRAME_LAYER for part in full_path.split("::"))


def _unit(document) -> tuple[str | None, float]:
    """The model's unit (interlock's short name) and the factor that takes its coordinates there (1, or to
    metres for a unit without a short name); (None, 1) for none."""
    system = str(document.Settings.ModelUnitSystem).rpartition(".")[2]
    for short, name in _RHINO_NAMES.items():
        if name == system:
            return short, 1.0
    if system in RHINO_UNITS:
        return "m", RHINO_UNITS[system] / METRES["m"]
    return None, 1.0


def _strings(document) -> list[tuple[str, str]]:
    """The document user text as ``(key, value)`` pairs, in file order."""
    table = document.Strings
    return [tuple(table[k]) for k in range(len(table))]


def _rhino3dm():
    try:
        import rhino3dm
    except ImportError:
        raise RhinoError(MISSING_MESSAGE) from None
    return rhino3dm


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


def _label(strings: dict[str, str]):
    """The label written by :func:`write_3dm`, rebuilt from its text."""
    return label_from_text(strings.get("label_type", "text"), strings.get("label", ""))
