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


# --- the README: its Python examples and its command lines give the output it shows ---------------------------

README = DOCS.parent / "README.md"


def _blocks(language: str) -> list[str]:
    import re

    return re.findall(rf"```{language}\n(.*?)```", README.read_text(), flags=re.DOTALL)


def _matches(expected: str, printed: str) -> bool:
    """Whether ``printed`` starts as ``expected``, ``...`` standing for any text, whitespace and line breaks aside.

    The README shows the start of an output (a command's first lines), so what follows is not compared.
    """
    import re

    def words(text):
        return " ".join(text.split())

    pattern = ".*".join(re.escape(part) for part in words(expected).split("..."))
    return re.match(pattern, words(printed), flags=re.DOTALL) is not None


def _expected_after(lines: list[str], end: int) -> str:
    """The comment lines right after line ``end`` (1-based, the statement's last line): its shown output."""
    shown = []
    for line in lines[end:]:
        if not line.startswith("# "):
            break
        shown.append(line[2:])
    return "\n".join(shown)


@pytest.mark.filterwarnings(r"error:interlock\.[\w.]+ moved to:DeprecationWarning")
def test_the_python_examples_of_the_readme_print_what_it_shows():
    import ast
    import contextlib
    import io

    namespace, wrong = {}, []  # the blocks run in order, as a reader would paste them
    for source in _blocks("python"):
        lines = source.splitlines()
        for statement in ast.parse(source).body:
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                exec(compile(ast.Module([statement], []), "README.md", "exec"), namespace)
            expected = _expected_after(lines, statement.end_lineno)
            if expected and not _matches(expected, printed.getvalue()):
                wrong.append((lines[statement.lineno - 1], expected, printed.getvalue()))
    assert wrong == []


def _commands() -> list[tuple[str, str]]:
    """(command, shown output) for every ``$ interlock ...`` line of the README's text blocks."""
    out = []
    for block in _blocks("text"):
        for chunk in block.split("$ ")[1:]:
            command, _, shown = chunk.partition("\n")
            out.append((command, shown.strip()))
    return out


#: The exit status of ``verify`` and ``periodic`` by the first word of the verdict they print (``interlock verify
#: --help``): 0 interlocked, 1 not interlocked, 3 inconclusive; the other commands exit 0 when they succeed.
VERDICT_STATUS = {"interlocked": 0, "not": 1, "inconclusive": 3}


def _documented_status(argv: list[str], shown: str) -> int:
    """The exit status the README's shown output documents for the command ``argv``."""
    if argv[0] not in ("verify", "periodic"):
        return 0
    first = shown.split(maxsplit=1)[0].rstrip(":,") if shown else ""
    assert first in VERDICT_STATUS, f"interlock {argv[0]} shows no verdict to read its exit status from: {shown!r}"
    return VERDICT_STATUS[first]


def test_the_documented_status_is_read_from_the_verdict_shown():
    assert _documented_status(["verify"], "interlocked, certified: ...") == 0
    assert _documented_status(["periodic"], "not interlocked: one cell ...") == 1
    assert _documented_status(["verify"], "not infinitesimally interlocked: ...") == 1
    assert _documented_status(["verify"], "inconclusive: time limit reached ...") == 3
    assert _documented_status(["generate"], "wrote p4.stl: 69 blocks, 24 in the frame") == 0


@pytest.mark.parametrize("command, shown", _commands(), ids=[c for c, _ in _commands()])
def test_the_commands_of_the_readme_print_what_it_shows(command, shown, reference_data, tmp_path):
    import contextlib
    import io
    import shlex

    from interlock.cli import main

    argv = shlex.split(command)[1:]
    if any("bunny/" in a for a in argv):  # the TopoLite bunny of the reference data, part_{1..80}.obj
        bunny = reference_data / "topolite" / "bunny"
        argv = [a for a in argv if "bunny/" not in a]
        argv[1:1] = [str(bunny / f"part_{k}.obj") for k in range(1, 81)]
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = main(argv)
    assert status == _documented_status(argv, shown), (status, shown, printed.getvalue())
    assert _matches(shown, printed.getvalue().strip().split("\ntimings:")[0]), (shown, printed.getvalue())
