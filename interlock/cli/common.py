"""What the commands share: reading block lists, numbers and mesh files, writing an assembly, the
``--time-limit`` clock."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from interlock.errors import InterlockError

EXIT_BAD_INPUT = 2
MOVING_SHOWN = 12

#: The formats ``verify``, ``stability`` and ``convert`` read (interlock.formats; any other trimesh reads).
MESH_FORMATS = ("OBJ, STL, PLY, GLB/GLTF, 3MF, OFF, VTU, XDMF, Rhino 3DM, COMPAS assembly JSON (and other formats "
                "trimesh reads); the files interlock generate writes keep their blocks and frame")


#: The suffixes ``generate -o`` and ``convert`` write (interlock.formats.FORMATS).
OUTPUT_SUFFIXES = (".stl", ".obj", ".ply", ".glb", ".3mf", ".vtu", ".xdmf", ".3dm", ".off", ".json")

#: The largest ``--exploded`` factor: blocks move by the factor times their distance from the centre, so a
#: factor of 1,000 already spreads them a thousand times wider than they are; beyond, positions overflow.
LARGEST_EXPLODED = 1000.0
#: The largest coordinate ``--deform`` takes (model units): cell lengths reach 1e30
#: (``interlock.wallpaper.lattice.LENGTH_RANGE``); products of coordinates must stay far within float64.
LARGEST_COORDINATE = 1e50


def output_arguments(parser) -> None:
    parser.add_argument("-o", "--output", required=True, metavar="FILE", type=output_file,
                        help=f"output file: {' '.join(OUTPUT_SUFFIXES)}, or .png for a picture (in a folder that "
                             "exists)")
    parser.add_argument("--exploded", type=exploded_factor, default=0.0,
                        help=f"move blocks apart by this factor, 0..{LARGEST_EXPLODED:g} (default 0)")
    parser.add_argument("--max-blocks", type=whole_number, default=None, metavar="N",
                        help="refuse to make more than N blocks (default 100,000; counted before anything is made)")


def lattice_arguments(parser) -> None:
    parser.add_argument("--a", type=real_number, default=1.0, help="cell edge a (default 1)")
    parser.add_argument("--b", type=real_number, default=None, help="cell edge b (default: a)")
    parser.add_argument("--gamma", type=real_number, default=None,
                        help="cell angle in degrees (default: the crystal system's)")


def output_file(text: str) -> str:
    """An argparse ``type`` for ``-o``: a file in a folder that exists and can be written, checked before anything
    is made (the one rule of every command: its output is created, the folders above it are not).

    >>> output_file("p4.stl")
    'p4.stl'
    """
    from interlock.files import unwritable

    problem = unwritable(text, hint=f"ending in one of {' '.join(OUTPUT_SUFFIXES)} .png")
    if problem:
        raise argparse.ArgumentTypeError(f"cannot write {text}: {problem}")
    return text


def real_number(text: str) -> float:
    """An argparse ``type``: a number written in ASCII (``float`` also reads '٢' and '０'); inf and nan pass,
    for the library to refuse with its own words.

    >>> real_number("1e-3"), real_number("inf")
    (0.001, inf)
    """
    if not text.isascii():
        raise argparse.ArgumentTypeError(f"{text!r} is not a number: write it with the digits 0-9")
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def whole_number(text: str) -> int:
    """An argparse ``type``: a whole number written with the ASCII digits 0-9 (``int`` also reads '٢', '０').

    >>> whole_number("12"), whole_number("-3")
    (12, -3)
    """
    digits = text.strip()
    if not (digits.isascii() and digits.lstrip("+-").isdigit()):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number: write it with the digits 0-9")
    return int(digits)


def length(text: str) -> float:
    """An argparse ``type`` for a length (``--height``): a finite number of size at most the largest cell length
    (``interlock.wallpaper.lattice.LENGTH_RANGE``, 1e30), so that no volume made from it overflows; its sign is
    for the library to judge.

    >>> length("0.5")
    0.5
    """
    from interlock.wallpaper.lattice import LENGTH_RANGE

    value = real_number(text)
    if not abs(value) <= LENGTH_RANGE[1]:  # nan too
        raise argparse.ArgumentTypeError(f"a length must be a finite number of size at most {LENGTH_RANGE[1]:g}, "
                                         f"got {text}")
    return value


def exploded_factor(text: str) -> float:
    """An argparse ``type`` for ``--exploded``: a number 0..:data:`LARGEST_EXPLODED`."""
    value = real_number(text)
    if not 0 <= value <= LARGEST_EXPLODED:  # nan too
        raise argparse.ArgumentTypeError(f"the factor must be a number from 0 to {LARGEST_EXPLODED:g}, got {text}")
    return value


def check_frames_option(args) -> None:
    """Check ``verify --frames FOLDER`` before any work: it needs ``--order 2`` (the frames show the finite motion
    that only the verdict beyond first order looks for, so without it they would never be written), and FOLDER
    is created but not the folders above it (the one rule of every output).

    >>> import argparse
    >>> check_frames_option(argparse.Namespace(frames="motion", order=1))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    interlock.errors.InterlockError: --frames writes the finite motion that --order 2 looks for; add --order 2 ...
    """
    frames = getattr(args, "frames", None)
    if frames is None:
        return
    if getattr(args, "order", 1) != 2:
        raise InterlockError("--frames writes the finite motion that --order 2 looks for; add --order 2 "
                             f"(or drop --frames {frames})")
    from interlock.files import unwritable

    problem = unwritable(frames, folder_output=True)
    if problem is None and Path(frames).exists() and not Path(frames).is_dir():
        problem = "it is a file, not a folder"
    if problem:
        raise InterlockError(f"cannot write the frames into {frames}: {problem}")


def command_started(args) -> float:
    """When the command began (``time.perf_counter``): the start of :func:`interlock.cli.main`, before the
    arguments were parsed, so that ``--time-limit`` bounds the whole wait; now for ``args`` made elsewhere."""
    return getattr(args, "started", None) or time.perf_counter()


def time_limit(seconds, started: float) -> float | None:
    """What is left of ``--time-limit`` (``seconds``) after what the command has spent since ``started`` (imports,
    reading the files), at least a millisecond; ``None`` without a limit.  A bad value is refused."""
    if seconds is None:
        return None
    if not seconds > 0 or math.isnan(seconds):
        raise InterlockError(f"--time-limit must be a number of seconds > 0, got {seconds:g}")
    return max(seconds - (time.perf_counter() - started), 1e-3)


#: How ``verify`` names where the frame came from (``Assembly.info["frame_from"]``).
FRAME_FROM = {"argument": "--fixed", "file": "the file", "upstream examples": "the upstream examples",
               "none": "none"}


def frame_text(frame, origin) -> str:
    """'[0, 8] (from --fixed)', '24 blocks (from the file)' or '[] (no --fixed given, none stored)'."""
    source = FRAME_FROM.get(origin, "none")
    if source == "none":
        return "[] (no --fixed given, none stored)"
    shown = str(list(frame)) if len(frame) <= MOVING_SHOWN else f"{len(frame)} blocks"
    return f"{shown} (from {source})"


def block_limit(args) -> dict:
    """``max_blocks`` for a generator, from ``--max-blocks`` (its default when not given)."""
    if args.max_blocks is None:
        return {}
    if args.max_blocks < 1:
        raise InterlockError(f"--max-blocks must be at least 1, got {args.max_blocks}")
    return {"max_blocks": args.max_blocks}


def bar_progress(bar):
    """A ``progress(done, total)`` callback that moves a tqdm bar."""
    def advance(done, total):
        bar.total = total
        bar.n = done + 1
        bar.refresh()
    return advance


def write_assembly(assembly, args) -> int:
    from pathlib import Path

    from interlock.formats import write
    from interlock.gallery import exploded, render

    from tqdm import tqdm

    if Path(args.output).suffix.lower() == ".png":
        path = render(assembly, args.output, exploded=args.exploded)
    else:
        moved = exploded(assembly, args.exploded)
        with tqdm(desc=f"writing {Path(args.output).name}", unit="block", disable=None, leave=False) as bar:
            path = write(moved, args.output, progress=bar_progress(bar))
    print(f"wrote {path}: {len(assembly)} blocks, {len(assembly.frame)} in the frame")
    return 0


def edge_points(text: str):
    """'0:0.25,0.1;0.4,0.2' -> (0, [(0.25, 0.1), (0.4, 0.2)]): an edge (ASCII digits) and at least one point of
    finite coordinates up to :data:`LARGEST_COORDINATE`.

    >>> edge_points("0:0.25,0.1;0.4,0.2")
    (0, [[0.25, 0.1], [0.4, 0.2]])
    >>> edge_points("0:")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    interlock.errors.InterlockError: cannot read --deform '0:': it gives edge 0 no point; use EDGE:X,Y[;X,Y...], ...
    """
    edge, colon, rest = text.partition(":")
    if not colon or not _ascii_digits(edge.strip()):
        raise InterlockError(f"cannot read --deform {text!r}: use EDGE:X,Y[;X,Y...], e.g. 0:0.25,0.1 "
                             "(EDGE written with the digits 0-9)")
    points = [numbers(point, float, "--deform", largest=LARGEST_COORDINATE) for point in rest.split(";")
              if point.strip()]
    if not points:
        raise InterlockError(f"cannot read --deform {text!r}: it gives edge {int(edge)} no point; use "
                             "EDGE:X,Y[;X,Y...], e.g. 0:0.25,0.1 (leave out --deform to keep an edge straight)")
    if any(len(p) != 2 for p in points):
        raise InterlockError(f"cannot read --deform {text!r}: every point needs two coordinates X,Y")
    return int(edge), points


def numbers(text: str, kind, flag: str, largest: float | None = None) -> list:
    """Comma-separated numbers of ``kind`` (int or float) written in ASCII; with ``largest``, each finite and of
    magnitude at most ``largest``.

    >>> numbers("1,2.5", float, "--tilt-axis"), numbers("3,0,1", int, "--staircase")
    ([1.0, 2.5], [3, 0, 1])
    """
    if not text.isascii():  # int() and float() read other scripts' digits ('٢', '０', ...), which no one means
        raise InterlockError(f"cannot read {flag} {text!r}: write the numbers with the digits 0-9")
    try:
        values = [kind(part) for part in text.split(",")]
    except ValueError:
        raise InterlockError(f"cannot read {flag} {text!r}: expected comma-separated numbers") from None
    if largest is not None:
        bad = [v for v in values if not abs(v) <= largest]  # nan, inf and the huge
        if bad:
            raise InterlockError(f"cannot read {flag} {text!r}: {bad[0]:g} is not a finite number of size at most "
                                 f"{largest:g}")
    return values


def axis_direction(text: str, flag: str = "--tilt-axis") -> list[float]:
    """'X,Y,Z' -> the direction of that vector, as three floats of largest magnitude 1 (so that no length of a
    huge vector overflows); a vector that is not finite, not 3 numbers or zero is refused.

    >>> axis_direction("1e308,1e308,0"), axis_direction("0,-2,0")
    ([1.0, 1.0, 0.0], [0.0, -1.0, 0.0])
    """
    values = numbers(text, float, flag)
    if len(values) != 3 or not all(math.isfinite(v) for v in values) or not any(values):
        raise InterlockError(f"cannot read {flag} {text!r}: give x, y, xy30 or a finite, non-zero vector X,Y,Z")
    largest = max(abs(v) for v in values)
    return [v / largest for v in values]




def load(paths, fixed, progress=None):
    """:func:`interlock.formats.read` with ``--fixed`` read as block indices in every format.  The library reads a
    COMPAS file's frame as node keys (what its ``is_support`` marks name); a CLI user counts blocks, as the output
    does, so for ``.json`` the indices are applied after loading."""
    from pathlib import Path

    from interlock.formats import read

    frame = None if fixed is None else indices(fixed)
    if frame is None or not isinstance(paths, (str, Path)) or Path(paths).suffix.lower() != ".json":
        return read(paths, frame=frame, progress=progress)
    assembly = read(paths, progress=progress)
    outside = [k for k in frame if k >= len(assembly)]
    if outside:
        raise InterlockError(f"--fixed names block {outside[0]}, but {Path(paths).name} holds {len(assembly)} blocks "
                             f"(indices 0-{len(assembly) - 1}; --fixed counts blocks in file order, not node keys)")
    chosen = assembly.with_frame(sorted(set(frame)))
    chosen.info["frame_from"] = "argument"
    return chosen


#: Block indices above this are refused while reading ``--fixed`` (before a range is spelled out in memory).
LARGEST_INDEX = 10_000_000


def indices(text: str) -> list[int]:
    """'0,1,4-6' -> [0, 1, 4, 5, 6]."""
    out = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        low, dash, high = (s.strip() for s in part.partition("-"))
        if not _ascii_digits(low) or (dash and not _ascii_digits(high)):
            raise InterlockError(f"cannot read block list {text!r}: use indices and ranges such as 0,1 or 0-3,7 "
                                 "(digits 0-9)")
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


def _ascii_digits(text: str) -> bool:
    """Only the digits 0-9 (``str.isdigit`` is also true of '²', '٢' and '０', which ``int`` refuses or misreads)."""
    return text.isascii() and text.isdigit()
