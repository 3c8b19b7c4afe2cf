"""``interlock periodic``: whether an infinite periodic assembly interlocks, from one cell."""

from __future__ import annotations

import argparse
import json

from interlock.cli.common import edge_points, lattice_arguments, length, numbers, whole_number
from interlock.cli.verify import EXIT_STATUS, exit_status
from interlock.errors import InterlockError


def add_parser(commands) -> None:
    periodic = commands.add_parser(
        "periodic", help="decide whether an infinite periodic assembly interlocks (one cell, Sec. 4.1)",
        description="Decide interlocking of the infinite assembly of an Escher block (a wallpaper group with "
                    "deformed edges) or of RhomBlocks on a periodic staircase tiling, from one cell.",
        epilog="examples:\n  interlock periodic p4 --deform 0:0.25,0.1\n  interlock periodic --staircase 1,1,0\n\n"
               + EXIT_STATUS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    periodic.add_argument("group", nargs="?", help="wallpaper group of an Escher block, e.g. p4")
    periodic.add_argument("--deform", action="append", default=[], metavar="EDGE:X,Y[;X,Y...]",
                          help="intermediate points of one edge (repeat for more edges), e.g. 0:0.25,0.1")
    periodic.add_argument("--height", type=length, default=1.0, help="block height (default 1)")
    lattice_arguments(periodic)
    periodic.add_argument("--staircase", metavar="N0,N1,N2",
                          help="RhomBlocks on the staircase tiling with these counts")
    periodic.add_argument("--variant", type=whole_number, default=0, choices=(0, 1), help="RhomBlock assembly variant")
    periodic.add_argument("--translational", action="store_true", help="translations only")
    periodic.add_argument("--certify", action="store_true", help="replay the reduction in exact arithmetic")
    periodic.add_argument("--json", action="store_true", help="print JSON instead of text")
    periodic.set_defaults(run=run)


def run(args) -> int:
    from interlock.blocks import escher_block, periodic_cell, rhomblock_assembly, staircase
    from interlock.verify import criterion_4_3, periodic_check

    if (args.group is None) == (args.staircase is None):
        raise InterlockError("give either a wallpaper group (with --deform) or --staircase N0,N1,N2, "
                             "not both or neither")
    criterion = None
    if args.staircase is not None:
        cell = rhomblock_assembly(staircase(numbers(args.staircase, int, "--staircase")), args.variant)
    else:
        from interlock import wallpaper  # numpy and shapely: imported by the commands that use them

        group = wallpaper.group(args.group, a=args.a, b=args.b, gamma=args.gamma)
        block = escher_block(group, dict(edge_points(text) for text in args.deform), height=args.height)
        cell = periodic_cell(block)
        criterion = criterion_4_3(block)
    verdict = periodic_check(cell, translational=args.translational, certify=args.certify)
    if args.json:
        record = verdict.to_dict()
        record["criterion_4_3"] = None if criterion is None else criterion.to_dict()
        print(json.dumps(record, indent=2))
        return exit_status(_answer(verdict))
    print(verdict)
    if criterion is not None:
        print(criterion)
    if verdict.moving:
        print("moving blocks (a, b, i: block i of the cell shifted by a v1 + b v2); motion (omega, t):")
        for b in verdict.moving:
            a, c, i = verdict.motion_blocks[b]
            print(f"   ({a:+d}, {c:+d}, {i})", " ".join(f"{x:+.4f}" for x in verdict.motion[b]))
    return exit_status(_answer(verdict))


def _answer(verdict):
    """True, False or None (inconclusive) from a periodic verdict's status."""
    return {"interlocked": True, "not interlocked": False}.get(verdict.status)
