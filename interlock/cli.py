"""The ``interlock`` command line.

Every command reports bad input as one line on stderr and exits non-zero;
no traceback reaches the user for an :class:`~interlock.InterlockError`.
"""

from __future__ import annotations

import argparse
import json
import sys

import interlock
from interlock import wallpaper
from interlock.errors import InterlockError

__all__ = ["main"]

EXIT_BAD_INPUT = 2
MOVING_SHOWN = 12


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.run(args)
    except InterlockError as error:
        print(f"interlock {args.command}: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("interlock: interrupted", file=sys.stderr)
        return 130


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="interlock",
        description="Generate, export and verify interlocking assemblies of rigid blocks.",
    )
    parser.add_argument("--version", action="version", version=f"interlock {interlock.__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    groups = commands.add_parser("groups", help="list the 17 wallpaper groups")
    groups.add_argument("--json", action="store_true", help="print JSON instead of a table")
    groups.set_defaults(run=_run_groups)

    one = commands.add_parser(
        "group", help="show one wallpaper group: lattice, fundamental domain and side pairings"
    )
    one.add_argument("name", help="short symbol, e.g. p6 or p4g")
    _lattice_arguments(one)
    one.add_argument("--json", action="store_true", help="print JSON instead of text")
    one.set_defaults(run=_run_group)

    verify = commands.add_parser(
        "verify", help="decide whether blocks from mesh files interlock (LP + rank, Def. 3.3)",
        description="Decide whether the blocks in the given mesh files interlock with the fixed blocks as frame. "
                    "Give one file per block (numbered from 0 in the order given) or one file holding all blocks.",
    )
    verify.add_argument("paths", nargs="+", help="OBJ/STL/PLY/GLB files")
    verify.add_argument("--fixed", default="", metavar="LIST",
                        help="frame: block indices, e.g. 0,1 or 0-3,7 (default: none)")
    verify.add_argument("--translational", action="store_true", help="translations only")
    verify.add_argument("--certify", action="store_true", help="re-check the verdict rigorously")
    verify.add_argument("--json", action="store_true", help="print JSON instead of text")
    verify.set_defaults(run=_run_verify)

    periodic = commands.add_parser(
        "periodic", help="decide whether an infinite periodic assembly interlocks (one cell, Sec. 4.1)",
        description="Decide interlocking of the infinite assembly of an Escher block (a wallpaper group with "
                    "deformed edges) or of RhomBlocks on a periodic staircase tiling, from one cell.",
    )
    periodic.add_argument("group", nargs="?", help="wallpaper group of an Escher block, e.g. p4")
    periodic.add_argument("--deform", action="append", default=[], metavar="EDGE:X,Y[;X,Y...]",
                          help="intermediate points of one edge (repeat for more edges), e.g. 0:0.25,0.1")
    periodic.add_argument("--height", type=float, default=1.0, help="block height (default 1)")
    _lattice_arguments(periodic)
    periodic.add_argument("--staircase", metavar="N0,N1,N2", help="RhomBlocks on the staircase tiling with these counts")
    periodic.add_argument("--variant", type=int, default=0, choices=(0, 1), help="RhomBlock assembly variant")
    periodic.add_argument("--translational", action="store_true", help="translations only")
    periodic.add_argument("--json", action="store_true", help="print JSON instead of text")
    periodic.set_defaults(run=_run_periodic)
    return parser


def _lattice_arguments(parser) -> None:
    parser.add_argument("--a", type=float, default=1.0, help="cell edge a (default 1)")
    parser.add_argument("--b", type=float, default=None, help="cell edge b (default: a)")
    parser.add_argument("--gamma", type=float, default=None, help="cell angle in degrees (default: the crystal system's)")


def _group_record(g: wallpaper.WallpaperGroup) -> dict:
    domain = g.fundamental_domain()
    return {
        "name": g.name,
        "crystal_system": g.crystal_system,
        "a": g.parameters.a,
        "b": g.parameters.b,
        "gamma": g.parameters.gamma,
        "lattice": g.lattice.tolist(),
        "point_group_order": g.point_group_order,
        "cosets": [str(r) for r in g.cosets],
        "fundamental_domain": [list(p) for p in domain.exterior.coords[:-1]],
        "side_pairings": [
            {"edge": s.edge, "partner": s.partner, "kind": s.kind, "element": str(s.element)}
            for s in g.side_pairings()
        ],
    }


def _run_groups(args) -> int:
    records = [_group_record(wallpaper.group(name)) for name in wallpaper.GROUPS]
    if args.json:
        print(json.dumps(records, indent=2))
        return 0
    print(f"{'group':6} {'system':20} {'|G/T|':>5} {'edges':>5} {'deformable pairs':>16}")
    for r in records:
        pairs = {tuple(sorted((s["edge"], s["partner"]))) for s in r["side_pairings"] if s["kind"] != "reflection"}
        print(f"{r['name']:6} {r['crystal_system']:20} {r['point_group_order']:>5} "
              f"{len(r['side_pairings']):>5} {len(pairs):>16}")
    return 0


def _run_verify(args) -> int:
    from interlock.blocks import Assembly
    from interlock.verify import check

    from tqdm import tqdm

    from interlock.verify.check import STAGES

    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = Assembly.load(paths, frame=_indices(args.fixed))
    stages = [s for s in STAGES if s != "certify" or args.certify]
    with tqdm(total=len(stages), desc="verify", unit="stage", disable=None, leave=False) as bar:
        def announce(stage):
            bar.set_description(f"verify: {stage}")
            bar.update(1)

        verdict = check(assembly, translational=args.translational, certify=args.certify, progress=announce)
    if args.json:
        record = verdict.to_dict()
        record["blocks"] = [str(label) for label in assembly.labels]
        print(json.dumps(record, indent=2))
        return 0
    print(verdict)
    print(f"blocks: {len(assembly)}, frame: {list(verdict.frame)}, contacts: {verdict.contacts}")
    if verdict.moving:
        shown = ", ".join(f"{b} ({assembly.labels[b]})" for b in verdict.moving[:MOVING_SHOWN])
        more = f" and {len(verdict.moving) - MOVING_SHOWN} more" if len(verdict.moving) > MOVING_SHOWN else ""
        print(f"moving blocks: {shown}{more}")
    if verdict.stress is not None and verdict.interlocked:
        print(f"self-stress: {len(verdict.stress)} positive weights, smallest {verdict.stress.min():.3g}")
    timings = ", ".join(f"{name} {seconds:.3f}s" for name, seconds in verdict.timings.items())
    print(f"timings: {timings}")
    return 0


def _run_periodic(args) -> int:
    from interlock.blocks import escher_block, periodic_cell, rhomblock_assembly, staircase
    from interlock.verify import criterion_4_3, periodic_check

    if (args.group is None) == (args.staircase is None):
        raise InterlockError("give either a wallpaper group (with --deform) or --staircase N0,N1,N2, not both or neither")
    criterion = None
    if args.staircase is not None:
        cell = rhomblock_assembly(staircase(_numbers(args.staircase, int, "--staircase")), args.variant)
    else:
        group = wallpaper.group(args.group, a=args.a, b=args.b, gamma=args.gamma)
        block = escher_block(group, dict(_edge_points(text) for text in args.deform), height=args.height)
        cell = periodic_cell(block)
        criterion = criterion_4_3(block)
    verdict = periodic_check(cell, translational=args.translational)
    if args.json:
        record = verdict.to_dict()
        record["criterion_4_3"] = None if criterion is None else criterion.to_dict()
        print(json.dumps(record, indent=2))
        return 0
    print(verdict)
    if criterion is not None:
        print(criterion)
    if verdict.moving:
        print("moving blocks (a, b, i: block i of the cell shifted by a v1 + b v2); motion (omega, t):")
        for b in verdict.moving:
            a, c, i = verdict.motion_blocks[b]
            print(f"   ({a:+d}, {c:+d}, {i})", " ".join(f"{x:+.4f}" for x in verdict.motion[b]))
    return 0


def _edge_points(text: str):
    """'0:0.25,0.1;0.4,0.2' -> (0, [(0.25, 0.1), (0.4, 0.2)])."""
    edge, colon, rest = text.partition(":")
    if not colon or not edge.strip().isdigit():
        raise InterlockError(f"cannot read --deform {text!r}: use EDGE:X,Y[;X,Y...], e.g. 0:0.25,0.1")
    points = [_numbers(point, float, "--deform") for point in rest.split(";") if point.strip()]
    if any(len(p) != 2 for p in points):
        raise InterlockError(f"cannot read --deform {text!r}: every point needs two coordinates X,Y")
    return int(edge), points


def _numbers(text: str, kind, flag: str) -> list:
    try:
        return [kind(part) for part in text.split(",")]
    except ValueError:
        raise InterlockError(f"cannot read {flag} {text!r}: expected comma-separated numbers") from None


def _indices(text: str) -> list[int]:
    """'0,1,4-6' -> [0, 1, 4, 5, 6]."""
    out = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        low, dash, high = part.partition("-")
        if not low.isdigit() or (dash and not high.isdigit()):
            raise InterlockError(f"cannot read block list {text!r}: use indices and ranges such as 0,1 or 0-3,7")
        out += list(range(int(low), int(high) + 1)) if dash else [int(low)]
    return out


def _run_group(args) -> int:
    record = _group_record(wallpaper.group(args.name, a=args.a, b=args.b, gamma=args.gamma))
    if args.json:
        print(json.dumps(record, indent=2))
        return 0
    print(f"{record['name']} ({record['crystal_system']}), a={record['a']:g} b={record['b']:g} "
          f"gamma={record['gamma']:g}, |G/T| = {record['point_group_order']}")
    print("lattice rows:", ", ".join(f"({x:.6g}, {y:.6g})" for x, y in record["lattice"]))
    print("cosets (lattice coordinates):", "; ".join(record["cosets"]))
    print("fundamental domain:")
    for i, (x, y) in enumerate(record["fundamental_domain"]):
        print(f"  v{i} = ({x:.6g}, {y:.6g})")
    print("side pairings (edge i runs from v_i to v_i+1):")
    for s in record["side_pairings"]:
        print(f"  edge {s['edge']} <- edge {s['partner']}: {s['kind']} {s['element']}")
    return 0
