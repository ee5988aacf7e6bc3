"""Generated blocks in Markdown: text between a BEGIN and an END marker that a command writes.

    <!-- BEGIN generated: NAME (COMMAND) -->
    ...written by COMMAND, replaced whole on refresh...
    <!-- END generated: NAME -->

The markers are HTML comments, invisible when the Markdown is rendered. A block whose BEGIN
marker ends its line holds whole lines (tables, pictures, paragraphs); a block whose markers
sit inside a line holds a few words of prose. `replace_block` rewrites the content and the
command in the BEGIN marker and leaves every character outside the markers as it was.
`lab/refresh/` knows the blocks and their commands (`tools/refresh_docs.py` runs them).
"""

from __future__ import annotations

import dataclasses as dc
import re
import textwrap

BEGIN = re.compile(r"<!-- BEGIN generated: (?P<name>[A-Za-z0-9_.-]+)(?: \((?P<command>.*?)\))? -->")
END = re.compile(r"<!-- END generated: (?P<name>[A-Za-z0-9_.-]+) -->")


class BlockError(ValueError):
    """A marker is missing, unmatched or repeated; the message names the block (and line)."""


@dc.dataclass(frozen=True)
class Block:
    name: str
    command: str
    begin: tuple[int, int]
    """Span of the BEGIN marker in the text."""
    end: tuple[int, int]
    """Span of the END marker."""
    line: int
    """1-based line of the BEGIN marker."""
    multiline: bool
    """The BEGIN marker ends its line: the block holds whole lines (else a few words)."""

    def content(self, text: str) -> str:
        """The text between the markers, without the line breaks that frame a multi-line
        block."""
        inner = text[self.begin[1]:self.end[0]]
        if self.multiline:
            inner = inner.removeprefix("\n").removesuffix("\n")
        return inner


def _line(text: str, pos: int) -> int:
    return text.count("\n", 0, pos) + 1


def find_blocks(text: str, source: str = "<text>") -> dict[str, Block]:
    """Every block in `text` by name, in order. Raises BlockError for an END without its
    BEGIN, a BEGIN without its END, nested blocks, or a name used twice."""
    blocks: dict[str, Block] = {}
    begins = list(BEGIN.finditer(text))
    ends = list(END.finditer(text))
    markers = sorted([(m.start(), "begin", m) for m in begins] +
                     [(m.start(), "end", m) for m in ends], key=lambda t: t[0])
    open_: re.Match | None = None
    for pos, kind, m in markers:
        name = m["name"]
        if kind == "begin":
            if open_ is not None:
                raise BlockError(f"{source}:{_line(text, pos)}: block {name!r} begins inside "
                                 f"block {open_['name']!r}")
            if name in blocks:
                raise BlockError(f"{source}:{_line(text, pos)}: block {name!r} appears twice")
            open_ = m
        else:
            if open_ is None or open_["name"] != name:
                raise BlockError(f"{source}:{_line(text, pos)}: END of block {name!r} without "
                                 f"its BEGIN")
            multiline = text.startswith("\n", open_.end())
            line_start = text.rfind("\n", 0, open_.start()) + 1
            if not multiline and not text[line_start:open_.start()].strip():
                raise BlockError(f"{source}:{_line(text, pos)}: block {name!r} sits inside a "
                                 f"line but its BEGIN marker starts the line (Markdown would "
                                 f"read the line as raw HTML): put text before it")
            blocks[name] = Block(name, open_["command"] or "", open_.span(), m.span(),
                                 _line(text, open_.start()), multiline)
            open_ = None
    if open_ is not None:
        raise BlockError(f"{source}:{_line(text, open_.start())}: block {open_['name']!r} has "
                         f"no END marker")
    return blocks


def replace_block(text: str, name: str, content: str, command: str | None = None,
                  source: str = "<text>") -> str:
    """`text` with block `name`'s content replaced by `content` (and the command in its BEGIN
    marker by `command`, if given). A multi-line block keeps its content on lines of its own.
    Raises BlockError when the block is not in `text`."""
    blocks = find_blocks(text, source)
    if name not in blocks:
        raise BlockError(f"{source}: no block {name!r} (expected a marker "
                         f"'<!-- BEGIN generated: {name} (...) -->')")
    block = blocks[name]
    if "-->" in content or (command and "-->" in command):
        raise BlockError(f"{source}: block {name!r}: content or command contains '-->'")
    if block.multiline:
        inner = "\n" + content.strip("\n") + "\n"
    else:
        if "\n" in content.strip("\n"):
            raise BlockError(f"{source}:{block.line}: block {name!r} sits inside a line: its "
                             f"content must be one line")
        inner = content.strip("\n")
    begin = text[block.begin[0]:block.begin[1]]
    if command is not None:
        begin = f"<!-- BEGIN generated: {name} ({command}) -->"
    return text[:block.begin[0]] + begin + inner + text[block.end[0]:]


def wrap_markdown(text: str, width: int = 98) -> str:
    """Prose paragraphs and list items of `text` filled to `width`; tables, code, pictures and
    HTML kept as they are."""
    out, fenced = [], False
    for paragraph in text.split("\n\n"):
        lines = paragraph.split("\n")
        starts_fence = sum(line.startswith("```") for line in lines) % 2 == 1
        keep = fenced or any(line.startswith(("|", "    ", "```", "![", "<", "#"))
                             for line in lines)
        fenced ^= starts_fence
        if keep:
            out.append(paragraph)
        elif lines[0].startswith("- "):
            items = re.split(r"\n(?=- )", paragraph)
            out.append("\n".join(textwrap.fill(" ".join(i.split()), width, subsequent_indent="  ",
                                                break_long_words=False, break_on_hyphens=False)
                                  for i in items))
        else:
            out.append(textwrap.fill(" ".join(paragraph.split()), width,
                                     break_long_words=False, break_on_hyphens=False))
    return "\n\n".join(out)
