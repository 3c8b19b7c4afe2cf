"""The documentation's examples run as written, and use no deprecated import path."""

import doctest
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
#: The pages with examples (doctests); every other page is prose only.
PAGES = ["interlocking.md", "certificates.md", "criterion.md", "periodic.md", "wallpaper.md", "statics.md",
         "beyond-first-order.md", "npod.md", "architecture.md"]


# the old paths warn "interlock.<old>.<name> moved to ..." (interlock.deprecation): a page must not use them
@pytest.mark.filterwarnings(r"error:interlock\.[\w.]+ moved to:DeprecationWarning")
@pytest.mark.parametrize("page", PAGES)
def test_the_examples_of_a_documentation_page_run(page):
    result = doctest.testfile(str(DOCS / page), module_relative=False, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_every_page_with_examples_is_tested():
    with_examples = sorted(p.name for p in DOCS.glob("*.md") if ">>> " in p.read_text())
    assert with_examples == sorted(PAGES)


def test_links_between_pages_point_to_pages():
    import re

    broken = [(p.name, link) for p in DOCS.glob("*.md") for link in re.findall(r"\]\(([\w.-]+\.md)\)", p.read_text())
              if not (DOCS / link).is_file()]
    assert broken == []
