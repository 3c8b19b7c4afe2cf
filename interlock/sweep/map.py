"""Verdict maps: one picture of a design-space sweep, each parameter point coloured by its verdict."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from interlock.files import atomic_write
from interlock.sweep.spec import SweepError

__all__ = ["verdict_map", "CATEGORIES", "COLOURS"]

#: The categories of a verdict map, in legend order.
CATEGORIES = ("interlocked", "not interlocked", "inconclusive", "invalid deformation", "failed")
#: Their colours (Okabe-Ito, colour-blind safe): bluish green, vermillion, orange, grey, black.
COLOURS = ("#009E73", "#D55E00", "#E69F00", "#999999", "#000000")
# Verdict word -> category: the positive words, the negative words, "inconclusive".
_WORDS = {"interlocked": 0, "holds": 0, "stable": 0, "not interlocked": 1, "not infinitesimally interlocked": 1,
          "fails": 1, "unstable": 1, "inconclusive": 2}
_STATUS = {"invalid": 3, "failed": 4}
# Colours of the theory lines (Okabe-Ito blue, reddish purple, sky blue), cycled.
_THEORY_COLOURS = ("#0072B2", "#CC79A7", "#56B4E9")


def verdict_map(records, x: str, y: str, verdict: str = "periodic", path=None, theory=(), title=None):
    """Draw the verdict of each point of a sweep over two of its parameters.

    Each point falls in one of :data:`CATEGORIES`, coloured by :data:`COLOURS`: the positive word
    (interlocked, holds, stable), the negative word (not (infinitesimally) interlocked, fails, unstable), inconclusive,
    invalid deformation (status ``"invalid"``), failed (status ``"failed"``); the legend names the
    words that occur, with counts.  Points filling a grid in (x, y) are an image with cell edges
    halfway between grid values; other points (random samples, a grid with gaps) a scatter.

    Parameters
    ----------
    records : iterable of dict
        Sweep records with ``"parameters"`` (name -> number), ``"status"`` (``"ok"``, ``"invalid"`` or
        ``"failed"``) and ``"verdicts"`` (name -> word); ``"index"`` names a record in errors.
    x, y : str
        The parameters on the horizontal and vertical axis.
    verdict : str
        The verdict that colours the points: ``"periodic"``, ``"criterion_4_3"``, ``"patch"``, ...
    path : str or path-like, optional
        Write a PNG there (150 dpi) and return ``Path(path)`` instead of the figure.
    theory : iterable of dict
        Dashed, labelled lines: ``{"axis": "x" or "y", "value": v, "label": s}`` (x = v or y = v) or
        ``{"points": [[x0, y0], [x1, y1], ...], "label": s}`` (a polyline).
    title : str, optional
        Default ``f"{verdict} over {x}, {y} ({n} points)"``.

    Returns
    -------
    matplotlib.figure.Figure or pathlib.Path

    Raises
    ------
    SweepError
        No records, an unknown parameter or verdict, a bad status, word or theory line, an unwritable
        path, or matplotlib missing (``pip install "interlock[plot]"``).

    Examples
    --------
    >>> records = [{"index": 3 * i + j, "parameters": {"s0": 0.1 * i, "t0": 0.5 * j}, "status": "ok",
    ...             "verdicts": {"periodic": "interlocked" if i + j < 3 else "not interlocked"}}
    ...            for i in range(3) for j in range(3)]
    >>> fig = verdict_map(records, "s0", "t0")
    >>> type(fig).__name__
    'Figure'
    >>> [text.get_text() for text in fig.axes[0].get_legend().get_texts()]
    ['interlocked (6)', 'not interlocked (3)']
    """
    records = list(records)
    if not records:
        raise SweepError("no records to draw; run the sweep first")
    names = sorted({name for record in records for name in record.get("parameters", {})})
    for axis in (x, y):
        if axis not in names:
            raise SweepError(f"unknown parameter {axis!r}; the records have {', '.join(map(repr, names)) or 'none'}")
    verdicts = sorted({name for record in records for name in record.get("verdicts") or {}})
    if verdict not in verdicts and any(record.get("status") == "ok" for record in records):  # all invalid: drawn
        raise SweepError(f"no record has the verdict {verdict!r}; "
                         f"the records have {', '.join(map(repr, verdicts)) or 'none'}")
    points, kinds, words = np.empty((len(records), 2)), np.empty(len(records), int), [set() for _ in CATEGORIES]
    for i, record in enumerate(records):
        where = f"record {record.get('index', i)}"
        try:
            points[i] = float(record["parameters"][x]), float(record["parameters"][y])
        except (KeyError, TypeError, ValueError):
            raise SweepError(f"{where} has no number for parameter {x!r} or {y!r}") from None
        status = record.get("status")
        if status in _STATUS:
            kinds[i] = _STATUS[status]
            continue
        if status != "ok":
            raise SweepError(f"{where} has status {status!r}; expected 'ok', 'invalid' or 'failed'")
        word = (record.get("verdicts") or {}).get(verdict)
        if word not in _WORDS:
            raise SweepError(f"{where} has verdict {verdict!r} = {word!r}; expected one of {', '.join(_WORDS)}")
        kinds[i] = _WORDS[word]
        words[kinds[i]].add(word)
    theory = [_theory_line(line) for line in theory]

    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.colors import BoundaryNorm, ListedColormap
        from matplotlib.figure import Figure
        from matplotlib.patches import Patch
    except ImportError:
        raise SweepError('drawing a verdict map needs matplotlib; '
                         'install it with pip install "interlock[plot]"') from None
    fig = Figure(figsize=(7.0, 5.0), layout="constrained", facecolor="white")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    labels = [f"{'/'.join(sorted(words[k])) or CATEGORIES[k]} ({np.count_nonzero(kinds == k)})"
              for k in range(len(CATEGORIES))]
    present = [k for k in range(len(CATEGORIES)) if np.any(kinds == k)]
    xs, ys = np.unique(points[:, 0]), np.unique(points[:, 1])
    cells = {(px, py): kind for (px, py), kind in zip(map(tuple, points), kinds)}
    if len(xs) > 1 and len(ys) > 1 and len(records) == len(cells) == len(xs) * len(ys):
        grid = np.array([[cells[px, py] for px in xs] for py in ys])
        ax.pcolormesh(_edges(xs), _edges(ys), grid, cmap=ListedColormap(COLOURS),
                      norm=BoundaryNorm(np.arange(len(COLOURS) + 1) - 0.5, len(COLOURS)))
        handles = [Patch(facecolor=COLOURS[k], label=labels[k]) for k in present]
    else:
        handles = [ax.scatter(*points[kinds == k].T, s=24, color=COLOURS[k], label=labels[k]) for k in present]
    for n, (kind, where, label) in enumerate(theory):
        colour = _THEORY_COLOURS[n % len(_THEORY_COLOURS)]
        style = {"linestyle": "--", "linewidth": 1.5, "color": colour, "label": label}
        if kind == "points":
            handles.extend(ax.plot(*np.transpose(where), **style))
        else:
            handles.append((ax.axvline if kind == "x" else ax.axhline)(where, **style))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.set_title(f"{verdict} over {x}, {y} ({len(records)} points)" if title is None else title)
    if path is None:
        return fig
    try:
        with atomic_write(path) as temporary:  # whole or not at all (interlock.files)
            fig.savefig(temporary, format="png", dpi=150, facecolor="white")
    except OSError as error:
        raise SweepError(f"cannot write {path}: {error.strerror or error}") from None
    finally:
        fig.clf()
    return Path(path)


def _edges(values: np.ndarray) -> np.ndarray:
    """Cell edges halfway between sorted grid values, the outer cells as wide as their neighbours."""
    middle = (values[1:] + values[:-1]) / 2
    return np.concatenate([[2 * values[0] - middle[0]], middle, [2 * values[-1] - middle[-1]]])


def _theory_line(line) -> tuple:
    """A theory overlay, checked, as ("x" or "y", value, label) or ("points", [[x, y], ...], label)."""
    if not isinstance(line, dict) or not isinstance(line.get("label"), str):
        raise SweepError(f"a theory line is a dict with a string 'label', got {line!r}")
    try:
        if "points" in line:
            points = np.asarray(line["points"], float)
            if points.ndim == 2 and points.shape[1] == 2 and len(points) >= 2 and np.isfinite(points).all():
                return "points", points.tolist(), line["label"]
        elif line.get("axis") in ("x", "y") and np.isfinite(float(line["value"])):
            return line["axis"], float(line["value"]), line["label"]
    except (KeyError, TypeError, ValueError):
        pass
    raise SweepError(f"a theory line needs 'axis' ('x' or 'y') and a finite 'value', or 'points' "
                     f"[[x0, y0], [x1, y1], ...]; got {line!r}")
