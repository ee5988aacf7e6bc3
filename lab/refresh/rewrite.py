"""Refreshing and checking the blocks: the markers against the registered blocks, the --list, the
rewrite."""

from __future__ import annotations

import difflib
import sys
import time

from lab.docs_blocks import BlockError, find_blocks, replace_block, wrap_markdown
from lab.refresh.runner import DOCS, REPO, Runner, Spec


def check_markers(specs: list[Spec]) -> list[str]:
    """Problems: a registered block without its markers, a marker no block owns, bad markers."""
    problems = []
    owned = {(s.file, s.name) for s in specs}
    for doc in DOCS:
        try:
            found = find_blocks((REPO / doc).read_text(), doc)
        except BlockError as e:
            problems.append(str(e))
            continue
        problems += [f"{doc}:{b.line}: block {n!r} is not one refresh_docs.py knows"
                     for n, b in found.items() if (doc, n) not in owned]
        problems += [f"{doc}: no block {s.name!r}" for s in specs
                     if s.file == doc and s.name not in found]
    return problems


def list_blocks(specs: list[Spec]) -> None:
    for s in specs:
        line = find_blocks((REPO / s.file).read_text(), s.file)[s.name].line
        cheap = " (--check)" if s.cheap else ""
        print(f"{s.name:32s} {s.file}:{line}  {s.kind}{cheap}, ~{s.seconds:.0f} s\n"
              f"{'':32s} {s.shown}")


def refresh(specs: list[Spec], check: bool) -> int:
    """Renders each block; writes it (or, with `check`, reports a difference). 1 on drift or
    when a block's command failed (the other blocks are still refreshed)."""
    runner, status = Runner(), 0
    start = time.perf_counter()
    for i, spec in enumerate(specs, 1):
        print(f"== [{i}/{len(specs)}] {spec.name} ({spec.kind}, ~{spec.seconds:.0f} s; "
              f"{time.perf_counter() - start:.0f} s so far)", file=sys.stderr, flush=True)
        path = REPO / spec.file
        try:
            content = spec.render(runner.outputs(spec))
            if find_blocks(path.read_text(), spec.file)[spec.name].multiline:
                content = wrap_markdown(content)
        except Exception as e:  # one block's failure leaves the others to refresh
            print(f"{spec.name}: FAILED, left as it was: {type(e).__name__}: {e}", flush=True)
            status = 1
            continue
        text = path.read_text()
        new = replace_block(text, spec.name, content, spec.shown, spec.file)
        if new == text:
            print(f"{spec.name}: unchanged", flush=True)
            continue
        if check:
            status = 1
            old = find_blocks(text, spec.file)[spec.name].content(text)
            print(f"{spec.file}: block {spec.name} differs from what its command prints now:")
            sys.stdout.writelines(difflib.unified_diff(
                (old + "\n").splitlines(True), (content + "\n").splitlines(True),
                "in the file", "now"))
        else:
            path.write_text(new)
            print(f"{spec.name}: rewrote {spec.file}", flush=True)
    return status

