"""``--time-limit`` as the user gave it: one budget from the command's start, named in the answer (issue 40)."""

import trimesh

from interlock.blocks import Assembly
from interlock.cli import main
from interlock.formats import write


def test_verify_names_the_limit_the_user_gave(tmp_path, capsys):
    # a limit far below what reading and validating take: the answer is "inconclusive", exit 3, and it names the
    # user's limit, not what was left of it after parsing and reading
    grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    path = tmp_path / "grid.obj"
    write(Assembly.from_meshes(grid, frame=[0, 1, 2, 3, 5, 6, 7, 8]), path)
    assert main(["verify", str(path), "--time-limit", "1e-6"]) == 3
    out = capsys.readouterr().out
    assert "inconclusive: time limit reached in" in out and "(time_limit = 1e-06 s)" in out
