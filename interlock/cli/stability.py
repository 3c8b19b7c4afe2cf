"""``interlock stability``: whether an assembly stands under its own weight with friction (RBE / CRA)."""

from __future__ import annotations

import argparse
import json

from interlock.cli.common import MESH_FORMATS, axis_direction, command_started, load, real_number, time_limit
from interlock.cli.view import add_html_argument, write_html
from interlock.errors import InterlockError

#: The largest ``--density``: weights are densities times volumes, and forces sums of weights, so far beyond
#: (1e300) they overflow float64; the verdict does not depend on a density shared by every block.
LARGEST_DENSITY = 1e30


def add_parser(commands) -> None:
    stability = commands.add_parser(
        "stability", help="does an assembly stand under its own weight with friction (RBE or CRA)?",
        description="Rigid-block equilibrium (RBE): compression-only forces at the contact vertices, linearised "
                    "friction cones, self-weight; coupled rigid-block analysis (CRA) also asks for a virtual "
                    "motion that realises them. COMPAS assembly JSON takes its supports as the frame; mesh files "
                    "name theirs with --fixed (unless interlock wrote the frame into them), and --density sets "
                    "the weight of every block.",
        epilog="examples:\n  interlock stability type-a.json --mu 0.84\n"
               "  interlock stability part_*.obj --fixed 0,1 --density 2400 --mu 0.6\n"
               "  interlock stability H.json --mu 0.84 --method cra\n"
               "  interlock stability type-c.json --mu 0.2 --tilt-axis xy30 --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    stability.add_argument("paths", nargs="+",
                           help=f"a COMPAS JSON file, or mesh files (one per block): {MESH_FORMATS}")
    stability.add_argument("--mu", type=real_number, required=True, help="friction coefficient")
    stability.add_argument("--method", default="rbe", choices=("rbe", "cra"),
                           help="rbe: equilibrium only (default); cra: equilibrium realised by a virtual motion "
                                "(exact MILP, slower)")
    stability.add_argument("--fixed", default=None, metavar="LIST",
                           help="the supports (frame) of mesh files: block indices, e.g. 0,1 or 0-3,7 (a COMPAS "
                                "file marks its own)")
    stability.add_argument("--density", type=_density, default=1.0,
                           help=f"density of every block, at most {LARGEST_DENSITY:g} (default 1)")
    stability.add_argument("--cone", default="paper", choices=("paper", "inner"),
                           help="paper: the circumscribed octagon; inner: an inscribed one (conservative)")
    stability.add_argument("--tilt-axis", metavar="AXIS", help="also find the critical tilt about x, y, xy30 or X,Y,Z")
    stability.add_argument("--time-limit", type=real_number, default=None, metavar="SECONDS",
                           help="seconds for the whole command (reading the files, rbe or cra, the tilt scan); past "
                                "it the answer is 'inconclusive: time limit reached in <stage>' (default: no limit; "
                                "the route cra takes never depends on the clock)")
    stability.add_argument("--no-hold-out", dest="hold_out", action="store_false",
                           help="cra on large models: stop at the Coulomb fixed point and name the blocks that "
                                "slide to the bound eta, instead of proving the rest without them and then "
                                "placing them (the default; needs interlock[nlp])")
    stability.add_argument("--contacts", default="interfaces", choices=("interfaces", "exact"),
                           help="interfaces: faces that meet across small gaps and tilts, relative to each block "
                                "pair's thickness (default); exact: faces that touch")
    stability.add_argument("--interfaces", metavar="FILE",
                           help="use the interfaces a COMPAS assembly JSON file stores (as compas_assembly / "
                                "compas_cra write them) instead of finding contacts")
    stability.add_argument("--json", action="store_true", help="print JSON instead of text")
    add_html_argument(stability)
    stability.set_defaults(run=run)


def _density(text: str) -> float:
    value = real_number(text)
    if value > LARGEST_DENSITY:  # 0, negative, nan and inf: the library's words
        raise argparse.ArgumentTypeError(f"the density must be at most {LARGEST_DENSITY:g} (the blocks' weights "
                                         f"would overflow), got {text}")
    return value


def run(args) -> int:
    started = command_started(args)
    time_limit(args.time_limit, started)
    from tqdm import tqdm

    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = load(paths, args.fixed)
    if not assembly.frame:  # the library's message speaks of frame=[...]; a CLI user gives --fixed
        stored = "no supports are marked in the file" if args.fixed is None else "--fixed names none"
        raise InterlockError(f"the assembly has no supports ({stored}): give the fixed blocks with --fixed, "
                             "e.g. --fixed 0,1; without supports nothing can carry the weight")
    if not args.hold_out and args.method != "cra":
        raise InterlockError("--no-hold-out applies to --method cra only")
    cra_options = {} if args.hold_out else {"hold_out": False}
    found = args.contacts
    if args.interfaces is not None:
        from interlock.verify.statics import compas_interfaces

        found = compas_interfaces(args.interfaces, assembly)
        if not found:
            raise InterlockError(f"{args.interfaces} stores no interfaces; drop --interfaces to find them "
                                 "(--contacts interfaces or exact)")
    if args.method == "cra":
        from interlock.verify.statics import cra  # imported under the budget, and only for the method asked for

        with tqdm(desc="cra", unit="stage", disable=None, leave=False) as bar:
            def stage(words):
                bar.set_postfix_str(words)
                bar.update(1)

            result = cra(assembly, args.mu, density=args.density, cone=args.cone, contacts=found,
                         progress=stage, time_limit=time_limit(args.time_limit, started), **cra_options)
    else:
        from interlock.verify.statics import rbe

        result = rbe(assembly, args.mu, density=args.density, cone=args.cone, contacts=found,
                     time_limit=time_limit(args.time_limit, started))
    write_html(args, assembly, result)
    tilt = None
    if args.tilt_axis is not None:
        from interlock.verify.statics import tilt_scan

        axis = args.tilt_axis if args.tilt_axis in ("x", "y", "xy30") else axis_direction(args.tilt_axis)
        with tqdm(desc=f"tilt about {args.tilt_axis}", unit="angle", disable=None) as bar:
            def advance(angle, stable):
                words = {True: "stable", False: "not stable"}.get(stable, "undecided")
                bar.set_postfix_str(f"{angle:.2f} deg {words}")
                bar.update(1)

            tilt = tilt_scan(assembly, axis, args.mu, method=args.method, density=args.density, cone=args.cone,
                             cra_options=cra_options or None, progress=advance, contacts=found,
                             time_limit=time_limit(args.time_limit, started))
    if args.json:
        print(json.dumps({**result.to_dict(), "critical_tilt_degrees": None if tilt is None else tilt.angle,
                          **({} if tilt is None else {"critical_tilt": tilt.to_dict()})}, indent=2))
        return 0
    print(result)
    if "friction utilisation" in str(result):
        print("  (friction utilisation: the largest |friction| / (mu x normal force) at one contact vertex of the "
              "forces found, against the round cone; not a safety factor, and above 1 on the polygonal cone's "
              "corners; see docs/statics.md)")
    if tilt is not None and tilt.status == "decided":
        angle = "stable up to 180 degrees" if tilt.angle >= 180 else f"{tilt.angle:.1f} degrees"
        print(f"critical tilt about {args.tilt_axis}: {angle}")
    elif tilt is not None:
        print(f"critical tilt about {args.tilt_axis}: inconclusive, stable up to {tilt.stable_below:.1f} degrees, "
              f"undecided at {tilt.angle:.2f} degrees ({tilt.undecided[-1][1]})")
    return 0
