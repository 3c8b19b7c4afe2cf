"""``interlock gallery``: generate, verify, export and draw the gallery."""

from __future__ import annotations

import argparse
import sys

from interlock.cli.common import whole_number


def add_parser(commands) -> None:
    gallery = commands.add_parser(
        "gallery", help="generate, verify and export the gallery of assemblies (STL, GLB, PNG; index.html, 3D views)",
        description="Build the gallery: Escher blocks of the wallpaper groups, the paper's examples and RhomBlock "
                    "assemblies, each verified (finite and periodic), exported and drawn, with an offline "
                    "index.html: a table of contents, the legend, and per entry its verdict in one sentence and an "
                    "interactive 3D view (interlock view). Exits 1 if a verdict contradicts what the paper proves.",
        epilog="example:\n  interlock gallery gallery-out/ --quick\n  open gallery-out/index.html",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    gallery.add_argument("out", help="folder to write (created if missing; the folder above it must exist)")
    gallery.add_argument("--quick", action="store_true", help="a small gallery of five entries")
    gallery.add_argument("--seed", type=whole_number, default=0, help="seed of the random deformations and tilings")
    gallery.set_defaults(run=run)


def run(args) -> int:
    from tqdm import tqdm

    from interlock.gallery import build, entries
    from interlock.gallery.builder import finite_word

    total = len(entries(args.quick, args.seed))
    with tqdm(total=total, desc="gallery", unit="entry", disable=None) as bar:
        def advance(name):
            bar.set_postfix_str(name)
            bar.update(1)

        gallery = build(args.out, quick=args.quick, seed=args.seed, progress=advance)
    print(f"{'entry':34} {'blocks':>6}  {'finite':23} {'periodic':16} {'claims':8} {'seconds':>7}")
    for result in gallery.entries:
        r = result.record
        finite = finite_word(r)
        periodic = r["periodic"]["status"] if r["periodic"] else "-"
        agree = sum(c["holds"] is True for c in r["claims"])
        print(f"{result.name:34} {r['blocks']:>6}  {finite:23} {periodic:16} {agree}/{len(r['claims']):<6} "
              f"{sum(r['timings'].values()):7.2f}")
    print(f"{len(gallery.entries)} entries in {gallery.seconds:.1f} s: {gallery.index}")
    for line in gallery.contradictions:
        print(f"CONTRADICTION {line}", file=sys.stderr)
    return 1 if gallery.contradictions else 0
