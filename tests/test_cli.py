"""The command line: help, version, groups, and one-line errors without tracebacks."""

import json
import subprocess
import sys

import pytest

import interlock
from interlock.cli import main


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"interlock {interlock.__version__}"
    assert main([]) == 0
    assert "groups" in capsys.readouterr().out


def test_groups_lists_all_17(capsys):
    assert main(["groups", "--json"]) == 0
    records = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in records] == list(interlock.wallpaper.GROUPS)
    assert main(["groups"]) == 0
    assert len(capsys.readouterr().out.strip().splitlines()) == 18


def test_group_detail(capsys):
    assert main(["group", "p4", "--a", "2", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["point_group_order"] == 4 and record["lattice"] == [[2.0, 0.0], [0.0, 2.0]]
    assert main(["group", "p6"]) == 0
    assert "edge 1 <- edge 2: rotation" in capsys.readouterr().out


@pytest.mark.parametrize("argv,message", [
    (["group", "p5"], "unknown wallpaper group 'p5'"),
    (["group", "p4", "--gamma", "100"], "gamma must be 90 degrees"),
    (["group", "p1", "--a", "-1"], "must be positive"),
])
def test_bad_input_is_one_line_and_nonzero(argv, message):
    run = subprocess.run([sys.executable, "-m", "interlock", *argv], capture_output=True, text=True)
    assert run.returncode == 2
    assert "Traceback" not in run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and lines[0].startswith("interlock group: error:")
