"""docs/benchmarks.md's index is made from the blocks themselves (docs/_ext/corobot_docs/
benchmarks.py): every generated block of the docs has its row, with its command, and a link
to the section of its page that holds it; a timing's row carries its block's date. (The site's
build checks that each link's anchor exists.)"""

import re

import pytest

from conftest import REPO
from lab.docs_blocks import find_blocks
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


def test_every_block_and_its_row_carry_its_command_and_date(index):
    """Every block says when it was made (a timing measured: the machine, its load, Drake's
    version; a simulation result or picture produced, `lab.refresh.text.stamp`) and by which
    command, where the page shows it (not only in the marker); its row in the index carries
    the date (the latest of the block's)."""
    found, wrong = rows(index), []
    for spec in blocks():
        text = (REPO / spec.file).read_text()
        block = find_blocks(text, spec.file)[spec.name]
        content = block.content(text)
        dates = re.findall(r"\b20\d\d-\d\d-\d\d\b", content)
        # an inline block's command may be in its paragraph; the command the page shows may
        # leave out `python `
        shown = _paragraph_without_marker(text, block) if not block.multiline else content
        words = " ".join(shown.split())
        unshown = [c.text for c in spec.commands
                   if " ".join(c.text.split()).removeprefix("python ") not in words]
        if not dates or unshown:
            wrong.append(f"{spec.file}: {spec.name}: " + ("no date; " if not dates else "") +
                         (f"does not show {unshown}" if unshown else ""))
            continue
        assert f"| {max(dates)}" in found[spec.name], spec.name
    assert wrong == []


def _paragraph_without_marker(text: str, block) -> str:
    """The paragraph an inline block sits in, its BEGIN marker (which holds the command) left
    out."""
    start = text.rfind("\n\n", 0, block.begin[0]) + 2
    end = text.find("\n\n", block.end[1])
    return text[start:block.begin[0]] + text[block.begin[1]:end if end >= 0 else None]


def test_a_recorded_measurement_has_its_row_date_and_commands(index):
    """A measurement kept by hand (`<!-- recorded: NAME -->`, not regenerated) says its date and
    its commands in its section, and has its row with that date and a link to the section."""
    from corobot_docs.benchmarks import recorded, section_anchors

    from lab.refresh.runner import DOCS

    found, names = rows(index), []
    for doc in DOCS:
        text = (REPO / doc).read_text()
        for name, line, date in recorded(doc, text):
            names.append(name)
            assert date, name
            assert found[name].rstrip(" |").endswith(date), found[name]
            anchor = [a for n, _, a in section_anchors(text) if n < line][-1]
            assert f"#{anchor})" in found[name], (name, anchor)
            nxt = [n for n, _, _ in section_anchors(text) if n > line]
            section = text.splitlines()[line:nxt[0] - 1 if nxt else None]
            assert any(s.startswith("    ") and "python" in s for s in section), name
    assert "sensor-plugins-and-robot-files" in names
