"""How many blocks a generator makes before it is asked to: counted first, refused above a limit the caller raises."""

from __future__ import annotations

from interlock.errors import InterlockError

__all__ = ["SizeError", "MAX_BLOCKS", "BYTES_PER_BLOCK", "check_block_count", "memory_text"]

#: The most blocks a generator (``patch``, ``random_hexagon``, ``cell_patch``) makes unless its
#: ``max_blocks`` says more (CLI: ``--max-blocks``).  Twenty times the largest assembly of the
#: benchmarks (4,800 RhomBlocks), and about 7 GB to verify (:data:`BYTES_PER_BLOCK`).
MAX_BLOCKS = 100_000
#: Memory to verify one block, measured on the 40 x 40 x 40 RhomBlock hexagon with its ring fixed (325 MB
#: above imports for 4,800 blocks; benchmarks/results/scaling.json): about 70 KB.
BYTES_PER_BLOCK = 70_000


class SizeError(InterlockError):
    """An assembly larger than the limit its generator was given (``max_blocks``, ``--max-blocks``)."""


def check_block_count(count: float, what: str, max_blocks: int = MAX_BLOCKS) -> int:
    """``count`` as an int if it is at most ``max_blocks``; else a :class:`SizeError` that says how much.

    Parameters
    ----------
    count : float
        The number of blocks (or an estimate) the generator would make.
    what : str
        What would be made, for the message (e.g. ``"a p4 patch of radius 1e+06"``).
    max_blocks : int
        The limit (an integer >= 1).

    Examples
    --------
    >>> check_block_count(300, "a 10 x 10 x 10 hexagon")
    300
    >>> check_block_count(3e6, "a 1000 x 1000 x 1000 hexagon")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    interlock.blocks.limits.SizeError: a 1000 x 1000 x 1000 hexagon would be 3,000,000 blocks (about 210 GB ...
    """
    if isinstance(max_blocks, bool) or not isinstance(max_blocks, int) or max_blocks < 1:
        raise SizeError(f"max_blocks must be an integer >= 1, got {max_blocks!r}")
    count = float(count)  # a Python float: a numpy one past 1e308 would warn on the way
    if not count <= max_blocks:  # NaN and inf too
        shown = f"{count:,.0f}" if count < 1e15 else f"{count:.2g}"
        raise SizeError(f"{what} would be {shown} blocks (about {memory_text(count * BYTES_PER_BLOCK)} to verify), "
                        f"more than the limit of {max_blocks:,}; make it smaller, or raise the limit "
                        "(max_blocks=..., CLI --max-blocks)")
    return int(count)


def memory_text(size: float) -> str:
    """A number of bytes in words: ``'210 GB'``.

    >>> memory_text(3.5e5), memory_text(2.9e13)
    ('350 KB', '29 TB')
    """
    for unit in ("B", "KB", "MB", "GB", "TB", "PB"):
        if size < 1000 or unit == "PB":
            return f"{size:.3g} {unit}" if size < 1e4 else f"{size:.2g} {unit}"
        size /= 1000
    raise AssertionError("unreachable")
