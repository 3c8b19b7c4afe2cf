"""``interlock groups`` and ``interlock group NAME``: the 17 wallpaper groups."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from interlock.cli.common import lattice_arguments

if TYPE_CHECKING:  # the commands import interlock.wallpaper (numpy, shapely) when they run, not at start-up
    from interlock.wallpaper import WallpaperGroup


def add_parser(commands) -> None:
    groups = commands.add_parser(
        "groups", help="list the 17 wallpaper groups",
        description="List the 17 plane crystallographic (wallpaper) groups: crystal system, |G/T| (blocks per "
                    "cell), the edges of the fundamental domain and how many pairs of them can be deformed "
                    "(the Escher trick; mirror edges cannot). interlock group NAME shows one in full.",
    )
    groups.add_argument("--json", action="store_true", help="print JSON instead of a table")
    groups.set_defaults(run=run_groups)

    one = commands.add_parser(
        "group", help="show one wallpaper group: lattice, fundamental domain and side pairings",
        description="Show one wallpaper group on a lattice: the lattice vectors, the coset representatives, the "
                    "fundamental domain F (vertices v0, v1, ...; edge i runs from v_i to v_i+1) and the side "
                    "pairings: edge i <- edge j means the element maps edge j onto edge i, so a point given to "
                    "edge j by --deform appears on edge i too.",
    )
    one.add_argument("name", help="short symbol, e.g. p6 or p4g")
    lattice_arguments(one)
    one.add_argument("--json", action="store_true", help="print JSON instead of text")
    one.set_defaults(run=run_group)


def group_record(g: WallpaperGroup) -> dict:
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


def run_groups(args) -> int:
    from interlock import wallpaper

    records = [group_record(wallpaper.group(name)) for name in wallpaper.GROUPS]
    if args.json:
        print(json.dumps(records, indent=2))
        return 0
    print(f"{'group':6} {'system':20} {'|G/T|':>5} {'edges':>5} {'deformable pairs':>16}")
    for r in records:
        pairs = {tuple(sorted((s["edge"], s["partner"]))) for s in r["side_pairings"] if s["kind"] != "reflection"}
        print(f"{r['name']:6} {r['crystal_system']:20} {r['point_group_order']:>5} "
              f"{len(r['side_pairings']):>5} {len(pairs):>16}")
    return 0


def run_group(args) -> int:
    from interlock import wallpaper

    record = group_record(wallpaper.group(args.name, a=args.a, b=args.b, gamma=args.gamma))
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
