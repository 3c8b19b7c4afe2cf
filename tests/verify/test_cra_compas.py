"""compas_cra as a source of candidate CRA motions (interlock/verify/cra_compas.py); needs compas_cra 0.8."""

import builtins
import math
from pathlib import Path

import numpy as np
import pytest

compas_cra = pytest.importorskip("compas_cra")

import scipy.sparse as sp  # noqa: E402
import trimesh  # noqa: E402
from scipy.optimize import linprog  # noqa: E402

from interlock.blocks import Assembly, load_compas, semicircular_arch  # noqa: E402
from interlock.errors import InterlockError  # noqa: E402
from interlock.verify import contacts as find_contacts  # noqa: E402
from interlock.verify.statics.cra import CRAProblem  # noqa: E402
from interlock.verify.statics.cra_compas import (MISSING_MESSAGE, _to_minus_z, upstream_motion,  # noqa: E402
                                                 upstream_solution)
from interlock.verify.statics import StabilityError, tilted_gravity  # noqa: E402
from interlock.verify.statics.equilibrium import gravity_vector  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "data" / "compas_cra"
ARCH_MU = math.tan(math.radians(43.0))


def test_missing_package_message(monkeypatch):
    real_import = builtins.__import__

    def no_compas(name, *args, **kwargs):
        if name.split(".")[0] in ("compas", "compas_cra", "compas_assembly"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_compas)
    with pytest.raises(StabilityError) as error:
        upstream_motion(_stack(), mu=0.5)
    assert isinstance(error.value, InterlockError)
    assert str(error.value) == MISSING_MESSAGE
    assert "pip install compas_cra==0.8.0" in str(error.value) and "backend='compas_cra'" in str(error.value)


@pytest.mark.parametrize("gravity", [(0, 0, -1), (0, 0, 1), (1, 0, 0), (0.3, -2, 0.5), (1e-9, 0, -1)])
def test_rotation_turns_gravity_down(gravity):
    g = np.asarray(gravity, dtype=float)
    r = _to_minus_z(g)
    assert np.allclose(r @ r.T, np.eye(3)) and np.isclose(np.linalg.det(r), 1.0)
    assert np.allclose(r @ (g / np.linalg.norm(g)), [0, 0, -1])



def test_cube_stack_sinks_by_eps():
    stack = _stack()
    motion = upstream_motion(stack, mu=0.5)
    eps = 1e-5 * stack.scale
    assert motion.shape == (1, 6)
    assert motion[0, 2] < 0 and abs(motion[0, 2] + eps) <= 0.01 * eps  # down into the bottom cube, by eps
    assert np.abs(motion[0, :2]).max() < 1e-6 * eps and np.abs(motion[0, 3:]).max() < 1e-6 * eps / stack.scale


def test_cube_stack_motion_is_certified_by_our_exact_lp():
    stack = _stack()
    problem, b_eq, q, dd = _in_eps_units(stack, 0.5, (0, 0, -1), upstream_motion(stack, mu=0.5))
    # IPOPT stops at an interior point: the cube sinks by 0.998 eps, not exactly eps ...
    assert np.all(np.abs(dd[:, 0] + 1.0) < 0.01) and not np.any(dd[:, 0] + 1.0 <= 1e-7)
    # ... so the vertices it (nearly) closes are closed exactly, with the least change, before the exact LP
    snapped = _snap(problem, q, dd[:, 0] + 1.0 <= 0.01)
    assert np.abs(snapped - q).max() < 0.01
    assert problem.exact(b_eq, snapped) is not None


def test_tilted_cube_stack_motion_turns_back():
    stack = _stack()
    gravity = tilted_gravity("x", 10)  # turned about x: gravity gains a -y part, the top cube slides along -y
    motion = upstream_motion(stack, mu=0.5, gravity=gravity)
    assert motion[0, 1] < 0 and motion[0, 2] < 0 and abs(motion[0, 0]) < 1e-9
    problem, b_eq, q, dd = _in_eps_units(stack, 0.5, gravity, motion)
    assert np.all(dd[:, 0] + 1.0 <= 1e-3)
    assert problem.exact(b_eq, _snap(problem, q, dd[:, 0] + 1.0 <= 1e-3)) is not None
    assert upstream_motion(stack, mu=0.5, gravity=tilted_gravity("x", 30)) is None  # tan 30 > 0.5: it slides
    assert upstream_motion(stack, mu=0.5, gravity=(0, 0, 1)) is None  # nothing holds it up


def test_upstream_forces_balance_in_our_model():
    """Same vertices, frames, centres and loads: upstream's forces are an equilibrium of our A_eq."""
    arch = semicircular_arch()
    contacts = find_contacts(arch)
    gravity = tilted_gravity("y", 5)
    motion, forces = upstream_solution(arch, ARCH_MU, gravity=gravity, contacts=contacts)
    problem = CRAProblem.build(arch, ARCH_MU, contacts=contacts)
    weight = np.outer(problem.system.weights, gravity_vector(gravity))
    b_eq = -np.hstack([weight, problem.system.arms]).ravel()
    assert forces.shape == (len(problem.system.points), 3)
    assert np.abs(problem.system.a_eq @ forces.ravel() - b_eq).max() < 1e-6 * np.abs(weight).sum()
    assert motion.shape == (len(problem.system.free), 6)


def test_model_h_upstream_finds_no_motion():
    """compas_cra's IPOPT finds no solution for H (the block between two walls) at mu = 0.84: like cra()."""
    h = load_compas(DATA / "H.json")
    assert upstream_motion(h, mu=0.84) is None


@pytest.mark.parametrize("angle", [0.0, 5.0])
def test_arch_motion_not_certified(angle):
    """The 38-block arch (Table 1: stable up to 8.2 deg at 43 deg friction).

    compas_cra returns a motion in about a second, within the bounds, but it is an
    interior point of IPOPT (every vertex carries some force, loaded vertices open by
    up to a few eps), and neither it nor its least-change snap onto upstream's
    (nearly) closed vertices is accepted by our exact LP.
    """
    arch = semicircular_arch()
    gravity = tilted_gravity("y", angle)
    motion = upstream_motion(arch, ARCH_MU, gravity=gravity)
    assert motion is not None and motion.shape == (36, 6) and np.all(np.isfinite(motion))
    problem, b_eq, q, dd = _in_eps_units(arch, ARCH_MU, gravity, motion)
    assert dd[:, 0].min() >= -1.0 - 1e-3 and np.abs(dd).max() <= problem.ratio * (1 + 1e-3)
    closed = dd[:, 0] + 1.0 <= 0.01
    # (exact needs a closed vertex: with none, its LP has no unknowns and scipy refuses it)
    accepted = [bool((dd[:, 0] + 1.0 <= 1e-7).any()) and problem.exact(b_eq, q) is not None]
    snapped = _snap(problem, q, closed)
    accepted.append(snapped is not None and bool(closed.any()) and problem.exact(b_eq, snapped) is not None)
    if any(accepted):
        pytest.fail(f"our exact LP now accepts upstream's arch motion at {angle} deg (raw, snapped): {accepted}")


# --- helpers ----------------------------------------------------------------------------------------------------

def _stack():
    cubes = [trimesh.creation.box(bounds=[[0, 0, z], [1, 1, z + 1]]) for z in (0, 1)]
    return Assembly.from_meshes(cubes, frame=[0])


def _in_eps_units(assembly, mu, gravity, motion):
    """The CRA problem, its b_eq (as in CRAProblem.solve), the motion in units of eps (as in decider) and dd."""
    problem = CRAProblem.build(assembly, mu)
    load = np.outer(problem.system.weights, gravity_vector(gravity))
    b_eq = -np.hstack([load, problem.system.arms]).ravel() / float(np.abs(load).sum())
    eps, length = problem.parameters["eps_absolute"], problem.parameters["length"]
    q = np.hstack([motion[:, :3] / eps, motion[:, 3:] * length / eps]).ravel()
    return problem, b_eq, q, (problem.kinematic @ q).reshape(-1, 3)


def _snap(problem, q, closed):
    """The motion nearest ``q`` (L1) closing the ``closed`` vertices exactly (dd_n = -1), the others not
    overlapping, |dd| <= eta / eps; ``None`` if there is none."""
    d = problem.kinematic
    n = d.shape[1]
    d_n = d[0::3]
    a_eq = sp.hstack([d_n[closed], -d_n[closed]])
    b_eq = -1.0 - d_n[closed] @ q
    a_ub = sp.vstack([sp.hstack([-d_n[~closed], d_n[~closed]]), sp.hstack([d, -d]), sp.hstack([-d, d])])
    b_ub = np.concatenate([1.0 + d_n[~closed] @ q, problem.ratio - d @ q, problem.ratio + d @ q])
    outcome = linprog(np.ones(2 * n), A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=(0, None), method="highs")
    return q + outcome.x[:n] - outcome.x[n:] if outcome.status == 0 else None
