"""The labelling and scoring rules of benchmarks/accuracy.py: labels only from what is proven."""

import pytest

from benchmarks.accuracy import (INCONCLUSIVE, INTERLOCKED, NOT_INTERLOCKED, escher_case, label, score, staircases,
                                 summarise)


def test_p1_translations_are_labelled_by_criterion_4_3_whatever_certification_says():
    assert label("p1", "translational", True, None) == (INTERLOCKED, "Criterion 4.3 holds (Thm. 4.7)")
    assert label("p1", "translational", False, (INTERLOCKED, True))[0] == NOT_INTERLOCKED
    # the full question in p1 is not Thm. 4.7: a holding criterion leaves it to certification
    assert label("p1", "full", True, (INTERLOCKED, False)) == (None, "unlabelled")


@pytest.mark.parametrize("family", ["p2", "p3", "p4", "p6"])
@pytest.mark.parametrize("question", ["translational", "full"])
def test_a_failing_criterion_proves_not_interlocked_for_every_group_and_question(family, question):
    assert label(family, question, False, (INTERLOCKED, True))[0] == NOT_INTERLOCKED


def test_rhomblocks_interlock_by_theorem_4_9_only_for_the_full_question():
    assert label("rhomblock", "full", None, None) == (INTERLOCKED, "Thm. 4.9 (periodic RhomBlock tiling)")
    assert label("rhomblock", "translational", None, (INTERLOCKED, True)) == (INTERLOCKED, "certified periodic verdict")
    assert label("rhomblock", "translational", None, (INTERLOCKED, False)) == (None, "unlabelled")


def test_only_certified_decided_verdicts_label_the_rest():
    assert label("p4", "full", True, (NOT_INTERLOCKED, True)) == (NOT_INTERLOCKED, "certified periodic verdict")
    assert label("p4", "full", True, (INCONCLUSIVE, True)) == (None, "unlabelled")
    assert label("p4", "full", True, (INTERLOCKED, False)) == (None, "unlabelled")


def test_inconclusive_is_never_correct_and_unlabelled_is_not_scored():
    assert score(INCONCLUSIVE, INTERLOCKED) == INCONCLUSIVE
    assert score(INCONCLUSIVE, NOT_INTERLOCKED) == INCONCLUSIVE
    assert score(INTERLOCKED, NOT_INTERLOCKED) == "wrong"
    assert score(NOT_INTERLOCKED, NOT_INTERLOCKED) == "correct"
    assert score(INTERLOCKED, None) is None


def test_shares_leave_out_unlabelled_verdicts():
    studies = [{"question": "full", "skipped": [], "verdicts": [{"method": "periodic", "seconds": s, "score": sc}]}
               for s, sc in [(1.0, "correct"), (2.0, INCONCLUSIVE), (3.0, None), (4.0, "wrong")]]
    row = summarise(studies, radii=())["full"]["periodic"]
    assert (row["verdicts"], row["labelled"], row["median_seconds"]) == (4, 3, 2.5)
    assert (row["correct_share"], row["inconclusive_share"], row["wrong_share"]) == pytest.approx((1 / 3, 1 / 3, 1 / 3))


def test_cases_are_reproducible_from_group_and_seed():
    a, b = escher_case("p2", 7), escher_case("p2", 7)
    assert a.parameters == b.parameters and "escher_case('p2', 7)" in a.reproduce
    assert len(staircases()) == 49 and (1, 1, 1) in staircases() and (2, 2, 2) not in staircases()
