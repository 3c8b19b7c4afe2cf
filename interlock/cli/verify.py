"""``interlock verify``: whether the blocks of mesh files interlock."""

from __future__ import annotations

import argparse
import json

from interlock.cli.common import (EXIT_BAD_INPUT, FRAME_FROM, MESH_FORMATS, MOVING_SHOWN, check_frames_option,
                                  command_started, frame_text, load, real_number, time_limit, whole_number)
from interlock.cli.view import add_html_argument, write_html

#: The exit status of ``verify`` and ``periodic`` by their answer, as diff and grep answer with theirs; bad input
#: (a file that cannot be read, a wrong option) is ``EXIT_BAD_INPUT``, 2.
EXIT_INTERLOCKED, EXIT_NOT_INTERLOCKED, EXIT_INCONCLUSIVE = 0, 1, 3
#: The exit statuses in words, the end of the help of ``verify`` and ``periodic``.
EXIT_STATUS = (f"exit status: {EXIT_INTERLOCKED} interlocked, {EXIT_NOT_INTERLOCKED} not interlocked, "
               f"{EXIT_INCONCLUSIVE} inconclusive (time limit, undecided solver), {EXIT_BAD_INPUT} bad input "
               "(unreadable file, wrong option); the same with --json")


def exit_status(interlocked) -> int:
    """The exit status of an answer: True, False or None (inconclusive)."""
    return {True: EXIT_INTERLOCKED, False: EXIT_NOT_INTERLOCKED}.get(interlocked, EXIT_INCONCLUSIVE)


def add_parser(commands) -> None:
    verify = commands.add_parser(
        "verify", help="decide whether blocks from mesh files interlock (LP + rank, Def. 3.3)",
        description="Decide whether the blocks in the given mesh files interlock with the fixed blocks as frame. "
                    "Give one file per block (numbered from 0 in the order given) or one file holding all blocks. "
                    "The frame is --fixed if given, else the one the files store (interlock generate writes it "
                    "into every format), else none; the output says which.",
        epilog="examples:\n  interlock generate wallpaper p4 --deform 0:0.25,0.1 -o p4.vtu\n"
               "  interlock verify p4.vtu                 (the frame stored in p4.vtu)\n"
               "  interlock verify p4.vtu --fixed 0-3,7   (another frame)\n"
               "  interlock verify p4.vtu && echo interlocks\n\n" + EXIT_STATUS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    verify.add_argument("paths", nargs="+", help=f"mesh files: {MESH_FORMATS}")
    verify.add_argument("--fixed", default=None, metavar="LIST",
                        help="frame: block indices, e.g. 0,1 or 0-3,7 (default: the frame stored in the file, "
                             "if any, else none)")
    verify.add_argument("--translational", action="store_true", help="translations only")
    verify.add_argument("--certify", action="store_true", help="re-check the verdict rigorously")
    verify.add_argument("--order", type=whole_number, choices=(1, 2), default=1,
                        help="2: take a verdict that is not 'interlocked' to second order and try the motion "
                             "as a finite one (default 1: first order)")
    verify.add_argument("--frames", metavar="FOLDER",
                        help="with --order 2: write a finite motion shown into FOLDER, frame by frame "
                             "(STL, and PNG with the plot extra)")
    verify.add_argument("--time-limit", type=real_number, default=None, metavar="SECONDS",
                        help="seconds for the whole command (reading the files included); past it the answer is "
                             "'inconclusive: time limit reached in <stage>' (default: no limit)")
    verify.add_argument("--json", action="store_true", help="print JSON instead of text")
    add_html_argument(verify)
    verify.set_defaults(run=run)


def run(args) -> int:
    check_frames_option(args)
    started = command_started(args)
    time_limit(args.time_limit, started)
    from interlock.verify import check
    from interlock.verify.budget import Budget

    from tqdm import tqdm

    from interlock.verify.check import STAGES

    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = load(paths, args.fixed)
    stages = [s for s in STAGES if (s != "certify" or args.certify) and (s != "beyond" or args.order == 2)]
    with tqdm(total=len(stages), desc="verify", unit="stage", disable=None, leave=False) as bar:
        def announce(stage):
            bar.set_description(f"verify: {stage}")
            bar.update(1)

        # one budget from the command's start, so that "time_limit = ..." is what the user asked for
        limit = {} if args.time_limit is None else {"time_limit": Budget(float(args.time_limit), started)}
        verdict = check(assembly, translational=args.translational, certify=args.certify, progress=announce,
                        order=args.order, **limit)
    write_html(args, assembly, verdict)
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
        record["frame_from"] = FRAME_FROM.get(assembly.info.get("frame_from"), "none")
        print(json.dumps(record, indent=2))
        return exit_status(verdict.interlocked)
    print(verdict)
    print(f"blocks: {len(assembly)}, frame: {frame_text(verdict.frame, assembly.info.get('frame_from'))}, "
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
    return exit_status(verdict.interlocked)
