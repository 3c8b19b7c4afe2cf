"""The ``interlock`` command line.

Every command reports bad input as one line on stderr and exits non-zero;
no traceback reaches the user for an :class:`~interlock.InterlockError`.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings

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
        print(f"interlock {args.command}: error: {_one_line(error)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # the reader of our output went away (``interlock verify x.stl | head``)
        sys.stderr.close()
        return 141
    except OSError as error:  # a file the checks could not foresee (permissions, a full disk, ...)
        where = f" {error.filename}" if error.filename else ""
        print(f"interlock {args.command}: error:{where}: {error.strerror or error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MemoryError:
        print(f"interlock {args.command}: error: out of memory; try a smaller input (or --max-blocks / --max-points "
              "lower)", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interlock: interrupted", file=sys.stderr)
        return 130


class _Parser(argparse.ArgumentParser):
    """argparse, but a bad argument is one line on stderr (``interlock verify: error: ...``) and exit status 2."""

    def error(self, message):
        command = self.prog if self.prog.startswith("interlock") else f"interlock {self.prog}"
        self.exit(EXIT_BAD_INPUT, f"{command}: error: {message} (see {command} --help)\n")


def _one_line(error) -> str:
    """An error's message on one line (a message quoting a file's line may hold a line break)."""
    return " ".join(str(error).split())


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
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
                    "Give one file per block (numbered from 0 in the order given) or one file holding all blocks. "
                    "The frame is --fixed if given, else the one the files store (interlock generate writes it "
                    "into every format), else none; the output says which.",
        epilog="examples:\n  interlock generate wallpaper p4 --deform 0:0.25,0.1 -o p4.vtu\n"
               "  interlock verify p4.vtu                 (the frame stored in p4.vtu)\n"
               "  interlock verify p4.vtu --fixed 0-3,7   (another frame)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    verify.add_argument("paths", nargs="+", help=f"mesh files: {MESH_FORMATS}")
    verify.add_argument("--fixed", default=None, metavar="LIST",
                        help="frame: block indices, e.g. 0,1 or 0-3,7 (default: the frame stored in the file, "
                             "if any, else none)")
    verify.add_argument("--translational", action="store_true", help="translations only")
    verify.add_argument("--certify", action="store_true", help="re-check the verdict rigorously")
    verify.add_argument("--order", type=int, choices=(1, 2), default=1,
                        help="2: take a verdict that is not 'interlocked' to second order and try the motion "
                             "as a finite one (default 1: first order)")
    verify.add_argument("--frames", metavar="FOLDER",
                        help="with --order 2: write a finite motion shown into FOLDER, frame by frame "
                             "(STL, and PNG with the plot extra)")
    verify.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
                        help="seconds for the whole command (reading the files included); past it the answer is "
                             "'inconclusive: time limit reached in <stage>' (default: no limit)")
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
    periodic.add_argument("--staircase", metavar="N0,N1,N2",
                          help="RhomBlocks on the staircase tiling with these counts")
    periodic.add_argument("--variant", type=int, default=0, choices=(0, 1), help="RhomBlock assembly variant")
    periodic.add_argument("--translational", action="store_true", help="translations only")
    periodic.add_argument("--certify", action="store_true", help="replay the reduction in exact arithmetic")
    periodic.add_argument("--json", action="store_true", help="print JSON instead of text")
    periodic.set_defaults(run=_run_periodic)

    gallery = commands.add_parser(
        "gallery", help="generate, verify and export the gallery of assemblies (STL, GLB, PNG, index.html)",
        description="Build the gallery: Escher blocks of the wallpaper groups, the paper's examples and RhomBlock "
                    "assemblies, each verified (finite and periodic), exported and drawn, with an offline "
                    "index.html. Exits 1 if a verdict contradicts what the paper proves.",
        epilog="example:\n  interlock gallery gallery/ --quick\n  open gallery/index.html",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    gallery.add_argument("out", help="folder to write (created if missing)")
    gallery.add_argument("--quick", action="store_true", help="a small gallery of five entries")
    gallery.add_argument("--seed", type=int, default=0, help="seed of the random deformations and tilings")
    gallery.set_defaults(run=_run_gallery)

    stability = commands.add_parser(
        "stability", help="does an assembly stand under its own weight with friction (RBE / CRA, seed 001)?",
        description="Rigid-block equilibrium (RBE): compression-only forces at the contact vertices, linearised "
                    "friction cones, self-weight; coupled rigid-block analysis (CRA) also asks for a virtual "
                    "motion that realises them. COMPAS assembly JSON takes its supports as the frame.",
        epilog="examples:\n  interlock stability type-a.json --mu 0.84\n"
               "  interlock stability H.json --mu 0.84 --method cra\n"
               "  interlock stability type-c.json --mu 0.2 --tilt-axis xy30 --json",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    stability.add_argument("paths", nargs="+",
                           help=f"a COMPAS JSON file, or mesh files (one per block): {MESH_FORMATS}")
    stability.add_argument("--mu", type=float, required=True, help="friction coefficient")
    stability.add_argument("--method", default="rbe", choices=("rbe", "cra"),
                           help="rbe: equilibrium only (default); cra: equilibrium realised by a virtual motion "
                                "(exact MILP, slower)")
    stability.add_argument("--fixed", default=None, metavar="LIST", help="frame for mesh files, e.g. 0,1")
    stability.add_argument("--density", type=float, default=1.0, help="density of every block (default 1)")
    stability.add_argument("--cone", default="paper", choices=("paper", "inner"),
                           help="paper: the circumscribed octagon; inner: an inscribed one (conservative)")
    stability.add_argument("--tilt-axis", metavar="AXIS", help="also find the critical tilt about x, y, xy30 or X,Y,Z")
    stability.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
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
    stability.set_defaults(run=_run_stability)

    sweep = commands.add_parser(
        "sweep", help="sweep a design space (deformations or tilings) and record the verdicts at every point",
        description="Evaluate a TOML sweep spec (see interlock.sweep.spec) point by point, on local processes "
                    "or a Dask cluster; records go to JSON lines or Parquet as they arrive, so a stopped sweep "
                    "resumes. A sweep over two parameters also gets a PNG map per verdict (with the plot extra).",
        epilog="examples:\n  interlock sweep p1.toml -o p1.jsonl\n  interlock sweep p1.toml -o p1.jsonl --resume\n"
               "  interlock sweep p1.toml -o p1.parquet --scheduler tcp://10.0.0.5:8786",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sweep.add_argument("spec", help="the sweep spec (TOML)")
    sweep.add_argument("-o", "--output", required=True, metavar="RESULTS", help="*.jsonl or *.parquet")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="a running Dask scheduler (needs the sweep extra)")
    sweep.add_argument("--workers", type=int, metavar="N", help="local processes (default: all cores)")
    sweep.add_argument("--resume", action="store_true",
                       help="keep the records in RESULTS (they must be of this spec), evaluate the rest")
    sweep.add_argument("--max-points", type=int, default=None, metavar="N",
                       help="refuse a spec with more points than N (default 1,000,000)")
    sweep.set_defaults(run=_run_sweep)

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
    convert.set_defaults(run=_run_convert)

    generate = commands.add_parser("generate", help="generate an assembly and write it (format by suffix)")
    kinds = generate.add_subparsers(dest="kind", metavar="KIND", required=True)
    escher = kinds.add_parser(
        "wallpaper", help="a patch of Escher blocks of a wallpaper group",
        description="Deform edges of the group's fundamental domain, build the block and write the blocks g(X) "
                    "for the tiles within --radius.",
        epilog="example:\n  interlock generate wallpaper p4 --deform 0:0.25,0.1 --radius 2 -o p4.stl",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    escher.add_argument("group", help="wallpaper group, e.g. p4")
    escher.add_argument("--deform", action="append", default=[], metavar="EDGE:X,Y[;X,Y...]",
                        help="intermediate points of one edge (repeat for more edges), e.g. 0:0.25,0.1")
    escher.add_argument("--height", type=float, default=1.0, help="block height (default 1)")
    escher.add_argument("--radius", type=float, default=2.0, help="patch radius in cell lengths (default 2)")
    _lattice_arguments(escher)
    _output_arguments(escher)
    escher.set_defaults(run=_run_generate_wallpaper)
    rhomb = kinds.add_parser(
        "rhomblock", help="RhomBlocks on a random hexagon or a periodic staircase tiling",
        description="Place RhomBlocks on a uniformly random lozenge tiling of an A x B x C hexagon, or on a patch "
                    "of a periodic staircase tiling (KIND = N0,N1,N2, or one of " + ", ".join(PERIODIC_KINDS) + ").",
        epilog="examples:\n  interlock generate rhomblock --hexagon 10 10 10 --seed 1 -o hexagon.3mf\n"
               "  interlock generate rhomblock --periodic 1,1,0 --variant 1 -o staircase.glb",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    source = rhomb.add_mutually_exclusive_group(required=True)
    source.add_argument("--hexagon", type=int, nargs=3, metavar=("A", "B", "C"), help="hexagon side lengths")
    source.add_argument("--periodic", metavar="KIND", help="staircase counts N0,N1,N2 or a named tiling")
    rhomb.add_argument("--seed", type=int, default=0, help="seed of the random hexagon tiling (default 0)")
    rhomb.add_argument("--variant", type=int, default=0, choices=(0, 1), help="RhomBlock assembly variant")
    rhomb.add_argument("--radius", type=int, default=2, help="cells around the periodic cell (default 2)")
    _output_arguments(rhomb)
    rhomb.set_defaults(run=_run_generate_rhomblock)
    return parser


#: The formats ``verify``, ``stability`` and ``convert`` read (interlock.blocks.meshfiles; any other trimesh reads).
MESH_FORMATS = ("OBJ, STL, PLY, GLB/GLTF, 3MF, OFF, VTU, XDMF, Rhino 3DM, COMPAS assembly JSON (and other formats "
                "trimesh reads); the files interlock generate writes keep their blocks and frame")
#: The suffixes ``generate -o`` and ``convert`` write (interlock.gallery.export.FORMATS).
OUTPUT_SUFFIXES = (".stl", ".obj", ".ply", ".glb", ".3mf", ".vtu", ".xdmf", ".3dm", ".json")
#: Named periodic lozenge tilings for ``generate rhomblock --periodic``: their staircase counts.
PERIODIC_KINDS = {"one-orientation": (1, 0, 0), "two-orientations": (1, 1, 0), "three-orientations": (1, 1, 1)}


def _output_arguments(parser) -> None:
    parser.add_argument("-o", "--output", required=True, metavar="FILE",
                        help=f"output file: {' '.join(OUTPUT_SUFFIXES)}, or .png for a picture")
    parser.add_argument("--exploded", type=float, default=0.0, help="move blocks apart by this factor (default 0)")
    parser.add_argument("--max-blocks", type=int, default=None, metavar="N",
                        help="refuse to make more than N blocks (default 100,000; counted before anything is made)")


def _lattice_arguments(parser) -> None:
    parser.add_argument("--a", type=float, default=1.0, help="cell edge a (default 1)")
    parser.add_argument("--b", type=float, default=None, help="cell edge b (default: a)")
    parser.add_argument("--gamma", type=float, default=None,
                        help="cell angle in degrees (default: the crystal system's)")


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


def _time_limit(seconds, started: float) -> float | None:
    """What is left of ``--time-limit`` (``seconds``) after what the command has spent since ``started`` (imports,
    reading the files), at least a millisecond; ``None`` without a limit.  A bad value is refused."""
    if seconds is None:
        return None
    if not seconds > 0 or math.isnan(seconds):
        raise InterlockError(f"--time-limit must be a number of seconds > 0, got {seconds:g}")
    return max(seconds - (time.perf_counter() - started), 1e-3)


def _run_verify(args) -> int:
    started = time.perf_counter()
    _time_limit(args.time_limit, started)
    from interlock.verify import check

    from tqdm import tqdm

    from interlock.verify.check import STAGES

    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = _load(paths, args.fixed)
    stages = [s for s in STAGES if (s != "certify" or args.certify) and (s != "beyond" or args.order == 2)]
    with tqdm(total=len(stages), desc="verify", unit="stage", disable=None, leave=False) as bar:
        def announce(stage):
            bar.set_description(f"verify: {stage}")
            bar.update(1)

        limit = {} if args.time_limit is None else {"time_limit": _time_limit(args.time_limit, started)}
        verdict = check(assembly, translational=args.translational, certify=args.certify, progress=announce,
                        order=args.order, **limit)
    frames = []
    if args.frames and verdict.finite_motion is not None and verdict.finite_motion.shown:
        import importlib.util

        from interlock.gallery.motion import export_motion

        frames = export_motion(assembly, verdict.finite_motion, args.frames)
        if importlib.util.find_spec("matplotlib") is not None:  # pictures too, with the plot extra
            frames += export_motion(assembly, verdict.finite_motion, args.frames, format="png")
    if args.json:
        record = verdict.to_dict()
        record["blocks"] = [str(label) for label in assembly.labels]
        record["frame_from"] = _FRAME_FROM.get(assembly.info.get("frame_from"), "none")
        print(json.dumps(record, indent=2))
        return 0
    print(verdict)
    print(f"blocks: {len(assembly)}, frame: {_frame_text(verdict.frame, assembly.info.get('frame_from'))}, "
          f"contacts: {verdict.contacts}")
    if verdict.moving:
        shown = ", ".join(f"{b} ({assembly.labels[b]})" for b in verdict.moving[:MOVING_SHOWN])
        more = f" and {len(verdict.moving) - MOVING_SHOWN} more" if len(verdict.moving) > MOVING_SHOWN else ""
        print(f"moving blocks: {shown}{more}")
    if verdict.stress is not None and verdict.interlocked:
        print(f"self-stress: {len(verdict.stress)} positive weights, smallest {verdict.stress.min():.3g}")
    if verdict.second_order is not None:
        print(verdict.second_order)
    if verdict.finite_motion is not None:
        print(f"finite motion: {verdict.finite_motion.message}")
        if frames:
            kinds = " and ".join(sorted({p.suffix[1:].upper() for p in frames}))
            print(f"frames of the motion: {len(frames)} {kinds} files in {args.frames}")
    timings = ", ".join(f"{name} {seconds:.3f}s" for name, seconds in verdict.timings.items())
    print(f"timings: {timings}")
    return 0


#: How ``verify`` names where the frame came from (``Assembly.info["frame_from"]``).
_FRAME_FROM = {"argument": "--fixed", "file": "the file", "upstream examples": "the upstream examples",
               "none": "none"}


def _frame_text(frame, origin) -> str:
    """'[0, 8] (from --fixed)', '24 blocks (from the file)' or '[] (no --fixed given, none stored)'."""
    source = _FRAME_FROM.get(origin, "none")
    if source == "none":
        return "[] (no --fixed given, none stored)"
    shown = str(list(frame)) if len(frame) <= MOVING_SHOWN else f"{len(frame)} blocks"
    return f"{shown} (from {source})"


def _run_periodic(args) -> int:
    from interlock.blocks import escher_block, periodic_cell, rhomblock_assembly, staircase
    from interlock.verify import criterion_4_3, periodic_check

    if (args.group is None) == (args.staircase is None):
        raise InterlockError("give either a wallpaper group (with --deform) or --staircase N0,N1,N2, "
                             "not both or neither")
    criterion = None
    if args.staircase is not None:
        cell = rhomblock_assembly(staircase(_numbers(args.staircase, int, "--staircase")), args.variant)
    else:
        group = wallpaper.group(args.group, a=args.a, b=args.b, gamma=args.gamma)
        block = escher_block(group, dict(_edge_points(text) for text in args.deform), height=args.height)
        cell = periodic_cell(block)
        criterion = criterion_4_3(block)
    verdict = periodic_check(cell, translational=args.translational, certify=args.certify)
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


def _run_stability(args) -> int:
    started = time.perf_counter()
    _time_limit(args.time_limit, started)
    from tqdm import tqdm

    from interlock.verify import rbe
    from interlock.verify.statics import cra, tilt_scan

    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = _load(paths, args.fixed)
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
        with tqdm(desc="cra", unit="stage", disable=None, leave=False) as bar:
            def stage(words):
                bar.set_postfix_str(words)
                bar.update(1)

            result = cra(assembly, args.mu, density=args.density, cone=args.cone, contacts=found,
                         progress=stage, time_limit=_time_limit(args.time_limit, started), **cra_options)
    else:
        result = rbe(assembly, args.mu, density=args.density, cone=args.cone, contacts=found,
                     time_limit=_time_limit(args.time_limit, started))
    tilt = None
    if args.tilt_axis is not None:
        axis = (args.tilt_axis if args.tilt_axis in ("x", "y", "xy30")
                else _numbers(args.tilt_axis, float, "--tilt-axis"))
        with tqdm(desc=f"tilt about {args.tilt_axis}", unit="angle", disable=None) as bar:
            def advance(angle, stable):
                words = {True: "stable", False: "not stable"}.get(stable, "undecided")
                bar.set_postfix_str(f"{angle:.2f} deg {words}")
                bar.update(1)

            tilt = tilt_scan(assembly, axis, args.mu, method=args.method, density=args.density, cone=args.cone,
                             cra_options=cra_options or None, progress=advance, contacts=found,
                             time_limit=_time_limit(args.time_limit, started))
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


def _run_gallery(args) -> int:
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


def _run_sweep(args) -> int:
    from collections import Counter
    from pathlib import Path

    from tqdm import tqdm

    from interlock.sweep import MAX_POINTS, SweepError, SweepWarning, check_size, load_spec, run

    spec = load_spec(args.spec)
    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers must be at least 1, got {args.workers}")
    limit = MAX_POINTS if args.max_points is None else args.max_points
    if limit < 1:
        raise SweepError(f"--max-points must be at least 1, got {limit}")
    total = check_size(spec, limit)
    client = None
    if args.scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise SweepError('--scheduler needs Dask: pip install "interlock[sweep]"') from None
        try:
            client = Client(args.scheduler, timeout=10)
        except OSError as error:
            raise SweepError(f"no Dask scheduler at {args.scheduler}: {error}") from None
    try:
        with tqdm(total=total, desc="sweep", unit="point", disable=None) as bar, \
                warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SweepWarning)
            records = run(spec, args.output, executor=client, workers=args.workers, resume=args.resume,
                          progress=bar.update, max_points=limit)
    finally:
        if client is not None:
            client.close()
    for warning in caught:  # a damaged record, skipped: one line each; other warnings as Python shows them
        if issubclass(warning.category, SweepWarning):
            print(f"interlock sweep: warning: {warning.message}", file=sys.stderr)
        else:
            warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)
    counts = Counter(r["status"] for r in records)
    print(f"{len(records)} points ({', '.join(f'{n} {s}' for s, n in sorted(counts.items()))}): {args.output}")
    for verdict in spec.verdicts:
        words = Counter(r["verdicts"].get(verdict) for r in records if r["status"] == "ok")
        print(f"  {verdict}: " + ", ".join(f"{n} {w}" for w, n in sorted(words.items())))
    if len(spec.parameters) == 2:
        from interlock.sweep.map import verdict_map

        x, y = (p.name for p in spec.parameters)
        output = Path(args.output)
        for verdict in spec.verdicts:
            try:
                path = verdict_map(records, x, y, verdict, output.with_name(f"{output.stem}-{verdict}.png"),
                                   theory=spec.theory(x, y))
            except SweepError as error:  # e.g. matplotlib missing: the records are the result
                print(f"  no map: {error}", file=sys.stderr)
                break
            print(f"  map: {path}")
    if records and not counts["ok"]:
        first = records[0]
        print(f"interlock sweep: no point succeeded; point {first['index']} is {first['status']}: {first['message']}",
              file=sys.stderr)
        return 1
    return 0


def _run_generate_wallpaper(args) -> int:
    import math

    from interlock.blocks import escher_block, patch

    group = wallpaper.group(args.group, a=args.a, b=args.b, gamma=args.gamma)
    block = escher_block(group, dict(_edge_points(text) for text in args.deform), height=args.height)
    assembly = patch(block, args.radius * math.sqrt(group.cell_area), frame="boundary", **_limit(args))
    return _write(assembly, args)


def _run_generate_rhomblock(args) -> int:
    from interlock.blocks import cell_patch, random_hexagon, rhomblock_assembly, staircase

    if args.hexagon is not None:
        from tqdm import tqdm

        with tqdm(desc="random tiling", unit="sweep", disable=None, leave=False) as bar:
            tiling = random_hexagon(*args.hexagon, seed=args.seed, progress=bar.update, **_limit(args))
        assembly = rhomblock_assembly(tiling, args.variant, frame="boundary")
    else:
        counts = PERIODIC_KINDS.get(args.periodic)
        if counts is None:
            try:
                counts = [int(part) for part in args.periodic.split(",")]
            except ValueError:
                raise InterlockError(f"cannot read --periodic {args.periodic!r}: give staircase counts N0,N1,N2 "
                                     f"or one of {', '.join(PERIODIC_KINDS)}") from None
        assembly = cell_patch(rhomblock_assembly(staircase(counts), args.variant), args.radius, **_limit(args))
    return _write(assembly, args)


def _limit(args) -> dict:
    """``max_blocks`` for a generator, from ``--max-blocks`` (its default when not given)."""
    if args.max_blocks is None:
        return {}
    if args.max_blocks < 1:
        raise InterlockError(f"--max-blocks must be at least 1, got {args.max_blocks}")
    return {"max_blocks": args.max_blocks}


def _run_convert(args) -> int:
    from pathlib import Path

    from interlock.gallery import export
    from interlock.gallery.export import LABELLED_FORMATS

    if Path(args.target).suffix.lower() not in OUTPUT_SUFFIXES:
        raise InterlockError(f"cannot write {args.target}: choose a suffix from {', '.join(OUTPUT_SUFFIXES)}")
    if Path(args.source).resolve() == Path(args.target).resolve():
        raise InterlockError(f"IN and OUT are the same file ({args.source}); write to another name")
    from tqdm import tqdm

    with tqdm(desc=f"convert: reading {Path(args.source).name}", unit="block", disable=None, leave=False) as bar:
        assembly = _load(args.source, args.fixed, progress=_bar_progress(bar))
    with tqdm(desc=f"convert: writing {Path(args.target).name}", unit="block", disable=None, leave=False) as bar:
        path = export(assembly, args.target, progress=_bar_progress(bar))
    kept = "" if path.suffix.lower() in LABELLED_FORMATS else (
        f"; labels not kept ({path.suffix} stores none: use {', '.join(LABELLED_FORMATS)})")
    print(f"wrote {path}: {len(assembly)} blocks, frame {_frame_text(assembly.frame, assembly.info.get('frame_from'))}"
          f"{kept}")
    return 0


def _bar_progress(bar):
    """A ``progress(done, total)`` callback that moves a tqdm bar."""
    def advance(done, total):
        bar.total = total
        bar.n = done + 1
        bar.refresh()
    return advance


def _write(assembly, args) -> int:
    from pathlib import Path

    from interlock.gallery import export, render

    from tqdm import tqdm

    if Path(args.output).suffix.lower() == ".png":
        path = render(assembly, args.output, exploded=args.exploded)
    else:
        with tqdm(desc=f"writing {Path(args.output).name}", unit="block", disable=None, leave=False) as bar:
            path = export(assembly, args.output, exploded=args.exploded, progress=_bar_progress(bar))
    print(f"wrote {path}: {len(assembly)} blocks, {len(assembly.frame)} in the frame")
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


def _load(paths, fixed, progress=None):
    """``Assembly.load`` with ``--fixed`` read as block indices in every format.  The library reads a COMPAS
    file's frame as node keys (what its ``is_support`` marks name); a CLI user counts blocks, as the output
    does, so for ``.json`` the indices are applied after loading."""
    from pathlib import Path

    from interlock.blocks import Assembly

    frame = None if fixed is None else _indices(fixed)
    if frame is None or not isinstance(paths, (str, Path)) or Path(paths).suffix.lower() != ".json":
        return Assembly.load(paths, frame=frame, progress=progress)
    assembly = Assembly.load(paths, progress=progress)
    outside = [k for k in frame if k >= len(assembly)]
    if outside:
        raise InterlockError(f"--fixed names block {outside[0]}, but {Path(paths).name} holds {len(assembly)} blocks "
                             f"(indices 0-{len(assembly) - 1}; --fixed counts blocks in file order, not node keys)")
    chosen = assembly.with_frame(sorted(set(frame)))
    chosen.info["frame_from"] = "argument"
    return chosen


#: Block indices above this are refused while reading ``--fixed`` (before a range is spelled out in memory).
LARGEST_INDEX = 10_000_000


def _indices(text: str) -> list[int]:
    """'0,1,4-6' -> [0, 1, 4, 5, 6]."""
    out = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        low, dash, high = (s.strip() for s in part.partition("-"))
        if not low.isdigit() or (dash and not high.isdigit()):
            raise InterlockError(f"cannot read block list {text!r}: use indices and ranges such as 0,1 or 0-3,7")
        if max(int(low), int(high) if dash else 0) > LARGEST_INDEX:
            raise InterlockError(f"cannot read block list {text!r}: {part} reaches beyond block {LARGEST_INDEX:,}; "
                                 f"give indices of the file's blocks")
        if dash and int(high) < int(low):
            raise InterlockError(f"cannot read block list {text!r}: the range {part} runs backwards; write it "
                                 f"{int(high)}-{int(low)}")
        out += list(range(int(low), int(high) + 1)) if dash else [int(low)]
    if not out and text.strip():  # "" is an explicit empty frame; "," names nothing by mistake
        raise InterlockError(f"cannot read block list {text!r}: it names no block; use indices and ranges such as "
                             "0,1 or 0-3,7")
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
