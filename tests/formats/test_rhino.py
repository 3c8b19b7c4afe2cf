"""interlock/formats/rhino.py: a designer's .3dm keeps its unit, names, layers and user text through interlock."""

import numpy as np
import pytest

import interlock
from interlock.cli import main

rhino3dm = pytest.importorskip("rhino3dm")


def _drawn(path, unit="Meters", size=1.0):
    """A stack of three boxes as a designer draws them: on layers ``supports`` (under ``frame``) and ``blocks``
    (a sublayer of ``model``), named ``base``, ``middle`` and ``top``, with user text, in ``unit``."""
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = getattr(rhino3dm.UnitSystem, unit)
    layers = {}
    for full in ("frame", "frame::supports", "model", "model::blocks"):
        parent, _, name = full.rpartition("::")
        layer = rhino3dm.Layer()
        layer.Name = name
        layer.Color = (10, 20, 30, 255) if name == "blocks" else (200, 0, 0, 255)
        if parent:
            layer.ParentLayerId = model.Layers[layers[parent]].Id
        layers[full] = model.Layers.Add(layer)
    for k, (name, layer) in enumerate([("base", "frame::supports"), ("middle", "model::blocks"),
                                       ("top", "model::blocks")]):
        attributes = rhino3dm.ObjectAttributes()
        attributes.Name = name
        attributes.LayerIndex = layers[layer]
        attributes.SetUserString("material", f"stone {k}")
        box = rhino3dm.Box(rhino3dm.BoundingBox(0, 0, k * size, size, size, (k + 1) * size))
        model.Objects.AddBrep(rhino3dm.Brep.CreateFromBox(box), attributes)
    model.Strings["project"] = "vault 7"
    assert model.Write(str(path), 7)
    return path


def _objects(path):
    model = rhino3dm.File3dm.Read(str(path))
    layers = [model.Layers[k] for k in range(len(model.Layers))]
    out = []
    for k in range(len(model.Objects)):
        item = model.Objects[k]
        out.append((item.Attributes.Name, layers[item.Attributes.LayerIndex].FullPath,
                    item.Attributes.GetUserString("material")))
    return model, out


def test_layer_and_object_names_and_user_text_survive_3dm_to_3dm(tmp_path):
    source = _drawn(tmp_path / "drawn.3dm")
    assert main(["convert", str(source), str(tmp_path / "out.3dm")]) == 0
    model, objects = _objects(tmp_path / "out.3dm")
    assert objects == [("base", "frame::supports", "stone 0"), ("middle", "model::blocks", "stone 1"),
                       ("top", "model::blocks", "stone 2")]
    colours = {model.Layers[k].FullPath: tuple(model.Layers[k].Color) for k in range(len(model.Layers))}
    assert colours["model::blocks"] == (10, 20, 30, 255)
    assert model.Strings["project"] == "vault 7"
    assert str(model.Settings.ModelUnitSystem) == "UnitSystem.Meters"
    back = interlock.read(tmp_path / "out.3dm")
    assert back.frame == (0,) and back.info["names"] == ["base", "middle", "top"]


def test_names_survive_3dm_to_glb_and_json_and_back_to_3dm(tmp_path):
    source = _drawn(tmp_path / "drawn.3dm")
    for step in ("step.json", "step.glb"):
        assert main(["convert", str(source), str(tmp_path / step)]) == 0
        assert main(["convert", str(tmp_path / step), str(tmp_path / f"{step}.3dm")]) == 0
        _, objects = _objects(tmp_path / f"{step}.3dm")
        assert [o[:2] for o in objects] == [("base", "frame::supports"), ("middle", "model::blocks"),
                                            ("top", "model::blocks")]


@pytest.mark.parametrize("unit, short, size", [("Meters", "m", 1.0), ("Inches", "in", 12.0)])
@pytest.mark.parametrize("suffix", [".3dm", ".3mf", ".glb"])
def test_a_3dm_in_metres_or_inches_keeps_unit_and_every_size_through_convert(tmp_path, unit, short, size, suffix):
    source = _drawn(tmp_path / "drawn.3dm", unit, size)
    drawn = interlock.read(source)
    assert drawn.unit == short
    there, back = tmp_path / f"there{suffix}", tmp_path / "back.3dm"
    assert main(["convert", str(source), str(there)]) == 0
    assert main(["convert", str(there), str(back)]) == 0
    model = rhino3dm.File3dm.Read(str(back))
    assert str(model.Settings.ModelUnitSystem) == f"UnitSystem.{unit}"
    again = interlock.read(back)
    rtol = 1e-6 if suffix == ".glb" else 1e-12  # glTF vertex positions are float32
    assert again.unit == short and again.frame == drawn.frame
    np.testing.assert_allclose(again.volumes, drawn.volumes, rtol=rtol)
    np.testing.assert_allclose(again.bounds, drawn.bounds, rtol=rtol, atol=rtol * size)


def test_convert_with_unit_converts_and_says_so(tmp_path, capsys):
    source = _drawn(tmp_path / "drawn.3dm", "Meters", 1.0)
    assert main(["convert", str(source), str(tmp_path / "print.3mf"), "--unit", "mm"]) == 0
    assert "converted from m to mm, every size kept" in capsys.readouterr().out
    back = interlock.read(tmp_path / "print.3mf")
    assert back.unit == "mm" and back.bounds[:, 1, 2].max() == pytest.approx(3000.0)


def test_convert_with_scale_changes_sizes_and_says_so(tmp_path, capsys):
    source = _drawn(tmp_path / "drawn.3dm", "Meters", 1.0)
    assert main(["convert", str(source), str(tmp_path / "half.3dm"), "--scale", "0.5"]) == 0
    assert "scaled by 0.5" in capsys.readouterr().out
    back = interlock.read(tmp_path / "half.3dm")
    assert back.unit == "m" and back.bounds[:, 1, 2].max() == pytest.approx(1.5)


def test_a_rhino_unit_without_a_short_name_is_read_in_metres(tmp_path):
    back = interlock.read(_drawn(tmp_path / "km.3dm", "Kilometers", 1.0))
    assert back.unit == "m" and back.bounds[:, 1, 2].max() == pytest.approx(3000.0)


@pytest.mark.parametrize("kind", ["wallpaper", "rhomblock"])
def test_generate_takes_unit_and_scale(tmp_path, kind, capsys):
    extra = ["p4", "--deform", "0:0.25,0.1", "--radius", "1"] if kind == "wallpaper" else ["--hexagon", "2", "2", "2"]
    path = tmp_path / "made.3dm"
    assert main(["generate", kind, *extra, "--unit", "mm", "--scale", "20", "-o", str(path)]) == 0
    assert "unit mm (scaled by 20; declared in mm, as it stated none)" in capsys.readouterr().out
    made = interlock.read(path)
    plain = interlock.read(interlock.write(interlock.read(path), tmp_path / "same.json"))
    assert made.unit == "mm" == plain.unit
    assert str(rhino3dm.File3dm.Read(str(path)).Settings.ModelUnitSystem) == "UnitSystem.Millimeters"
    assert made.block_size > 10  # unit-sized blocks, 20 times larger
