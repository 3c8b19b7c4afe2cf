"""``interlock view``: one offline HTML file showing an assembly in 3D with its verdicts; ``--html`` for
``verify`` and ``stability``."""

from __future__ import annotations

import argparse
import sys

from interlock.cli.common import MESH_FORMATS, command_started, load, time_limit
from interlock.errors import InterlockError

__all__ = ["add_parser", "run", "add_html_argument", "write_html"]


def add_parser(commands) -> None:
    view = commands.add_parser(
        "view", help="write an interactive 3D view of an assembly and its verdict (one offline HTML file)",
        description="Verify the assembly (and, with --stability, whether it stands) and write one self-contained "
                    "HTML file: orbit, zoom and pan; blocks coloured by class with the frame grey; the verdict in "
                    "one plain sentence; the motion of a 'not interlocked' verdict with play/pause and a slider; "
                    "contact forces or the collapse; click a block for its index, label, volume and contacts; "
                    "'Pick frame' copies a --fixed list. The file loads nothing from the network.",
        epilog="examples:\n  interlock generate wallpaper p4 --deform 0:0.25,0.1 -o p4.vtu\n"
               "  interlock view p4.vtu -o p4.html\n"
               "  interlock view cubes.stl --fixed 0-3,5-8 --order 2 -o cubes.html\n"
               "  interlock view arch.json --stability --mu 0.6 -o arch.html",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    view.add_argument("paths", nargs="+", help=f"mesh files: {MESH_FORMATS}")
    view.add_argument("-o", "--output", required=True, metavar="FILE", help="the .html file to write")
    view.add_argument("--fixed", default=None, metavar="LIST",
                      help="frame: block indices, e.g. 0,1 or 0-3,7 (default: the frame stored in the file)")
    view.add_argument("--order", type=int, choices=(1, 2), default=1,
                      help="2: take a verdict that is not 'interlocked' further and show the finite motion, if "
                           "one is shown (default 1: the first-order motion)")
    view.add_argument("--translational", action="store_true", help="translations only")
    view.add_argument("--no-verdict", dest="verdict", action="store_false",
                      help="only the blocks: do not run the interlocking verdict")
    view.add_argument("--stability", action="store_true",
                      help="also decide whether it stands under its own weight (needs --mu): forces, or the collapse")
    view.add_argument("--mu", type=float, default=None, help="friction coefficient for --stability")
    view.add_argument("--method", default="rbe", choices=("rbe", "cra"), help="--stability by rbe (default) or cra")
    view.add_argument("--title", default=None, help="the page's title (default: the file's name)")
    view.add_argument("--time-limit", type=float, default=None, metavar="SECONDS",
                      help="seconds for the verdicts (default: no limit)")
    view.set_defaults(run=run)


def run(args) -> int:
    started = command_started(args)
    time_limit(args.time_limit, started)
    if args.stability and args.mu is None:
        raise InterlockError("--stability needs the friction coefficient: give --mu, e.g. --mu 0.6")
    if args.mu is not None and not args.stability:
        raise InterlockError("--mu applies to --stability only; add --stability to see the forces")
    from pathlib import Path

    from interlock.files import unwritable

    if Path(args.output).suffix.lower() not in (".html", ".htm"):
        raise InterlockError(f"-o {args.output}: the view is an HTML file; give a name ending in .html")
    reason = unwritable(args.output)
    if reason:
        raise InterlockError(f"cannot write {args.output}: {reason}")
    paths = args.paths[0] if len(args.paths) == 1 else args.paths
    assembly = load(paths, args.fixed)
    verdict = stability = None
    found = None
    if args.verdict:
        from interlock.verify import check, contacts

        found = contacts(assembly)
        limit = {} if args.time_limit is None else {"time_limit": time_limit(args.time_limit, started)}
        verdict = check(assembly, translational=args.translational, order=args.order, contacts=found, **limit)
        print(verdict)
    if args.stability:
        stability = _stability(assembly, args, started)
        print(stability)
    title = args.title or (Path(args.paths[0]).name if len(args.paths) == 1 else f"{len(args.paths)} files")
    from interlock.gallery.view import write_view

    path = write_view(assembly, args.output, verdict, stability, title=title, contacts=found)
    print(f"wrote {path}: {len(assembly)} blocks, {len(assembly.frame if verdict is None else verdict.frame)} in "
          f"the frame, {path.stat().st_size / 1e6:.1f} MB")
    return 0


def _stability(assembly, args, started):
    if not assembly.frame:
        raise InterlockError("the assembly has no supports: give the fixed blocks with --fixed, e.g. --fixed 0,1; "
                             "without supports nothing can carry the weight")
    from interlock.verify.statics import cra, rbe

    method = cra if args.method == "cra" else rbe
    return method(assembly, args.mu, time_limit=time_limit(args.time_limit, started))


def add_html_argument(parser) -> None:
    """``--html FILE`` for ``verify`` and ``stability``: the same view as ``interlock view``."""
    parser.add_argument("--html", default=None, metavar="FILE",
                        help="also write an interactive 3D view of the assembly and this verdict to FILE (.html, "
                             "offline, one file)")


def write_html(args, assembly, result) -> None:
    """Write the view of ``--html`` (if given) for a :class:`Verdict`, :class:`StabilityResult` or
    :class:`CRAResult`, and say so on stderr (stdout stays the verdict, or JSON)."""
    if getattr(args, "html", None) is None:
        return None
    from pathlib import Path

    from interlock.gallery.view import write_view
    from interlock.verify import Verdict

    if Path(args.html).suffix.lower() not in (".html", ".htm"):
        raise InterlockError(f"--html {args.html}: the view is an HTML file; give a name ending in .html")
    is_verdict = isinstance(result, Verdict)
    title = Path(args.paths[0]).name if len(args.paths) == 1 else f"{len(args.paths)} files"
    path = write_view(assembly, args.html, result if is_verdict else None, None if is_verdict else result,
                      title=title)
    print(f"wrote {path}", file=sys.stderr)
    return path
