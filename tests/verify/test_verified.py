"""Verified floating point at scale (interlock/verify/verified.py): proofs that hold, and refusals where they cannot."""

from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from interlock.blocks import presets, random_hexagon, rhomblock_assembly
from interlock.verify import check, interlocking_matrix
from interlock.verify.verified import singular_value_bound, verified_sparse_stress

flint = pytest.importorskip("flint")


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), condition=st.sampled_from([1e0, 1e-3, 1e-5, 1e-7, 1e-9, 0.0]))
def test_the_bound_never_exceeds_the_smallest_singular_value(seed, condition):
    rng = np.random.default_rng(seed)
    m, n = int(rng.integers(4, 30)), int(rng.integers(1, 4))
    n = min(n + int(rng.integers(0, 10)), m)
    u, _ = np.linalg.qr(rng.standard_normal((m, n)))
    v, _ = np.linalg.qr(rng.standard_normal((n, n)))
    values = np.geomspace(1.0, max(condition, 1e-300), n) if condition else np.r_[np.ones(n - 1), 0.0]
    A = (u * values) @ v.T
    sigma, _ = singular_value_bound(sp.csr_matrix(A))
    assert 0.0 <= sigma <= np.linalg.svd(A, compute_uv=False).min() * (1 + 1e-9) + 1e-300
    if condition == 0.0:
        assert sigma == 0.0


def test_a_matrix_with_a_motion_gets_no_stress():
    # rows (1, 0), (0, 1), (1, 1): x = (1, 1) opens every row, so no positive stress exists
    A = sp.csr_matrix(np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]))
    assert verified_sparse_stress(A, np.ones(3)).smallest <= 0


def test_a_sliding_motion_gets_no_bound():
    grid = presets.interlocking_cubes()
    A = interlocking_matrix(grid, frame=[0]).matrix  # one block fixed: the others move
    assert verified_sparse_stress(A, np.ones(A.shape[0])).smallest <= 0


@pytest.mark.parametrize("build", [presets.interlocking_cubes,
                                   lambda: rhomblock_assembly(random_hexagon(3, 3, 3, seed=0))])
def test_what_verified_floating_point_proves_exact_arithmetic_confirms(build):
    assembly = build()
    frame = assembly.frame or assembly.boundary()
    verdict = check(assembly, frame=frame, validate=False)
    A = interlocking_matrix(assembly, frame=frame).matrix
    proved = verified_sparse_stress(A, verdict.stress)
    assert proved.smallest > 0 and proved.sigma > 0
    exact = flint.fmpq_mat(*A.shape, [flint.fmpq(*Fraction(v).as_integer_ratio()) for v in A.toarray().ravel()])
    assert exact.rank() == A.shape[1]
