"""docs/benchmarks.md's index is made from the blocks themselves (docs/_ext/corobot_docs/
benchmarks.py): every generated block of the docs has its row, with its command, and a link
to the section of its page that holds it; a timing's row carries its block's date. (The site's
build checks that each link's anchor exists.)"""

import re

import pytest

from conftest import REPO
from lab.docs_blocks import find_blocks
from lab.refresh.runner import TIMING
from lab.refresh.specs import blocks


@pytest.fixture(scope="module")
def index(monkeypatch_module):
    from corobot_docs import benchmarks

    return benchmarks.page()


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as mp:
        mp.syspath_prepend(str(REPO / "docs" / "_ext"))
        yield mp


def rows(index: str) -> dict[str, str]:
    return {m[1]: m[0] for m in re.finditer(r"^\| `([\w.-]+)` \|.*$", index, re.MULTILINE)}


def test_every_block_has_its_row_with_its_command(index):
    found = rows(index)
    for spec in blocks():
        assert spec.name in found, spec.name
        assert spec.shown.replace("|", "\\|") in found[spec.name], spec.name


def test_a_docs_pages_block_links_to_its_section(index):
    from corobot_docs.benchmarks import section_anchors

    found = rows(index)
    for spec in blocks():
        if not spec.file.startswith("docs/"):
            continue
        page = spec.file.removeprefix("docs/")
        link = re.search(rf"\]\({re.escape(page)}#([\w-]+)\)", found[spec.name])
        assert link, (spec.name, found[spec.name])
        text = (REPO / spec.file).read_text()
        line = find_blocks(text, spec.file)[spec.name].line
        above = [anchor for n, _, anchor in section_anchors(text) if n < line]
        assert link[1] == above[-1], (spec.name, link[1], above[-1])


def test_every_timing_block_and_its_row_carry_the_blocks_date(index):
    """A timing is of its day (the machine, its load, Drake's version): each timing block says
    when it was measured, and its row in the index the same (the latest of the block's dates)."""
    found, undated = rows(index), []
    for spec in blocks():
        if spec.kind != TIMING:
            continue
        text = (REPO / spec.file).read_text()
        dates = re.findall(r"\b20\d\d-\d\d-\d\d\b", find_blocks(text, spec.file)[spec.name]
                           .content(text))
        if not dates:
            undated.append(f"{spec.file}: {spec.name}")
            continue
        assert found[spec.name].rstrip(" |").endswith(max(dates)), spec.name
    assert undated == []
