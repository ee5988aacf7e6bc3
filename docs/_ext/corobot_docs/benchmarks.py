"""The benchmarks' index: every generated measurement block of the docs (`lab/refresh`'s
specs, the ones `python tools/refresh_docs.py --list` lists), with its kind, the page and
section it sits in (a link), its command and the date it was measured, read from the block."""

from __future__ import annotations

import re

from corobot_docs.markdown import cell, table

DATE = re.compile(r"\b(20\d\d-\d\d-\d\d)\b")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
KINDS = {"deterministic": "simulation result (the same on every run)",
         "picture": "picture", "timing": "timing (varies with the machine)"}


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


def page() -> str:
    from lab.docs_blocks import find_blocks
    from lab.refresh.runner import REPO
    from lab.refresh.specs import blocks

    rows = []
    texts: dict[str, str] = {}
    for spec in sorted(blocks(), key=lambda s: (s.kind != "deterministic", s.file, s.name)):
        text = texts.setdefault(spec.file, (REPO / spec.file).read_text())
        block = find_blocks(text, spec.file)[spec.name]
        dates = DATE.findall(block.content(text))
        when = max(dates) if dates else ("held by `--check`" if spec.cheap else "")
        rows.append([f"`{spec.name}`", KINDS.get(spec.kind, spec.kind),
                     _where(spec.file, text, block.line), f"`{cell(spec.shown)}`", when])
    return table(["block", "kind", "where", "command", "measured"], rows)
