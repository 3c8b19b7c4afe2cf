"""Rigid-block equilibrium (CRA paper, Sec. 2.1, Eqs. (1)-(5), App. B) and the tilting test (Table 2)."""

import json
import math

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly, load_compas, presets, random_hexagon, rhomblock_assembly
from interlock.errors import InterlockError
from interlock.verify import contacts
from interlock.verify.statics import critical_tilt, rbe, tilted_gravity

TOL = 0.1  # the bisection tolerance of critical_tilt, degrees


def _stack(heights=(1.0, 1.0)):
    """Blocks of unit square base stacked along z; block 0 is the frame."""
    boxes, z = [], 0.0
    for h in heights:
        boxes.append(trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + h]]))
        z += h
    return Assembly.from_meshes(boxes, frame=[0])


# --- a block on a fixed block -------------------------------------------------------------------------------


@pytest.mark.parametrize("mu", [0.0, 0.2, 0.84])
def test_cube_on_cube_stable_under_vertical_gravity(mu):
    result = rbe(_stack(), mu=mu, density=2.0)
    assert result.stable and result.status == 0
    assert np.all(result.forces[:, 0] >= -1e-12)
    assert result.resultants[0] == pytest.approx([0.0, 0.0, 2.0], abs=1e-9)  # carries the weight
    assert result.centres_of_pressure[0] == pytest.approx([0.5, 0.5, 1.0], abs=1e-9)
    assert result.friction_utilisation == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("mu", [0.2, 0.5])
def test_cube_slides_at_atan_mu_about_a_face_normal_of_the_octagon(mu):
    # downhill along y: a face normal of App. B's octagon, where it touches the Coulomb cone
    assert critical_tilt(_stack(), "x", mu) == pytest.approx(math.degrees(math.atan(mu)), abs=TOL)
    assert critical_tilt(_stack(), "y", mu) == pytest.approx(math.degrees(math.atan(mu)), abs=TOL)


@pytest.mark.parametrize("mu", [0.2, 0.5])
def test_octagon_admits_more_friction_between_its_faces(mu):
    # about xy30 the block slides along 120 deg, 15 deg off the octagon's face normal at 135 deg: the
    # circumscribed ("paper") octagon allows mu / cos 15 deg there, the inscribed one mu cos 22.5 / cos 15
    paper = math.degrees(math.atan(mu / math.cos(math.radians(15))))
    inner = math.degrees(math.atan(mu * math.cos(math.radians(22.5)) / math.cos(math.radians(15))))
    assert critical_tilt(_stack(), "xy30", mu) == pytest.approx(paper, abs=TOL)
    assert critical_tilt(_stack(), "xy30", mu, cone="inner") == pytest.approx(inner, abs=TOL)
    assert critical_tilt(_stack(), "xy30", mu) > math.degrees(math.atan(mu)) + 2 * TOL


def test_inner_cone_about_a_face_normal_is_mu_cos_pi_over_8():
    expected = math.degrees(math.atan(0.5 * math.cos(math.pi / 8)))
    assert critical_tilt(_stack(), "x", 0.5, cone="inner") == pytest.approx(expected, abs=TOL)


def test_more_sides_approach_the_coulomb_cone():
    exact = math.degrees(math.atan(0.5))
    for cone in ("paper", "inner"):
        assert critical_tilt(_stack(), "xy30", 0.5, cone=cone, sides=64) == pytest.approx(exact, abs=0.1)


def test_tall_block_tips_when_the_resultant_leaves_the_base():
    tall = _stack((1.0, 3.0))
    tipping = math.degrees(math.atan(0.5 / 1.5))  # centroid 1.5 above the base, 0.5 from its edge
    assert critical_tilt(tall, "x", 1.0) == pytest.approx(tipping, abs=TOL)
    near = rbe(tall, mu=1.0, gravity=tilted_gravity("x", tipping - 0.2))
    assert near.stable and not rbe(tall, mu=1.0, gravity=tilted_gravity("x", tipping + 0.2)).stable
    # the centre of pressure has moved almost to the downhill edge y = 0 (turning about +x lowers y = 0)
    assert near.centres_of_pressure[0, 1] == pytest.approx(0.0, abs=0.02)


@pytest.mark.parametrize("method", ["rbe", "cra"])
def test_critical_tilt_reports_every_angle_it_decides(method):
    # a block on a block slides at atan(0.5) = 26.57 deg: scan 0, 5, .., 30 (unstable), then bisect (25, 30)
    seen = []
    angle = critical_tilt(_stack(), "x", 0.5, method=method, progress=lambda a, ok: seen.append((a, ok)))
    angles = [a for a, _ in seen]
    assert angles[:8] == [0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 27.5]
    assert all(ok for a, ok in seen if a < 26.5) and not any(ok for a, ok in seen if a > 26.6)
    assert min(a for a, ok in seen if not ok) == angle


def test_tilted_gravity_turns_the_assembly_counter_clockwise():
    # turning the assembly by +90 deg about x brings its +y axis up, so gravity points along -y in its frame
    assert tilted_gravity("x", 90) == pytest.approx([0, -1, 0], abs=1e-12)
    assert tilted_gravity((0, 0, 1), 37) == pytest.approx([0, 0, -1])
    assert tilted_gravity("xy30", 180) == pytest.approx([0, 0, 1], abs=1e-12)


# --- Table 2 of the CRA paper: RBE critical tilt of the wedges ------------------------------------------------

#: (model, axis): RBE critical angle for mu = 0.20 and mu = 0.84 (Table 2, column "RBE").
TABLE_2_RBE = {
    ("type-a", "x"): (25.0, 180.0), ("type-a", "y"): (71.3, 180.0), ("type-a", "xy30"): (28.0, 180.0),
    ("type-b", "x"): (25.0, 180.0), ("type-b", "y"): (67.4, 180.0), ("type-b", "xy30"): (28.0, 180.0),
    ("type-c", "x"): (13.0, 47.0), ("type-c", "y"): (41.3, 65.7), ("type-c", "xy30"): (15.0, 51.0),
    ("type-d", "x"): (13.0, 50.0), ("type-d", "y"): (41.3, 70.0), ("type-d", "xy30"): (15.0, 54.0),
}
TABLE_2_TOL = {0.20: 1.0, 0.84: 2.5}


@pytest.fixture(scope="module")
def wedges(reference_data):
    loaded = {}
    for model in ("type-a", "type-b", "type-c", "type-d"):
        assembly = load_compas(reference_data / "compas_cra" / f"{model}.json")
        loaded[model] = (assembly, contacts(assembly))
    return loaded


@pytest.mark.parametrize("mu", [0.20, 0.84])
@pytest.mark.parametrize("model, axis", list(TABLE_2_RBE))
def test_table_2_rbe_critical_tilt(wedges, model, axis, mu):
    paper = TABLE_2_RBE[model, axis][0 if mu == 0.20 else 1]
    assembly, found = wedges[model]
    ours = critical_tilt(assembly, axis, mu, contacts=found)
    if paper == 180.0:
        assert ours == 180.0  # stable all the way round, also upside down (the sharp-wedge artefact of RBE)
        assert rbe(assembly, mu, gravity=tilted_gravity(axis, 180.0), contacts=found).stable
    else:
        assert ours == pytest.approx(paper, abs=TABLE_2_TOL[mu])


def test_model_h_is_stable_under_rbe(reference_data):
    # Table 1 / Sec. 2.2: RBE finds a prestressed equilibrium between the two walls, whatever mu
    h = load_compas(reference_data / "compas_cra" / "H.json")
    assert rbe(h, mu=0.84).stable and rbe(h, mu=0.2).stable


# --- interlocked implies stable without friction ------------------------------------------------------------


def _directions():
    axes = np.vstack([np.eye(3), -np.eye(3)])
    random = np.random.default_rng(9).normal(size=(5, 3))
    return np.vstack([axes, random])


def test_interlocking_cubes_stable_without_friction_in_every_direction():
    cubes = presets.interlocking_cubes()
    for g in _directions():
        assert rbe(cubes, mu=0.0, gravity=g).stable, g


def test_rhomblock_patch_with_ring_frame_stable_without_friction():
    patch = rhomblock_assembly(random_hexagon(3, 3, 3, seed=0), 0, frame="boundary")
    found = contacts(patch)
    for g in _directions():
        assert rbe(patch, mu=0.0, gravity=g, contacts=found).stable, g


def test_topolite_bunny_with_its_frame_stable_without_friction(reference_data):
    # interlocked (test_check: full rank with parts 1 and 2 fixed), so any load is carried without friction
    from tests.verify.test_check import BUNNY_PARTS

    paths = [reference_data / "topolite" / "bunny" / f"part_{k}.obj" for k in range(1, BUNNY_PARTS + 1)]
    bunny = Assembly.load(paths).with_frame([0, 1])
    found = contacts(bunny)
    for g in _directions():
        assert rbe(bunny, mu=0.0, gravity=g, contacts=found).stable, g


def test_plain_grid_falls_without_friction_but_rbe_wedges_it_with_friction():
    grid = [trimesh.creation.box(bounds=[[x, y, 0], [x + 1, y + 1, 1]]) for x in range(3) for y in range(3)]
    assembly = Assembly.from_meshes(grid, frame=[0, 1, 2, 3, 5, 6, 7, 8])
    assert not rbe(assembly, mu=0.0).stable
    assert rbe(assembly, mu=0.3).stable  # prestress between opposite walls, as in model H


# --- the result ----------------------------------------------------------------------------------------------


def test_result_is_a_serialisable_value():
    result = rbe(_stack(), mu=0.5, gravity=(0.1, 0, -1))
    assert str(result).startswith("RBE stable (mu 0.5, paper cone with 8 sides)")
    data = json.loads(json.dumps(result.to_dict()))
    assert data["stable"] and data["parameters"]["gravity"] == [0.1, 0.0, -1.0]
    assert set(result.timings) == {"contacts", "build", "solve"}
    # the resultant needs |f_t| / f_n = 0.1 / 1; single vertices may need more, never beyond the octagon
    assert 0.1 / 0.5 - 1e-9 <= result.friction_utilisation <= 1 / math.cos(math.pi / 8) + 1e-9
    with pytest.raises(AttributeError):
        result.stable = False


def test_unstable_result_has_no_forces():
    result = rbe(_stack(), mu=0.1, gravity=tilted_gravity("x", 20))
    assert not result.stable and result.status == 2
    assert np.isnan(result.forces).all() and math.isnan(result.friction_utilisation)


def test_density_per_block():
    result = rbe(_stack((1.0, 1.0, 1.0)), mu=0.5, density=[1.0, 1.0, 3.0])
    assert result.resultants[0] == pytest.approx([0, 0, 4.0], abs=1e-9)


# --- bad input -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, message", [
    ({"mu": -0.1}, "mu must be"), ({"mu": math.nan}, "mu must be"), ({"mu": math.inf}, "mu must be"),
    ({"mu": 0.5, "gravity": (0, 0, 0)}, "gravity is zero"), ({"mu": 0.5, "gravity": (0, math.nan, -1)}, "finite"),
    ({"mu": 0.5, "gravity": (0, -1)}, "3-vector"), ({"mu": 0.5, "density": 0.0}, "density"),
    ({"mu": 0.5, "density": [1.0]}, "one per block"), ({"mu": 0.5, "cone": "round"}, "cone must be"),
    ({"mu": 0.5, "sides": 3}, "sides"), ({"mu": 0.5, "frame": [5]}, "out of range"),
    ({"mu": 0.5, "density": 1e308}, "at most 1e\\+30"), ({"mu": 0.5, "density": [1.0, 1e300]}, "at most 1e\\+30"),
])
def test_bad_input_raises(kwargs, message):
    with pytest.raises(InterlockError, match=message):
        rbe(_stack(), **kwargs)


def test_no_frame_raises():
    with pytest.raises(InterlockError, match="no frame"):
        rbe(_stack().with_frame([]), mu=0.5)


def test_not_an_assembly_raises():
    with pytest.raises(InterlockError, match="Assembly"):
        rbe([trimesh.creation.box()], mu=0.5)


def test_unknown_method_raises():
    with pytest.raises(InterlockError, match="method must be 'rbe' or 'cra'"):
        critical_tilt(_stack(), "x", 0.5, method="fem")
    with pytest.raises(InterlockError, match="cra_options"):
        critical_tilt(_stack(), "x", 0.5, cra_options={"eps": 1e-5})


@pytest.mark.parametrize("axis", ["z", (0, 0, 0), (1, 2)])
def test_bad_tilt_axis_raises(axis):
    with pytest.raises(InterlockError, match="tilt axis"):
        critical_tilt(_stack(), axis, 0.5)


def test_equilibrium_matrix_normal_columns_are_the_interlocking_matrix_transposed():
    # docs/statics.md: A_eq is the transpose of the kinematic matrix; rows here are (force, moment), there (omega, t)
    from interlock.verify import interlocking_matrix
    from interlock.verify.statics.equilibrium import EquilibriumSystem

    row = [trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)]
    assembly = Assembly.from_meshes(row, frame=[0])
    matrix = interlocking_matrix(assembly)
    kinematic = matrix.matrix.toarray()
    normal_columns = EquilibriumSystem.build(assembly, 0.5, 1.0, None, "paper", 8, None).a_eq.toarray()[:, 0::3]
    swap = np.r_[3:6, 0:3, 9:12, 6:9]
    # moment arms are divided by each matrix's own length (statics: the model size; kinematics: its length_scale)
    moments = np.r_[3:6, 9:12]
    normal_columns[moments] *= assembly.scale / matrix.length_scale
    assert np.allclose(normal_columns, kinematic.T[swap])


# --- large models: Clarabel --------------------------------------------------------------------------------------


@pytest.mark.parametrize("angle", [0.0, 30.0, 60.0, 120.0])
def test_clarabel_path_agrees_with_highs(reference_data, monkeypatch, angle):
    import interlock.verify.statics.equilibrium as equilibrium

    assembly = load_compas(reference_data / "compas_cra" / "type-c.json")
    found = contacts(assembly)
    gravity = tilted_gravity("xy30", angle)
    expected = rbe(assembly, 0.84, gravity=gravity, contacts=found)
    monkeypatch.setattr(equilibrium, "LARGE_LP", 0)
    large = rbe(assembly, 0.84, gravity=gravity, contacts=found)
    assert large.stable == expected.stable and large.message.startswith("Clarabel")
    if large.stable:
        assert large.resultants.sum(axis=0) == pytest.approx(expected.resultants.sum(axis=0), abs=1e-6)


def test_armadillo_vault_stands_with_upstream_contacts(reference_data):
    # 399 blocks, 33 supports; contacts as compas_assembly finds them (tmax = 0.05, amin = 1e-4, any angle)
    vault = load_compas(reference_data / "compas_cra" / "armadillo.json")
    found = contacts(vault, gap=0.05 / vault.scale, area_rtol=1e-4 / vault.scale**2, angle_tol=0.2)
    result = rbe(vault, mu=0.84, contacts=found)
    assert result.stable and result.message.startswith("Clarabel")
    weight = vault.volumes[[b for b in range(len(vault)) if b not in vault.frame]].sum()
    on_supports = [k for k, c in enumerate(result.contacts) if (c.i in vault.frame) != (c.j in vault.frame)]
    vertical = sum(result.resultants[k, 2] * (1 if result.contacts[k].j not in vault.frame else -1) for k in on_supports)
    assert vertical == pytest.approx(weight, rel=1e-6)  # the supports carry the whole weight


# --- solver status is never physics; undecided angles; limits ----------------------------------------------------


def _squeezed_row():
    """Three unit cubes in a row, the two ends fixed: the middle one is held by friction alone (every mu > 0)."""
    return Assembly.from_meshes([trimesh.creation.box(bounds=[[x, 0, 0], [x + 1, 1, 1]]) for x in range(3)],
                                frame=[0, 2])


@pytest.mark.parametrize("mu", [1e-6, 0.5, 1e14, 1e15])
def test_a_squeezed_row_is_never_called_unstable_by_a_solver(mu):
    # HiGHS' "Model error" at mu = 1e15 (mu reached its largest matrix value) was printed as "RBE unstable"; the
    # friction rows are now scaled, and an undecided solve would be "inconclusive (solver: ...)", never "unstable"
    result = rbe(_squeezed_row(), mu)
    assert result.stable is not False, result.message
    assert result.stable is True or result.message.startswith("solver:")


@pytest.mark.parametrize("mu", [1e-9, 1e20, -1.0, math.nan])
def test_mu_outside_the_solvers_range_is_refused_up_front(mu):
    with pytest.raises(InterlockError, match="mu"):
        rbe(_squeezed_row(), mu)


def test_an_undecided_lp_is_inconclusive_not_unstable(monkeypatch):
    from interlock.verify.statics.equilibrium import EquilibriumSystem

    monkeypatch.setattr(EquilibriumSystem, "solve_lp",
                        lambda self, gravity, least_force, budget=None: (None, 4, "solver: HiGHS stalled", 1.0))
    result = rbe(_stack(), 0.5)
    assert result.stable is None and result.message == "solver: HiGHS stalled"
    assert str(result).startswith("RBE inconclusive (solver: HiGHS stalled)")
    assert result.to_dict()["stable"] is None


def test_critical_tilt_of_curve_3_blocks_about_1_minus_1_0_with_its_stored_interfaces(reference_data):
    # issue 40: HiGHS' simplex ends in its status 15 at 48.75 degrees; the scan raised StabilityError. Clarabel
    # decides first now, and an angle no solver decides would be carried as "inconclusive" with its reason
    from interlock.verify.statics import compas_interfaces, tilt_scan

    path = reference_data / "compas_cra" / "curve-3-blocks.json"
    assembly = load_compas(path)
    stored = compas_interfaces(path, assembly)
    assert len(stored) == 40
    scan = tilt_scan(assembly, (1, -1, 0), 0.84, contacts=stored)
    assert scan.status in ("decided", "inconclusive") and 0 < scan.angle < 180
    assert all(reason for _, reason in scan.undecided)
    assert critical_tilt(assembly, (1, -1, 0), 0.84, contacts=stored) == scan.angle


@pytest.mark.parametrize("at, status", [(30.0, "decided"), (20.0, "inconclusive")])
def test_a_tilt_scan_carries_an_undecided_angle_and_goes_on(monkeypatch, at, status):
    # an angle that no solver decides counts as not stable (the safe side), is recorded with its reason, and the
    # bisection goes on below it: past the critical angle (atan 0.5 = 26.57 degrees) the scan still finds it;
    # below it, the answer is the undecided angle, "inconclusive", with the last stable angle below
    from interlock.verify.statics import tilt_scan
    from interlock.verify.statics.equilibrium import EquilibriumSystem

    feasible = EquilibriumSystem.feasible
    undecided = tilted_gravity("x", at)

    def flaky(self, gravity, budget=None):
        if np.allclose(gravity, undecided):
            return None, "solver: Clarabel: NumericalError; HiGHS simplex: status 15"
        return feasible(self, gravity, budget)

    monkeypatch.setattr(EquilibriumSystem, "feasible", flaky)
    scan = tilt_scan(_stack(), "x", 0.5)
    assert scan.undecided == ((at, "solver: Clarabel: NumericalError; HiGHS simplex: status 15"),)
    assert (at, None) in scan.angles and scan.status == status and len(scan.angles) > 6  # bisected on
    if status == "decided":
        assert abs(scan.angle - math.degrees(math.atan(0.5))) <= 0.1
    else:
        assert scan.angle == at and at - 0.1 <= scan.stable_below < at and "undecided at 20.00" in str(scan)
    assert "critical tilt" in str(scan) and json.dumps(scan.to_dict())


def test_a_spent_time_limit_makes_rbe_and_the_tilt_scan_inconclusive():
    from interlock.verify.statics import tilt_scan

    result = rbe(_stack(), 0.5, time_limit=1e-9)  # spent before the first solve
    assert result.stable is None and result.message.startswith("time limit reached in")
    scan = tilt_scan(_stack(), "x", 0.5, time_limit=1e-9)
    assert scan.status == "inconclusive" and scan.undecided[0][1].startswith("time limit reached in")
    assert "inconclusive" in str(scan)
