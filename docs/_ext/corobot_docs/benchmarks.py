"""The benchmarks' index: every generated measurement block of the docs (`lab/refresh`'s
specs, the ones `python tools/refresh_docs.py --list` lists), with its kind, the page and
section it sits in (a link), its command and the date it was made, read from the block; then
each recorded one-off measurement (a section marked `<!-- recorded: NAME -->`, kept by hand:
its commands and date in its text, never regenerated)."""

from __future__ import annotations

import re

from corobot_docs.markdown import cell, table

DATE = re.compile(r"\b(20\d\d-\d\d-\d\d)\b")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
RECORDED = re.compile(r"^<!-- recorded: ([A-Za-z0-9_.-]+) -->$", re.MULTILINE)
KINDS = {"deterministic": "simulation result (the same on every run)",
         "picture": "picture", "timing": "timing (varies with the machine)",
         "recorded": "recorded once, by hand (not regenerated)"}


def _slug(title: str) -> str:
    """MyST's GitHub-style anchor of a heading's text (its inline code and links as text)."""
    from myst_parser.slugs import github_slugify

    title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title).replace("`", "")
    return github_slugify(title.replace("**", "").replace("*", ""))


def section_anchors(text: str) -> list[tuple[int, str, str]]:
    """(1-based line, heading, anchor) of each heading outside code, anchors made unique as
    MyST makes them (a repeated heading's anchor gains -1, -2, ...)."""
    seen: dict[str, int] = {}
    out, fence = [], None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        if stripped.startswith(("```", "~~~")):
            mark = stripped[:3]
            fence = None if fence == mark else fence or mark
            continue
        m = HEADING.match(line)
        if fence or not m or line.startswith("    "):
            continue
        slug = _slug(m.group(2))
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.append((number, m.group(2), slug if n == 0 else f"{slug}-{n}"))
    return out


def _where(file: str, text: str, line: int) -> str:
    """A link to the section a block sits in (from the docs' root, as pages link)."""
    above = [(h, a) for n, h, a in section_anchors(text) if n < line]
    heading, anchor = above[-1] if above else (file, "")
    if not file.startswith("docs/"):
        return f"{file}, \"{cell(heading)}\""
    page = file.removeprefix("docs/")
    return f"[{page}, {cell(heading)}]({page}#{anchor})" if anchor else f"[{page}]({page})"


def recorded(file: str, text: str) -> list[tuple[str, int, str]]:
    """(name, 1-based line, latest date) of each recorded one-off measurement in a page: its
    marker, and the dates of its section's text (to the next heading)."""
    out = []
    for m in RECORDED.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        below = [n for n, _, _ in section_anchors(text) if n > line]
        lines = text.splitlines()[line:below[0] - 1 if below else None]
        dates = DATE.findall("\n".join(lines))
        out.append((m[1], line, max(dates) if dates else ""))
    return out


def page() -> str:
    from lab.docs_blocks import find_blocks
    from lab.refresh.runner import DOCS, REPO
    from lab.refresh.specs import blocks
    from lab.refresh.text import FROM_GIT

    rows = []
    texts = {doc: (REPO / doc).read_text() for doc in DOCS}
    for spec in sorted(blocks(), key=lambda s: (s.kind != "deterministic", s.file, s.name)):
        text = texts[spec.file]
        block = find_blocks(text, spec.file)[spec.name]
        content = block.content(text)
        dates = DATE.findall(content)
        when = (max(dates) if dates else "") + (" (from git)" if FROM_GIT in content else "") \
            + (" (held by `--check`)" if spec.cheap else "")
        rows.append([f"`{spec.name}`", KINDS.get(spec.kind, spec.kind),
                     _where(spec.file, text, block.line), f"`{cell(spec.shown)}`", when])
    for doc, text in texts.items():
        rows += [[f"`{name}`", KINDS["recorded"], _where(doc, text, line),
                  "the commands in its section", when] for name, line, when in recorded(doc, text)]
    return table(["block", "kind", "where", "command", "made"], rows)
