"""``interlock convert``: an assembly from one file format to another."""

from __future__ import annotations

import argparse

from interlock.cli.common import MESH_FORMATS, OUTPUT_SUFFIXES, bar_progress, frame_text, load
from interlock.errors import InterlockError


def add_parser(commands) -> None:
    convert = commands.add_parser(
        "convert", help="convert an assembly between file formats, keeping its blocks, frame and names",
        description="Read an assembly (one file holding every block) and write it in the format of OUT's suffix: "
                    f"{', '.join(OUTPUT_SUFFIXES)}.  The frame is --fixed if given, else the one IN stores; "
                    "labels, classes and the assembly's info travel where the format can hold them "
                    "(3dm: object names, layers and user text; COMPAS JSON: node attributes).",
        epilog="examples:\n  interlock convert p4.stl p4.3dm\n  interlock convert armadillo.json armadillo.glb\n"
               "  interlock convert vault.3dm vault.json --fixed 0-7",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    convert.add_argument("source", metavar="IN", help=f"an assembly file: {MESH_FORMATS}")
    convert.add_argument("target", metavar="OUT", help=f"the file to write: {', '.join(OUTPUT_SUFFIXES)}")
    convert.add_argument("--fixed", default=None, metavar="LIST",
                         help="frame: block indices, e.g. 0,1 or 0-3,7 (default: the frame IN stores)")
    convert.set_defaults(run=run)


def run(args) -> int:
    from pathlib import Path

    from interlock.gallery import export
    from interlock.gallery.export import LABELLED_FORMATS

    if Path(args.target).suffix.lower() not in OUTPUT_SUFFIXES:
        raise InterlockError(f"cannot write {args.target}: choose a suffix from {', '.join(OUTPUT_SUFFIXES)}")
    if Path(args.source).resolve() == Path(args.target).resolve():
        raise InterlockError(f"IN and OUT are the same file ({args.source}); write to another name")
    from tqdm import tqdm

    with tqdm(desc=f"convert: reading {Path(args.source).name}", unit="block", disable=None, leave=False) as bar:
        assembly = load(args.source, args.fixed, progress=bar_progress(bar))
    with tqdm(desc=f"convert: writing {Path(args.target).name}", unit="block", disable=None, leave=False) as bar:
        path = export(assembly, args.target, progress=bar_progress(bar))
    kept = "" if path.suffix.lower() in LABELLED_FORMATS else (
        f"; labels not kept ({path.suffix} stores none: use {', '.join(LABELLED_FORMATS)})")
    print(f"wrote {path}: {len(assembly)} blocks, frame {frame_text(assembly.frame, assembly.info.get('frame_from'))}"
          f"{kept}")
    return 0
