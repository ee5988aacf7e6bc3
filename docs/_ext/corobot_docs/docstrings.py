"""The package's docstrings as autodoc reads them (reStructuredText), written as they are:
`name` is code, a paragraph ending in ":" may be followed by an indented example, and |x| is
an absolute value, not a substitution."""

from __future__ import annotations

import re

INLINE = re.compile(r"(?<![`:\w])`([^`\n]+)`(?![`_\w])")
"""`code` in the docstrings' own style: ``code`` in reStructuredText (a role's `target`, as
:class:`X`, is left as it is)."""
BARS = re.compile(r"(?<![\w|])\|([^|\s][^|]*)\|(?![\w|])")


def _line(line: str) -> str:
    line = INLINE.sub(r"``\1``", line)
    return BARS.sub(r"\\|\1\\|", line)


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _paragraphs(lines: list[str]):
    """(first, end) of each run of non-blank lines."""
    i = 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        j = i
        while j < len(lines) and lines[j].strip():
            j += 1
        yield i, j
        i = j


def rst(lines: list[str]) -> list[str]:
    """The docstring's lines as reStructuredText (see the module's docstring): a paragraph
    indented deeper than the one before it is an example, made a literal block."""
    out, previous, literal_indent = [], None, None
    for first, end in _paragraphs(lines):
        block = lines[first:end]
        indent = _indent(block[0])
        if literal_indent is not None and indent >= literal_indent:
            out += ["", *block]  # the example goes on
            continue
        literal_indent = None
        if previous is not None and indent > max(_indent(x) for x in previous) \
                and not previous[0].lstrip().startswith(".."):
            literal_indent = indent
            last = out[-1].rstrip()
            if not last.endswith("::"):
                if last.endswith(":"):
                    out[-1] = last + ":"
                else:
                    out += ["", "::"]
            out += ["", *block]
        else:
            out += ([""] if out else []) + [x if x.lstrip().startswith("..") else _line(x)
                                            for x in block]
        previous = block
    return out


def process(app, what, name, obj, options, lines: list[str]) -> None:
    """autodoc-process-docstring: `lines` made reStructuredText in place."""
    lines[:] = [*rst(lines), ""]


def describe_fields(app, domain: str, objtype: str, content) -> None:
    """object-description-transform: a dataclass field autodoc lists without a docstring (a
    sensor map a decorator adds: autodoc fires no docstring event for it) gets the scenario
    reference's description (`scenario.field_doc`), its `code` as literals."""
    from docutils import nodes

    if domain != "py" or objtype != "attribute" or content.children:
        return
    signature = content.parent.children[0]
    doc = field_doc(f"{signature.get('module', '')}.{signature.get('fullname', '')}")
    if doc:
        parts = doc.split("`")
        content += nodes.paragraph("", "", *[
            nodes.literal(part, part) if i % 2 else nodes.Text(part)
            for i, part in enumerate(parts) if part])


def field_doc(name: str) -> str:
    """The scenario reference's description of the dataclass field `module.Class.field`; ""
    for anything else."""
    import dataclasses as dc
    import importlib

    from corobot_docs import scenario

    owner, _, field = name.rpartition(".")
    module, _, cls_name = owner.rpartition(".")
    try:
        cls = getattr(importlib.import_module(module), cls_name)
    except (ImportError, AttributeError, ValueError):
        return ""
    return scenario.field_doc(cls, field) if dc.is_dataclass(cls) else ""
