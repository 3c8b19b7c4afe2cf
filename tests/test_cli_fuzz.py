"""Fuzzing the command line: bad argument values and damaged files give exit 2 and one line on stderr.

A run may also succeed (some values are good ones); what it must never do is
print a traceback, print several lines of error, exit with another status, or
load a damaged file as fewer blocks than it holds.
"""

import contextlib
import io
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from interlock.blocks import random_hexagon, rhomblock_assembly
from interlock.cli import main
from interlock.gallery import export

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
    return folder, {suffix: export(hexagon, folder / f"hexagon{suffix}").read_bytes() for suffix in FORMATS}


def _run(argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = main([str(a) for a in argv])
        except SystemExit as stop:  # argparse
            status = stop.code
    return status, out.getvalue(), err.getvalue()


def _assert_clean(status, err):
    """Success, or exit 2 with one line on stderr; never a traceback."""
    assert "Traceback" not in err
    if status != 0:
        assert status == 2, err
        assert err.count("\n") == 1 and err.startswith("interlock"), err


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
