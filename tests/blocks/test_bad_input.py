"""The library's answers to the bad input of issue 22: one InterlockError each, with a message naming the problem."""

import pytest

import interlock
from interlock import InterlockError, wallpaper
from interlock.blocks import escher_block, patch, random_hexagon, rhomblock_assembly


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad")
    hexagon = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0), 0, frame="boundary")
    vtu, obj, stl = (interlock.write(hexagon, folder / f"h.{kind}").read_bytes() for kind in ("vtu", "obj", "stl"))
    (folder / "empty.vtu").write_bytes(b"")
    (folder / "empty.xdmf").write_bytes(b"")
    (folder / "half.vtu").write_bytes(vtu[:len(vtu) // 2])
    (folder / "half.obj").write_bytes(obj[:len(obj) // 2])
    import trimesh

    plain = trimesh.exchange.stl.export_stl(trimesh.creation.box())
    (folder / "half-plain.stl").write_bytes(plain[:len(plain) // 2])
    (folder / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n")
    (folder / "parts.stl").mkdir()
    return folder


@pytest.mark.parametrize("name, message", [
    ("empty.vtu", r"empty.vtu is empty \(0 bytes\): it holds no mesh"),
    ("empty.xdmf", r"empty.xdmf is empty \(0 bytes\): it holds no mesh"),
    ("half.vtu", "cannot read .*half.vtu as VTU: the file is empty, cut short or damaged"),
    ("half.obj", "cut short or damaged: it announces 27 blocks"),
    ("half-plain.stl", "is not a complete STL: .* announces 12 triangles .* cut short"),
    ("nan.obj", "line 3: a vertex coordinate is not a finite number"),
    ("parts.stl", "is a folder, not a mesh file"),
])
def test_a_bad_file_is_an_error_that_names_the_problem(files, name, message, capsys):
    with pytest.raises(InterlockError, match=message):
        interlock.read(files / name)
    assert capsys.readouterr() == ("", "")  # meshio's own printing silenced


def test_the_first_half_of_an_obj_export_does_not_load_as_some_of_its_blocks(files):
    with pytest.raises(InterlockError, match="27 blocks of 432 triangles in all, it holds 14 objects"):
        interlock.read(files / "half.obj")


@pytest.mark.parametrize("paths", [None, 42, [1, "a.obj"]])
def test_load_of_something_that_is_not_a_path_is_an_assembly_error(paths):
    with pytest.raises(InterlockError, match="needs a file path"):
        interlock.read(paths)


def test_escher_points_that_are_not_numbers_are_a_deformation_error():
    with pytest.raises(InterlockError, match="edge 0: intermediate points must be a sequence of .* number pairs"):
        escher_block(wallpaper.group("p4"), {0: "abc"})


def test_an_empty_hexagon_and_a_negative_seed_are_tiling_errors():
    with pytest.raises(InterlockError, match="the tiling has no lozenges"):
        rhomblock_assembly(random_hexagon(0, 0, 0, seed=0))
    with pytest.raises(InterlockError, match="seed must be an integer >= 0"):
        random_hexagon(2, 2, 2, seed=-1)


def test_generators_refuse_more_blocks_than_their_limit_before_allocating():
    block = escher_block(wallpaper.group("p4"), {})
    with pytest.raises(InterlockError, match=r"p4 patch of radius 1000000.0 would be 12,566,\d{3},\d{3},\d{3} blocks "
                                             r"\(about .* PB to verify\), more than the limit of 100,000"):
        patch(block, 1e6)
    with pytest.raises(InterlockError, match="1000 x 1000 x 1000 hexagon would be 3,000,000 blocks"):
        random_hexagon(1000, 1000, 1000, seed=0)
    assert len(patch(block, 2.0, max_blocks=1000)) < 1000
    with pytest.raises(InterlockError, match="more than the limit of 10"):
        patch(block, 2.0, max_blocks=10)


def test_an_obj_export_whose_header_is_damaged_is_refused(files):
    text = (files / "half.obj").read_text()
    (files / "no-header.obj").write_text(text.replace("interlock blocks=27", "interlock blocks~27", 1))
    with pytest.raises(InterlockError, match="header .* is damaged, so it cannot tell whether it is whole"):
        interlock.read(files / "no-header.obj")
