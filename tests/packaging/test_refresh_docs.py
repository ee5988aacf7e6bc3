"""The generated blocks of README.md and docs/ (lab/docs_blocks.py,
tools/refresh_docs.py): the marker logic, and the cheap deterministic blocks against what their
commands print now."""

import subprocess
import sys

import pytest

from conftest import REPO
from lab.docs_blocks import (
    BlockError,
    find_blocks,
    replace_block,
    wrap_markdown,
)
from lab.refresh.specs import blocks

TOOL = REPO / "tools" / "refresh_docs.py"

DOC = """# Title

Some text before, with a figure <!-- BEGIN generated: speed (python tools/a.py) -->0.6 m/s\
<!-- END generated: speed --> inline.

<!-- BEGIN generated: table (python tools/b.py --x 1) -->
| a | b |
|---|---|
| 1 | 2 |
<!-- END generated: table -->

Text after, untouched.
"""


def test_replacing_a_block_changes_only_its_content():
    new = replace_block(DOC, "table", "| a | b |\n|---|---|\n| 3 | 4 |")
    assert "| 3 | 4 |" in new and "| 1 | 2 |" not in new
    before = DOC.split("<!-- BEGIN generated: table")[0]
    assert new.startswith(before)
    assert new.endswith("<!-- END generated: table -->\n\nText after, untouched.\n")
    assert find_blocks(new)["table"].content(new) == "| a | b |\n|---|---|\n| 3 | 4 |"


def test_replacing_an_inline_block_keeps_the_line():
    new = replace_block(DOC, "speed", "0.61 m/s")
    assert ("figure <!-- BEGIN generated: speed (python tools/a.py) -->0.61 m/s"
            "<!-- END generated: speed --> inline.") in new
    assert new.replace("0.61 m/s", "0.6 m/s") == DOC
    with pytest.raises(BlockError, match="one line"):
        replace_block(DOC, "speed", "two\nlines")


def test_the_marker_takes_the_new_command():
    new = replace_block(DOC, "table", "x", command="python tools/b.py --x 2")
    block = find_blocks(new)["table"]
    assert block.command == "python tools/b.py --x 2"
    assert block.content(new) == "x"
    assert new.count("python tools/b.py") == 1


def test_same_content_gives_the_same_text():
    for name, block in find_blocks(DOC).items():
        assert replace_block(DOC, name, block.content(DOC), block.command) == DOC


def test_a_missing_marker_is_an_error():
    with pytest.raises(BlockError, match="no block 'drift'"):
        replace_block(DOC, "drift", "1 mm")
    without_end = DOC.replace("<!-- END generated: table -->", "")
    with pytest.raises(BlockError, match="'table' has no END marker"):
        find_blocks(without_end, "doc.md")
    without_begin = DOC.replace("<!-- BEGIN generated: table (python tools/b.py --x 1) -->", "")
    with pytest.raises(BlockError, match=r"doc\.md:\d+: END of block 'table' without its BEGIN"):
        find_blocks(without_begin, "doc.md")


def test_repeated_nested_and_line_starting_inline_blocks_are_errors():
    with pytest.raises(BlockError, match="appears twice"):
        find_blocks(DOC + DOC)
    nested = DOC.replace("| 1 | 2 |", "<!-- BEGIN generated: x () -->y<!-- END generated: x -->")
    with pytest.raises(BlockError, match="begins inside"):
        find_blocks(nested)
    line_start = "<!-- BEGIN generated: x () -->1 mm<!-- END generated: x --> of drift\n"
    with pytest.raises(BlockError, match="raw HTML"):
        find_blocks(line_start)


def test_wrap_markdown_fills_prose_and_keeps_tables_and_code():
    text = ("word " * 40).strip() + "\n\n| a |\n|---|\n\n    code line " + "x" * 120 + \
        "\n\n- item " + "y " * 60
    wrapped = wrap_markdown(text, width=50)
    assert all(len(line) <= 50 for line in wrapped.split("\n\n")[0].splitlines())
    assert "| a |\n|---|" in wrapped
    assert "    code line " + "x" * 120 in wrapped
    item = wrapped.split("\n\n")[3].splitlines()
    assert item[0].startswith("- item") and all(line.startswith("  ") for line in item[1:])


def test_a_blocks_date_line_is_left_out_of_the_check():
    """`stamp` ends an undated block with the day it was made and its command; `unstamped`
    takes exactly that line off, so a block made on another day still checks equal."""
    from lab.refresh.text import stamp, unstamped

    table = "| a |\n|---|\n| 1 |"
    made = stamp(table, "2026-01-02", ["python tools/a.py"], multiline=True)
    assert made == table + "\n\n*Produced 2026-01-02 by `python tools/a.py`.*"
    again = wrap_markdown(stamp(table, "2026-03-04", ["python tools/a.py --long " + "x " * 60],
                                multiline=True, from_git=True))
    assert unstamped(made) == unstamped(again) == table
    shown = stamp("`python tools/a.py`:\n\n" + table, "2026-01-02", ["python tools/a.py"], True)
    assert shown.endswith("*Produced 2026-01-02 by the command above.*")
    inline = stamp("0.6 m/s", "2026-01-02", ["python tools/a.py"], multiline=False)
    assert inline == "0.6 m/s (produced 2026-01-02 by `python tools/a.py`)"
    assert unstamped(inline) == "0.6 m/s" and unstamped("0.6 m/s (at rest)") == "0.6 m/s (at rest)"
    assert unstamped(table + "\n\n*Produced by hand.*") == table + "\n\n*Produced by hand.*"


def _tool(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(TOOL), *args], cwd=REPO, capture_output=True,
                          text=True, timeout=900)


def test_every_block_in_the_docs_has_a_command_and_every_command_its_block():
    run = _tool("--list")
    assert run.returncode == 0, run.stderr
    assert "landing-errors" in run.stdout and "python tools/landing_errors.py" in run.stdout


CHEAP_BLOCKS = [s.name for s in blocks() if s.cheap]
"""What `tools/refresh_docs.py --check` re-renders, one test each (so the workers share them)."""


def test_the_cheap_blocks_are_checked():
    assert "step-counts" in CHEAP_BLOCKS and len(CHEAP_BLOCKS) >= 5


@pytest.mark.parametrize("name", CHEAP_BLOCKS)
def test_a_cheap_deterministic_block_is_what_its_command_prints(name):
    """Simulation results are deterministic: the figures in the docs are what the tools print
    today (timings are not checked). On failure: python tools/refresh_docs.py --only NAME."""
    run = _tool("--check", "--only", name)
    assert run.returncode == 0, run.stdout + run.stderr[-3000:]


def test_the_gallery_pictures_every_scenario_and_every_shipped_robot():
    """lab/refresh/gallery.py's PICTURES (hand-kept: each picture's camera) against what ships:
    a picture of each scenarios/*.yaml, and one of each robot of `robots.ROBOTS` (`gallery-<robot>`,
    in a scenario that has that robot), each picture's PNG committed and its block in the page."""
    import shlex

    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.robots import ROBOTS
    from lab.refresh.gallery import GALLERY, PICTURES

    def scenario_of(arguments: str) -> str:
        words = shlex.split(arguments)
        return words[words.index("--scenario") + 1] if "--scenario" in words \
            else str(DEFAULT_SCENARIO.relative_to(REPO))

    pictured = {scenario_of(arguments) for name, _, _, arguments in PICTURES
                if name.startswith("gallery-scenario-")}
    shipped = {str(p.relative_to(REPO)) for p in sorted((REPO / "scenarios").glob("*.yaml"))}
    assert pictured == shipped
    by_name = {name: scenario_of(arguments) for name, _, _, arguments in PICTURES}
    for robot in ROBOTS:
        scenario = by_name.get(f"gallery-{robot}")
        assert scenario is not None, f"no picture of the {robot}"
        robots = {r.robot for r in load_scenario(REPO / scenario).robots.values()}
        assert robot in robots, (robot, scenario, robots)
    page = (REPO / GALLERY).read_text()
    for name, _, png, _ in PICTURES:
        assert (REPO / "docs" / "images" / png).is_file(), png
        assert f"<!-- BEGIN generated: {name} (" in page, name
