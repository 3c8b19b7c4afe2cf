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
