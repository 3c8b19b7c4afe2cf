"""The files interlock writes and reads back: their markers and names, and :class:`MeshFile`, what a reader finds.

:func:`~interlock.gallery.export.export` writes these markers and
:mod:`~interlock.blocks.meshfiles` (STL, PLY, VTU, XDMF, GLB, 3MF) and
:mod:`~interlock.blocks.objfile` (OBJ) read them: the header that announces
the blocks (:func:`file_header`, so a file cut short is found), the per-triangle
block index and frame flag, the ``fixed`` word of object names, where labels
and ``Assembly.info`` are kept, and glTF's +Y up.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from interlock.blocks.labels import label_from_text
from interlock.errors import AssemblyError

__all__ = ["MeshFile", "file_header", "header_counts", "flagged_name", "named_frame", "touching_bodies", "json_value",
           "is_label_pair", "stored_meaning", "HEADER_MARKER", "STL_RECORD", "BLOCK_DATA", "FIXED_DATA", "FIXED_WORD",
           "STL_FIXED_BIT", "STL_MAX_FRAMED", "OBJ_SECOND_LINE", "OBJ_LABEL", "OBJ_INFO", "LABELS_KEY", "INFO_KEY",
           "GLTF_TO_Z_UP", "GLTF_SUFFIXES"]

#: How an exported file says that it holds interlock blocks, and how many: the start of a binary STL's
#: 80-byte header, a PLY or OBJ comment, GLB scene extras, 3MF model metadata (see :func:`file_header`).
HEADER_MARKER = b"interlock blocks="
#: One triangle of a binary STL: normal, three vertices, and the 2-byte attribute holding the block index.
STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("block", "<u2")])
#: Name of the per-triangle block index in PLY (face property), VTU and XDMF (cell data) files.
BLOCK_DATA = "block"
#: Name of the per-triangle frame flag (1: the triangle's block is fixed) in PLY, VTU and XDMF files.
FIXED_DATA = "fixed"
#: The last word of the name of a fixed block's object (OBJ ``o block_0007 fixed``), node (GLB) or item (3MF).
FIXED_WORD = "fixed"
#: In a binary STL whose header counts the fixed blocks (``fixed=K``), this bit of each triangle's attribute
#: marks the triangles of fixed blocks, and the 15 bits below it hold the block index.
STL_FIXED_BIT = 1 << 15
#: The most blocks a binary STL stores with their frame: block indices below :data:`STL_FIXED_BIT`.
STL_MAX_FRAMED = STL_FIXED_BIT

#: How the second line of an OBJ export starts (after its :func:`file_header`): a file with it and without a
#: readable header is damaged.
OBJ_SECOND_LINE = "# one object per block, named 'fixed' in the frame"
#: OBJ comment lines of :func:`~interlock.gallery.export.export`: after an ``o`` line, the block's label as the
#: JSON pair ``[kind, text]`` of :func:`~interlock.blocks.labels.label_text`; in the header, ``Assembly.info``
#: as JSON (:func:`~interlock.blocks.info.plain`).
OBJ_LABEL, OBJ_INFO = "# interlock label ", "# interlock info "
#: GLB scene extras, 3MF model metadata and PLY comments of :func:`~interlock.gallery.export.export`: the
#: labels, as ``{block name: [kind, text]}``, and ``Assembly.info`` as JSON.
LABELS_KEY, INFO_KEY = "interlock_labels", "interlock_info"
#: glTF 2.0 says +Y is up; interlock's gravity is along -Z.  This rotation turns glTF coordinates into
#: interlock's, ``(x, y, z) -> (x, -z, y)``: reading applies it to every node, writing its inverse (transpose),
#: so a file written and read back has the same coordinates to the last bit (the entries are 0 and +-1).
GLTF_TO_Z_UP = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
#: The suffixes of glTF files, read and written +Y up (:data:`GLTF_TO_Z_UP`).
GLTF_SUFFIXES = (".glb", ".gltf")
_HEADER = re.compile(re.escape(HEADER_MARKER.decode()) + r"(\d+)(?: fixed=(\d+))?(?: triangles=(\d+))?")


def file_header(blocks: int, fixed: int | None = None, triangles: int | None = None) -> str:
    """The text by which an exported file announces its blocks, fixed blocks and (OBJ) triangles.

    Loading checks a file against it: a file with fewer blocks or triangles
    than announced is cut short.

    Examples
    --------
    >>> file_header(27, 3)
    'interlock blocks=27 fixed=3'
    >>> header_counts(file_header(27, 3, triangles=972))
    (27, 3, 972)
    """
    text = HEADER_MARKER.decode() + str(blocks)
    if fixed is not None:
        text += f" fixed={fixed}"
    if triangles is not None:
        text += f" triangles={triangles}"
    return text


@dataclass(frozen=True)
class MeshFile:
    """The blocks of a mesh file: names and meshes (file coordinates) in file order, and the stored frame.

    ``frame`` lists the indices of the blocks that the file marks fixed, or is
    None when the file stores no frame.  ``announced`` is the number of
    blocks that the file says it holds (its :func:`file_header`, or its
    block indices), or None if it does not say.  ``labels`` maps block names
    to the labels the file stores for them (OBJ, GLB and 3MF files of
    :func:`~interlock.gallery.export.export`; :mod:`~interlock.blocks.labels`),
    and ``info`` is the ``Assembly.info`` it stores (plain values), or None.
    """

    names: tuple[str, ...]
    meshes: tuple[trimesh.Trimesh, ...]
    frame: tuple[int, ...] | None = None
    announced: int | None = None
    labels: dict = field(default_factory=dict)
    info: dict | None = None


def header_counts(text) -> tuple[int, int | None, int | None] | None:
    """(blocks, fixed, triangles) from a :func:`file_header` in ``text``; None without one."""
    if isinstance(text, bytes):
        text = text.decode("ascii", errors="replace")
    match = _HEADER.search(text or "")
    if match is None:
        return None
    return tuple(None if group is None else int(group) for group in match.groups())


def flagged_name(name: str) -> tuple[str, bool]:
    """``'block_0007 fixed'`` -> ``('block_0007', True)``; other names unchanged."""
    stem, _, last = name.strip().rpartition(" ")
    return (stem.rstrip(), True) if stem and last.lower() == FIXED_WORD else (name.strip(), False)


def named_frame(path: Path, fixed, header) -> tuple[int, ...] | None:
    """The blocks whose names end in :data:`FIXED_WORD` (``fixed``: a flag per block); None if none does and
    the file has no header (``header``: what :func:`header_counts` found, or None)."""
    frame = tuple(k for k, flag in enumerate(fixed) if flag)
    if header is not None and header[1] is not None and header[1] != len(frame):
        raise AssemblyError(f"{path} is cut short or damaged: it announces {header[1]} fixed blocks, its "
                            f"names mark {len(frame)}")
    return frame if frame or header is not None else None


def touching_bodies(path: Path) -> str:
    """The error for bodies that touch in a file that cannot tell them apart."""
    if path.suffix.lower() == ".obj":
        return (f"{path} holds several bodies that touch and share vertices (welded), which an OBJ file without "
                "objects cannot separate; give each block its own object ('o') or group ('g'), or export with "
                "vertices not welded (merged) across blocks")
    return (f"{path} holds several bodies that touch, which a single {path.suffix} file cannot separate; give one "
            "file per block, or an OBJ file with one object ('o') or group ('g') per block")


def json_value(text):
    """The value of a JSON text; None for one that is not JSON."""
    try:
        return json.loads(text or "")
    except ValueError:
        return None


def stored_meaning(stored: dict) -> tuple[dict, dict | None]:
    """``({block name: label}, info)`` from what a GLB, 3MF or PLY file stores under :data:`LABELS_KEY` (a
    ``{block name: [kind, text]}`` dict) and :data:`INFO_KEY` (a dict).  What is not as
    :func:`~interlock.gallery.export.export` writes it (a file edited by hand) is left out: a pair that is not
    one, a value that is not a dict."""
    pairs, info = stored.get(LABELS_KEY), stored.get(INFO_KEY)
    labels = {name: label_from_text(*pair) for name, pair in pairs.items() if is_label_pair(pair)} \
        if isinstance(pairs, dict) else {}
    return labels, info if isinstance(info, dict) else None


def is_label_pair(value) -> bool:
    """Whether ``value`` is a ``[kind, text]`` pair of :func:`~interlock.blocks.labels.label_text`."""
    return isinstance(value, list) and len(value) == 2 and all(isinstance(v, str) for v in value)
