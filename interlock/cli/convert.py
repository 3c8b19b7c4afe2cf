"""``interlock convert``: an assembly from one file format to another, in the unit and up-axis asked for."""

from __future__ import annotations

import argparse
import os

from interlock.cli.common import MESH_FORMATS, OUTPUT_SUFFIXES, bar_progress, frame_text, load, output_file
from interlock.errors import InterlockError

#: What ``--unit``, ``--scale`` and ``--up`` mean, in the help of ``convert`` and ``generate``.
UNIT_HELP = ("the unit to write in: mm, cm, m, in, ft or um; a model that states its unit is converted (every size "
             "kept), one that states none is declared in it (default: the model's own unit)")
SCALE_HELP = "multiply every coordinate by this factor (sizes change; the unit stays) (default 1)"
UP_HELP = ("the up-axis of OUT for formats without a convention of their own (STL, OBJ, PLY, VTU, XDMF; default z); "
           "y suits Blender's and three.js' importers; GLB is always y up, 3MF, 3DM and JSON z up")


def add_parser(commands) -> None:
    convert = commands.add_parser(
        "convert", help="convert an assembly between file formats, keeping its blocks, frame, names and unit",
        description="Read an assembly (one file holding every block) and write it in the format of OUT's suffix: "
                    f"{', '.join(OUTPUT_SUFFIXES)}.  The frame is --fixed if given, else the one IN stores; "
                    "labels, classes, the unit and the assembly's info travel where the format can hold them "
                    "(3dm: the designer's object names, layers and user text; COMPAS JSON: node attributes).  "
                    "Sizes never change unless --scale says so: --unit converts.",
        epilog="examples:\n  interlock convert p4.stl p4.3dm\n  interlock convert armadillo.json armadillo.glb\n"
               "  interlock convert vault.3dm vault.json --fixed 0-7\n"
               "  interlock convert drawn.3dm print.3mf --unit mm\n  interlock convert p4.3dm p4.obj --up y",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    convert.add_argument("source", metavar="IN", help=f"an assembly file: {MESH_FORMATS}")
    convert.add_argument("target", metavar="OUT", type=output_file, help=f"the file to write: {', '.join(OUTPUT_SUFFIXES)}")
    convert.add_argument("--fixed", default=None, metavar="LIST",
                         help="frame: block indices, e.g. 0,1 or 0-3,7 (default: the frame IN stores)")
    unit_arguments(convert)
    convert.set_defaults(run=run)


def unit_arguments(parser) -> None:
    """``--unit``, ``--scale`` and ``--up``, as ``convert`` and ``generate`` take them."""
    parser.add_argument("--unit", default=None, metavar="UNIT", help=UNIT_HELP)
    parser.add_argument("--scale", type=float, default=None, metavar="FACTOR", help=SCALE_HELP)
    parser.add_argument("--up", default=None, choices=("z", "y"), help=UP_HELP)


def sized(assembly, args):
    """The assembly scaled by ``--scale`` and in ``--unit``, and words saying what happened to its size."""
    from interlock.formats import converted, scaled

    words = []
    if args.scale is not None:
        assembly = scaled(assembly, args.scale)
        words.append(f"scaled by {args.scale:g}")
    if args.unit is not None:
        before = assembly.unit
        assembly = converted(assembly, args.unit)
        if before is None:
            words.append(f"declared in {assembly.unit}, as it stated none")
        elif before != assembly.unit:
            words.append(f"converted from {before} to {assembly.unit}, every size kept")
    return assembly, words


def run(args) -> int:
    from pathlib import Path

    from interlock.formats import LABELLED_FORMATS, writable_target, write

    writable_target(args.target)  # before reading: a folder, a device, an unknown suffix are said at once
    if _same_file(args.source, args.target):
        raise InterlockError(f"IN and OUT are the same file ({args.source}); write to another name")
    from tqdm import tqdm

    with tqdm(desc=f"convert: reading {Path(args.source).name}", unit="block", disable=None, leave=False) as bar:
        assembly = load(args.source, args.fixed, progress=bar_progress(bar))
    assembly, words = sized(assembly, args)
    with tqdm(desc=f"convert: writing {Path(args.target).name}", unit="block", disable=None, leave=False) as bar:
        path = write(assembly, args.target, up=args.up, progress=bar_progress(bar))
    kept = "" if path.suffix.lower() in LABELLED_FORMATS else (
        f"; labels not kept ({path.suffix} stores none: use {', '.join(LABELLED_FORMATS)})")
    unit = f", unit {assembly.unit}" if assembly.unit else ", no unit"
    size = f" ({'; '.join(words)})" if words else ""
    print(f"wrote {path}: {len(assembly)} blocks, frame {frame_text(assembly.frame, assembly.info.get('frame_from'))}"
          f"{unit}{size}{kept}")
    return 0


def _same_file(source, target) -> bool:
    """Whether IN and OUT name one file (through links too); a loop of links is IN's error, said when read."""
    try:
        return os.path.exists(target) and os.path.samefile(source, target)
    except OSError:
        return os.path.abspath(source) == os.path.abspath(target)
