"""Block labels in files (interlock.blocks.labels): every label an assembly makes comes back as itself."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from interlock import wallpaper
from interlock.blocks.labels import LABEL_KINDS, label_from_text, label_text
from interlock.blocks.lozenge import Lozenge

_plain = st.recursive(st.one_of(st.text(), st.integers(-10 ** 12, 10 ** 12),
                                st.floats(allow_nan=False, allow_infinity=False)),
                      lambda inner: st.lists(inner, max_size=4).map(tuple), max_leaves=12)


@given(_plain)
def test_text_numbers_and_nested_tuples_come_back_equal_and_of_the_same_type(label):
    kind, text = label_text(label)
    assert kind in LABEL_KINDS and isinstance(text, str)
    back = label_from_text(kind, text)
    assert back == label and type(back) is type(label)


def test_group_elements_and_lozenges_come_back_as_themselves():
    elements = wallpaper.group("p4g").elements_within(1.5)
    assert [label_from_text(*label_text(g)) for g in elements] == list(elements)
    lozenges = [Lozenge(2, -1, 0), Lozenge(0, 3, 2)]
    assert [label_from_text(*label_text(z)) for z in lozenges] == lozenges
    assert [label_text(g)[0] for g in elements[:1]] + [label_text(lozenges[0])[0]] == ["element", "lozenge"]


@pytest.mark.parametrize("label, kind", [(7, "int"), ((1, -2, 3), "integers"), ((), "integers"), ("keystone", "str"),
                                         (("voussoir", 3), "json"), (0.5, "json"), (True, "text"), (None, "text"),
                                         ((1.5, float("nan")), "text")])
def test_each_label_gets_its_kind(label, kind):
    assert label_text(label)[0] == kind


@pytest.mark.parametrize("kind, text", [("int", "seven"), ("element", "not a symop"), ("lozenge", "1,2"),
                                        ("json", "[1, 2"), ("json", '{"a": 1}'), ("later kind", "x")])
def test_a_text_edited_by_hand_comes_back_as_the_text(kind, text):
    assert label_from_text(kind, text) == text


@given(st.sampled_from(LABEL_KINDS + ("unknown",)), st.text(max_size=40))
def test_any_text_of_any_kind_gives_a_label_and_never_an_exception(kind, text):
    label_from_text(kind, text)  # a damaged or hand-edited file: the text at worst, no traceback
