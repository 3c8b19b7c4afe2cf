"""3MF: one build item per block, one object per block type and class, in the assembly's unit.

The model's ``unit`` is the assembly's (micron, millimeter, centimeter, inch, foot, meter); an assembly without
unit is written in metres, as glTF is, so a model is the same size in every file (the header says it had none).
Each item's part number is ``block_0007`` (``block_0007 fixed`` in the frame) and its metadata group holds
``interlock:block``, ``interlock:label`` and ``interlock:fixed``; the model metadata hold the header, the labels
and ``Assembly.info``.  Materials (base materials) are named by class.  3MF is +Z up (the build platform).
"""

from __future__ import annotations

import io
import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree
from xml.sax.saxutils import escape

from interlock.blocks.assembly import Assembly
from interlock.blocks.info import plain
from interlock.blocks.labels import label_text
from interlock.files import atomic_write
from interlock.formats.common import (INFO_KEY, LABELS_KEY, PALETTE, FormatError, MeshFile, block_name, class_name,
                                      classes, file_header, header_counts, header_words, instanced_parts, json_value,
                                      label_pairs, one_line_json, stored_meaning)
from interlock.formats.scene import read_scene
from interlock.formats.units import unit_name

__all__ = ["read_3mf", "write_3mf", "THREEMF_UNITS"]

#: 3MF's names of the units (the ``unit`` attribute of ``<model>``; 3MF core specification, 3.4).
THREEMF_UNITS = {"um": "micron", "mm": "millimeter", "cm": "centimeter", "in": "inch", "ft": "foot", "m": "meter"}
# Custom 3MF metadata names need a namespace of their own.
_NAMESPACE = "urn:interlock:3mf"


def read_3mf(path: Path) -> MeshFile:
    """The blocks of a 3MF file (its build items), in the unit the model states (millimetres if none, as 3MF
    says); an error naming an item whose object the model does not define."""
    header, stored, unit = None, {}, "mm"
    with zipfile.ZipFile(path) as package:
        for name in (n for n in package.namelist() if n.lower().endswith(".model")):
            for event, element in ElementTree.iterparse(package.open(name), events=("start", "end")):
                tag = element.tag.rpartition("}")[2]
                if event == "start" and tag == "model":
                    unit = unit_name(element.get("unit") or "millimeter")
                elif tag == "resources":  # the model's metadata come before its resources
                    break
                elif event == "end" and tag == "metadata" and (element.get("name") or "").startswith("interlock:"):
                    key = element.get("name").partition(":")[2]
                    if key == "header":
                        header = element.text or ""
                    elif key in (LABELS_KEY, INFO_KEY):
                        stored[key] = json_value(element.text)
            if name.lower().endswith("3dmodel.model"):
                _check_items(path, package.read(name))
    if header is not None and header_counts(header) is not None and "unit" not in header_words(header):
        unit = None  # an assembly without unit: written in metres, read as it was
    return read_scene(path, None, header, stored_meaning(stored), unit)


def _check_items(path: Path, model: bytes) -> None:
    """An error naming a build item whose object the model does not define (trimesh would log and skip it)."""
    defined = set(re.findall(rb"<(?:\w+:)?object\b[^>]*?\sid=\"([^\"]*)\"", model))
    items = re.findall(rb"<(?:\w+:)?item\b[^>]*?\sobjectid=\"([^\"]*)\"", model)
    undefined = [item for item in items if item not in defined]
    if undefined:
        names = ", ".join(sorted(d.decode(errors="replace") for d in defined)) or "none"
        raise FormatError(f"{path} is damaged: a build item refers to object id "
                          f"{undefined[0].decode(errors='replace')}, which its model does not define (defined: {names})")


def write_3mf(assembly: Assembly, path: Path) -> None:
    """A 3MF package: shared objects per block type and class, one build item per block, the assembly's unit."""
    meshes, part_classes, part_of, placements = instanced_parts(assembly)
    values, kind = classes(assembly)
    unit = THREEMF_UNITS[assembly.unit or "m"]
    header = file_header(len(assembly), len(assembly.frame), unit=assembly.unit)
    used = sorted(set(part_classes.tolist()))
    material = {value: k for k, value in enumerate(used)}
    model = io.StringIO()
    model.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                f'<model unit="{unit}" xml:lang="en-US" '
                'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" '
                f'xmlns:interlock="{_NAMESPACE}">\n'
                f'<metadata name="interlock:header">{header}</metadata>\n'
                f'<metadata name="interlock:{LABELS_KEY}">{escape(one_line_json(label_pairs(assembly)))}</metadata>\n'
                f'<metadata name="interlock:{INFO_KEY}">{escape(one_line_json(plain(assembly.info)))}</metadata>\n'
                '<resources>\n<basematerials id="1">\n')
    for value in used:
        colour = bytes(PALETTE[value % len(PALETTE)].tolist()).hex().upper()
        model.write(f'<base name="{class_name(kind, value)}" displaycolor="#{colour}"/>\n')
    model.write("</basematerials>\n")
    for k, (mesh, value) in enumerate(zip(meshes, part_classes.tolist())):
        model.write(f'<object id="{k + 2}" type="model" name="part_{k}" pid="1" pindex="{material[value]}">\n'
                    '<mesh>\n<vertices>\n')
        model.write('<vertex x="%r" y="%r" z="%r"/>\n' * len(mesh.vertices) % tuple(mesh.vertices.ravel().tolist()))
        model.write("</vertices>\n<triangles>\n")
        model.write('<triangle v1="%d" v2="%d" v3="%d"/>\n' * len(mesh.faces) % tuple(mesh.faces.ravel().tolist()))
        model.write("</triangles>\n</mesh>\n</object>\n")
    model.write("</resources>\n<build>\n")
    frame = set(assembly.frame)
    for i, (k, placement) in enumerate(zip(part_of, placements)):
        # 3MF multiplies row vectors: the 4x3 matrix is the transpose of the top 3x4 of ours
        transform = " ".join(map(repr, placement[:3, :4].T.ravel().tolist()))
        label_type, label = label_text(assembly.labels[i])
        model.write(f'<item objectid="{k + 2}" transform="{transform}" partnumber="{block_name(i, frame)}">\n'
                    f'<metadatagroup>\n<metadata name="interlock:block">{i}</metadata>\n'
                    f'<metadata name="interlock:label">{escape(label)}</metadata>\n'
                    f'<metadata name="interlock:label_type">{escape(label_type)}</metadata>\n'
                    f'<metadata name="interlock:class">{escape(class_name(kind, int(values[i])))}</metadata>\n'
                    f'<metadata name="interlock:fixed">{str(i in frame).lower()}</metadata>\n'
                    '</metadatagroup>\n</item>\n')
    model.write("</build>\n</model>\n")
    with atomic_write(path) as temporary, zipfile.ZipFile(temporary, "w", compression=zipfile.ZIP_DEFLATED) as package:
        package.writestr("[Content_Types].xml", _CONTENT_TYPES)
        package.writestr("_rels/.rels", _RELATIONSHIPS)
        package.writestr("3D/3dmodel.model", model.getvalue())


_CONTENT_TYPES = """<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"""
_RELATIONSHIPS = """<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
<Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"""
