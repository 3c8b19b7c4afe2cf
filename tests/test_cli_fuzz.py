"""Fuzzing the command line: bad argument values and damaged files give exit 2 and one line on stderr.

A run may also succeed (some values are good ones); what it must never do is
print a traceback, print several lines of error, exit with another status, or
load a damaged file as fewer blocks than it holds.
"""

import argparse
import contextlib
import io
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from interlock.blocks import random_hexagon, rhomblock_assembly
from interlock.cli import main
from interlock import write

#: The formats of a multi-block file that a damaged copy is made of.
FORMATS = (".obj", ".stl", ".ply", ".vtu", ".xdmf", ".glb", ".3mf")
BLOCKS = 27
#: The bytes of a file's header lines, which flips spare (a damaged OBJ header: tests/blocks/test_bad_input.py).
HEADER_BYTES = 160
FUZZ = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 3 x 3 x 3 RhomBlock hexagon (27 blocks, ring fixed) in every format, and a folder to write into."""
    folder = tmp_path_factory.mktemp("fuzz")
    hexagon = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0), 0, frame="boundary")
    return folder, {suffix: write(hexagon, folder / f"hexagon{suffix}").read_bytes() for suffix in FORMATS}


def _run(argv) -> tuple[int, str, str]:
    status, out, err, _ = _run_recording(argv)
    return status, out, err


def _run_recording(argv) -> tuple[int, str, str, list[str]]:
    """``_run``, and the RuntimeWarnings (numpy's overflow, invalid value, ...) the run raised on the way, which
    would reach stderr before the one line in a real process (pytest records them instead)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            status = main([str(a) for a in argv])
        except SystemExit as stop:  # argparse
            status = stop.code
    runtime = [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in caught
               if issubclass(w.category, RuntimeWarning)]
    return status, out.getvalue(), err.getvalue(), runtime


def _assert_clean(status, err):
    """An answer (0; verify and periodic: 1 not interlocked, 3 inconclusive), or exit 2 with one line on stderr;
    never a traceback."""
    assert "Traceback" not in err
    if status == 2:
        assert err.count("\n") == 1 and err.startswith("interlock"), err
    else:
        assert status in (0, 1, 3) and ": error:" not in err, (status, err)


numbers = st.one_of(st.integers(-10, 6).map(str), st.sampled_from(["0", "-0", "1e6", "nan", "inf", "-inf", "", "x",
                                                                   "1,2", "0x10", "1e400", " 3"]))
texts = st.text(st.sampled_from("0123456789-,.:; abxyz"), max_size=12)


@FUZZ
@given(sides=st.tuples(numbers, numbers, numbers), seed=numbers, variant=numbers)
def test_generate_rhomblock_with_any_values_succeeds_or_says_what_is_wrong_in_one_line(files, sides, seed, variant):
    folder, _ = files
    status, _, err = _run(["generate", "rhomblock", "--hexagon", *sides, "--seed", seed, "--variant", variant,
                           "--max-blocks", 200, "-o", folder / "out.stl"])
    _assert_clean(status, err)


@FUZZ
@given(group=st.sampled_from(["p4", "p1", "p6", "pm", "p7", "", "P4"]), radius=numbers, deform=texts, height=numbers)
def test_generate_wallpaper_with_any_values_succeeds_or_says_what_is_wrong_in_one_line(files, group, radius, deform,
                                                                                     height):
    folder, _ = files
    status, _, err = _run(["generate", "wallpaper", group, "--radius", radius, "--deform", deform, "--height", height,
                           "--max-blocks", 200, "-o", folder / "out.obj"])
    _assert_clean(status, err)


@FUZZ
@given(fixed=texts, order=st.sampled_from(["1", "2", "3", "x"]))
def test_verify_with_any_frame_succeeds_or_says_what_is_wrong_in_one_line(files, fixed, order):
    folder, _ = files
    assume(fixed.strip() and not fixed.startswith("-"))  # argparse reads "-..." as an option
    status, out, err = _run(["verify", folder / "hexagon.stl", "--fixed", fixed, "--order", order])
    _assert_clean(status, err)


@FUZZ
@given(mu=numbers, fixed=texts, method=st.sampled_from(["rbe", "cra", "x"]))
def test_stability_with_any_values_succeeds_or_says_what_is_wrong_in_one_line(files, mu, fixed, method):
    folder, _ = files
    assume(not fixed.startswith("-") and not mu.startswith("-"))
    status, _, err = _run(["stability", folder / "hexagon.obj", "--mu", mu, "--fixed", fixed, "--method", method,
                           "--time-limit", "5"])
    _assert_clean(status, err)


toml_values = st.sampled_from(["0", "-1", "0.5", "1e10", '"s"', '"q"', "[1, 2]", "{}", "nan", "true", '"p4"', ""])


@FUZZ
@given(group=toml_values, mu=toml_values, edge=toml_values, steps=toml_values, offset=toml_values)
def test_sweep_with_any_spec_succeeds_or_says_what_is_wrong_in_one_line(files, group, mu, edge, steps, offset):
    folder, _ = files
    spec = folder / "spec.toml"
    spec.write_text(f"group = {group}\nverdicts = [\"criterion_4_3\"]\nmu = {mu}\n"
                    f"[parameters]\ns = {{range = [-0.1, 0.1], steps = {steps}}}\n"
                    f"[[points]]\nedge = {edge}\nalong = 0.5\noffset = {offset}\n")
    output = folder / "sweep.jsonl"
    output.unlink(missing_ok=True)
    status, _, err = _run(["sweep", spec, "-o", output, "--workers", "1", "--max-points", "20"])
    _assert_clean(status, err)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(suffix=st.sampled_from(FORMATS), cut=st.floats(0.0, 1.0), flips=st.lists(st.tuples(st.floats(0, 1),
                                                                                          st.integers(0, 255)),
                                                                                max_size=3))
def test_a_damaged_file_is_refused_in_one_line_or_read_whole(files, suffix, cut, flips):
    folder, originals = files
    data = bytearray(originals[suffix][:int(len(originals[suffix]) * cut)])
    for where, value in flips:  # past the header lines: a file whose header is destroyed cannot say it is cut short
        if len(data) > HEADER_BYTES:
            data[HEADER_BYTES + int(where * (len(data) - 1 - HEADER_BYTES))] = value
    damaged = folder / f"damaged{suffix}"
    damaged.write_bytes(bytes(data))
    status, out, err = _run(["verify", damaged])
    _assert_clean(status, err)
    if status == 0:  # read: then as all its blocks, never as the part before the cut
        assert f"blocks: {BLOCKS}," in out, out


@pytest.mark.parametrize("argv", [
    ["generate", "rhomblock", "--hexagon", "0", "0", "0", "-o", "{folder}/h.stl"],
    ["generate", "rhomblock", "--hexagon", "2", "2", "2", "--seed", "-5", "-o", "{folder}/h.stl"],
    ["generate", "rhomblock", "--hexagon", "1000", "1000", "1000", "-o", "{folder}/h.stl"],
    ["generate", "wallpaper", "p4", "--radius", "1e6", "-o", "{folder}/f.stl"],
    ["sweep", "{folder}", "-o", "{folder}/x.jsonl"],
    ["verify", "{folder}"],
    ["verify", "{folder}/hexagon.stl", "--fixed", "8-0"],
    ["gallery", "{folder}/g", "--seed", "-5"],
])
def test_the_cases_of_issue_22_are_one_line_errors_in_a_real_process(files, argv):
    folder, _ = files
    done = subprocess.run([sys.executable, "-m", "interlock", *(a.format(folder=folder) for a in argv)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1 and done.stderr.startswith("interlock"), done.stderr
    assert not Path(folder / "g").exists()


# --- issue 36: Unicode digits, huge and non-finite numbers, scheduler addresses, symlinks --------------------

#: Digits of other scripts, and superscripts: ``str.isdigit`` is true of all, ``int`` reads some and not others.
OTHER_DIGITS = "²³¹٠١٢٣٤٥٦٧٨٩۰۱۲०१२০১০１２߀๑"
#: Text in which some digit is not one of 0-9: never read as a number.
foreign_digits = st.text(st.sampled_from("0123456789,.-:;" + OTHER_DIGITS), min_size=1, max_size=10).filter(
    lambda text: not text.isascii())
#: Numbers as a user might type them that float64 cannot hold, or whose products overflow it.
huge_numbers = st.one_of(st.floats(1e100, 1.7e308), st.floats(-1.7e308, -1e100),
                         st.sampled_from([float("inf"), float("-inf"), float("nan"), 5e-324, 1e-320])).map(repr) | \
    st.sampled_from(["1e400", "-1e400", "1e308", "1.7976931348623157e308", "INF", "-nan"])
SPEC = ('group = "p1"\nverdicts = ["criterion_4_3"]\n[parameters]\ns = {values = [-0.2, 0.2]}\n'
        '[[points]]\nedge = 0\nalong = 0.5\noffset = "s"\n')


def _assert_quiet(status, err, runtime):
    """Clean (success, or exit 2 and one line), and no numpy warning on the way."""
    _assert_clean(status, err)
    assert runtime == [], runtime


@FUZZ
@given(text=foreign_digits, where=st.sampled_from(["fixed", "deform", "staircase", "tilt-axis", "a", "exploded",
                                                   "max-blocks", "max-points", "workers", "mu"]))
def test_digits_of_other_scripts_are_never_read_as_numbers(files, text, where):
    folder, _ = files
    spec = folder / "unicode.toml"
    spec.write_text(SPEC)
    argv = {"fixed": ["verify", folder / "hexagon.stl", f"--fixed={text}"],
            "deform": ["periodic", "p4", f"--deform={text}"],
            "staircase": ["periodic", f"--staircase={text}"],
            "tilt-axis": ["stability", folder / "hexagon.obj", "--mu", "0.5", f"--tilt-axis={text}"],
            "a": ["generate", "wallpaper", "p4", f"--a={text}", "-o", folder / "u.stl"],
            "exploded": ["generate", "wallpaper", "p4", f"--exploded={text}", "-o", folder / "u.stl"],
            "max-blocks": ["generate", "wallpaper", "p4", f"--max-blocks={text}", "-o", folder / "u.stl"],
            "max-points": ["sweep", spec, "-o", folder / "u.jsonl", f"--max-points={text}"],
            "workers": ["sweep", spec, "-o", folder / "u.jsonl", f"--workers={text}"],
            "mu": ["stability", folder / "hexagon.obj", f"--mu={text}"]}[where]
    status, _, err, runtime = _run_recording(argv)
    _assert_quiet(status, err, runtime)
    assert status == 2, f"{text!r} was read as a number"
    assert "digits 0-9" in err or "cannot read" in err or "not a" in err, err


@FUZZ
@given(x=huge_numbers, y=huge_numbers, where=st.sampled_from(["a", "b", "exploded", "deform", "tilt-axis", "density",
                                                                "mu"]))
def test_huge_and_non_finite_numbers_give_one_line_and_no_numpy_warning(files, x, y, where):
    folder, _ = files
    generate = ["generate", "wallpaper", "p4", "--max-blocks", 200, "-o", folder / "h.stl"]
    argv = {"a": generate + [f"--a={x}"],
            "b": ["generate", "wallpaper", "pm", "--max-blocks", 200, "-o", folder / "h.stl", f"--b={x}"],
            "exploded": generate + [f"--exploded={x}"],
            "deform": ["periodic", "p4", f"--deform=0:{x},{y}"],
            "tilt-axis": ["stability", folder / "hexagon.obj", "--mu", "0.5", f"--tilt-axis={x},{y},0"],
            "density": ["stability", folder / "hexagon.obj", "--mu", "0.5", f"--density={x}"],
            "mu": ["stability", folder / "hexagon.obj", f"--mu={x}"]}[where]
    status, _, err, runtime = _run_recording(argv)
    _assert_quiet(status, err, runtime)
    if where in ("a", "b", "exploded", "deform", "density"):
        assert status == 2


def _two_cubes(scale: float) -> str:
    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    faces = [(1, 3, 7, 5), (2, 6, 8, 4), (1, 5, 6, 2), (3, 4, 8, 7), (1, 2, 4, 3), (5, 7, 8, 6)]
    lines = []
    for block in range(2):
        lines += [f"o block{block}"]
        lines += [f"v {(x + block) * scale!r} {y * scale!r} {z * scale!r}" for x, y, z in corners]
        lines += ["f " + " ".join(str(k + 8 * block) for k in face) for face in faces]
    return "\n".join(lines) + "\n"


@FUZZ
@given(scale=st.one_of(st.floats(1e101, 8e307), st.sampled_from([1e200, 1e300, 1.7e308 / 2])))
def test_coordinates_beyond_1e100_are_one_line_and_no_numpy_warning(files, scale):
    folder, _ = files
    huge = folder / "huge.obj"
    huge.write_text(_two_cubes(scale))
    for argv in (["verify", huge], ["convert", huge, folder / "huge.glb"],
                 ["stability", huge, "--mu", "0.5", "--fixed", "0"]):
        status, _, err, runtime = _run_recording(argv)
        _assert_quiet(status, err, runtime)
        assert status == 2 and "1e+100" in err, err  # the reader's words, or the assembly's


fast_failing_addresses = st.one_of(
    st.text(st.characters(blacklist_characters=":", blacklist_categories=("Cs",)), max_size=20),  # no port
    st.builds("{}://{}:{}".format, st.sampled_from(["udp", "http", "ftp", "file", "x", "tcp+udp"]),
              st.sampled_from(["127.0.0.1", "localhost", "[::1]", "example.org"]), st.integers(1, 65535)),
    st.builds("tcp://127.0.0.1:{}".format, st.integers().filter(lambda port: not 0 < port < 65536)),
    st.builds("tcp://{} {}:8786".format, st.text("ab.", max_size=3), st.text("ab.", max_size=3)),
    st.sampled_from(["not a url", "udp://127.0.0.1:9", "tcp://[::1", ":", "x:y", "tcp://:1.5", "inproc://x"]))


@FUZZ
@given(address=fast_failing_addresses)
def test_a_scheduler_address_dask_cannot_use_is_one_line(files, address):
    pytest.importorskip("distributed")
    folder, _ = files
    spec = folder / "scheduler.toml"
    spec.write_text(SPEC)
    status, _, err, runtime = _run_recording(["sweep", spec, "-o", folder / "s.jsonl", f"--scheduler={address}"])
    _assert_quiet(status, err, runtime)
    assert status == 2 and "--scheduler" in err or "no Dask scheduler at" in err, err
    assert not (folder / "s.jsonl").exists()


@pytest.mark.parametrize("where", ["spec", "output", "output --resume"])
def test_a_symlink_loop_as_a_sweeps_spec_or_output_is_one_line(tmp_path, where):
    loop, spec = tmp_path / "loop.jsonl", tmp_path / "spec.toml"
    loop.symlink_to(loop)
    spec.write_text(SPEC)
    if where == "spec":
        spec = tmp_path / "loop.toml"
        spec.symlink_to(spec)
    output = loop if where.startswith("output") else tmp_path / "out.jsonl"
    status, _, err, runtime = _run_recording(["sweep", spec, "-o", output, "--workers", "1"]
                                             + (["--resume"] if where.endswith("--resume") else []))
    _assert_quiet(status, err, runtime)
    assert status == 2 and loop.is_symlink(), err


def test_frames_without_order_2_or_without_their_parent_folder_are_refused_by_the_helper_verify_calls(tmp_path):
    from interlock import InterlockError
    from interlock.cli.common import check_frames_option

    with pytest.raises(InterlockError, match="add --order 2"):
        check_frames_option(argparse.Namespace(frames=str(tmp_path / "motion"), order=1))
    with pytest.raises(InterlockError, match="does not exist; create it first"):
        check_frames_option(argparse.Namespace(frames=str(tmp_path / "missing" / "motion"), order=2))
    (tmp_path / "file").write_text("x")
    with pytest.raises(InterlockError, match="it is a file"):
        check_frames_option(argparse.Namespace(frames=str(tmp_path / "file"), order=2))
    check_frames_option(argparse.Namespace(frames=str(tmp_path / "motion"), order=2))
    check_frames_option(argparse.Namespace(frames=None, order=1))
    assert not (tmp_path / "motion").exists()  # checked, not made


def _synopsis(command: str) -> str:
    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    block = readme.split("## Command line", 1)[1].split("```text", 1)[1].split("```", 1)[0]
    entries = re.split(r"\n(?=interlock )", block)
    return next(entry for entry in entries if entry.startswith(f"interlock {command} "))


@pytest.mark.parametrize("command", ["stability", "sweep", "verify", "groups", "group"])
def test_the_readme_synopsis_names_only_options_the_command_has(command):
    from interlock.cli import parser

    commands = next(a for a in parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    known = {flag for action in commands[command]._actions for flag in action.option_strings}
    shown = set(re.findall(r"(?<![\w-])(--[a-z][\w-]*)", _synopsis(command)))
    assert shown <= known, shown - known
    if command == "stability":  # mesh files need them: the synopsis shows them
        assert {"--fixed", "--density"} <= shown


@pytest.mark.parametrize("command", ["groups", "group", "stability", "sweep", "verify", "periodic", "convert"])
def test_the_commands_have_descriptions_and_the_help_speaks_no_project_jargon(command):
    from interlock.cli import parser

    top = parser()
    commands = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    assert commands.choices[command].description
    assert not re.search(r"seed \d{3}", top.format_help())


@pytest.mark.parametrize("argv, status, words", [
    (["stability", "{folder}/hexagon.obj", "--mu", "0.5", "--tilt-axis", "1e308,1e308,0"], 0, ""),
    (["periodic", "p4", "--deform", "0:1e308,1e308"], 2, "is not a finite number of size at most"),
    (["periodic", "p4", "--deform", "0:0.2,0.1", "--a", "1e200"], 2, "the length a = 1e+200 is outside"),
    (["generate", "wallpaper", "p4", "--a", "1e200", "-o", "{folder}/a.stl"], 2, "the length a = 1e+200"),
    (["generate", "wallpaper", "p4", "--exploded", "1e308", "-o", "{folder}/e.stl"], 2, "argument --exploded"),
    (["verify", "{folder}/hexagon.stl", "--fixed", "²"], 2, "digits 0-9"),
    (["verify", "{folder}/hexagon.stl", "--fixed", "٢"], 2, "digits 0-9"),
    (["periodic", "p4", "--deform", "²:0.5,0.1"], 2, "digits 0-9"),
    (["periodic", "p4", "--deform", "０:0.5,0.1"], 2, "digits 0-9"),
    (["periodic", "p4", "--deform", "0:"], 2, "gives edge 0 no point"),
    (["sweep", "{folder}/real.toml", "-o", "{folder}/r.jsonl", "--scheduler", "not a url"], 2, "--scheduler"),
    (["sweep", "{folder}/real.toml", "-o", "{folder}/r.jsonl", "--scheduler", "udp://127.0.0.1:9"], 2, "--scheduler"),
    (["sweep", "{folder}/real.toml", "-o", "{folder}/r.jsonl", "--max-points", "1e20"], 2, "argument --max-points"),
    (["verify", "{folder}/huge-real.obj"], 2, "1e+100"),
])
def test_the_cases_of_issue_36_are_one_line_without_warnings_in_a_real_process(files, argv, status, words):
    folder, _ = files
    (folder / "real.toml").write_text(SPEC)
    (folder / "huge-real.obj").write_text(_two_cubes(1e200))
    done = subprocess.run([sys.executable, "-m", "interlock", *(a.format(folder=folder) for a in argv)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == status, done.stderr
    assert "Warning" not in done.stderr and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.count("\n") == (1 if status else 0), done.stderr
    assert words in done.stderr and "intermediate point" not in done.stderr
    assert not (folder / "r.jsonl").exists()
