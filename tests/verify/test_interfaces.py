"""Interfaces for statics (interlock/verify/statics/interfaces.py) and CRA at the armadillo's scale (issue 24).

The CRA paper's Armadillo vault (Table 5: 399 blocks, 1,014 interfaces, stable) has faces that meet only
approximately; the default contact model of RBE and CRA is the per-pair interface rule.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly, load_compas
from interlock.errors import InterlockError
from interlock.verify.validate import OverlapError
from interlock.verify import contacts
from interlock.verify.statics import cra, rbe
from interlock.verify.statics.cra import CRAProblem
from interlock.verify.statics.equilibrium import FRICTION_RTOL, friction_utilisation
from interlock.verify.statics.interfaces import (DEFAULT_GAP_THICKNESS, Interfaces, compas_interfaces, interfaces,
                                                 statics_contacts, thickness)

#: The armadillo's touching block pairs: 1,014 with a free block (upstream's interfaces, tmax = 0.05) and 29
#: between two supports (tests/verify/test_contacts.py).
ARMADILLO_PAIRS, ARMADILLO_SUPPORT_PAIRS = 1014, 29


def slab(z0, height, size=2.0, x0=0.0):
    return trimesh.creation.box(bounds=[[x0, 0, z0], [x0 + size, size, z0 + height]])


@pytest.fixture(scope="module")
def vault():
    from interlock.blocks.compas import UPSTREAM_SUPPORTS
    from tests.conftest import REFERENCE_DATA

    assembly = load_compas(REFERENCE_DATA / "compas_cra" / "armadillo.json")
    assert sorted(assembly.frame) == sorted(UPSTREAM_SUPPORTS["armadillo"])
    return assembly, interfaces(assembly)


# --- the rule --------------------------------------------------------------------------------------------


def test_thickness_is_the_least_width():
    a = Assembly.from_meshes([slab(0, 0.5), trimesh.creation.box(extents=[1, 3, 2])])
    assert thickness(a) == pytest.approx([0.5, 1.0])


@pytest.mark.parametrize("gap, found", [(0.0, True), (0.1, True), (0.24, True), (0.26, False)])
def test_gap_relative_to_the_thinner_block(gap, found):
    # a thin slab (0.2) on a thick one (2.0): the gap counts against the thin one's thickness
    a = Assembly.from_meshes([slab(0, 2.0), slab(2.0 + gap * 0.2, 0.2)])
    result = interfaces(a)
    assert (len(result.contacts) == 1) is found
    if found:
        assert result.contacts[0].separation == pytest.approx(gap * 0.2 if gap else 0.0, abs=1e-9)


def test_tilted_faces_within_the_gap_meet():
    thin = slab(1.0, 0.5)
    thin.apply_transform(trimesh.transformations.rotation_matrix(0.04, [1, 0, 0], [1, 1, 1]))
    a = Assembly.from_meshes([slab(0, 1.0), thin])
    assert not contacts(a) and len(interfaces(a).contacts) == 1


def test_one_call_equals_a_call_per_pair():
    # three pairs of different thickness; each pair alone with its own tolerances gives the same contacts
    blocks = [slab(0, 1.0, x0=0), slab(1.06, 0.3, x0=0), slab(0, 1.0, x0=3), slab(1.05, 0.1, x0=3),
              slab(0, 1.0, x0=6), slab(1.2, 1.0, x0=6)]
    a = Assembly.from_meshes(blocks)
    together = {(c.i, c.j): c for c in interfaces(a).contacts}
    assert set(together) == {(0, 1), (4, 5)}  # 0.05 > 0.25 * 0.1 between blocks 2 and 3
    widths = thickness(a)
    for i, j in [(0, 1), (2, 3), (4, 5)]:
        pair = Assembly.from_meshes([blocks[i], blocks[j]])
        t = min(widths[i], widths[j])
        alone = contacts(pair, gap=DEFAULT_GAP_THICKNESS * t / pair.scale, angle_tol=2 * DEFAULT_GAP_THICKNESS,
                         area_rtol=1e-3 * t**2 / pair.scale**2, rtol=1e-5 * a.scale / pair.scale)
        assert len(alone) == ((i, j) in together)
        if alone:
            assert alone[0].area == pytest.approx(together[(i, j)].area)
            assert alone[0].vertices == pytest.approx(together[(i, j)].vertices)


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, "0.1", True, 0.8])
def test_bad_gap(bad):
    with pytest.raises(InterlockError, match="gap"):
        interfaces(Assembly.from_meshes([slab(0, 1), slab(1, 1)]), gap=bad)


def test_statics_contacts_models():
    a = Assembly.from_meshes([slab(0, 1), slab(1.1, 1)], frame=[0])
    assert statics_contacts(a)[1]["model"] == "interfaces"
    assert statics_contacts(a, "exact") == ((), {"model": "exact", "contacts": 0})
    assert statics_contacts(a, contacts(a))[1] == {"model": "given", "contacts": 0}
    with pytest.raises(InterlockError, match="contacts must be one of"):
        statics_contacts(a, "loose")
    assert rbe(a, 0.5).stable and not rbe(a, 0.5, contacts="exact").stable  # 0.1 apart: an interface, no contact
    result = rbe(a, 0.5)
    assert result.parameters["contacts"]["gap_thickness"] == DEFAULT_GAP_THICKNESS
    assert "faces within 0.25 of the thinner block's thickness" in str(result)


# --- friction utilisation ------------------------------------------------------------------------------


def test_friction_utilisation_ignores_vertices_at_the_solver_tolerance():
    # one real vertex at the octagon's corner, one with f_n ~ 5e-10 (the armadillo's artefact)
    corner = 0.5 / math.cos(math.pi / 8)
    forces = np.array([[1.0, corner * math.cos(math.pi / 8), corner * math.sin(math.pi / 8)], [5e-10, 2e-9, 0.0]])
    assert friction_utilisation(forces, 0.5) == pytest.approx(1 / math.cos(math.pi / 8))
    assert friction_utilisation(forces, 0.5, rtol=0.0) == pytest.approx(8.0)
    assert FRICTION_RTOL == 1e-5


# --- COMPAS-stored interfaces --------------------------------------------------------------------------


@pytest.mark.parametrize("name, count, pairs", [("curve-3-blocks", 40, {(0, 1), (1, 2)}),
                                                ("cube-curve-short", 72, {(0, 1)}),
                                                ("concave-short", 7, {(0, 1)}), ("type-a", 0, set())])
def test_compas_interfaces(reference_data, name, count, pairs):
    path = reference_data / "compas_cra" / f"{name}.json"
    a = load_compas(path)
    stored = compas_interfaces(path, a)
    assert len(stored) == count and {(c.i, c.j) for c in stored} == pairs
    for c in stored:
        assert np.linalg.norm(c.normal) == pytest.approx(1.0) and c.area > 0
        assert np.cross(*c.basis) == pytest.approx(c.normal)
    if name == "curve-3-blocks":  # a stack: each normal points up, from the lower block i to the upper j
        assert all(c.normal[2] > 0 for c in stored)
        assert rbe(a, 0.84, contacts=stored).stable == rbe(a, 0.84).stable is True


def test_compas_interfaces_bad_file(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    with pytest.raises(InterlockError, match="not a readable COMPAS"):
        compas_interfaces(bad, Assembly.from_meshes([slab(0, 1)]))


# --- the Armadillo vault (Table 5) ---------------------------------------------------------------------


def test_armadillo_interfaces_by_default(vault):
    assembly, found = vault
    assert isinstance(found, Interfaces)
    pairs = {(c.i, c.j) for c in found.contacts}
    supports = set(assembly.frame)
    assert len({p for p in pairs if set(p) <= supports}) == ARMADILLO_SUPPORT_PAIRS
    assert len({p for p in pairs if not set(p) <= supports}) == ARMADILLO_PAIRS
    assert found.separations.max() <= DEFAULT_GAP_THICKNESS + 1e-9
    assert len(contacts(assembly)) < 400  # the exact contacts miss most of them (341)


def test_armadillo_rbe_stable_with_default_options(vault):
    assembly, found = vault
    result = rbe(assembly, 0.84, contacts=found)
    assert result.stable
    assert result.parameters["contacts"]["model"] == "interfaces"
    assert result.friction_utilisation <= 1 / math.cos(math.pi / 8) + 1e-4  # the octagon's corners, no artefact


def test_armadillo_cra_is_stable_by_holding_block_238_out(vault):
    # docs/statics.md, "CRA at scale": RBE stable (necessary); the motion of most work is not exact (eta is
    # active); the Coulomb fixed point cannot hold block 238 (it slides to the bound eta round after round), so
    # the large route holds it out: the other 398 blocks are proved, then 238 is placed by IPOPT with Benders
    # cuts, and the exact LP of the whole accepts the motion. The certificate passes the independent check of (11)
    from tests.verify.test_cra import _certificate_holds

    assembly, found = vault
    result = cra(assembly, 0.84, contacts=found)
    assert result.parameters.get("route") == "large"
    assert result.status == "stable", result.message
    assert "holding out block 238" in result.message and "placed by IPOPT" in result.message
    _certificate_holds(assembly, result, (0.0, 0.0, -1.0))


def test_armadillo_cra_without_holding_out_names_block_238(vault):
    # hold_out=False stops at the Coulomb fixed point: inconclusive, saying why (RBE is only necessary, the
    # motion of most work fails, what the closest motion leaves unbalanced), how large the MILP would be, the
    # paper's time, and the block that slides to eta with the option that holds it out; never "unstable"
    assembly, found = vault
    result = cra(assembly, 0.84, contacts=found, hold_out=False)
    assert result.status == "inconclusive" and result.parameters.get("route") == "large"
    assert "RBE has an equilibrium" in result.message and "binaries" in result.message
    assert "2,424 s" in result.message  # the paper's IPOPT time for this vault (Table 5)
    assert "the Coulomb fixed point ran" in result.message and "of the load unbalanced, at" in result.message
    assert "block 238 slid to the bound eta" in result.message and "hold_out=True" in result.message


#: The stored certificate: the armadillo's interfaces as the rule found them when the motion was found (3,051 with a
#: free block, 10,901 vertices; stored, so that a later change of the contact search cannot unmake it), the motion
#: (world twists per free block) and the forces (per vertex, in each contact's frame) that Clarabel found at it.
CERTIFICATE = Path(__file__).parents[1] / "data" / "certificates" / "armadillo_cra_certificate.npz"
#: The check's tolerance, of the load: the exact check's (``cra_large.CHECK_RTOL``).  The stored forces meet
#: equilibrium to 4.6e-10 of the largest load component (200 times inside it) and every pyramid row strictly, so
#: ``CERTIFICATE_MARGIN`` (a hundredth of the tolerance) is asserted as well: recomputing ``A_eq f`` on another
#: machine, BLAS or thread count moves the residual by about 1e-15 of the load, far less than the margin.
CERTIFICATE_RTOL = 1e-7
CERTIFICATE_MARGIN = 1e-9


def stored_certificate():
    """The armadillo, its stored contacts, motion (solver units) and forces, and the CRA problem on those contacts."""
    import shapely

    from interlock.blocks.contact import Contact
    from tests.conftest import REFERENCE_DATA

    with np.load(CERTIFICATE) as stored_arrays:  # read each array once: an NpzFile decompresses on every lookup
        data = {name: stored_arrays[name] for name in stored_arrays.files}
    assembly = load_compas(REFERENCE_DATA / "compas_cra" / "armadillo.json")
    ends = np.cumsum(data["counts"])
    stored = []
    for k, (i, j) in enumerate(data["pairs"]):
        vertices = data["vertices"][ends[k] - data["counts"][k]:ends[k]]
        origin, basis = data["origins"][k], data["bases"][k]
        stored.append(Contact(int(i), int(j), data["normals"][k], vertices, float(data["areas"][k]),
                              int(data["facets"][k, 0]), int(data["facets"][k, 1]),
                              shapely.Polygon((vertices - origin) @ basis.T), origin, basis,
                              separation=float(data["separations"][k])))
    problem = CRAProblem.build(assembly, float(data["mu"]), contacts=stored)
    return assembly, problem, problem.internal_motion(data["motion"]), data["forces"]


def check_certificate() -> float:
    """Check the stored certificate of (11) (independently of the solvers) and return its equilibrium residual, a
    fraction of the largest load component; run in a fresh interpreter by the test, with one thread and with all."""
    from tests.verify.test_cra import _certificate_holds

    assembly, problem, motion, forces = stored_certificate()
    b_eq, total = problem._right_hand_side(np.array([0.0, 0.0, -1.0]))
    lp = problem.motion_lp(motion)
    assert lp is not None and lp.closed.any()
    x = forces / total
    residual = float(np.abs(problem.system.a_eq @ x.ravel() - b_eq).max() / np.abs(b_eq).max())
    assert residual <= CERTIFICATE_MARGIN  # equilibrium (7b), far inside the tolerance
    assert (problem.system.a_ub @ x.ravel()).max() <= 0.0  # the pyramid (7c), strictly
    assert np.all(x[~lp.closed] == 0) and np.all(x[:, 0] >= 0)  # contact (10) and no tension (7d)
    result = problem._result("stable", "certificate", forces, motion, problem.parameters, {})
    _certificate_holds(assembly, result, (0.0, 0.0, -1.0))  # at CERTIFICATE_RTOL = CHECK_RTOL, with alignment (9)
    # 238 is held by friction: its closed vertices slide, with friction against the slides
    at_238 = np.array([238 in (c.i, c.j) for c in result.contacts])[result.vertex_contact]
    assert (result.closed & at_238).sum() >= 3 and np.abs(result.forces[at_238, 1:]).sum() > 0
    return residual


@pytest.mark.parametrize("threads", ["1", None])
def test_armadillo_is_cra_stable_by_its_certificate(threads):
    # The whole vault, all 399 blocks, is CRA-stable (the paper's verdict, Table 5): a motion that the split route
    # found (cra_split; the rest's proved motion with block 238 placed by IPOPT after two Benders cuts), stored with
    # the contacts it was found on and the forces it realises. No solver runs: the forces are checked against (11)
    # at the motion, to CERTIFICATE_RTOL of the load (the exact check's tolerance) and, for equilibrium, to
    # CERTIFICATE_MARGIN (the stored forces meet it to 4.6e-10, 200 times inside the tolerance; machines differ by
    # ~1e-15). Once under OMP_NUM_THREADS=1 and once with all threads, each in a fresh interpreter.
    import os
    import subprocess
    import sys

    environment = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
    if threads is not None:
        environment["OMP_NUM_THREADS"] = threads
    root = Path(__file__).parents[2]
    finished = subprocess.run([sys.executable, "-c", "from tests.verify.test_interfaces import check_certificate; "
                               "print(check_certificate())"], cwd=root, env=environment, capture_output=True,
                              text=True, timeout=600)
    assert finished.returncode == 0, finished.stderr[-3000:]
    assert float(finished.stdout.strip().splitlines()[-1]) <= CERTIFICATE_MARGIN


def test_armadillo_without_its_edge_block_238_is_proved_stable_by_cra(vault):
    # docs/statics.md, "CRA at scale": the whole vault stays inconclusive because of block 238 (an edge block held
    # only by friction between two upright faces). The other 398 blocks, on the same supports and interfaces, are
    # proved CRA-stable by `cra` itself within the fixed point's 40 rounds (counted, not timed, so the same on
    # every machine): the last one shut exactly, accepted by the exact LP and by the independent check of (11)
    # below. The first CRA proof at the scale of a real structure (53 s here, median of 3, not the paper's 2,424 s
    # for IPOPT's local answer); no time limit, so a slower machine only takes longer.
    from tests.verify.test_cra import _certificate_holds

    assembly, _ = vault
    meshes = assembly.world_meshes()
    kept = [k for k in range(len(meshes)) if k != 238]
    rest = Assembly.from_meshes([meshes[k] for k in kept], frame=[kept.index(k) for k in assembly.frame])
    result = cra(rest, 0.84, contacts=interfaces(rest))
    assert result.status == "stable", result.message
    assert "Coulomb fixed point" in result.message and result.parameters.get("route") == "large"
    _certificate_holds(rest, result, (0.0, 0.0, -1.0))


# --- interpenetrating blocks are refused, not balanced --------------------------------------------------------------


def _box(lo, hi):
    return trimesh.creation.box(bounds=[lo, hi])


def test_a_block_duplicated_in_place_is_refused_by_rbe():
    # before: "RBE stable", the copy and the original sharing the load
    grid = [_box([x, y, 0], [x + 1, y + 1, 1]) for x in range(3) for y in range(3)]
    twice = Assembly.from_meshes(grid + [grid[4].copy()], frame=[0, 1, 2, 3, 5, 6, 7, 8])
    with pytest.raises(OverlapError, match=r"blocks 4 \(.*\) and 9 \(.*\) overlap 0.333 deep, more than 0.25 of the "
                                           r"thinner one's thickness"):
        rbe(twice, 0.5)


def test_a_block_pushed_into_two_walls_without_an_interface_is_refused():
    # 0.3 into each wall: shallower than the interface rule's quarter thickness (mean depth 0.19), but its faces
    # lie 0.3 inside the walls, beyond the rule's gap, so no interface joins them; before: "RBE unstable, 0 contacts"
    walls = [_box([-1, 0, 0], [0, 1, 3]), _box([1.7, 0, 0], [2.7, 1, 3])]
    pushed = Assembly.from_meshes(walls + [_box([-0.3, 0, 1], [2.0, 1, 2])], frame=[0, 1])
    with pytest.raises(OverlapError, match="overlap 0.187 deep .* without a face of one lying on a face of the other"):
        rbe(pushed, 0.6)
    apart = Assembly.from_meshes([walls[0], _box([1, 0, 0], [2, 1, 3]), _box([0, 0, 1], [1, 1, 2])], frame=[0, 1])
    assert rbe(apart, 0.6).stable is True


def test_the_reference_files_overlap_within_the_interface_rule(reference_data):
    # the armadillo's blocks overlap up to 0.01 deep (1.4 % of a block): within a quarter of their thickness
    for path in sorted((reference_data / "compas_cra").glob("*.json")):
        assembly = load_compas(path)
        found, model = statics_contacts(assembly)
        assert model["model"] == "interfaces" and len(found) > 0, path.name


def test_stored_interfaces_of_a_file_that_names_its_nodes(reference_data, tmp_path):
    # node labels ("stone_0", ...) become block labels; the stored interfaces still name node keys
    data = json.loads((reference_data / "compas_cra" / "curve-3-blocks.json").read_text())
    for key, node in data["data"]["graph"]["data"]["node"].items():
        node["label"] = f"stone_{key}"
    path = tmp_path / "named.json"
    path.write_text(json.dumps(data))
    assembly = load_compas(path)
    assert assembly.labels == ("stone_0", "stone_1", "stone_2")
    stored = compas_interfaces(path, assembly)
    assert len(stored) == 40 and rbe(assembly, 0.84, contacts=stored).stable is True
