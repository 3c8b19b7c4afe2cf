"""One point of a sweep: build the block (or tiling) and compute its verdicts, as a plain record.

A record is a JSON-ready dict::

    {"index": 7, "parameters": {"s": 0.1}, "status": "ok" | "invalid" | "failed",
     "verdicts": {"periodic": "interlocked", "criterion_4_3": "holds", ...},
     "message": "", "tolerances": {...}, "seconds": 0.12}

"invalid" means the parameters give no valid block (a :class:`DeformationError`
or :class:`TilingError`, e.g. a self-intersecting ``F'``); "failed" means an
unexpected error at this point, whose type and text are the message.  Neither
stops a sweep.  Verdict words: "interlocked" / "not interlocked" /
"inconclusive" (periodic), "interlocked" / "not infinitesimally interlocked" /
"inconclusive" (patch: the first-order verdict of :func:`~interlock.verify.check`,
whose motion need not be a finite one), "holds" / "fails" / "inconclusive"
(criterion_4_3), "stable" / "unstable" (stability).
"""

from __future__ import annotations

import math
import time

import numpy as np

from interlock.sweep.spec import SweepSpec

__all__ = ["evaluate", "evaluate_chunk", "deformation"]

STATUSES = ("ok", "invalid", "failed")


def evaluate_chunk(spec: SweepSpec, indexed_points) -> list[dict]:
    """:func:`evaluate` for each ``(index, parameters)``: the task a worker runs."""
    return [evaluate(spec, index, parameters) for index, parameters in indexed_points]


def evaluate(spec: SweepSpec, index: int, parameters: dict) -> dict:
    """The record of one point (see the module docstring); never raises for a bad point.

    >>> from interlock.sweep.spec import load_spec
    >>> spec = load_spec({"group": "p1", "verdicts": ["criterion_4_3"],
    ...                   "parameters": {"s": {"values": [0.0, 0.1]}},
    ...                   "points": [{"edge": 0, "along": 0.5, "offset": "s"}]})
    >>> [evaluate(spec, i, p)["verdicts"] for i, p in enumerate(spec.points())]
    [{'criterion_4_3': 'fails'}, {'criterion_4_3': 'holds'}]
    """
    from interlock.blocks import DeformationError, TilingError  # the blocks load in the worker, not with the spec

    started = time.perf_counter()
    record = {"index": int(index), "parameters": dict(parameters), "status": "ok", "verdicts": {}, "message": "",
              "tolerances": {}}
    try:
        verdicts, tolerances = _verdicts(spec, parameters)
        record["verdicts"], record["tolerances"] = verdicts, tolerances
    except (DeformationError, TilingError) as error:
        record["status"], record["message"] = "invalid", str(error)
    except Exception as error:  # one bad point must not stop a sweep: it is recorded instead
        record["status"], record["message"] = "failed", f"{type(error).__name__}: {error}"
    record["seconds"] = time.perf_counter() - started
    return record


def deformation(spec: SweepSpec, parameters: dict) -> dict:
    """The Escher deformation ``{edge: [(x, y), ...]}`` of a group family at these parameter values.

    A point ``(along, offset)`` of edge ``e`` from corner ``p`` to ``q`` is
    ``p + along (q - p) + offset R(q - p)`` with ``R`` the quarter turn to the left.
    """
    from interlock import wallpaper
    from interlock.blocks import DeformationError

    group = wallpaper.group(spec.family["group"])
    corners = np.asarray(group.fundamental_domain().exterior.coords)[:-1]
    per_edge: dict[int, list] = {}
    for point in spec.family["points"]:
        edge = point["edge"]
        if edge >= len(corners):
            raise DeformationError(f"edge {edge} does not exist: {group.name}'s fundamental domain has edges "
                                   f"0..{len(corners) - 1}")
        p, q = corners[edge], corners[(edge + 1) % len(corners)]
        along, offset = (_resolve(point[key], parameters) for key in ("along", "offset"))
        left = np.array([p[1] - q[1], q[0] - p[0]])
        per_edge.setdefault(edge, []).append((along, p + along * (q - p) + offset * left))
    return {edge: [xy.tolist() for _, xy in sorted(points, key=lambda item: item[0])]
            for edge, points in per_edge.items()}


def _verdicts(spec: SweepSpec, parameters: dict) -> tuple[dict, dict]:
    from interlock.blocks import escher_block, patch, periodic_cell, random_hexagon, rhomblock_assembly
    from interlock.verify import check, criterion_4_3, periodic_check
    from interlock.verify.statics import rbe

    verdicts, tolerances = {}, {}
    if "group" in spec.family:
        from interlock import wallpaper

        group = wallpaper.group(spec.family["group"])
        block = escher_block(group, deformation(spec, parameters), _resolve(spec.family["height"], parameters))
        finite = patch(block, spec.patch_radius * math.sqrt(group.cell_area), frame="boundary") \
            if {"patch", "stability"} & set(spec.verdicts) else None
    else:
        tiling = {k: _resolve(v, parameters) for k, v in spec.family["tiling"].items() if k != "kind"}
        counts = [_whole(tiling[k], f"tiling.{k}") for k in "abc"]
        hexagon = random_hexagon(*counts, seed=_whole(tiling["seed"], "tiling.seed"))
        finite = rhomblock_assembly(hexagon, _whole(tiling["variant"], "tiling.variant"), frame="boundary")
    for name in spec.verdicts:
        if name == "periodic":
            verdict = periodic_check(periodic_cell(block))
            verdicts[name], tolerances[name] = verdict.status, dict(verdict.tolerances)
        elif name == "criterion_4_3":
            verdicts[name] = {True: "holds", False: "fails", None: "inconclusive"}[criterion_4_3(block).holds]
        elif name == "patch":
            verdict = check(finite, validate=False)
            verdicts[name] = {True: "interlocked", False: "not infinitesimally interlocked",
                              None: "inconclusive"}[verdict.interlocked]
            tolerances[name] = dict(verdict.tolerances)
        elif name == "stability":
            result = rbe(finite, spec.mu)
            verdicts[name] = "stable" if result.stable else "unstable"
            tolerances[name] = {"mu": spec.mu, "cone": result.parameters["cone"], "sides": result.parameters["sides"]}
    return verdicts, tolerances


def _resolve(value, parameters: dict) -> float:
    return float(parameters[value]) if isinstance(value, str) else float(value)


def _whole(value: float, what: str) -> int:
    from interlock.blocks import TilingError

    if not float(value).is_integer():
        raise TilingError(f"{what} must be a whole number, got {value}")
    return int(value)
