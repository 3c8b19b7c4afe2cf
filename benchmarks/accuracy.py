"""Speed against accuracy: every verdict method on a labelled set of periodic assemblies.

Data set (seeded, reproducible)
    * Escher blocks in p1, p2, p3, p4 and p6 (:func:`escher_case`): random
      lattices where the group allows (p1, p2: ``b`` in [0.7, 1.3],
      ``gamma`` in [60, 120] degrees), random heights, one or two points pushed
      off each deformable edge pair, and each pair left undeformed with
      probability ``SKIP`` -- so some blocks are partly undeformed and some
      fail Criterion 4.3.  Case ``(group, seed)`` draws from
      ``numpy.random.default_rng([seed, GROUPS.index(group)])``.
    * RhomBlock periodic cells ``rhomblock_assembly(staircase(counts), variant)``
      (:func:`rhomblock_case`) for every gcd-reduced ``counts`` with entries
      0..3 (49 staircases) and both variants.

Each assembly is asked two questions: translational interlocking (blocks may
only translate) and full interlocking (translations and rotations), both for
motions of finite support of the infinite assembly.

Labels come only from what is proven (:func:`label`), with their source:
    1. p1, translations: Criterion 4.3 (Thm. 4.7: interlocked iff it holds);
    2. any group, Criterion 4.3 fails: "not interlocked" (a finite set H of
       blocks lifts out), for both questions;
    3. RhomBlocks, full question: "interlocked" (Thm. 4.9);
    4. otherwise the certified periodic verdict, when it is certified;
    5. anything else is unlabelled: counted, left out of every share.

Methods, each timed once per verdict with ``time.perf_counter`` (BLAS limited
to one thread, as ``periodic_check`` does itself; see ``BLAS_THREADS``):
    * ``patch r`` (r = 1..6): ``check(cell_patch(cell, r), validate=False)``,
      the translates with ``max(|a|, |b|) <= r`` free inside a fixed ring.  A
      motion is a finite-support motion of the infinite assembly (a proof of
      "not interlocked"); "interlocked" is only a guess for the infinite
      assembly, correct when the label agrees.  Radii 1 and 2 run on every
      assembly, radii 3..6 on ``deep_per_family`` cases of each family (the
      first seeds of each group, RhomBlock cells spread over the list); an
      assembly stops growing once one patch check takes longer than
      ``CAP_SECONDS`` (the radii left out are counted as skipped).
    * ``periodic``: ``periodic_check(cell)`` (patches of radius 1, 2 as its
      fallback).
    * ``criterion 4.3`` (translational question, Escher blocks only):
      interlocked iff ``criterion_4_3(block).holds``.
    * ``certified``: ``periodic_check(cell, certify=True)``; an uncertified
      verdict counts as inconclusive.
Where a method is the source of a label its verdict is correct by
construction (criterion on p1 and on failing blocks, certified on rule 4);
the other cases cross-check it.

Reading the chart: one panel per question; x is the median seconds per
verdict (log axis), y the share of labelled verdicts that are correct (filled
markers) and, at the same x, the share that is inconclusive (hollow markers).
Inconclusive is never counted as correct; what is neither is wrong.  Patch
radii are joined by a line and marked r=1..6.  ``benchmarks/results/accuracy.json``
lists every wrong verdict with the call that reproduces it.
"""

from __future__ import annotations

import itertools
import math
import statistics
import time
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from benchmarks.common import main, pyplot, save_chart, write_json
from interlock import wallpaper
from interlock.blocks import DeformationError, cell_patch, escher_block, periodic_cell, rhomblock_assembly, staircase
from interlock.verify import check, criterion_4_3, periodic_check

GROUPS = ("p1", "p2", "p3", "p4", "p6")
FAMILIES = GROUPS + ("rhomblock",)
QUESTIONS = ("translational", "full")
#: Probability that a deformable edge pair is left undeformed.
SKIP = 0.35
#: An assembly stops growing its patch once one patch check takes longer than this.
CAP_SECONDS = 10.0
#: Threads of the BLAS during every timed call (periodic_check limits itself to one as well).
BLAS_THREADS = 1
INTERLOCKED, NOT_INTERLOCKED, INCONCLUSIVE = "interlocked", "not interlocked", "inconclusive"


@dataclass(frozen=True)
class Settings:
    """The size of a run: Escher cases per group, RhomBlock cells (None: all), patch radii."""

    escher_per_group: int
    rhomblocks: int | None
    radii: tuple[int, ...]
    deep_per_family: int  # cases per family that also get the radii beyond SHALLOW_RADIUS


SHALLOW_RADIUS = 2
FULL = Settings(escher_per_group=45, rhomblocks=None, radii=(1, 2, 3, 4, 5, 6), deep_per_family=6)
QUICK = Settings(escher_per_group=3, rhomblocks=4, radii=(1, 2), deep_per_family=0)


@dataclass(frozen=True)
class Case:
    """One periodic assembly of the data set: its cell, its Escher block (None for RhomBlocks), how to rebuild it."""

    family: str
    seed: int
    cell: object
    block: object
    parameters: dict
    reproduce: str
    deep: bool = False


# --- the data set ---------------------------------------------------------------------------------


def escher_case(name: str, seed: int, skip: float = SKIP) -> Case:
    """The random Escher block ``seed`` of group ``name`` and its periodic cell (reproducible from the two)."""
    rng = np.random.default_rng([seed, GROUPS.index(name)])
    lattice = {}
    if name in ("p1", "p2"):
        lattice = {"b": float(rng.uniform(0.7, 1.3)), "gamma": float(rng.uniform(60.0, 120.0))}
    group = wallpaper.group(name, **lattice)
    for _ in range(100):
        deformation = _random_deformation(group, rng, skip)
        height = float(rng.uniform(0.5, 2.0))
        try:
            block = escher_block(group, deformation, height=height)
        except DeformationError:
            continue
        parameters = {"group": name, **lattice, "height": height,
                      "deformation": {int(e): np.asarray(p).tolist() for e, p in deformation.items()}}
        return Case(name, seed, periodic_cell(block), block, parameters,
                    f"from benchmarks.accuracy import escher_case; case = escher_case({name!r}, {seed})")
    raise RuntimeError(f"no valid random deformation of {name} for seed {seed}")


def _random_deformation(group, rng, skip: float) -> dict:
    """One or two points pushed 3-20 % of the edge length off each deformable edge pair kept (probability 1 - skip)."""
    corners = np.asarray(group.fundamental_domain().exterior.coords)
    deformation = {}
    for s in group.side_pairings():
        if s.partner < s.edge or s.self_paired:
            continue
        m = int(rng.integers(1, 3))
        along = (np.arange(1, m + 1) + rng.uniform(-0.3, 0.3, m)) / (m + 1)  # increasing, inside (0, 1)
        offsets = rng.choice([-1.0, 1.0], m) * rng.uniform(0.03, 0.2, m)
        if rng.random() < skip:  # drawn after the points, so skipping does not shift the stream
            continue
        p, q = corners[s.edge], corners[s.edge + 1]
        normal = np.array([q[1] - p[1], p[0] - q[0]])
        deformation[s.edge] = p + along[:, None] * (q - p) + offsets[:, None] * normal
    return deformation


def staircases() -> list[tuple[int, int, int]]:
    """Every ``(n0, n1, n2)`` with entries 0..3, not all zero, over their gcd (as ``staircase`` reduces them)."""
    reduced = set()
    for counts in itertools.product(range(4), repeat=3):
        if max(counts):
            g = math.gcd(*counts)
            reduced.add(tuple(c // g for c in counts))
    return sorted(reduced, key=lambda c: (sum(c), c))


def rhomblock_case(counts, variant: int, seed: int = 0) -> Case:
    """The periodic RhomBlock cell of the staircase ``counts`` (main paper Thm. 4.9)."""
    counts = tuple(int(c) for c in counts)
    return Case("rhomblock", seed, rhomblock_assembly(staircase(counts), variant), None,
                {"counts": list(counts), "variant": int(variant)},
                f"from benchmarks.accuracy import rhomblock_case; case = rhomblock_case({counts}, {variant})")


def data_set(settings: Settings) -> list[Case]:
    """Every case of a run, Escher blocks first; the first ``deep_per_family`` of each family get every radius."""
    cases = []
    for name in GROUPS:
        for seed in range(settings.escher_per_group):
            case = escher_case(name, seed)
            cases.append(_deep(case, seed < settings.deep_per_family))
    rhombs = [(c, v) for c in staircases() for v in (0, 1)]
    chosen = _spread(len(rhombs), settings.rhomblocks)
    deep = set(_spread(len(chosen), settings.deep_per_family))
    for k, index in enumerate(chosen):
        cases.append(_deep(rhomblock_case(*rhombs[index], seed=index), k in deep))
    return cases


def _deep(case: Case, deep: bool) -> Case:
    return Case(case.family, case.seed, case.cell, case.block, case.parameters, case.reproduce, deep)


def _spread(n: int, k: int | None) -> list[int]:
    """``k`` indices spread evenly over ``range(n)`` (all of them when ``k`` is None or at least ``n``)."""
    if k is None or k >= n:
        return list(range(n))
    if k <= 0:
        return []
    return sorted({round(i * (n - 1) / max(k - 1, 1)) for i in range(k)})


# --- labels and scores ----------------------------------------------------------------------------


def label(family: str, question: str, criterion_holds: bool | None, certified: tuple[str, bool] | None):
    """The proven answer for one assembly and question, and its source; ``(None, "unlabelled")`` when nothing is proven.

    ``criterion_holds`` is Criterion 4.3 for an Escher block (None for RhomBlocks);
    ``certified`` is the ``(status, certified)`` of ``periodic_check(..., certify=True)``.

    >>> label("p1", "translational", True, ("inconclusive", False))
    ('interlocked', 'Criterion 4.3 holds (Thm. 4.7)')
    >>> label("p4", "full", False, ("interlocked", True))[0]
    'not interlocked'
    >>> label("p4", "full", True, ("interlocked", False))
    (None, 'unlabelled')
    """
    if family == "p1" and question == "translational" and criterion_holds is not None:
        return (INTERLOCKED, "Criterion 4.3 holds (Thm. 4.7)") if criterion_holds else \
            (NOT_INTERLOCKED, "Criterion 4.3 fails (Thm. 4.7)")
    if criterion_holds is False:
        return NOT_INTERLOCKED, "Criterion 4.3 fails: a finite set H of blocks lifts out"
    if family == "rhomblock" and question == "full":
        return INTERLOCKED, "Thm. 4.9 (periodic RhomBlock tiling)"
    if certified is not None and certified[1] and certified[0] in (INTERLOCKED, NOT_INTERLOCKED):
        return certified[0], "certified periodic verdict"
    return None, "unlabelled"


def score(verdict: str, truth: str | None) -> str | None:
    """"correct", "wrong" or "inconclusive" (never correct) against a label; None when there is no label.

    >>> score("interlocked", "not interlocked"), score("inconclusive", "interlocked"), score("interlocked", None)
    ('wrong', 'inconclusive', None)
    """
    if truth is None:
        return None
    if verdict == INCONCLUSIVE:
        return INCONCLUSIVE
    return "correct" if verdict == truth else "wrong"


def _from_bool(interlocked: bool | None) -> str:
    return {True: INTERLOCKED, False: NOT_INTERLOCKED, None: INCONCLUSIVE}[interlocked]


# --- running the methods --------------------------------------------------------------------------


def _timed(fn):
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


def _patch_verdicts(cell, translational: bool, radii) -> tuple[list[dict], list[int]]:
    """``check`` on patches of growing radius until one takes longer than CAP_SECONDS; (verdicts, skipped radii)."""
    out = []
    for k, r in enumerate(radii):
        verdict, seconds = _timed(lambda: check(cell_patch(cell, r), translational=translational, validate=False))
        out.append({"method": f"patch r={r}", "radius": r, "verdict": _from_bool(verdict.interlocked),
                    "seconds": seconds})
        if seconds > CAP_SECONDS:
            return out, list(radii[k + 1:])
    return out, []


def study(case: Case, question: str, radii, criterion) -> dict:
    """Every method's verdict and time for one case and question, with the label and each verdict's score."""
    translational = question == "translational"
    radii = [r for r in radii if case.deep or r <= SHALLOW_RADIUS]
    records, skipped = _patch_verdicts(case.cell, translational, radii)
    periodic, seconds = _timed(lambda: periodic_check(case.cell, translational=translational))
    records.append({"method": "periodic", "verdict": periodic.status, "seconds": seconds})
    if translational and criterion is not None:
        holds = criterion[0].holds
        verdict = INCONCLUSIVE if holds is None else INTERLOCKED if holds else NOT_INTERLOCKED
        records.append({"method": "criterion 4.3", "verdict": verdict, "seconds": criterion[1]})
    certified, seconds = _timed(lambda: periodic_check(case.cell, translational=translational, certify=True))
    records.append({"method": "certified", "verdict": certified.status if certified.certified else INCONCLUSIVE,
                    "seconds": seconds, "status": certified.status, "reason": certified.reason})
    truth, source = label(case.family, question, None if criterion is None else criterion[0].holds,
                          (certified.status, certified.certified))
    for record in records:
        record["score"] = score(record["verdict"], truth)
        record["seconds"] = round(record["seconds"], 6)  # microseconds
    return {"family": case.family, "seed": case.seed, "question": question, "label": truth, "source": source,
            "verdicts": records, "skipped": [f"patch r={r}" for r in skipped]}


def _warm_up() -> None:
    """One untimed pass through every method, so imports and first-call costs do not land in the first case."""
    case = escher_case("p4", 0)
    criterion_4_3(case.block)
    for question in QUESTIONS:
        study(case, question, (1,), (criterion_4_3(case.block), 0.0))


# --- summaries ------------------------------------------------------------------------------------


def method_order(radii) -> list[str]:
    return [f"patch r={r}" for r in radii] + ["periodic", "criterion 4.3", "certified"]


def summarise(studies: list[dict], radii) -> dict:
    """Per question and method: verdicts, median seconds, correct / wrong / inconclusive (labelled only), skipped."""
    out = {}
    for question in QUESTIONS:
        rows = {}
        for method in method_order(radii):
            found = [v for s in studies if s["question"] == question for v in s["verdicts"] if v["method"] == method]
            skipped = sum(method in s["skipped"] for s in studies if s["question"] == question)
            if not found:
                continue
            scores = [v["score"] for v in found if v["score"] is not None]
            rows[method] = {"verdicts": len(found), "median_seconds": statistics.median(v["seconds"] for v in found),
                            "labelled": len(scores), "correct": scores.count("correct"),
                            "wrong": scores.count("wrong"), "inconclusive": scores.count(INCONCLUSIVE),
                            "skipped_over_cap": skipped}
            for key in ("correct", "wrong", "inconclusive"):
                rows[method][f"{key}_share"] = rows[method][key] / len(scores) if scores else None
        out[question] = rows
    return out


def composition(cases: list[Case], studies: list[dict]) -> dict:
    """Cases per family, and per question labels by family and by source."""
    out = {"cases": {f: sum(c.family == f for c in cases) for f in FAMILIES},
           "deep_cases": {f: sum(c.family == f and c.deep for c in cases) for f in FAMILIES}}
    for question in QUESTIONS:
        mine = [s for s in studies if s["question"] == question]
        by_family = {}
        for f in FAMILIES:
            labels = [s["label"] or "unlabelled" for s in mine if s["family"] == f]
            by_family[f] = {name: labels.count(name) for name in (INTERLOCKED, NOT_INTERLOCKED, "unlabelled")}
        sources = {}
        for s in mine:
            sources[s["source"]] = sources.get(s["source"], 0) + 1
        out[question] = {"by_family": by_family, "by_source": sources}
    return out


def wrong_verdicts(studies: list[dict], cases: list[Case]) -> list[dict]:
    """Every wrong verdict with the case, the label and its source, and how to reproduce it."""
    reproduce = {(c.family, c.seed): c.reproduce for c in cases}
    out = []
    for s in studies:
        for v in s["verdicts"]:
            if v["score"] == "wrong":
                out.append({"family": s["family"], "seed": s["seed"], "question": s["question"],
                            "method": v["method"], "verdict": v["verdict"], "label": s["label"], "source": s["source"],
                            "reproduce": reproduce[(s["family"], s["seed"])]})
    return out


def notable(studies: list[dict], cases: list[Case]) -> list[dict]:
    """The studies with an unlabelled question or a verdict that is not correct: each method's verdict and seconds."""
    cells = {(c.family, c.seed): c for c in cases}
    out = []
    for s in studies:
        if s["label"] is None or any(v["score"] != "correct" for v in s["verdicts"]):
            case = cells[(s["family"], s["seed"])]
            drawn = {k: v for k, v in case.parameters.items() if k != "deformation"}  # rebuilt by `reproduce`
            out.append({"family": s["family"], "seed": s["seed"], "question": s["question"], "label": s["label"],
                        "source": s["source"], **drawn, "verdicts": {v["method"]: v["verdict"] for v in s["verdicts"]},
                        "certified": next({"status": v["status"], "reason": v["reason"]} for v in s["verdicts"]
                                          if v["method"] == "certified"),
                        "reproduce": case.reproduce})
    return out


# --- the benchmark --------------------------------------------------------------------------------


def run(quick: bool = False) -> dict:
    settings = QUICK if quick else FULL
    start = time.perf_counter()
    with threadpool_limits(BLAS_THREADS, "blas"):
        cases = data_set(settings)
        _warm_up()
        studies = []
        for family in FAMILIES:
            mine = [c for c in cases if c.family == family]
            begun = time.perf_counter()
            for case in mine:
                criterion = _timed(lambda: criterion_4_3(case.block)) if case.block is not None else None
                studies += [study(case, question, settings.radii, criterion) for question in QUESTIONS]
            print(f"{family}: {len(mine)} cases in {time.perf_counter() - begun:.1f} s")
    summary = summarise(studies, settings.radii)
    wrong = wrong_verdicts(studies, cases)
    payload = {"benchmark": "speed against accuracy on labelled periodic assemblies", "quick": quick,
               "settings": {"escher_per_group": settings.escher_per_group, "rhomblocks": settings.rhomblocks,
                            "radii": list(settings.radii), "all_cases_up_to_radius": SHALLOW_RADIUS,
                            "deep_per_family": settings.deep_per_family, "skip": SKIP, "cap_seconds": CAP_SECONDS,
                            "blas_threads": BLAS_THREADS, "timing": "one timed call per verdict, after one "
                            "untimed warm-up case; medians over the verdicts of a method"},
               "assemblies": len(cases), "labelled": {q: sum(s["label"] is not None for s in studies
                                                             if s["question"] == q) for q in QUESTIONS},
               "composition": composition(cases, studies), "methods": summary, "wrong": wrong,
               "seconds": time.perf_counter() - start,
               "notable": notable(studies, cases)}
    payload["edge_contact"] = run_edge_contacts(quick)
    _report(summary, wrong, payload)
    write_json("accuracy", payload)
    _chart(summary, len(cases), payload["labelled"], settings, sum(c.deep for c in cases))
    return payload


def _report(summary: dict, wrong: list[dict], payload: dict) -> None:
    for question, rows in summary.items():
        print(f"{question} ({payload['labelled'][question]} labelled of {payload['assemblies']}):")
        for method, row in rows.items():
            print(f"  {method:14s} {row['verdicts']:4d} verdicts, median {1000 * row['median_seconds']:8.1f} ms: "
                  f"{row['correct']} correct, {row['wrong']} wrong, {row['inconclusive']} inconclusive"
                  + (f", {row['skipped_over_cap']} skipped (cap)" if row["skipped_over_cap"] else ""))
    for w in wrong:
        print(f"WRONG: {w['family']} seed {w['seed']} {w['question']} {w['method']}: {w['verdict']}, "
              f"label {w['label']} ({w['source']})")
    print(f"{payload['assemblies']} assemblies in {payload['seconds']:.1f} s")


def _chart(summary: dict, assemblies: int, labelled: dict, settings: Settings, deep: int) -> None:
    plt = pyplot()
    if plt is None:
        return
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.4), sharex=True, sharey=True)
    colours = {"patch": "C0", "periodic": "C1", "criterion 4.3": "C2", "certified": "C3"}
    handles = {}
    for ax, question in zip(axes, QUESTIONS):
        rows = summary[question]
        patches = [(m, rows[m]) for m in method_order(settings.radii) if m.startswith("patch") and m in rows
                   and rows[m]["labelled"]]
        if patches:
            xs = [r["median_seconds"] for _, r in patches]
            handles["patch, correct"], = ax.plot(xs, [r["correct_share"] for _, r in patches], "o-",
                                                 color=colours["patch"])
            handles["patch, inconclusive"], = ax.plot(xs, [r["inconclusive_share"] for _, r in patches], "o--",
                                                      color=colours["patch"], markerfacecolor="none")
            for k, (method, r) in enumerate(patches):
                ax.annotate(method.split()[1], (r["median_seconds"], r["correct_share"]), textcoords="offset points",
                            xytext=(-8, -15 if k % 2 == 0 else 8), fontsize=8, color=colours["patch"])
        for method, marker in (("periodic", "s"), ("criterion 4.3", "D"), ("certified", "^")):
            r = rows.get(method)
            if r is None or not r["labelled"]:
                continue
            handles[f"{method}, correct"], = ax.plot(r["median_seconds"], r["correct_share"], marker,
                                                     color=colours[method], markersize=9)
            handles[f"{method}, inconclusive"], = ax.plot(r["median_seconds"], r["inconclusive_share"], marker,
                                                          color=colours[method], markersize=9, markerfacecolor="none")
        wrong = [f"{m}: {r['wrong']}" for m, r in rows.items() if r["wrong"]]
        ax.text(0.98, 0.3, "wrong verdicts\n" + ("\n".join(wrong) if wrong else "none"), transform=ax.transAxes,
                ha="right", va="center", fontsize=8, bbox={"boxstyle": "round", "facecolor": "white", "alpha": 0.8})
        ax.set_xscale("log")
        ax.set_ylim(-0.04, 1.08)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("median seconds per verdict (log)")
        ax.set_title(f"{question} interlocking ({labelled[question]} labelled verdicts)")
    seconds = [r["median_seconds"] for rows in summary.values() for r in rows.values() if r["labelled"]]
    if seconds:  # from a whole decade, so that a labelled major tick shows
        axes[0].set_xlim(10.0 ** math.floor(math.log10(min(seconds) / 1.5)), 2 * max(seconds))
    axes[0].xaxis.set_minor_formatter(plt.NullFormatter())
    axes[0].set_ylabel("share of labelled verdicts: filled correct, hollow inconclusive")
    axes[0].legend(handles.values(), handles.keys(), fontsize=7, loc="center left")
    deep_radii = [r for r in settings.radii if r > SHALLOW_RADIUS]
    note = f"patch radii {deep_radii[0]}..{deep_radii[-1]} on {deep} of them; " if deep_radii else ""
    fig.suptitle(f"Speed against accuracy: {assemblies} periodic assemblies (p1-p6 Escher blocks, RhomBlock cells)\n"
                 f"{note}wrong = neither correct nor inconclusive; unlabelled verdicts left out",
                 fontsize=10)
    save_chart(fig, "accuracy")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)


# --- the edge-contact family (issue 38): finite assemblies held by edges and corners ----------------------
#
# Blocks that touch along edges and at corners (main paper Remark 3.11): the tetrahedra layers of Fig. 5, the
# tetrahedral-octahedral honeycomb layer, and one tetrahedron held by seven edge-edge contacts only.  Labels,
# again only from what is proven:
#     * Fig. 5a with its red frame: "interlocked" (the main paper, [11, 6]);
#     * the held tetrahedron: "interlocked" by its seven rows written out in numpy (a positive stress on rows of
#       rank 6, Stiemke's lemma), independent of the package;
#     * "not interlocked" where the verdict's motion is a translation of each moving block that manifold3d finds
#       free of overlap at five distances up to the model size (checked here, not by the package);
#     * "interlocked" where ``check(..., certify=True)`` certifies it (an exact positive self-stress on the
#       rows of every contact type);
#     * anything else unlabelled.
# Methods: ``check`` with every contact type (the default), with ``contacts="faces"`` (Def. 3.3 alone), and the
# default at ``order=2``.

#: Radii of the tetrahedra layers (lattice units) and of the honeycomb layer (edge lengths).
EDGE_TETRAHEDRA_RADII = (1.0, 1.5, 2.0, 2.5)
EDGE_HONEYCOMB_RADII = (1.0, 1.5, 2.0, 3.0)
#: The held tetrahedron: (axis, side, s) of each small holder (tests/verify/test_point_contacts.py).
HELD_TETRAHEDRON = ((0, 1, -0.45), (0, -1, 0.03), (1, 1, 0.39), (1, -1, -0.46), (2, 1, 0.35), (2, -1, 0.31),
                    (0, 1, 0.44))
#: A translation witness: distances (fractions of the model size) and the overlap allowed (of the smaller block).
WITNESS_STEPS = (1e-3, 1e-2, 0.1, 0.3, 1.0)
WITNESS_OVERLAP = 1e-6
EDGE_METHODS = ("all types", "faces only", "all types, order 2")


def edge_contact_cases(quick: bool = False) -> list[dict]:
    """The family's assemblies: name, how to rebuild it, and a label fixed in advance (or None)."""
    from interlock.blocks import presets

    radii = EDGE_TETRAHEDRA_RADII[:2] if quick else EDGE_TETRAHEDRA_RADII
    cases = []
    for r in radii:
        cases.append({"name": f"tetrahedra p4 r={r} red frame", "build": lambda r=r: presets.tetrahedra("p4", r),
                      "reproduce": f"presets.tetrahedra('p4', {r})", "label": INTERLOCKED,
                      "source": "main paper Fig. 5a (red frame)"})
        for group in ("p4", "p3", "p6"):
            cases.append({"name": f"tetrahedra {group} r={r} ring", "reproduce":
                          f"presets.tetrahedra({group!r}, {r}, frame='boundary')",
                          "build": lambda r=r, g=group: presets.tetrahedra(g, r, frame="boundary"), "label": None})
    for r in (EDGE_HONEYCOMB_RADII[:2] if quick else EDGE_HONEYCOMB_RADII):
        cases.append({"name": f"honeycomb r={r} ring", "build": lambda r=r: presets.honeycomb_layer(r),
                      "reproduce": f"presets.honeycomb_layer({r})", "label": None})
    held, stress_ok = _held_tetrahedron(HELD_TETRAHEDRON)
    cases.append({"name": "tetrahedron held by 7 edges", "build": lambda: held, "reproduce": "HELD_TETRAHEDRON",
                  "label": INTERLOCKED if stress_ok else None,
                  "source": "rows written out in numpy: a positive stress on 7 rows of rank 6"})
    for k in range(len(HELD_TETRAHEDRON)):
        fewer = HELD_TETRAHEDRON[:k] + HELD_TETRAHEDRON[k + 1:]
        cases.append({"name": f"tetrahedron held by 6 edges (holder {k} removed)",
                      "build": lambda fewer=fewer: _held_tetrahedron(fewer)[0],
                      "reproduce": f"HELD_TETRAHEDRON without holder {k}", "label": None})
    return cases


def run_edge_contacts(quick: bool = False) -> dict:
    """The edge-contact family: every method on every case, labels, scores; writes accuracy_edge_contacts.json."""
    rows = []
    for case in edge_contact_cases(quick):
        assembly = case["build"]()
        verdicts = {}
        for method in EDGE_METHODS:
            kwargs = {"contacts": "faces"} if method == "faces only" else {}
            if method.endswith("order 2"):
                kwargs["order"] = 2
            verdict, seconds = _timed(lambda: check(assembly, **kwargs))
            verdicts[method] = (verdict, seconds)
        truth, source = case["label"], case.get("source", "unlabelled")
        if truth is None:
            truth, source = _edge_label(assembly, verdicts["all types"][0], verdicts["all types, order 2"][0])
        rows.append({"case": case["name"], "reproduce": case["reproduce"], "blocks": len(assembly),
                     "label": truth, "source": source,
                     "verdicts": [{"method": m, "verdict": _from_bool(v.interlocked), "seconds": t,
                                   "score": score(_from_bool(v.interlocked), truth), "status": str(v)[:300]}
                                  for m, (v, t) in verdicts.items()]})
    summary = {}
    for method in EDGE_METHODS:
        scores = [v["score"] for r in rows for v in r["verdicts"] if v["method"] == method]
        summary[method] = {name: scores.count(name) for name in ("correct", "wrong", INCONCLUSIVE)}
        summary[method]["unlabelled"] = scores.count(None)
        summary[method]["median_seconds"] = statistics.median(v["seconds"] for r in rows for v in r["verdicts"]
                                                              if v["method"] == method)
    for method, row in summary.items():
        print(f"edge-contact {method:20s}: {row['correct']} correct, {row['wrong']} wrong, "
              f"{row[INCONCLUSIVE]} inconclusive, {row['unlabelled']} unlabelled, median "
              f"{1000 * row['median_seconds']:.0f} ms")
    wrong = [dict(r, verdicts=[v for v in r["verdicts"] if v["score"] == "wrong"]) for r in rows
             if any(v["score"] == "wrong" for v in r["verdicts"])]
    payload = {"family": "edge-contact", "quick": quick, "cases": rows, "summary": summary,
               "wrong": [{"case": r["case"], "methods": [v["method"] for v in r["verdicts"]]} for r in wrong]}
    write_json("accuracy_edge_contacts" + ("_quick" if quick else ""), payload)
    return {"summary": summary, "cases": len(rows)}


def _edge_label(assembly, verdict, beyond) -> tuple[str | None, str]:
    """A label proven here: a translation witness checked by booleans (the first-order motion, or the one the
    order-2 verdict followed), or the certified verdict; else none."""
    followed = None if beyond.finite_motion is None or not beyond.finite_motion.shown else beyond.finite_motion.twists
    for motion in (verdict.motion, followed):
        if verdict.interlocked is False and motion is not None and _translation_witness(assembly, motion):
            return NOT_INTERLOCKED, "a translation of the moving blocks, free of overlap at 5 distances (manifold3d)"
    certified = check(assembly, certify=True)
    if certified.interlocked is True and certified.certified:
        return INTERLOCKED, "certified verdict with every contact type (exact positive self-stress)"
    return None, "unlabelled"


def _translation_witness(assembly, motion) -> bool:
    """Whether moving each block by ``s t_b`` (no turn) keeps every pair apart, for the steps of WITNESS_STEPS."""
    import manifold3d

    motion = np.asarray(motion, dtype=float)
    if np.abs(motion[:, :3]).max() > 1e-12 or not np.abs(motion[:, 3:]).max() > 0:
        return False
    size = assembly.scale / float(np.abs(motion[:, 3:]).max())
    meshes = assembly.world_meshes()

    def solid(mesh, shift):
        return manifold3d.Manifold(manifold3d.Mesh(np.asarray(mesh.vertices + shift, np.float32),
                                                   np.asarray(mesh.faces, np.uint32)))

    moving = np.flatnonzero(np.abs(motion[:, 3:]).max(axis=1) > 0)
    for step in WITNESS_STEPS:
        solids = [solid(m, step * size * motion[b, 3:]) for b, m in enumerate(meshes)]
        for i in moving:
            for j in range(len(meshes)):
                if j == i or (j in moving and j < i):
                    continue
                volume = (solids[i] ^ solids[j]).volume()
                if volume > WITNESS_OVERLAP * min(meshes[i].volume, meshes[j].volume):
                    return False
    return True


def _held_tetrahedron(holders):
    """The regular tetrahedron of the cube [-1, 1]^3 and small fixed tetrahedra whose edges cross its edges; and
    whether its rows, written out here, admit a positive stress with rank 6 (so that it is interlocked)."""
    import trimesh

    from interlock.blocks import Assembly

    corners = np.array([(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)], dtype=float)
    faces = [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)]

    def outward(vertices):
        out = []
        for face in faces:
            a, b, c = vertices[list(face)]
            other = vertices[[k for k in range(4) if k not in face][0]]
            out.append(face if np.cross(b - a, c - a) @ (a - other) > 0 else face[::-1])
        return trimesh.Trimesh(vertices, out, process=False)

    meshes, rows = [outward(corners.copy())], []
    for axis, side, s in holders:
        centre = np.array([1.3, s - 0.1, s + 0.1] if side > 0 else [-1.3, s - 0.1, -s - 0.1])
        turn = np.roll(np.eye(3), axis, axis=0)
        meshes.append(outward((corners * 0.3 + centre) @ turn.T))
        point = turn @ (np.array([1, s, s]) if side > 0 else np.array([-1, s, -s]))
        normal = turn @ np.array([-side, 0.0, 0.0])
        rows.append(np.r_[np.cross(point, normal), normal])  # the held block's row at the crossing
    A = np.array(rows)
    stress = np.linalg.svd(A.T)[2][-1]
    positive = np.linalg.matrix_rank(A) == 6 and len(A) > 6 and (np.all(stress > 0) or np.all(stress < 0))
    return Assembly.from_meshes(meshes, frame=list(range(1, len(meshes)))), bool(positive)
