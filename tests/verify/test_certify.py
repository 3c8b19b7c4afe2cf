"""Certificates (interlock/verify/certify.py): verified floating point for the stress, exact arithmetic otherwise."""

import numpy as np
import pytest
import scipy.sparse as sp

from interlock.blocks import presets, random_hexagon, rhomblock_assembly
from interlock.verify import check, interlocking_matrix
from interlock.verify import certify as module
from interlock.verify.certify import verified_stress
from interlock.verify.verified import VerifiedStress


def _without_sparse_verification(monkeypatch):
    monkeypatch.setattr(module, "verified_sparse_stress", lambda A, w: VerifiedStress(-np.inf, 0.0, np.inf))


def test_verified_floating_point_certifies_an_interlocked_hexagon():
    hexagon = rhomblock_assembly(random_hexagon(6, 6, 6, seed=0))
    v = check(hexagon, frame=hexagon.boundary(), certify=True, validate=False)
    assert v.interlocked is True and v.certified and "by verified floating point" in v.status


def test_the_verified_bound_agrees_with_exact_arithmetic(monkeypatch):
    cubes = presets.interlocking_cubes()
    fast = check(cubes, certify=True)
    _without_sparse_verification(monkeypatch)
    dense = check(cubes, certify=True)
    monkeypatch.setattr(module, "VERIFIED_COLUMNS", 0)  # exact rational arithmetic only
    exact = check(cubes, certify=True)
    assert fast.certified and dense.certified and exact.certified and "exactly invertible" in exact.status
    assert "smallest singular value at least" in fast.status and "invertible row basis" in dense.status


def test_no_bound_for_a_singular_basis_or_a_stress_that_changes_sign():
    singular = np.array([[1.0, 2.0], [2.0, 4.0]])
    assert verified_stress(singular, sp.csr_matrix(np.array([[1.0, 0.0]])), np.array([1.0])) is None
    # B^T w_b = -R^T w_rest with R = (1, 1), w_rest = 1: w_b = (-1, -1), not positive
    bound = verified_stress(np.eye(2), sp.csr_matrix(np.array([[1.0, 1.0]])), np.array([1.0]))
    assert bound is not None and bound < 0


def test_the_bound_is_close_to_the_exact_smallest_weight():
    # B = I, R = (-1, -2): w_b = (1, 2) exactly; the bound is below 1 by rounding only
    bound = verified_stress(np.eye(2), sp.csr_matrix(np.array([[-1.0, -2.0]])), np.array([1.0]))
    assert 1 - 1e-12 < bound <= 1
    A = interlocking_matrix(presets.interlocking_cubes()).matrix
    assert A.shape[1] <= module.VERIFIED_COLUMNS


def test_beyond_both_limits_the_verdict_says_it_is_not_certified_and_why(monkeypatch):
    _without_sparse_verification(monkeypatch)
    monkeypatch.setattr(module, "VERIFIED_COLUMNS", 0)
    monkeypatch.setattr(module, "EXACT_COLUMNS", 0)
    v = check(presets.interlocking_cubes(), certify=True)
    assert v.interlocked is True and not v.certified
    assert "too many for verified floating point (at most 0)" in v.status


def test_a_spent_budget_stops_the_certificate():
    from interlock.blocks import presets as _presets
    from interlock.verify.budget import Budget, TimeLimitReached
    from interlock.verify.certify import certify_verdict
    from interlock.verify.matrix import interlocking_matrix

    cubes = _presets.interlocking_cubes()
    verdict = check(cubes)
    with pytest.raises(TimeLimitReached, match="certify"):
        certify_verdict(cubes, interlocking_matrix(cubes), verdict, budget=Budget(limit=1e-9, started=0.0))


def test_edge_contact_rows_are_covered_by_the_stress_certificate():
    from interlock.blocks import presets as _presets

    v = check(_presets.tetrahedra("p3"), certify=True)
    assert v.interlocked is True and v.certified and v.contact_kinds["edge-edge"] > 0
