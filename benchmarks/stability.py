"""Stability under self-weight side by side with compas_cra 0.8: RBE, CRA and the interlocking verdict.

The assemblies are compas_cra's own sample files (``tests/data/compas_cra``)
with the supports and parameters of the upstream examples:

- the wedges ``type-a`` … ``type-d`` of the CRA paper's Table 2, tilted about
  x, y and xy30 = (√3, 1, 0) at μ = 0.20 and 0.84, scanned every 10° (30° quick);
- the models ``H`` and ``A`` (unstable in reality, RBE says stable), the
  ``shelf`` (unstable, Fig. 7) and ``shelf-stable``, the ``cubes`` and the
  ``bridge``, upright only (the paper's statements are about 0°).

Per case and angle: the verdicts of our :func:`~interlock.verify.statics.rbe`
and ``cra`` (``interlock.verify.cra``, guarded until it exists), the
interlocking verdict of :func:`~interlock.verify.check` (gravity-free: an
interlocked assembly carries any load, a not interlocked one is not claimed
stable), and, when ``compas_cra`` imports (a separate benchmark environment,
``benchmarks/requirements-compare.txt``; never a dependency of interlock),
upstream's ``rbe_solve`` and ``cra_solve``.  A solve that raises upstream counts
as "unstable"; upstream's RBE allows tension at a penalty, so it says "stable"
when its tension is at most :data:`TENSION_RTOL` of the free weight.

Upstream tilts by rotating the assembly about the origin under gravity
(0, 0, -1); ours turns gravity the other way (``tilted_gravity``).  The two are
checked to agree on one case by rotating our assembly too.

Times are per solve with the contacts given (upstream: interfaces computed),
the median of several, BLAS on one thread; ratio = upstream / ours.  Targets:
a wedge solve ≤ 50 ms, the 38-block arch ≤ 1 s, RBE on the 399-block
armadillo vault ≤ 10 s, CRA on it ≤ 60 s (issue 24).

The armadillo (CRA paper, Table 5: stable, CRA 2,424 s) is solved with our
default interfaces (:func:`~interlock.verify.statics.interfaces.interfaces`),
with exact contacts and with upstream's ``tmax``; upstream's ``cra_solve`` is
stopped after :data:`ARMADILLO_CRA_LIMIT` seconds.  ``cra_scaling`` records CRA's
time per upright solve against the block count (wedges, H, A, shelves, cubes,
bridge, arch, armadillo), ours and upstream, for the chart's second panel.

``exported``: our arch and a re-exported sample written by ``interlock.write(...,
"x.json")`` (COMPAS assembly JSON), solved by compas_cra from that file alone
and by us from the same file read back (issue 23).
"""

from __future__ import annotations

import contextlib
import inspect
import io
import math
import statistics
import time
from dataclasses import dataclass, field

import numpy as np
import trimesh

from benchmarks.common import (BLAS_THREADS, REFERENCE_DATA, limited_blas, main, pyplot, results_folder, save_chart,
                               write_json)
import interlock
from interlock.formats.compas import UPSTREAM_SUPPORTS
from interlock.verify import check, contacts
from interlock.verify.statics import TILT_AXES, rbe, tilted_gravity
from interlock.verify.statics.interfaces import interfaces

DATA = REFERENCE_DATA / "compas_cra"
#: Table 2 of the CRA paper: critical tilt (degrees) by (wedge, axis), as (3DEC, CRA, RBE) at mu 0.20 and 0.84.
TABLE2 = {
    ("type-a", "x"): ((21.8, 21.8, 25.0), (59.2, 59.2, 180.0)),
    ("type-a", "y"): ((71.3, 71.3, 71.3), (100.0, 100.0, 180.0)),
    ("type-a", "xy30"): ((24.8, 24.7, 28.0), (62.7, 62.9, 180.0)),
    ("type-b", "x"): ((21.8, 21.8, 25.0), (58.7, 58.5, 180.0)),
    ("type-b", "y"): ((67.4, 67.4, 67.4), (109.1, 109.1, 180.0)),
    ("type-b", "xy30"): ((24.8, 24.7, 28.0), (63.1, 62.0, 180.0)),
    ("type-c", "x"): ((13.0, 13.0, 13.0), (44.1, 44.1, 47.0)),
    ("type-c", "y"): ((41.3, 41.3, 41.3), (64.5, 64.4, 65.7)),
    ("type-c", "xy30"): ((14.9, 14.9, 15.0), (48.1, 40.2, 51.0)),
    ("type-d", "x"): ((13.0, 13.0, 13.0), (44.1, 44.1, 50.0)),
    ("type-d", "y"): ((41.3, 41.3, 41.3), (70.0, 70.0, 70.0)),
    ("type-d", "xy30"): ((14.9, 14.9, 15.0), (49.0, 48.5, 54.0)),
}
MUS = (0.20, 0.84)
#: Angles this close (degrees) to a reference critical angle are not judged (the paper rounds to 0.1°, we scan).
BORDER = 2.5
#: Upstream RBE (penalty form) is "stable" when its total tension is at most this fraction of the free weight.
TENSION_RTOL = 1e-3
#: Upstream interface detection as in its examples: wedges, H, A, cubes / shelf, bridge.
COARSE = {"nmax": 10, "amin": 1e-2, "tmax": 1e-2}
FINE = {"amin": 1e-6, "tmax": 1e-4}
#: Timing targets (seconds) of issue 9.
TARGETS = {"wedge solve": 0.05, "38-block arch": 1.0, "armadillo RBE": 10.0, "armadillo CRA": 60.0}
#: Upstream's interface detection for the armadillo (absolute, model units), and the angle our contacts allow.
ARMADILLO_TMAX, ARMADILLO_AMIN, ARMADILLO_ANGLE = 0.05, 1e-4, 0.2
#: Seconds after which our RBE on the armadillo with upstream's gap is stopped (10 x the target).
ARMADILLO_LIMIT = 100.0
#: Seconds after which upstream's cra_solve on the armadillo is stopped (the paper: 2,424 s, Table 5).
ARMADILLO_CRA_LIMIT = 1800.0
#: The CRA paper's time for the armadillo (Table 5, seconds).
ARMADILLO_PAPER_CRA = 2424.0


@dataclass
class Case:
    """One row: an assembly, a friction coefficient and a tilt axis (None: upright only)."""

    name: str
    stem: str
    mu: float
    axis: str | None = None
    critical: float | None = None     # 3DEC (reference): stable below this tilt
    paper_cra: float | None = None
    paper_rbe: float | None = None    # the paper's RBE critical tilt
    upright: bool | None = None       # reference verdict at 0 degrees (non-wedges)
    paper_rbe_upright: bool | None = None
    density: dict = field(default_factory=dict)  # node key -> density (others 1)
    interfaces: dict = field(default_factory=lambda: dict(COARSE))
    cra_options: dict = field(default_factory=dict)

    def reference(self, angle: float) -> bool | None:
        """The paper's verdict (3DEC / reality) at ``angle``, None where it says nothing or too close to call."""
        if self.critical is not None:
            if self.critical >= 180.0:
                return True
            return None if abs(angle - self.critical) < BORDER else angle < self.critical
        return self.upright if angle == 0 else None

    def paper_rbe_verdict(self, angle: float) -> bool | None:
        if self.paper_rbe is not None:
            if self.paper_rbe >= 180.0:
                return True
            return None if abs(angle - self.paper_rbe) < BORDER else angle < self.paper_rbe
        return self.paper_rbe_upright if angle == 0 else None


def cases(quick: bool) -> list[Case]:
    wedges = []
    for (stem, axis), columns in TABLE2.items():
        for mu, (dec, cra_angle, rbe_angle) in zip(MUS, columns):
            wedges.append(Case(f"{stem} {axis} μ{mu:.2f}", stem, mu, axis, dec, cra_angle, rbe_angle,
                               cra_options={"d_bnd": 1e-2}))
    others = [
        Case("H μ0.84", "H", 0.84, upright=False, paper_rbe_upright=True),
        Case("A μ0.84", "A", 0.84, upright=False, paper_rbe_upright=True),
        Case("shelf μ0.90", "shelf", 0.9, upright=False, paper_rbe_upright=True, interfaces=dict(FINE),
             cra_options={"d_bnd": 0.1, "eps": 1e-3}),
        Case("shelf-stable μ0.90", "shelf-stable", 0.9, upright=True, interfaces=dict(FINE),
             cra_options={"d_bnd": 0.1, "eps": 1e-3}),
        Case("cubes μ0.84", "cubes", 0.84),
        Case("bridge μ0.90", "bridge", 0.9, density={k: 3.51 for k in range(11, 16)}, interfaces=dict(FINE),
             cra_options={"d_bnd": 0.1, "eps": 0.0}),
    ]
    if quick:
        keep = ("type-c x μ0.84", "type-a y μ0.20", "H μ0.84")
        return [c for c in wedges + others if c.name in keep]
    return wedges + others


def run(quick: bool = False) -> dict:
    if not DATA.is_dir():
        print(f"skipping stability: {DATA} is absent")
        return {}
    angles = [0.0, 30.0, 60.0, 90.0] if quick else [float(a) for a in range(0, 181, 10)]
    repeats = 1 if quick else 5
    upstream, upstream_reason = _upstream()
    ours_cra, cra_reason = _ours_cra()
    cra_limit = 3.0 if quick else None  # seconds per MILP where ``cra`` takes a time_limit
    notes = []
    if upstream is None:
        notes.append(f"compas_cra not compared: {upstream_reason}")
    if ours_cra is None:
        notes.append(f"our CRA not run: {cra_reason}")
    elif cra_limit is not None and "time_limit" in inspect.signature(ours_cra).parameters:
        notes.append(f"quick run: our cra with time_limit={cra_limit} s (inconclusive past it)")
    rows = []
    with limited_blas():
        for case in cases(quick):
            rows.append(_run_case(case, angles, ours_cra, cra_limit, upstream))
        equivalence = _tilt_equivalence(angles, rows)
        scaling = []
        timing, targets = _timing(rows, repeats, ours_cra, cra_limit, upstream, quick, notes, scaling)
    payload = {
        "benchmark": "stability side by side with compas_cra",
        "quick": quick,
        "compas_cra": None if upstream is None else upstream["about"],
        "compas_cra_reason": upstream_reason,
        "our_cra": ours_cra is not None,
        "our_cra_reason": cra_reason,
        "angles": angles,
        "repeats": repeats,
        "blas_threads": BLAS_THREADS,
        "tension_rtol": TENSION_RTOL,
        "border_degrees": BORDER,
        "cases": rows,
        "agreement": _agreement(rows),
        "against_reference": _against_reference(rows),
        "rbe_vs_paper_rbe": _rbe_vs_paper(rows),
        "tilt_equivalence": equivalence,
        "timing": timing,
        "targets": targets,
        "cra_scaling": scaling,
        "armadillo": dict(_ARMADILLO),
        "exported": exported_side_by_side(upstream, quick),
        "notes": notes,
    }
    _print_summary(payload)
    write_json("stability", payload)
    _chart(payload)
    return payload


# --- one case ---------------------------------------------------------------------------

def _load(case: Case):
    assembly = interlock.read(DATA / f"{case.stem}.json")
    density = np.array([case.density.get(label, 1.0) for label in assembly.labels])
    return assembly, (float(density[0]) if np.all(density == density[0]) else density)


def _run_case(case: Case, angles, ours_cra, cra_limit, upstream) -> dict:
    assembly, density = _load(case)
    found = contacts(assembly)
    verdict = check(assembly)
    interlocked = verdict.interlocked
    scan = angles if case.axis is not None else [0.0]
    records = []
    for angle in scan:
        gravity = tilted_gravity(case.axis or "x", angle)
        record = {"angle": angle, "reference": case.reference(angle), "paper_rbe": case.paper_rbe_verdict(angle),
                  "interlocked": interlocked, "seconds": {}}
        start = time.perf_counter()
        record["rbe"] = bool(rbe(assembly, case.mu, density=density, gravity=gravity, contacts=found).stable)
        record["seconds"]["rbe"] = time.perf_counter() - start
        if ours_cra is not None:
            start = time.perf_counter()
            record["cra"] = _cra_verdict(ours_cra, assembly, case.mu, density, gravity, found, cra_limit)
            record["seconds"]["cra"] = time.perf_counter() - start
        if upstream is not None:
            tilted = _upstream_assembly(upstream, case, angle)
            for method in ("rbe", "cra"):
                start = time.perf_counter()
                record[f"upstream_{method}"], record[f"upstream_{method}_message"] = \
                    _upstream_solve(upstream, method, tilted, case)
                record["seconds"][f"upstream_{method}"] = time.perf_counter() - start
        records.append(record)
    line = " ".join(f"{r['angle']:.0f}:{_mark(r.get('rbe'))}{_mark(r.get('cra'))}"
                    + (f"/{_mark(r['upstream_rbe'])}{_mark(r['upstream_cra'])}" if upstream else "") for r in records)
    print(f"{case.name:22s} {line}", flush=True)
    return {"name": case.name, "stem": case.stem, "mu": case.mu, "axis": case.axis, "blocks": len(assembly),
            "frame": list(assembly.frame), "contacts": len(found), "density": case.density or 1.0,
            "reference_critical_3dec": case.critical, "paper_cra_critical": case.paper_cra,
            "paper_rbe_critical": case.paper_rbe, "reference_upright": case.upright,
            "interlocked": interlocked, "interlocking_status": verdict.status,
            "upstream_interfaces": dict(case.interfaces), "upstream_cra_options": dict(case.cra_options),
            "first_unstable": {m: next((r["angle"] for r in records if r.get(m) is False), None)
                               for m in ("rbe", "cra", "upstream_rbe", "upstream_cra")},
            "verdicts": records}


def _mark(value) -> str:
    return {True: "S", False: "u", None: "?"}.get(value, "-")


def _cra_verdict(ours_cra, assembly, mu, density, gravity, found, cra_limit):
    options = {}
    if cra_limit is not None and "time_limit" in inspect.signature(ours_cra).parameters:
        options["time_limit"] = cra_limit
    result = ours_cra(assembly, mu, density=density, gravity=gravity, contacts=found, **options)
    return None if result.stable is None else bool(result.stable)


def _tilt_equivalence(angles, rows) -> dict:
    """Our RBE with turned gravity vs our RBE on the assembly turned about the origin (upstream's tilt).

    Also the largest difference between ``tilted_gravity`` and ``R^T (0, 0, -1)``, and upstream's
    verdicts on the same case where the scan has them.
    """
    stem, axis, mu = "type-c", "xy30", 0.84
    assembly, _ = _load(Case("", stem, mu))
    scanned = {r["angle"]: r for row in rows if row["name"] == f"{stem} {axis} μ{mu:.2f}" for r in row["verdicts"]}
    out, difference = [], 0.0
    for angle in angles:
        turn = trimesh.transformations.rotation_matrix(math.radians(angle), TILT_AXES[axis], [0, 0, 0])
        difference = max(difference, float(np.abs(turn[:3, :3].T @ [0, 0, -1] - tilted_gravity(axis, angle)).max()))
        turned = type(assembly).from_meshes([m.copy().apply_transform(turn) for m in assembly.world_meshes()],
                                            frame=assembly.frame, labels=assembly.labels)
        record = {"angle": angle, "assembly_turned": bool(rbe(turned, mu).stable),
                  "gravity_turned": bool(rbe(assembly, mu, gravity=tilted_gravity(axis, angle)).stable)}
        if "upstream_rbe" in scanned.get(angle, {}):
            record["upstream_rbe"] = scanned[angle]["upstream_rbe"]
        out.append(record)
    agree = sum(r["gravity_turned"] == r["assembly_turned"] == r.get("upstream_rbe", r["assembly_turned"])
                for r in out)
    print(f"tilt equivalence ({stem} {axis} μ{mu}): {agree}/{len(out)} angles agree; "
          f"gravity differs by {difference:.1e}")
    return {"case": f"{stem} {axis} μ{mu:.2f}", "agree": agree, "compared": len(out),
            "gravity_max_difference": difference, "rows": out}


# --- summaries --------------------------------------------------------------------------

def _agreement(rows) -> dict:
    """Ours against upstream, per method: counts and the disagreeing (case, angle)."""
    out = {}
    for method in ("rbe", "cra"):
        pairs = [(row["name"], r["angle"], r.get(method), r.get(f"upstream_{method}")) for row in rows
                 for r in row["verdicts"] if f"upstream_{method}" in r and method in r]
        decided = [p for p in pairs if p[2] is not None]
        disagree = [{"case": c, "angle": a, "ours": o, "upstream": u} for c, a, o, u in decided if o != u]
        out[method] = {"compared": len(pairs), "decided": len(decided), "agree": len(decided) - len(disagree),
                       "ours_inconclusive": len(pairs) - len(decided), "disagree": disagree}
    return out


def _against_reference(rows) -> dict:
    """Per method: right / unsafe (says stable, reference unstable) / conservative / inconclusive."""
    out = {}
    for method in ("rbe", "cra", "interlocked", "upstream_rbe", "upstream_cra"):
        tally = {"judged": 0, "right": 0, "unsafe": [], "conservative": [], "inconclusive": 0}
        for row in rows:
            for r in row["verdicts"]:
                if r["reference"] is None or method not in r:
                    continue
                said = r[method]
                tally["judged"] += 1
                if method == "interlocked":  # sufficient only: not interlocked claims nothing
                    said = True if said else None
                if said is None:
                    tally["inconclusive"] += 1
                elif said == r["reference"]:
                    tally["right"] += 1
                else:
                    tally["unsafe" if said else "conservative"].append({"case": row["name"], "angle": r["angle"]})
        if tally["judged"]:
            out[method] = tally
    return out


def _rbe_vs_paper(rows) -> dict:
    """Our RBE against the paper's RBE column (Table 2) and its statements on H, A and the shelf."""
    compared, mismatches = 0, []
    for row in rows:
        for r in row["verdicts"]:
            if r["paper_rbe"] is not None:
                compared += 1
                if r["rbe"] != r["paper_rbe"]:
                    mismatches.append({"case": row["name"], "angle": r["angle"], "ours": r["rbe"],
                                       "paper": r["paper_rbe"]})
    return {"compared": compared, "mismatches": mismatches}


# --- timing -----------------------------------------------------------------------------

def _median_seconds(fn, repeats: int, slow: float = 2.0) -> tuple[float, int]:
    """(median seconds, runs) of ``fn()``: the first run counts; past ``slow`` seconds no more are made."""
    first = _seconds(fn)
    if repeats <= 1 or first > slow:
        return first, 1
    times = [first] + [_seconds(fn) for _ in range(repeats - 1)]
    return statistics.median(times), len(times)


def _seconds(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _timing(rows, repeats, ours_cra, cra_limit, upstream, quick, notes, scaling):
    """Timing rows (ours vs upstream, median per solve) and the issue's targets; ``scaling`` receives CRA's
    upright solves by block count."""
    table, targets = [], []
    scan = [r for row in rows if row["axis"] for r in row["verdicts"]]
    for method in ("rbe", "cra"):
        ours = [r["seconds"][method] for r in scan if method in r["seconds"]]
        theirs = [r["seconds"][f"upstream_{method}"] for r in scan if f"upstream_{method}" in r["seconds"]]
        if not ours:
            continue
        table.append(_timing_row(f"wedge scan, {method} per solve (median of {len(ours)})", method,
                                 statistics.median(ours), statistics.median(theirs) if theirs else None))
        for verdict, word in ((True, "stable"), (False, "unstable")):
            # where both say the same (ours alone without upstream): proving stable and unstable cost differently
            same = [r for r in scan if r.get(method) is verdict and r.get(f"upstream_{method}", verdict) is verdict]
            if not same:
                continue
            seconds = statistics.median(r["seconds"][method] for r in same)
            theirs = [r["seconds"][f"upstream_{method}"] for r in same if f"upstream_{method}" in r["seconds"]]
            table.append(_timing_row(f"wedge scan, {method} per solve, {word} verdicts (median of {len(same)})",
                                     method, seconds, statistics.median(theirs) if theirs else None))
            targets.append(_target("wedge solve", f"our {method}, median per solve over the wedge scans' {word} "
                                   f"verdicts", seconds))
    # upright solves, median of repeats
    for row in [] if quick else rows:  # quick: the scan's times are enough
        if row["axis"] not in (None, "x"):
            continue  # upright is the same for every axis: one row per wedge and mu
        case = next(c for c in cases(quick) if c.name == row["name"])
        assembly, density = _load(case)
        found = contacts(assembly)
        up = _upstream_assembly(upstream, case, 0.0) if upstream is not None else None
        for method in ("rbe", "cra"):
            if method == "rbe":
                def ours():
                    rbe(assembly, case.mu, density=density, contacts=found)
            elif ours_cra is not None:
                def ours():
                    _cra_verdict(ours_cra, assembly, case.mu, density, (0.0, 0.0, -1.0), found, cra_limit)
            else:
                ours = None
            ours_s = _median_seconds(ours, repeats) if ours else (None, 0)
            theirs_s = (_median_seconds(lambda: _upstream_solve(upstream, method, up, case), repeats)
                        if up is not None else (None, 0))
            table.append(_timing_row(f"{row['name'].replace(' x ', ' ')} upright, {method}", method, ours_s[0],
                                     theirs_s[0], ours_s[1], theirs_s[1]))
            if method == "cra":
                upright = row["verdicts"][0]
                scaling.append({"case": row["name"].replace(" x ", " "), "blocks": row["blocks"],
                                "ours_seconds": ours_s[0], "ours": upright.get("cra"),
                                "upstream_seconds": theirs_s[0], "upstream": upright.get("upstream_cra")})
    targets += _arch(repeats, ours_cra, upstream, quick, table, notes, scaling)
    targets += _armadillo(repeats, upstream, ours_cra, quick, table, notes, scaling)
    return table, targets


def _timing_row(what, method, ours, theirs, ours_runs=None, theirs_runs=None) -> dict:
    row = {"what": what, "method": method, "ours_seconds": ours, "upstream_seconds": theirs,
           "ratio_upstream_over_ours": (theirs / ours) if (ours and theirs) else None}
    if ours_runs is not None:
        row["runs"] = {"ours": ours_runs, "upstream": theirs_runs}
    return row


def _target(name, what, seconds, timed_out: bool = False) -> dict:
    limit = TARGETS[name]
    return {"target": name, "what": what, "limit_seconds": limit, "seconds": seconds,
            "met": False if timed_out else None if seconds is None else bool(seconds <= limit)}


def _arch(repeats, ours_cra, upstream, quick, table, notes, scaling) -> list:
    try:
        from interlock.blocks import semicircular_arch
    except ImportError:
        notes.append("interlock.blocks.semicircular_arch does not exist yet: arch target skipped")
        return []
    arch = semicircular_arch()  # 36 voussoirs, t / r = 0.15, 2 supports: the paper's "arch thick"
    mu = math.tan(math.radians(43.0))
    start = time.perf_counter()
    found = contacts(arch)
    contact_seconds = time.perf_counter() - start
    out = []
    rbe_s, runs = _median_seconds(lambda: rbe(arch, mu, contacts=found), repeats)
    end_to_end = contact_seconds + rbe_s
    up = _upstream_from_meshes(upstream, arch, mu) if upstream is not None else None
    theirs = _median_seconds(lambda: _upstream_solve(upstream, "rbe", up, None, mu=mu), repeats)[0] if up else None
    table.append(_timing_row(f"arch {len(arch)} blocks upright, rbe (contacts {contact_seconds:.3f} s apart)",
                             "rbe", rbe_s, theirs))
    out.append(_target("38-block arch", f"our rbe, {len(arch)} blocks, contacts + solve", end_to_end))
    if ours_cra is not None and not quick:
        cra_s, _ = _median_seconds(lambda: _cra_verdict(ours_cra, arch, mu, 1.0, (0, 0, -1), found, None), repeats)
        theirs = _median_seconds(lambda: _upstream_solve(upstream, "cra", up, None, mu=mu), repeats)[0] \
            if up else None
        table.append(_timing_row(f"arch {len(arch)} blocks upright, cra", "cra", cra_s, theirs))
        said = _cra_verdict(ours_cra, arch, mu, 1.0, (0, 0, -1), found, None)
        scaling.append({"case": f"arch ({len(arch) - 2} voussoirs)", "blocks": len(arch), "ours_seconds": cra_s,
                        "ours": said, "upstream_seconds": theirs,
                        "upstream": _upstream_solve(upstream, "cra", up, None, mu=mu)[0] if up else None})
        out.append(_target("38-block arch", f"our cra, {len(arch)} blocks, contacts + solve", contact_seconds + cra_s))
    return out


def _armadillo(repeats, upstream, ours_cra, quick, table, notes, scaling) -> list:
    """The 399-block armadillo vault (Table 5): contacts, RBE and CRA, ours with the default interfaces, exact
    contacts and upstream's gap; upstream's rbe_solve and cra_solve (stopped after ARMADILLO_CRA_LIMIT)."""
    if quick:
        return []
    assembly = interlock.read(DATA / "armadillo.json")
    rows = {}

    def ours(find):
        start = time.perf_counter()
        found = find()
        middle = time.perf_counter()
        result = rbe(assembly, 0.84, contacts=found)
        return {"contacts": len(result.contacts), "contact_seconds": middle - start,
                "rbe_seconds": time.perf_counter() - middle, "stable": bool(result.stable),
                "friction_utilisation": float(result.friction_utilisation) if result.stable else None}

    # our defaults: the interfaces of every pair (docs/statics.md, "Interfaces"), timed as medians
    found = interfaces(assembly)
    interface_s, interface_runs = _median_seconds(lambda: interfaces(assembly), min(repeats, 3), slow=30.0)
    rbe_result = rbe(assembly, 0.84, contacts=found)
    rbe_s, rbe_runs = _median_seconds(lambda: rbe(assembly, 0.84, contacts=found), min(repeats, 3), slow=30.0)
    default = {"contacts": len(rbe_result.contacts), "pairs": found.to_dict()["pairs"],
               "contact_seconds": interface_s, "contact_runs": interface_runs, "rbe_seconds": rbe_s,
               "rbe_runs": rbe_runs, "stable": bool(rbe_result.stable),
               "friction_utilisation": float(rbe_result.friction_utilisation), "interfaces": found.to_dict()}
    if ours_cra is not None:
        said = {}

        def solve_cra():
            said["result"] = ours_cra(assembly, 0.84, contacts=found)
        default["cra_seconds"], default["cra_runs"] = _median_seconds(solve_cra, min(repeats, 3), slow=120.0)
        result = said["result"]
        default["cra"] = result.status
        default["cra_message"] = result.message
        default["cra_timings"] = {k: v for k, v in result.timings.items() if k != "contacts"}
    rows["default interfaces"] = default
    rows["exact contacts"] = ours(lambda: contacts(assembly))
    # upstream's absolute tmax and amin relative to the model size; it tests no angle, and the armadillo's
    # facing faces are up to 0.16 rad apart (tests/verify/test_contacts.py)
    options = {"gap": ARMADILLO_TMAX / assembly.scale, "area_rtol": ARMADILLO_AMIN / assembly.scale ** 2,
               "angle_tol": ARMADILLO_ANGLE}
    rows["upstream's gap"] = _capped(lambda: ours(lambda: contacts(assembly, **options)), ARMADILLO_LIMIT) \
        or {"timed_out": ARMADILLO_LIMIT}
    notes.append(f"armadillo contacts with gap={options['gap']:.4g} (upstream tmax {ARMADILLO_TMAX} / scale), "
                 f"area_rtol={options['area_rtol']:.3g} (amin {ARMADILLO_AMIN}), angle_tol={ARMADILLO_ANGLE}; "
                 f"our RBE stopped after {ARMADILLO_LIMIT:.0f} s if unfinished")
    for name, row in rows.items():
        notes.append(f"armadillo ours ({name}): " + ", ".join(
            f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()
            if not isinstance(v, dict) and k != "cra_message"))
    theirs, upstream_record = None, None
    if upstream is not None:
        case = Case("armadillo", "armadillo", 0.84, interfaces={"tmax": ARMADILLO_TMAX, "amin": ARMADILLO_AMIN})
        start = time.perf_counter()
        up = _upstream_assembly(upstream, case, 0.0)
        interface_seconds = time.perf_counter() - start
        said = {}

        def solve():
            said["rbe"] = _upstream_solve(upstream, "rbe", up, None, mu=0.84)
        theirs = _median_seconds(solve, min(repeats, 3), slow=30.0)[0]
        count = sum(len(up.graph.edge_attribute(e, "interfaces")) for e in up.graph.edges())

        def solve_cra():
            start = time.perf_counter()
            stable, message = _upstream_solve(upstream, "cra", up, None, mu=0.84)
            return {"stable": stable, "message": message, "seconds": time.perf_counter() - start}
        cra_record = _capped(solve_cra, ARMADILLO_CRA_LIMIT) or {"timed_out": ARMADILLO_CRA_LIMIT}
        upstream_record = {"interfaces": count, "pairs": up.graph.number_of_edges(),
                           "interface_seconds": interface_seconds, "rbe_seconds": theirs,
                           "rbe_stable": said["rbe"][0], "cra": cra_record}
        notes.append(f"armadillo upstream: {count} interfaces ({up.graph.number_of_edges()} pairs) in "
                     f"{interface_seconds:.1f} s, rbe_solve stable={said['rbe'][0]} ({said['rbe'][1]}); "
                     f"cra_solve: {cra_record}")
    scaling.append({"case": "armadillo (Table 5)", "blocks": len(assembly),
                    "ours_seconds": default.get("cra_seconds"),
                    "ours": {"stable": True, "unstable": False}.get(default.get("cra")),
                    "upstream_seconds": (upstream_record["cra"].get("seconds", upstream_record["cra"].get("timed_out"))
                                         if upstream_record else None),
                    "upstream": (upstream_record["cra"].get("stable") if upstream_record else None),
                    "upstream_timed_out": bool(upstream_record and "timed_out" in upstream_record["cra"]),
                    "paper_seconds": ARMADILLO_PAPER_CRA})
    target = []
    for name, row in rows.items():
        seconds = row["rbe_seconds"] if "rbe_seconds" in row else None
        size = f"{row['contacts']} contacts" if "contacts" in row else f"stopped after {ARMADILLO_LIMIT:.0f} s"
        table.append(_timing_row(f"armadillo {len(assembly)} blocks, rbe solve, ours with {name} ({size})", "rbe",
                                 seconds, theirs))
        total = seconds + row["contact_seconds"] if seconds is not None else None
        verdict = (f" (did not finish in {ARMADILLO_LIMIT:.0f} s)" if total is None
                   else f", says {'stable' if row['stable'] else 'unstable'}")
        target.append(_target("armadillo RBE", f"our contacts + rbe, {len(assembly)} blocks, {name}{verdict}", total,
                              timed_out=total is None))
    if "cra_seconds" in default:
        up_cra = upstream_record["cra"] if upstream_record else {}
        table.append(_timing_row(f"armadillo {len(assembly)} blocks, cra, ours with default interfaces "
                                 f"({default['cra']}); upstream cra_solve"
                                 + (f" stopped after {ARMADILLO_CRA_LIMIT:.0f} s" if "timed_out" in up_cra else ""),
                                 "cra", default["cra_seconds"], up_cra.get("seconds")))
        target.append(_target("armadillo CRA", f"our interfaces + cra, {len(assembly)} blocks, says "
                              f"{default['cra']}", default["cra_seconds"] + default["contact_seconds"]))
    _ARMADILLO.clear()
    _ARMADILLO.update({"ours": rows, "upstream": upstream_record, "paper_cra_seconds": ARMADILLO_PAPER_CRA,
                       "mu": 0.84, "blocks": len(assembly), "supports": len(assembly.frame)})
    return target


#: The armadillo's record, filled by :func:`_armadillo` for the payload.
_ARMADILLO: dict = {}


def _capped(fn, seconds: float):
    """``fn()`` in a forked child, or None if it takes longer than ``seconds`` (the child is then ended)."""
    import multiprocessing

    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=lambda: queue.put(fn()), daemon=True)
    child.start()
    child.join(seconds)
    if child.is_alive():
        child.terminate()
        child.join()
        return None
    return queue.get() if not queue.empty() else None


# --- compas_cra (optional) ----------------------------------------------------------------

def _upstream():
    """compas_cra's pieces, or (None, why not)."""
    try:
        import compas
        import compas_cra
        from compas_assembly.datastructures import Block
        from compas_cra.algorithms import assembly_interfaces_numpy
        from compas_cra.datastructures import CRA_Assembly
        from compas_cra.equilibrium import cra_solve, density_setup, rbe_solve
    except ImportError as error:
        return None, f"compas_cra is not importable ({error}); pip install -r benchmarks/requirements-compare.txt"
    about = {"version": compas_cra.__version__}
    try:
        from compas_cra._native import IPOPT_VERSION
        about["ipopt"] = str(IPOPT_VERSION)
    except ImportError:
        pass
    return {"compas": compas, "CRA_Assembly": CRA_Assembly, "Block": Block, "interfaces": assembly_interfaces_numpy,
            "density_setup": density_setup, "rbe": rbe_solve, "cra": cra_solve, "about": about}, None


def _upstream_assembly(upstream, case: Case, angle: float):
    """The sample file as upstream's examples set it up: supports, densities, interfaces, then the tilt."""
    assembly = upstream["compas"].json_load(str(DATA / f"{case.stem}.json")).copy(cls=upstream["CRA_Assembly"])
    assembly.set_boundary_conditions(list(UPSTREAM_SUPPORTS[case.stem]))
    if case.density:
        upstream["density_setup"](assembly, {n: case.density.get(n, 1.0) for n in assembly.graph.nodes()})
    with contextlib.redirect_stdout(io.StringIO()):
        upstream["interfaces"](assembly, **case.interfaces)
    if angle:
        assembly.rotate_assembly([0, 0, 0], list(TILT_AXES[case.axis]), angle)
    return assembly


def _upstream_from_meshes(upstream, assembly, mu):
    """Our arch as an upstream assembly: one block per mesh with its planar faces as polygons."""
    up = upstream["CRA_Assembly"]()
    for k, mesh in enumerate(assembly.world_meshes()):
        up.add_block(upstream["Block"].from_vertices_and_faces(mesh.vertices.tolist(), _polygons(mesh)), node=k)
    up.set_boundary_conditions(list(assembly.frame))
    with contextlib.redirect_stdout(io.StringIO()):
        upstream["interfaces"](up, nmax=10, amin=1e-4 * assembly.scale ** 2, tmax=1e-4 * assembly.scale)
    return up


def _polygons(mesh: trimesh.Trimesh) -> list[list[int]]:
    """The faces of a convex mesh as polygons (coplanar triangles merged), counter-clockwise outside."""
    faces, done = [], np.zeros(len(mesh.faces), dtype=bool)
    for group in list(mesh.facets) + [[f] for f in range(len(mesh.faces))]:
        if done[group].any():
            continue
        done[group] = True
        edges = mesh.faces[group][:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        key = [tuple(sorted(e)) for e in edges.tolist()]
        boundary = [tuple(e) for e, k in zip(edges.tolist(), key) if key.count(k) == 1]
        following = dict(boundary)
        loop = [boundary[0][0]]
        while following[loop[-1]] != loop[0]:
            loop.append(following[loop[-1]])
        faces.append(loop)
    return faces


def _upstream_solve(upstream, method, assembly, case, mu=None):
    """(stable, message) of upstream's rbe_solve / cra_solve; a raise is "unstable"."""
    options = {"mu": case.mu if case else mu}
    if method == "cra" and case is not None:
        options.update(case.cra_options)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            upstream[method](assembly, **options)
    except Exception as error:  # noqa: BLE001 - upstream raises ValueError, sometimes others
        return False, f"{type(error).__name__}: {error}"
    if method == "cra":
        return True, "solved"
    graph = assembly.graph
    tension = sum(max(force.get("c_nn", 0.0), 0.0) for edge in graph.edges()
                  for interface in graph.edge_attribute(edge, "interfaces") for force in (interface.forces or []))
    weight = sum(graph.node_attribute(n, "block").volume() * graph.node_attribute(n, "block").attributes.get(
        "density", 1.0) for n in graph.nodes() if not graph.node_attribute(n, "is_support"))
    return bool(tension <= TENSION_RTOL * weight), f"solved, tension {tension / weight:.2g} of the weight"


def exported_side_by_side(upstream, quick: bool) -> list[dict]:
    """Our assemblies written as COMPAS JSON by ``interlock.write(..., "x.json")``, solved by compas_cra and by us.

    The file is what a compas_cra user receives: upstream reads it with
    ``compas.json_load`` (no other preparation than its own interface search,
    :data:`EXPORTED_INTERFACES`), takes the frame from ``is_support``, and runs
    ``rbe_solve`` and ``cra_solve``; ours runs ``rbe`` and ``cra`` on the same
    file read back by ``interlock.read``.
    """
    import tempfile
    from pathlib import Path

    from interlock.blocks import semicircular_arch

    mu = math.tan(math.radians(43.0))
    subjects = [("36-voussoir arch (2 supports)", semicircular_arch())]
    if not quick:
        subjects.append(("compas_cra shelf-stable, re-exported", interlock.read(DATA / "shelf-stable.json")))
    out = []
    with tempfile.TemporaryDirectory() as folder:
        for name, assembly in subjects:
            path = interlock.write(assembly, Path(folder) / "exported.json")
            back = interlock.read(path)
            row = {"case": name, "blocks": len(back), "frame": list(back.frame), "mu": mu,
                   "ours_rbe": bool(rbe(back, mu).stable)}
            ours_cra, _ = _ours_cra()
            if ours_cra is not None:
                row["ours_cra"] = ours_cra(back, mu).stable
            if upstream is not None:
                up = upstream["compas"].json_load(str(path)).copy(cls=upstream["CRA_Assembly"])
                with contextlib.redirect_stdout(io.StringIO()):
                    upstream["interfaces"](up, **{k: v * (back.scale ** (2 if k == "amin" else 1))
                                                  for k, v in EXPORTED_INTERFACES.items()})
                row["upstream_supports"] = sorted(n for n in up.graph.nodes()
                                                  if up.graph.node_attribute(n, "is_support"))
                row["upstream_rbe"], row["upstream_rbe_message"] = _upstream_solve(upstream, "rbe", up, None, mu=mu)
                row["upstream_cra"], row["upstream_cra_message"] = _upstream_solve(upstream, "cra", up, None, mu=mu)
            print(f"exported {name}: {row}")
            out.append(row)
    return out


#: compas_cra's interface search on exported files: ``amin`` relative to the model size squared, ``tmax``
#: to the model size (as for the arch above).
EXPORTED_INTERFACES = {"amin": 1e-4, "tmax": 1e-4}


def _ours_cra():
    try:
        from interlock.verify.statics import cra
    except ImportError as error:
        return None, f"interlock.verify.cra is not there yet ({error})"
    return cra, None


# --- output -----------------------------------------------------------------------------

def _print_summary(payload) -> None:
    for method, a in payload["agreement"].items():
        if a["compared"]:
            print(f"{method}: ours and compas_cra agree on {a['agree']}/{a['decided']} "
                  f"({a['ours_inconclusive']} ours inconclusive)")
    for method, t in payload["against_reference"].items():
        print(f"{method:13s} vs the paper's reference: {t['right']}/{t['judged']} right, {len(t['unsafe'])} unsafe, "
              f"{len(t['conservative'])} conservative, {t['inconclusive']} no claim")
    paper = payload["rbe_vs_paper_rbe"]
    print(f"our RBE vs the paper's RBE: {paper['compared'] - len(paper['mismatches'])}/{paper['compared']}")
    for row in payload["timing"]:
        ratio = row["ratio_upstream_over_ours"]
        print(f"  {row['what']:62s} ours {_ms(row['ours_seconds'])} upstream {_ms(row['upstream_seconds'])}"
              + (f"  x{ratio:.1f}" if ratio else ""))
    for t in payload["targets"]:
        print(f"  target {t['target']} <= {t['limit_seconds']} s: {t['what']}: {_ms(t['seconds'])} met={t['met']}")


def _ms(seconds) -> str:
    return "      -" if seconds is None else f"{1e3 * seconds:7.1f} ms"


#: Okabe-Ito (interlock.gallery.appearance.PALETTE): stable blue, unstable orange, no verdict grey.
STABLE, UNSTABLE, NONE, NOT_RUN = "#0072B2", "#E69F00", "#BBBBBB", "#FFFFFF"


def _chart(payload) -> None:
    plt = pyplot()
    if plt is None:
        return
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    rows, angles = payload["cases"], payload["angles"]
    methods = [("rbe", "our RBE"), ("cra", "our CRA"), ("interlocked", "interlocked (check)")]
    if any("upstream_cra" in r for row in rows for r in row["verdicts"]):
        methods += [("upstream_rbe", "compas_cra rbe_solve"), ("upstream_cra", "compas_cra cra_solve")]
    claims = any(r.get("interlocked") for row in rows for r in row["verdicts"])
    widths = [1.0 if method != "interlocked" or claims else 0.45 for method, _ in methods]
    scaling = [r for r in payload.get("cra_scaling", []) if r.get("ours_seconds") or r.get("upstream_seconds")]
    grid_height = 0.26 * len(rows) + 2.2
    panel = 3.6 if scaling else 0.0
    figure = plt.figure(figsize=(3.0 * sum(widths) + 2.2, grid_height + panel))
    if scaling:
        fig, lower = figure.subfigures(2, 1, height_ratios=[grid_height, panel])
        _scaling_panel(lower, scaling)
    else:
        fig = figure
    axes = fig.subplots(1, len(methods), sharey=True, squeeze=False, gridspec_kw={"width_ratios": widths})
    for ax, (method, title) in zip(axes[0], methods):
        for i, row in enumerate(rows):
            for r in row["verdicts"]:
                j = angles.index(r["angle"])
                said = r.get(method, "not run")
                if method == "interlocked" and said is not None:
                    said = True if said else None  # not interlocked: no claim
                colour = {True: STABLE, False: UNSTABLE, None: NONE}.get(said, NOT_RUN)
                ax.add_patch(plt.Rectangle((j - 0.5, i - 0.5), 1, 1, facecolor=colour, edgecolor="white", lw=0.5))
                ref = r["reference"]
                if said is True and ref is False:
                    ax.plot(j, i, marker="x", color="black", ms=6, mew=1.6)
                elif said is False and ref is True:
                    ax.plot(j, i, marker="o", color="black", ms=5, mfc="none", mew=1.2)
            if row["reference_critical_3dec"] is not None and row["reference_critical_3dec"] < 180:
                x = np.interp(row["reference_critical_3dec"], angles, np.arange(len(angles)))
                ax.plot([x, x], [i - 0.5, i + 0.5], color="black", lw=1.5)
        wedges = sum(1 for row in rows if row["axis"])
        if 0 < wedges < len(rows):
            ax.axhline(wedges - 0.5, color="black", lw=1)
        if method == "interlocked" and not claims:
            ax.text(len(angles) / 2 - 0.5, len(rows) / 2, "none is\ninterlocked:\nno claim", ha="center",
                    va="center", fontsize=8, bbox={"facecolor": "white", "edgecolor": "none"})
        done = sum(1 for row in rows for r in row["verdicts"] if method in r)
        ax.set_title(title if done else f"{title}\n(not run)", fontsize=9)
        ax.set_xlim(-0.5, len(angles) - 0.5)
        ax.set_ylim(len(rows) - 0.5, -0.5)
        step = max(1, len(angles) // (3 if method == "interlocked" and not claims else 7))
        ax.set_xticks(range(0, len(angles), step), [f"{angles[k]:.0f}" for k in range(0, len(angles), step)],
                      fontsize=7)
        ax.set_xlabel("tilt (degrees)", fontsize=8)
    axes[0][0].set_yticks(range(len(rows)), [row["name"] for row in rows], fontsize=7)
    legend = [Patch(facecolor=STABLE, label="says stable"), Patch(facecolor=UNSTABLE, label="says unstable"),
              Patch(facecolor=NONE, label="no claim / inconclusive"),
              Patch(facecolor=NOT_RUN, edgecolor="#999999", label="not run (upright only)"),
              Line2D([], [], marker="x", color="black", ls="none", label="wrong: stable, reference unstable"),
              Line2D([], [], marker="o", color="black", mfc="none", ls="none",
                     label="wrong: unstable, reference stable"),
              Line2D([], [], color="black", lw=1.5, label="3DEC critical tilt (Table 2)")]
    fig.legend(handles=legend, loc="lower center", ncol=4, fontsize=7, frameon=False)
    agreement = payload["agreement"]
    agree = "; ".join(f"{m.upper()} ours = compas_cra on {a['agree']}/{a['decided']}"
                      for m, a in agreement.items() if a["compared"]) or "compas_cra not installed: ours only"
    fig.suptitle("Stability verdicts on the CRA paper's assemblies (rows) by tilt (Table 2 axes). "
                 f"Reference: 3DEC / the paper. {agree}", fontsize=9, x=0.01, ha="left")
    fig.subplots_adjust(left=0.12, right=0.99, bottom=0.07 + 1.2 / grid_height, top=1 - 0.5 / grid_height,
                        wspace=0.08)
    save_chart(figure, "stability", tight=False)
    plt.close(figure)


def _scaling_panel(sub, scaling) -> None:
    """CRA time per upright solve against the number of blocks, ours and compas_cra (the armadillo: stopped,
    and the paper's 2,424 s)."""
    ax = sub.subplots(1, 1)
    marks = {True: "o", False: "s", None: "D"}
    for key, colour, label in (("ours", STABLE, "our cra"), ("upstream", UNSTABLE, "compas_cra cra_solve")):
        points = [(r["blocks"], r[f"{key}_seconds"], r.get(key), r) for r in scaling if r.get(f"{key}_seconds")]
        for said in (True, False, None):
            chosen = [(b, t) for b, t, v, _ in points if v is said]
            if chosen:
                xs, ys = zip(*chosen)
                word = {True: "stable", False: "unstable", None: "inconclusive"}[said]
                ax.scatter(xs, ys, color=colour, marker=marks[said], s=28, label=f"{label}: {word}",
                           edgecolor="black", linewidth=0.4)
        for b, t, _, r in points:
            if key == "upstream" and r.get("upstream_timed_out"):
                ax.annotate(f"stopped at {t:.0f} s", (b, t), textcoords="offset points", xytext=(-8, -12),
                            fontsize=7, ha="right")
    for r in scaling:
        if r.get("paper_seconds"):
            ax.scatter([r["blocks"]], [r["paper_seconds"]], marker="*", s=90, color="#009E73",
                       edgecolor="black", linewidth=0.4, label="the CRA paper (Table 5, IPOPT)")
    named = {}
    for r in scaling:
        named.setdefault(r["blocks"], r["case"].split(" μ")[0])
    for blocks, name in named.items():
        ax.annotate(name, (blocks, 1e-3), textcoords="offset points",
                    xytext=(0, 2), fontsize=6, rotation=90, ha="center", va="bottom", color="#555555")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(2, 1500)
    ax.set_ylim(1e-3, 1e4)
    ax.set_xlabel("blocks (log)", fontsize=8)
    ax.set_ylabel("seconds per CRA solve (log)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.grid(True, which="major", color="#DDDDDD", lw=0.5)
    ax.legend(fontsize=7, loc="upper left", frameon=False, ncol=2)
    ax.set_title("CRA time against block count (upright; wedges, H, A, shelves, cubes, bridge, arch, armadillo)",
                 fontsize=9)
    sub.subplots_adjust(left=0.12, right=0.99, bottom=0.2, top=0.86)


def run_armadillo() -> dict:
    """Only the armadillo, into the recorded ``stability.json``: its rows, targets and notes are replaced, and
    ``cra_scaling`` is rebuilt from the recorded upright CRA times (``python -m benchmarks.stability
    --armadillo``; the whole run takes about an hour on 2 shared cores, half of it upstream's cra_solve)."""
    import json

    path = results_folder() / "stability.json"
    payload = json.loads(path.read_text())
    payload.pop("machine", None)  # write_json records this run's
    upstream, _ = _upstream()
    ours_cra, _ = _ours_cra()
    scaling, notes, table = [], [], []
    names = {row["name"]: row for row in payload["cases"]}
    for row in payload["timing"]:
        what = row["what"]
        if what.endswith(" upright, cra"):
            name = what[:-len(" upright, cra")]
            case = next((r for n, r in names.items() if n.replace(" x ", " ") == name), None)
            if case is not None:
                upright = case["verdicts"][0]
                scaling.append({"case": name, "blocks": case["blocks"], "ours_seconds": row["ours_seconds"],
                                "ours": upright.get("cra"), "upstream_seconds": row["upstream_seconds"],
                                "upstream": upright.get("upstream_cra")})
            elif name.startswith("arch "):
                scaling.append({"case": "arch (36 voussoirs)", "blocks": int(name.split()[1]),
                                "ours_seconds": row["ours_seconds"], "ours": True,
                                "upstream_seconds": row["upstream_seconds"], "upstream": True})
    with limited_blas():
        targets = _armadillo(5, upstream, ours_cra, False, table, notes, scaling)
    payload["timing"] = [r for r in payload["timing"] if not r["what"].startswith("armadillo")] + table
    payload["targets"] = [t for t in payload["targets"] if not t["target"].startswith("armadillo")] + targets
    payload["notes"] = [n for n in payload["notes"] if not n.startswith("armadillo")] + notes + [
        f"armadillo rows and cra_scaling re-run alone (run_armadillo) at {time.strftime('%Y-%m-%d %H:%M')}; "
        "the other rows are from the last whole run"]
    payload["cra_scaling"] = scaling
    payload["armadillo"] = dict(_ARMADILLO)
    write_json("stability", payload)
    _chart(payload)
    return payload


def run_exported() -> dict:
    """Only :func:`exported_side_by_side`, into the recorded ``stability.json`` (``python -m benchmarks.stability
    --exported``, in the environment with compas_cra)."""
    import json

    path = results_folder() / "stability.json"
    payload = json.loads(path.read_text())
    payload.pop("machine", None)
    upstream, reason = _upstream()
    with limited_blas():
        payload["exported"] = exported_side_by_side(upstream, quick=False)
    payload["notes"] = [n for n in payload["notes"] if not n.startswith("exported")] + [
        f"exported rows re-run alone (run_exported) at {time.strftime('%Y-%m-%d %H:%M')}"
        + ("" if upstream is not None else f"; {reason}")]
    write_json("stability", payload)
    _chart(payload)
    return payload


if __name__ == "__main__":
    import sys

    if "--armadillo" in sys.argv:
        sys.argv.remove("--armadillo")
        main(lambda quick: run_armadillo(), __doc__)
    elif "--exported" in sys.argv:
        sys.argv.remove("--exported")
        main(lambda quick: run_exported(), __doc__)
    else:
        main(run, __doc__)
