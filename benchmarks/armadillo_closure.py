"""Why CRA is not yet decided on the Armadillo vault: which contact vertices one virtual motion can close.

A solution of the CRA problem (11) closes every loaded vertex by exactly ``eps``
(Eq. (10)) and slides every friction vertex against its friction (Eq. (9)).
This probe measures, on the vault (399 blocks, ``mu = 0.84``), how far the first
of these can be met, for two contact models:

- ``interfaces``: the default statics contacts
  (:func:`~interlock.verify.statics.interfaces.interfaces`).  The vault's faces
  are non-planar quadrilaterals, stored as two triangles each, so one pair of
  facing faces gives up to four contact polygons whose normals differ by up to
  13 degrees;
- ``planar``: those polygons merged, per block pair, into one planar polygon
  (the convex hull of their union, projected onto the area-weighted mean
  plane), as compas_assembly models an interface (one per face pair).

Per model: contacts and vertices; the allowed motion (``dd_n >= -eps``,
``|dd| <= eta``) that closes as many vertices as an LP can (least
``sum dd_n``); whether the closed vertices can carry the load
(:func:`~interlock.verify.statics.cra_large.carries`); the dimension of the
motions that keep them all closed (the null space of their normal rows, from
the eigenvalues of the Gram matrix); and the exact LP of (11) at that motion,
its equilibrium residual when the friction must lie along the slides (an LP
with slack: 0 would prove "stable").

Then, per model, the rounds of the Coulomb fixed point
(:mod:`interlock.verify.statics.cra_coulomb`): the same residual at each
round's motion, the blocks left unbalanced, and the components at the bound
``eta``; and ``cra`` itself with the default options, end to end.

Not part of ``python -m benchmarks`` (about four minutes); run
``python -m benchmarks.armadillo_closure``.  docs/statics.md, "CRA at scale",
quotes it.  If the planar model is adopted it belongs in
``interlock/verify/statics/interfaces.py``.
"""

from __future__ import annotations

import time
from collections import defaultdict

import networkx as nx
import numpy as np
import scipy.sparse as sp
import shapely

from benchmarks.common import REFERENCE_DATA, limited_blas, main, write_json
import interlock
from interlock.blocks.contact import Contact, plane_bases
from interlock.verify.statics import cra
from interlock.verify.statics.cra import CRAProblem
from interlock.verify.statics.cra_coulomb import coulomb_fixed_point, unbalanced
from interlock.verify.statics.cra_large import carries, exact
from interlock.verify.statics.cra_local import least_friction
from interlock.verify.statics.equilibrium import clarabel_lp
from interlock.verify.statics.interfaces import interfaces

MU = 0.84
#: A vertex counts as closed when ``dd_n + eps <= CLOSED * eps``.
CLOSED = 1e-6
#: Eigenvalues of the closed rows' Gram matrix below this times the largest span the null space.
NULL_RTOL = 1e-12
#: Rounds of the Coulomb fixed point reported per contact model (the large route runs 8; it cycles from ~8 on).
COULOMB_ROUNDS = 12


def planar_interfaces(contacts, angle: float) -> tuple[Contact, ...]:
    """One planar contact per connected group of a block pair's contacts whose normals are within ``angle``.

    The group's polygons are projected onto the plane through their area-weighted centroid with their
    area-weighted mean normal; the contact is the convex hull of the union there.
    """
    by_pair = defaultdict(list)
    for c in contacts:
        by_pair[(c.i, c.j)].append(c)
    merged = []
    for (i, j), group in by_pair.items():
        graph = nx.Graph()
        graph.add_nodes_from(range(len(group)))
        for a in range(len(group)):
            for b in range(a + 1, len(group)):
                if group[a].normal @ group[b].normal >= np.cos(angle) and _touch(group[a], group[b]):
                    graph.add_edge(a, b)
        for component in nx.connected_components(graph):
            parts = [group[k] for k in sorted(component)]
            merged.append(parts[0] if len(parts) == 1 else _merge(i, j, parts))
    return tuple(merged)


def _touch(a: Contact, b: Contact) -> bool:
    normal = (a.normal + b.normal) / np.linalg.norm(a.normal + b.normal)
    basis = plane_bases(normal[None])[0]
    first, second = shapely.Polygon(a.vertices @ basis.T), shapely.Polygon(b.vertices @ basis.T)
    return bool(first.buffer(1e-9 * first.length).intersects(second))


def _merge(i: int, j: int, parts: list[Contact]) -> Contact:
    weights = np.array([c.area for c in parts])
    normal = weights @ np.array([c.normal for c in parts])
    normal /= np.linalg.norm(normal)
    origin = weights @ np.array([c.vertices.mean(axis=0) for c in parts]) / weights.sum()
    basis = plane_bases(normal[None])[0]
    hull = shapely.union_all([shapely.Polygon((c.vertices - origin) @ basis.T).buffer(0) for c in parts]).convex_hull
    hull = shapely.orient_polygons(hull.simplify(1e-7 * np.sqrt(hull.area)))
    vertices = origin + np.asarray(hull.exterior.coords)[:-1] @ basis
    spread = float(np.abs((np.vstack([c.vertices for c in parts]) - origin) @ normal).max())
    return Contact(i, j, normal, vertices, float(hull.area), parts[0].facet_i, parts[0].facet_j, hull, origin, basis,
                   max(c.deviation for c in parts) + spread, False, max(c.separation for c in parts))


def closure(assembly, contacts) -> dict:
    """The measurements of the module docstring for one contact model."""
    started = time.perf_counter()
    problem = CRAProblem.build(assembly, MU, contacts=contacts)
    b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    a_ub, b_ub = problem.allowed_motions
    normal_rows = problem.kinematic[0::3].tocsr()
    solved = _solve(np.asarray(normal_rows.sum(axis=0)).ravel(), a_ub, b_ub)
    row = {"contacts": len(problem.system.contacts), "vertices": normal_rows.shape[0],
           "motion dofs": normal_rows.shape[1]}
    if solved is None:
        return {**row, "closing LP": "not solved"}
    motion = solved
    closed = normal_rows @ motion + 1.0 <= CLOSED
    rows = normal_rows[closed]
    motion = motion + sp.linalg.lsqr(rows, -1.0 - rows @ motion, atol=1e-15, btol=1e-15, iter_lim=10_000)[0]
    eigenvalues = np.linalg.eigvalsh((rows.T @ rows).toarray())
    row.update({"closed": int(closed.sum()), "closed fraction": float(closed.mean()),
                "closed carry the load": carries(problem, b_eq, closed),
                "motions keeping them closed (dimension)": int((eigenvalues < NULL_RTOL * eigenvalues[-1]).sum()),
                "exact LP residual at that motion": unbalanced(problem, b_eq, motion)[0],
                "load (|b|_1, the residual's scale)": float(np.abs(b_eq).sum()),
                "seconds": time.perf_counter() - started})
    return row


def coulomb_rounds(assembly, contacts, rounds: int) -> list[dict]:
    """Per round of the Coulomb fixed point (:mod:`interlock.verify.statics.cra_coulomb`): the exact LP's
    residual at the round's motion, the blocks it leaves unbalanced, the components at the bound ``eta``, and
    the seconds of the round (the cone program and the exact check, not this report)."""
    problem = CRAProblem.build(assembly, MU, contacts=contacts)
    b_eq, _ = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    frugal = least_friction(problem, b_eq, interior=True)
    rows, clock = [], [time.perf_counter()]

    def check(motion):
        forces = exact(problem, b_eq, motion)
        seconds = time.perf_counter() - clock[0]
        residual, blocks = unbalanced(problem, b_eq, motion)
        dd = problem.kinematic @ motion
        rows.append({"round": len(rows) + 1, "residual": residual, "unbalanced blocks": list(blocks),
                     "eta active": int(np.count_nonzero(np.abs(dd) >= problem.ratio * (1 - 1e-6))),
                     "accepted": forces is not None, "seconds": seconds})
        clock[0] = time.perf_counter()
        return forces

    coulomb_fixed_point(problem, b_eq, frugal[:, 0], check, iterations=rounds)
    return rows


def _solve(cost, constraints, right, equalities: int = 0):
    """Clarabel's primal solution when it reports "Solved" or "AlmostSolved" (the closing LP on the planar model
    stops at the latter), else ``None``."""
    solution = clarabel_lp(cost, constraints, right, equalities)
    return np.asarray(solution.x) if str(solution.status) in ("Solved", "AlmostSolved") else None


def run(quick: bool = False) -> dict:
    assembly = interlock.read(REFERENCE_DATA / "compas_cra" / "armadillo.json")
    found = interfaces(assembly)
    pairs = defaultdict(int)
    for c in found.contacts:
        pairs[(c.i, c.j)] += 1
    with limited_blas():
        models = {"interfaces": found.contacts, "planar": planar_interfaces(found.contacts, found.angle)}
        rows = {name: closure(assembly, contacts) for name, contacts in models.items()}
        rounds = {name: coulomb_rounds(assembly, contacts, 3 if quick else COULOMB_ROUNDS)
                  for name, contacts in models.items()}
        started = time.perf_counter()
        result = cra(assembly, MU, contacts=found)
        whole = {"status": result.status, "seconds": time.perf_counter() - started, "message": result.message}
    counts = np.bincount(list(pairs.values()))
    record = {"mu": MU, "closed tolerance": CLOSED, "contacts per block pair": {str(k): int(v) for k, v in
                                                                               enumerate(counts) if v},
              "models": rows, "coulomb fixed point": rounds, "cra (default interfaces, default options)": whole}
    write_json("armadillo_closure", record)
    for name, row in rows.items():
        print(name, row)
    return record


if __name__ == "__main__":
    main(run, __doc__)
