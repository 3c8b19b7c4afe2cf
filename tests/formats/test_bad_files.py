"""Bad files meet one line on stderr and exit status 2 (library: FormatError), never a traceback or a warning
(issue 36): counts that do not match, nesting, non-finite and huge coordinates, damaged 3MF, links, targets."""

import zipfile

import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

import interlock
from interlock.blocks import presets
from interlock.cli import main
from interlock.errors import AssemblyError, InterlockError
from interlock.formats import FormatError, read

TWO_CUBES = trimesh.util.concatenate([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in (0, 2)])
ASCII_PLY = trimesh.exchange.ply.export_ply(TWO_CUBES, encoding="ascii").decode()
PLY_LINES = len(ASCII_PLY.split("end_header\n")[1].splitlines())  # 16 vertices, 24 faces


def _one_line_error(capsys, command, *words):
    try:
        code = main(command)
    except SystemExit as error:  # argparse refused an argument
        code = error.code
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and "Warning" not in err, err
    for word in words:
        assert word in err
    return err


@given(kept=st.integers(min_value=0, max_value=PLY_LINES - 1))
def test_an_ascii_ply_cut_at_a_line_boundary_is_refused(tmp_path_factory, kept):
    head, body = ASCII_PLY.split("end_header\n")
    lines = body.splitlines()
    path = tmp_path_factory.mktemp("ply") / "cut.ply"
    path.write_text(head + "end_header\n" + "\n".join(lines[:kept]) + "\n")
    with pytest.raises(FormatError, match="is cut short: its header announces 16 vertices, 24 faces"):
        read(path)


def test_a_ply_announcing_a_million_faces_over_twelve_is_refused(tmp_path, capsys):
    path = tmp_path / "million.ply"
    path.write_text(ASCII_PLY.replace("element face 24", "element face 1000000"))
    for command in (["verify", str(path)], ["convert", str(path), str(tmp_path / "x.obj")]):
        _one_line_error(capsys, command, "announces 16 vertices, 1,000,000 faces", "24 of 1,000,000 faces")
    with pytest.raises(AssemblyError, match="cut short"), pytest.warns(DeprecationWarning):
        interlock.blocks.Assembly.load(path)


def test_an_ascii_ply_with_lines_more_than_announced_is_refused(tmp_path):
    path = tmp_path / "more.ply"
    path.write_text(ASCII_PLY.replace("element face 24", "element face 22"))
    with pytest.raises(FormatError, match="holds 2 lines more than its header announces"):
        read(path)


@given(cut=st.integers(min_value=1, max_value=60))
def test_an_obj_of_interlock_cut_at_a_line_boundary_is_refused(tmp_path_factory, cut):
    folder = tmp_path_factory.mktemp("obj")
    lines = interlock.write(presets.cube_grid(), folder / "grid.obj").read_text().splitlines()
    (folder / "cut.obj").write_text("\n".join(lines[:-cut]) + "\n")
    with pytest.raises(FormatError, match="cut short or damaged: it announces 9 blocks"):
        read(folder / "cut.obj")


@pytest.mark.parametrize("bracket", ["[", "{"])
def test_json_nested_200000_deep_is_one_line_everywhere(tmp_path, capsys, bracket):
    path = tmp_path / "deep.json"
    path.write_text(bracket * 200_000)
    for command in (["verify", str(path)], ["convert", str(path), str(tmp_path / "x.stl")],
                    ["stability", str(path), "--mu", "0.5"], ["stability", str(tmp_path / "ok.json"), "--mu", "0.5",
                                                              "--interfaces", str(path)]):
        if "ok.json" in command[1]:
            interlock.write(presets.cube_grid(), tmp_path / "ok.json")
        _one_line_error(capsys, command, "nests brackets 200000 deep")
    with pytest.raises(InterlockError, match="nests brackets 200000 deep"):
        read(path)
    with pytest.raises(AssemblyError, match="nests brackets"), pytest.warns(DeprecationWarning):
        interlock.blocks.Assembly.load(path)


@given(exponent=st.integers(min_value=101, max_value=308))
def test_huge_obj_coordinates_are_named_without_warnings(tmp_path_factory, exponent):
    folder = tmp_path_factory.mktemp("huge")
    path = folder / "huge.obj"
    path.write_text(_box_obj(f"1e{exponent}"))
    with _no_warnings():
        with pytest.raises(FormatError, match=f"vertex coordinate 1e\\+{exponent} that is beyond 1e\\+100"):
            read(path)


def test_huge_obj_coordinates_are_one_line_in_the_cli(tmp_path, capsys):
    path = tmp_path / "huge.obj"
    path.write_text(_box_obj("1e300"))
    _one_line_error(capsys, ["convert", str(path), str(tmp_path / "x.glb")], "1e+300", "scale the model down")


@pytest.mark.parametrize("number", ["1e400", "-1e999", "nan", "inf"])
def test_a_non_finite_ascii_stl_coordinate_is_named(tmp_path, capsys, number):
    text = trimesh.exchange.stl.export_stl_ascii(trimesh.creation.box())
    first = next(line for line in text.splitlines() if line.strip().startswith("vertex"))
    path = tmp_path / "bad.stl"
    path.write_text(text.replace(first, f"vertex {number} 0 0", 1))
    _one_line_error(capsys, ["verify", str(path)], "a vertex coordinate is not a finite number", number)


def test_a_3mf_item_of_an_undefined_object_is_one_line_without_trimesh_s_log(tmp_path, capsys):
    good = interlock.write(presets.cube_grid(), tmp_path / "grid.3mf")
    with zipfile.ZipFile(good) as package:
        files = {name: package.read(name) for name in package.namelist()}
    files["3D/3dmodel.model"] = files["3D/3dmodel.model"].replace(b'<item objectid="2"', b'<item objectid="7"', 1)
    bad = tmp_path / "undefined.3mf"
    with zipfile.ZipFile(bad, "w") as package:
        for name, data in files.items():
            package.writestr(name, data)
    err = _one_line_error(capsys, ["verify", str(bad)], "refers to object id 7")
    assert "included but not defined" not in err


def test_a_bow_tie_quad_obj_is_read_without_warnings(tmp_path, capsys):
    corners = "".join(f"v {x} {y} {z}\n" for x, y, z in trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]).vertices)
    faces = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    bow = faces.replace("f 1 2 4 3", "f 1 2 3 4")  # the corners out of order: a bow tie
    for name, text in (("cube.obj", faces), ("bow.obj", bow)):
        (tmp_path / name).write_text(corners + text)
        code = main(["convert", str(tmp_path / name), str(tmp_path / f"{name}.stl")])
        err = capsys.readouterr().err
        assert "Warning" not in err and err.count("\n") <= 1 and code in (0, 2)


def test_convert_on_a_loop_of_links_is_one_line(tmp_path, capsys):
    (tmp_path / "a.obj").symlink_to(tmp_path / "b.obj")
    (tmp_path / "b.obj").symlink_to(tmp_path / "a.obj")
    _one_line_error(capsys, ["convert", str(tmp_path / "a.obj"), str(tmp_path / "out.stl")], "symbolic link")


@pytest.mark.parametrize("target, words", [(".", "it is a folder"), ("/dev/null", "not a regular file")])
def test_output_targets_say_what_is_wrong(tmp_path, capsys, monkeypatch, target, words):
    monkeypatch.chdir(tmp_path)
    interlock.write(presets.cube_grid(), tmp_path / "grid.json")
    for command in (["convert", "grid.json", target], ["generate", "wallpaper", "p4", "-o", target]):
        err = _one_line_error(capsys, command, words)
        assert "cannot export to ''" not in err and "'null'" not in err


def _box_obj(size: str) -> str:
    """An OBJ cube from 0 to ``size`` (text, so that making it computes nothing)."""
    corners = "".join(f"v {x} {y} {z}\n" for x in ("0", size) for y in ("0", size) for z in ("0", size))
    return corners + "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n"


class _no_warnings:
    """A context in which any warning fails the test."""

    def __enter__(self):
        import warnings

        self._catcher = warnings.catch_warnings(record=True)
        self._caught = self._catcher.__enter__()
        warnings.simplefilter("always")
        return self

    def __exit__(self, *exc):
        self._catcher.__exit__(*exc)
        assert not self._caught, [str(w.message) for w in self._caught]
        return False
