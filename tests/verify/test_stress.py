"""The widest stress (interlock.verify.stress): largest support, exact certificate, both LP forms."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

from interlock.verify import stress as stress_module
from interlock.verify.stress import widest_stress


def _in_some_stress(A, row):
    """Whether some stress ``w >= 0``, ``A^T w = 0``, ``sum w = 1`` has ``w_row > 0`` (one LP per row)."""
    m = A.shape[0]
    cost = np.zeros(m)
    cost[row] = -1.0
    outcome = linprog(cost, A_eq=np.vstack([A.T, np.ones((1, m))]), b_eq=np.r_[np.zeros(A.shape[1]), 1.0],
                      bounds=(0, None), method="highs")
    return outcome.status == 0 and -outcome.fun > 1e-9


@given(st.integers(0, 2**32 - 1), st.integers(2, 9), st.integers(1, 4))
@settings(max_examples=60, deadline=None)
def test_the_support_is_every_row_that_some_stress_loads(seed, m, n):
    # small integer matrices: every row's membership is clear-cut
    A = np.random.default_rng(seed).integers(-2, 3, size=(m, n)).astype(float)
    found = widest_stress(A)
    assert found.support.tolist() == [_in_some_stress(A, i) for i in range(m)]
    assert np.all(found.stress >= 0) and np.all(found.stress[~found.support] == 0)
    assert np.abs(A.T @ found.stress).max() <= 1e-9 * max(found.stress.max(initial=0.0), 1.0)


def test_a_turned_matrix_with_entries_of_1e_10_keeps_the_support():
    # x and y are forced both ways; z >= 0 and x + y + z >= 0 are not (no row pulls z back)
    A = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [1, 1, 1]])
    angle = 1.2e-7
    turn = np.array([[1.0, 0, 0], [0, np.cos(angle), -np.sin(angle)], [0, np.sin(angle), np.cos(angle)]])
    turned = np.diag([1.0, 1.0, 1e-3, 1e-3, 1.0, 1.0]) @ A @ turn.T  # rows 2, 3 get entries of 1.2e-10
    assert 0 < np.abs(turned[2:4]).min(where=turned[2:4] != 0, initial=1.0) < 1e-9
    expected = [True, True, True, True, False, False]
    assert widest_stress(A).support.tolist() == expected
    assert widest_stress(turned).support.tolist() == expected


@pytest.mark.parametrize("dense_entries", [0, 10**9])
def test_the_sparse_and_the_dense_form_agree(monkeypatch, dense_entries):
    monkeypatch.setattr(stress_module, "DENSE_ENTRIES", dense_entries)
    A = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    found = widest_stress(A)
    assert found.support.tolist() == [True, True, False, False]
    assert found.value == pytest.approx(2.0)


def test_no_rows_and_a_stress_tolerance():
    assert widest_stress(np.zeros((0, 3))).support.shape == (0,)
    A = np.array([[1.0], [-1.0]])
    assert widest_stress(A, stress_tol=1e12).support.tolist() == [False, False]
