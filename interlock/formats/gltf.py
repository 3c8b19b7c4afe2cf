"""glTF 2.0 (``.glb``): one node per block, one mesh per block type and class, +Y up and metres as glTF says.

Writing: each node is named ``block_0007`` (``block_0007 fixed`` in the frame) and its ``extras`` hold
``block`` (the index), ``label``, ``label_type``, ``class``, ``fixed`` and, where the assembly has them, the
designer's ``name`` and ``layer`` (three.js puts extras in ``userData``, Blender in custom properties).  The
scene extras hold the header (``interlock blocks=N fixed=K unit=...``), the labels and ``Assembly.info``.
Coordinates are metres: an assembly in another unit is converted on writing and back on reading (the header
says which); one without unit is written as it is (1 unit = 1 m).  Materials are named by class
(:func:`~interlock.formats.common.class_name`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain
from interlock.blocks.labels import label_text
from interlock.files import write_atomically
from interlock.formats.common import (GLTF_TO_Z_UP, INFO_KEY, LABELS_KEY, PALETTE, MeshFile, block_name, class_name,
                                      classes, file_header, header_words, instanced_parts, label_pairs,
                                      stored_meaning)
from interlock.formats.scene import quiet_trimesh, read_scene
from interlock.formats.units import METRES, scaled, with_unit

__all__ = ["read_gltf", "write_gltf", "GLTF_UNIT"]

#: The unit of glTF coordinates (glTF 2.0, section 3.4: "the units for all linear distances are meters").
GLTF_UNIT = "m"


def read_gltf(path: Path) -> MeshFile:
    """The blocks of a glTF file, turned +Z up; in the unit its interlock header states (converted from
    metres), else in metres."""
    with quiet_trimesh():
        scene = trimesh.load_scene(path)
    metadata = scene.metadata if isinstance(scene.metadata, dict) else {}
    header = metadata.get("interlock") if isinstance(metadata.get("interlock"), str) else None
    found = read_scene(path, GLTF_TO_Z_UP, header, stored_meaning(metadata), GLTF_UNIT, scene)
    stated = header_words(header).get("unit") if header else GLTF_UNIT
    if header and stated is None:  # an assembly without unit, written as it was
        return _with(found, None)
    if stated in METRES and stated != GLTF_UNIT and found.meshes:
        factor = METRES[GLTF_UNIT] / METRES[stated]
        meshes = tuple(trimesh.Trimesh(np.asarray(m.vertices) * factor, m.faces, process=False) for m in found.meshes)
        return MeshFile(found.names, meshes, found.frame, found.announced, found.labels, found.info, stated)
    return found


def write_gltf(assembly: Assembly, path: Path) -> None:
    """A binary glTF (GLB): shared meshes per block type and class, one node per block, +Y up, metres."""
    unit = assembly.unit
    if unit is not None and unit != GLTF_UNIT:
        assembly = with_unit(scaled(assembly, METRES[unit] / METRES[GLTF_UNIT]), unit)
    meshes, part_classes, part_of, placements = instanced_parts(assembly)
    values, kind = classes(assembly)
    placements = GLTF_TO_Z_UP.T @ placements  # +Z up to glTF's +Y up; exact, read back by GLTF_TO_Z_UP
    scene = trimesh.Scene()
    for k, (mesh, value) in enumerate(zip(meshes, part_classes.tolist())):
        part = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
        part.visual = TextureVisuals(material=PBRMaterial(
            name=class_name(kind, value), baseColorFactor=PALETTE[value % len(PALETTE)], metallicFactor=0.0,
            roughnessFactor=0.8))
        scene.geometry[f"part_{k}"] = part
    frame = set(assembly.frame)
    extras = {}
    names, layers = _designer(assembly, "names"), _designer(assembly, "layers")
    for i, (k, placement) in enumerate(zip(part_of, placements)):
        node = block_name(i, frame)
        scene.graph.update(frame_from=scene.graph.base_frame, frame_to=node, matrix=placement, geometry=f"part_{k}")
        label_type, label = label_text(assembly.labels[i])
        extras[node] = {"block": i, "label": label, "label_type": label_type, "class": int(values[i]),
                        "class_kind": kind, "fixed": i in frame}
        if names is not None and isinstance(names[i], str):
            extras[node]["name"] = names[i]
        if layers is not None and isinstance(layers[i], str):
            extras[node]["layer"] = layers[i]
    scene.metadata["interlock"] = file_header(len(assembly), len(frame), unit=unit)  # the scene's extras
    scene.metadata[LABELS_KEY] = label_pairs(assembly)
    scene.metadata[INFO_KEY] = plain(assembly.info)

    def node_extras(tree):
        for node in tree.get("nodes", []):
            if node.get("name") in extras:
                node["extras"] = extras[node["name"]]

    write_atomically(path, trimesh.exchange.gltf.export_glb(scene, tree_postprocessor=node_extras))


def _designer(assembly: Assembly, key: str):
    """``info[key]`` if it lists one entry per block (names and layers read from a ``.3dm`` file), else None."""
    value = assembly.info.get(key)
    return value if isinstance(value, (list, tuple)) and len(value) == len(assembly) else None


def _with(found: MeshFile, unit) -> MeshFile:
    return MeshFile(found.names, found.meshes, found.frame, found.announced, found.labels, found.info, unit)
