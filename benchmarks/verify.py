"""The finite verifier on real data: the TopoLite bunny (80 parts, 0 and 1 fixed) against a naive baseline.

Three ways to the same verdict, each timed as the median of several runs in
the same process (so that their ratio means something on a shared machine),
with the median seconds of each stage, the BLAS on one thread
(:data:`benchmarks.common.BLAS_THREADS`):

- ``check`` without overlap validation (contacts, matrix, rank, LP);
- ``check`` with it (the default);
- the naive baseline (:func:`benchmarks.common.naive_verdict`): contacts over
  all pairs of blocks, the same matrix, a dense ``numpy.linalg.matrix_rank``
  and HiGHS on ``max t : A^T w = 0, w_i >= t, t <= 1``.

How the stages grow with the number of blocks is ``benchmarks/scaling.py``.
"""

from __future__ import annotations


import statistics
import time

from benchmarks.common import (BLAS_THREADS, NAIVE_STAGES, REFERENCE_DATA, limited_blas, main, naive_verdict, pyplot,
                               save_chart, write_json)
from interlock.formats import read
from interlock.verify import check

BUNNY = REFERENCE_DATA / "topolite" / "bunny"
BUNNY_PARTS = 80
FRAME = (0, 1)
#: The stages drawn, in order (validation only in the validated run).
STAGES = ("validate", *NAIVE_STAGES)


def run(quick: bool = False) -> dict:
    if not BUNNY.is_dir():
        print(f"skipping the bunny: {BUNNY} is absent")
        return {}
    repeats = 1 if quick else 7
    bunny = read([BUNNY / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)], frame=FRAME)
    verdicts = {}

    def ours(validate: bool):
        def one() -> dict:  # a fresh copy each run: nothing cached from the run before
            verdicts[validate] = check(bunny.with_frame(FRAME), validate=validate)
            return verdicts[validate].timings
        return one

    def naive() -> dict:
        verdicts["naive"], seconds = naive_verdict(bunny)
        return seconds

    rows = []
    with limited_blas():
        for method, fn in (("check (contacts -> verdict)", ours(False)), ("check with overlap validation", ours(True)),
                           ("naive: all pairs, dense rank, LP max t", naive)):
            seconds, stages = _median_runs(fn, repeats, warm_up=not quick)
            rows.append({"method": method, "median_seconds": seconds, "median_stage_seconds": stages})
            print(f"{method:40s} {seconds:.3f} s (median of {repeats}; "
                  + ", ".join(f"{k} {v:.3f}" for k, v in stages.items()) + ")")
    base = rows[-1]["median_seconds"]
    for row in rows:
        row["speedup_vs_naive"] = base / row["median_seconds"]
    result = {
        "benchmark": "verify_bunny",
        "blocks": len(bunny),
        "frame": list(FRAME),
        "verdict": str(verdicts[False]),
        "naive_verdict_interlocked": bool(verdicts["naive"]),
        "agrees": bool(verdicts["naive"]) == verdicts[False].interlocked,
        "repeats": repeats,
        "blas_threads": BLAS_THREADS,
        "rows": rows,
    }
    write_json("verify", result)
    _chart(rows)
    return result


def _median_runs(fn, repeats: int, warm_up: bool = True) -> tuple[float, dict]:
    """(median wall seconds, median seconds per stage) over ``repeats`` runs of ``fn``, after one more to warm up.

    ``fn`` returns the seconds of each of its stages.
    """
    if warm_up:
        fn()
    totals, stages = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        stages.append(fn())
        totals.append(time.perf_counter() - start)
    return statistics.median(totals), {k: statistics.median(s[k] for s in stages) for k in stages[0]}


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(9, 2.8))
    names = [r["method"] for r in rows]
    left = [0.0] * len(rows)
    for k, stage in enumerate(STAGES):
        widths = [r["median_stage_seconds"].get(stage, 0.0) for r in rows]
        ax.barh(names, widths, left=left, color=f"C{k}", label=stage)
        left = [a + b for a, b in zip(left, widths)]
    for y, r in enumerate(rows):
        ax.text(max(left[y], r["median_seconds"]), y, f"  {r['median_seconds']:.2f} s (median)", va="center",
                fontsize=8)
    ax.set_xlim(0, 1.3 * max(left + [r["median_seconds"] for r in rows]))
    ax.set_xlabel("seconds, median per stage (TopoLite bunny, 80 parts, 0 and 1 fixed)")
    ax.invert_yaxis()
    ax.legend(fontsize=7, loc="upper right", ncol=len(STAGES))
    save_chart(fig, "verify")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
