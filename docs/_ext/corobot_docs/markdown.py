"""Markdown pieces the reference pages are made of."""

from __future__ import annotations

import ast
import functools
import inspect
import itertools
import re
import textwrap


def cell(text: str) -> str:
    """`text` as one table cell: one line, its pipes escaped."""
    return re.sub(r"\s+", " ", text).strip().replace("|", "\\|")


def table(header, rows) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def fenced(text: str, language: str = "text") -> str:
    """`text` in a fenced code block whose fence no line of it closes."""
    fence = "```"
    while fence in text:
        fence += "`"
    return f"{fence}{language}\n{text.rstrip()}\n{fence}"


@functools.cache
def docs_below(obj) -> dict[str, str]:
    """{name: the string literal below its assignment} in a module's or a class's body (read
    with ast: attribute docstrings, which Python itself keeps nowhere); {} when the source
    cannot be had (a compiled class)."""
    try:
        source = textwrap.dedent(inspect.getsource(obj))
    except (OSError, TypeError):
        return {}
    tree = ast.parse(source)
    body = tree.body if inspect.ismodule(obj) else tree.body[0].body
    docs = {}
    for node, after in itertools.pairwise(body):
        targets = node.targets if isinstance(node, ast.Assign) else \
            [node.target] if isinstance(node, ast.AnnAssign) else []
        if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant) \
                and isinstance(after.value.value, str):
            for t in targets:
                if isinstance(t, ast.Name):
                    docs[t.id] = inspect.cleandoc(after.value.value)
    return docs
