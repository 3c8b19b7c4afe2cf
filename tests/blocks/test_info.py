"""Assembly.info in files (interlock/blocks/info.py): what is written comes back, contacts included."""

import math

import numpy as np
import pytest
import shapely

from interlock.formats import read
from interlock.blocks import Assembly, presets
from interlock.blocks.contact import Contact, ContactError
from interlock.blocks.info import CONTACT_TAG, ITEMS_TAG, plain, restored
from interlock.formats import write as export
from interlock.verify import check, contacts


def _same(first, second):
    return [c.to_dict() for c in first] == [c.to_dict() for c in second]


def test_face_contacts_come_back_exactly_with_their_polygons():
    found = contacts(presets.cube_grid())
    back = restored(plain({"contacts": found}))["contacts"]
    assert _same(found, back)
    assert all(a.polygon.equals_exact(b.polygon, 1e-12) for a, b in zip(found, back))


def test_a_contact_with_a_hole_keeps_its_rings():
    square = [(-2, -2), (2, -2), (2, 2), (-2, 2)]
    hole = [(-1, -1), (-1, 1), (1, 1), (1, -1)]
    polygon = shapely.Polygon(square, [hole])
    basis = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    origin = np.array([0.0, 0, 3])
    vertices = origin + np.array(square + hole, dtype=float) @ basis
    contact = Contact(0, 1, np.array([0.0, 0, 1]), vertices, polygon.area, 2, 5, polygon, origin, basis)
    back = Contact.from_dict(contact.to_dict())
    assert back.ring_sizes == (4, 4) and back.area == 12.0 and back.polygon.equals(polygon)


@pytest.mark.parametrize("suffix", [".json", ".3dm"])
def test_contacts_an_assembly_carries_survive_export_and_load(tmp_path, suffix):
    if suffix == ".3dm":
        pytest.importorskip("rhino3dm")
    pins = presets.block_on_pins()
    back = read(export(pins, tmp_path / f"pins{suffix}"))
    assert _same(pins.info["contacts"], back.info["contacts"])
    first, second = check(pins), check(back)
    assert (first.interlocked, first.rank) == (second.interlocked, second.rank)
    np.testing.assert_array_equal(first.motion, second.motion)


@pytest.mark.parametrize("suffix", [".json", ".3dm"])
def test_numbers_json_cannot_hold_come_back_as_text(tmp_path, suffix):
    if suffix == ".3dm":
        pytest.importorskip("rhino3dm")
    assembly = presets.cube_grid()
    assembly = Assembly(assembly.meshes, assembly.types, assembly.transforms, frame=assembly.frame,
                        info={"limit": math.inf, "scores": np.array([0.5, np.nan])})
    back = read(export(assembly, tmp_path / f"grid{suffix}")).info
    assert back["limit"] == "inf" and back["scores"][0] == 0.5 and back["scores"][1] == "nan"


def test_plain_keeps_literals_for_rhino_and_pairs_for_json():
    value = {np.int64(1): (np.float64(2.5), "a")}
    assert plain(value) == {ITEMS_TAG: [[1, [2.5, "a"]]]}
    assert plain(value, json=False) == {1: (2.5, "a")}
    assert plain({"other": object}) == {"other": str(object)}
    assert restored(plain({(0, 1): "edge"})) == {(0, 1): "edge"}


@pytest.mark.parametrize("suffix", [".json", ".3dm"])
def test_an_escher_patch_keeps_its_info_exactly(tmp_path, suffix):
    # the deformation is keyed by edge number: JSON keys are text, so it is stored as pairs
    if suffix == ".3dm":
        pytest.importorskip("rhino3dm")
    from interlock.blocks import escher_block, patch
    from interlock.wallpaper import group

    assembly = patch(escher_block(group("p4"), {0: [(0.25, 0.1)]}), 2)
    back = read(export(assembly, tmp_path / f"p4{suffix}")).info
    assert all(repr(back[key]) == repr(value) for key, value in assembly.info.items())


def test_a_damaged_stored_contact_is_a_clear_error():
    stored = plain({"contacts": contacts(presets.cube_grid())})
    del stored["contacts"][0][CONTACT_TAG]["normal"]
    with pytest.raises(ContactError, match="not a stored contact"):
        restored(stored)
    good = contacts(presets.cube_grid())[0].to_dict()
    with pytest.raises(ContactError, match="wrong shapes"):
        Contact.from_dict({**good, "ring_sizes": [1]})


def test_info_without_stored_contacts_is_left_as_it_is():
    info = {"contacts": ["a text someone wrote"], "seed": 3, "names": {"0": "a"}}
    assert restored(info) == info
