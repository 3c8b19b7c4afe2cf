"""``interlock generate wallpaper|rhomblock``: make an assembly and write it."""

from __future__ import annotations

import argparse

from interlock.cli.common import (block_limit, edge_points, lattice_arguments, length, numbers, output_arguments,
                                  whole_number)
from interlock.cli.convert import sized, unit_arguments
from interlock.errors import InterlockError

#: Named periodic lozenge tilings for ``generate rhomblock --periodic``: their staircase counts.
PERIODIC_KINDS = {"one-orientation": (1, 0, 0), "two-orientations": (1, 1, 0), "three-orientations": (1, 1, 1)}


def add_parser(commands) -> None:
    generate = commands.add_parser("generate", help="generate an assembly and write it (format by suffix)")
    kinds = generate.add_subparsers(dest="kind", metavar="KIND", required=True)
    escher = kinds.add_parser(
        "wallpaper", help="a patch of Escher blocks of a wallpaper group",
        description="Deform edges of the group's fundamental domain, build the block and write the blocks g(X) "
                    "for the tiles within --radius.",
        epilog="examples:\n  interlock generate wallpaper p4 --deform 0:0.25,0.1 --radius 2 -o p4.stl\n"
               "  interlock generate wallpaper p4 --deform 0:0.25,0.1 --unit mm --scale 20 -o p4.3mf",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    escher.add_argument("group", help="wallpaper group, e.g. p4")
    escher.add_argument("--deform", action="append", default=[], metavar="EDGE:X,Y[;X,Y...]",
                        help="intermediate points of one edge (repeat for more edges), e.g. 0:0.25,0.1")
    escher.add_argument("--height", type=length, default=1.0, help="block height (default 1)")
    escher.add_argument("--radius", type=length, default=2.0, help="patch radius in cell lengths (default 2)")
    lattice_arguments(escher)
    output_arguments(escher)
    unit_arguments(escher)
    escher.set_defaults(run=run_wallpaper)
    rhomb = kinds.add_parser(
        "rhomblock", help="RhomBlocks on a random hexagon or a periodic staircase tiling",
        description="Place RhomBlocks on a uniformly random lozenge tiling of an A x B x C hexagon, or on a patch "
                    "of a periodic staircase tiling (KIND = N0,N1,N2, or one of " + ", ".join(PERIODIC_KINDS) + ").",
        epilog="examples:\n  interlock generate rhomblock --hexagon 10 10 10 --seed 1 -o hexagon.3mf\n"
               "  interlock generate rhomblock --hexagon 4 4 4 --unit cm --scale 5 -o hexagon.3dm\n"
               "  interlock generate rhomblock --periodic 1,1,0 --variant 1 -o staircase.glb",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    source = rhomb.add_mutually_exclusive_group(required=True)
    source.add_argument("--hexagon", type=whole_number, nargs=3, metavar=("A", "B", "C"), help="hexagon side lengths")
    source.add_argument("--periodic", metavar="KIND", help="staircase counts N0,N1,N2 or a named tiling")
    rhomb.add_argument("--seed", type=whole_number, default=0, help="seed of the random hexagon tiling (default 0)")
    rhomb.add_argument("--variant", type=whole_number, default=0, choices=(0, 1), help="RhomBlock assembly variant")
    rhomb.add_argument("--radius", type=whole_number, default=2, help="cells around the periodic cell (default 2)")
    output_arguments(rhomb)
    unit_arguments(rhomb)
    rhomb.set_defaults(run=run_rhomblock)


def write_assembly(assembly, args) -> int:
    """Write the assembly to ``-o`` (a picture for ``.png``), scaled and in the unit asked for, and say so."""
    from pathlib import Path

    from tqdm import tqdm

    from interlock.cli.common import bar_progress
    from interlock.formats import write
    from interlock.gallery import exploded, render

    assembly, words = sized(assembly, args)
    if Path(args.output).suffix.lower() == ".png":
        path = render(assembly, args.output, exploded=args.exploded)
    else:
        with tqdm(desc=f"writing {Path(args.output).name}", unit="block", disable=None, leave=False) as bar:
            shown = exploded(assembly, args.exploded) if args.exploded else assembly
            path = write(shown, args.output, up=args.up, progress=bar_progress(bar))
    unit = f", unit {assembly.unit}" if assembly.unit else ""
    size = f" ({'; '.join(words)})" if words else ""
    print(f"wrote {path}: {len(assembly)} blocks, {len(assembly.frame)} in the frame{unit}{size}")
    return 0


def run_wallpaper(args) -> int:
    import math

    from interlock import wallpaper  # numpy and shapely: imported by the commands that use them
    from interlock.blocks import escher_block, patch

    group = wallpaper.group(args.group, a=args.a, b=args.b, gamma=args.gamma)
    block = escher_block(group, dict(edge_points(text) for text in args.deform), height=args.height)
    assembly = patch(block, args.radius * math.sqrt(group.cell_area), frame="boundary", **block_limit(args))
    return write_assembly(assembly, args)


def run_rhomblock(args) -> int:
    from interlock.blocks import cell_patch, random_hexagon, rhomblock_assembly, staircase

    if args.hexagon is not None:
        from tqdm import tqdm

        with tqdm(desc="random tiling", unit="sweep", disable=None, leave=False) as bar:
            tiling = random_hexagon(*args.hexagon, seed=args.seed, progress=bar.update, **block_limit(args))
        assembly = rhomblock_assembly(tiling, args.variant, frame="boundary")
    else:
        counts = PERIODIC_KINDS.get(args.periodic)
        if counts is None:
            try:
                counts = numbers(args.periodic, int, "--periodic")
            except InterlockError:
                raise InterlockError(f"cannot read --periodic {args.periodic!r}: give staircase counts N0,N1,N2 "
                                     f"(digits 0-9) or one of {', '.join(PERIODIC_KINDS)}") from None
        assembly = cell_patch(rhomblock_assembly(staircase(counts), args.variant), args.radius, **block_limit(args))
    return write_assembly(assembly, args)
