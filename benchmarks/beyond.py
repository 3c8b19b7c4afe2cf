"""Cost of going beyond first order: ``check(..., order=2)`` against ``check(...)`` on the same assemblies.

Order 2 adds, to a verdict that is not "interlocked", the prestress-stability
test (``interlock.verify.second_order``) and, unless that blocks, the finite
motion along the first-order motion (``interlock.verify.motion``).  Reports
the median time of each order, their ratio (measured in the same process),
the time of the added stage, and both verdicts.
"""

from __future__ import annotations

from benchmarks.common import limited_blas, main, median_time, pyplot, save_chart, write_json
from interlock import wallpaper
from interlock.blocks import escher_block, patch, presets
from interlock.verify import check


def cases(quick: bool):
    """``(name, assembly, check keyword arguments)``."""
    pinned = presets.block_on_pins(1.0, 2.0)
    out = [("cube grid 3x3 (Ex. 3.5)", presets.cube_grid(), {}),
           ("Versatile Blocks (Ex. 3.7)", presets.versatile_blocks(), {}),
           ("block on pins, h c = 2", pinned, {}),
           ("p1, one edge deformed, one block fixed", patch(escher_block(wallpaper.group("p1"), {0: [(0.5, 0.2)]}),
                                                            radius=1.5, frame=[0]), {})]
    if not quick:
        out.append(("cube grid 7x7, ring fixed", presets.cube_grid(7, 7), {}))
    return out


def run(quick: bool = False) -> dict:
    repeats = 3 if quick else 7
    rows = []
    with limited_blas():
        for name, assembly, options in cases(quick):
            first, second = check(assembly, **options), check(assembly, order=2, **options)
            t1 = median_time(lambda: check(assembly, **options), repeats)
            t2 = median_time(lambda: check(assembly, order=2, **options), repeats)
            rows.append({"case": name, "blocks": len(assembly), "free": len(assembly) - len(first.frame),
                         "first_order": str(first).split(":")[0], "second_order": str(second).split(":")[0],
                         "first_order_seconds": t1, "order_2_seconds": t2, "ratio": t2 / t1,
                         "beyond_seconds": second.timings.get("beyond", 0.0),
                         "finite_motion_steps": None if second.finite_motion is None
                         else len(second.finite_motion.parameters)})
            print(f"{name:42s} {t1 * 1e3:8.1f} ms -> {t2 * 1e3:8.1f} ms (x{t2 / t1:5.1f})  "
                  f"{rows[-1]['first_order']} -> {rows[-1]['second_order']}", flush=True)
    payload = {"benchmark": "check order 1 vs order 2", "quick": quick, "repeats": repeats, "rows": rows}
    write_json("beyond", payload)
    _chart(rows)
    return payload


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(8, 0.7 * len(rows) + 1.5))
    y = range(len(rows))
    ax.barh([k + 0.2 for k in y], [r["first_order_seconds"] * 1e3 for r in rows], 0.4, color="#0072B2",
            label="order 1 (first-order verdict)")
    ax.barh([k - 0.2 for k in y], [r["order_2_seconds"] * 1e3 for r in rows], 0.4, color="#E69F00",
            label="order 2 (+ second order, finite motion)")
    ax.set_yticks(list(y), [f"{r['case']}\n{r['second_order']}" for r in rows], fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel("median ms per check")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Cost of going beyond first order", fontsize=10)
    fig.tight_layout()
    save_chart(fig, "beyond")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
