"""Refreshing and checking the blocks: the markers against the registered blocks, the --list, the
rewrite."""

from __future__ import annotations

import datetime
import difflib
import re
import subprocess
import sys
import time

from lab.docs_blocks import Block, BlockError, find_blocks, replace_block, wrap_markdown
from lab.refresh.runner import DOCS, PICTURE, REPO, Runner, Spec
from lab.refresh.text import DATE, stamp, unstamped


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


def _dated(spec: Spec, content: str, outs: list, multiline: bool) -> str:
    """A rendered block with its date: a timing's renderer writes its own (with the load); any
    other block gets `stamp`'s date line, the day its command(s) started."""
    if DATE.search(content):
        return content
    day = min(o.started for runs in outs for o in runs).strftime("%Y-%m-%d")
    return stamp(content, day, [c.text for c in spec.commands], multiline)


def refresh(specs: list[Spec], check: bool) -> int:
    """Renders each block; writes it (or, with `check`, reports a difference in its figures:
    the date line aside). 1 on drift or when a block's command failed (the other blocks are
    still refreshed)."""
    runner, status = Runner(), 0
    start = time.perf_counter()
    for i, spec in enumerate(specs, 1):
        print(f"== [{i}/{len(specs)}] {spec.name} ({spec.kind}, ~{spec.seconds:.0f} s; "
              f"{time.perf_counter() - start:.0f} s so far)", file=sys.stderr, flush=True)
        path = REPO / spec.file
        try:
            outs = runner.outputs(spec)
            multiline = find_blocks(path.read_text(), spec.file)[spec.name].multiline
            content = _dated(spec, spec.render(outs), outs, multiline)
            if multiline:
                content = wrap_markdown(content)
        except Exception as e:  # one block's failure leaves the others to refresh
            print(f"{spec.name}: FAILED, left as it was: {type(e).__name__}: {e}", flush=True)
            status = 1
            continue
        text = path.read_text()
        new = replace_block(text, spec.name, content, spec.shown, spec.file)
        old = find_blocks(text, spec.file)[spec.name].content(text)
        if replace_block(text, spec.name, unstamped(content), spec.shown, spec.file) == \
                replace_block(text, spec.name, unstamped(old), None, spec.file):
            print(f"{spec.name}: unchanged" + ("" if check or new == text else
                                               ", its date line rewritten"), flush=True)
            if not check and new != text:
                path.write_text(new)
            continue
        if check:
            status = 1
            print(f"{spec.file}: block {spec.name} differs from what its command prints now:")
            sys.stdout.writelines(difflib.unified_diff(
                (unstamped(old) + "\n").splitlines(True),
                (unstamped(content) + "\n").splitlines(True), "in the file", "now"))
        else:
            path.write_text(new)
            print(f"{spec.name}: rewrote {spec.file}", flush=True)
    return status


def _last_change(file: str, block: Block, text: str, picture_only: bool) -> str:
    """The UTC day of the last commit that changed the block's lines (between its markers) or
    a picture it shows (`picture_only`: the picture's alone, the text around it being only its
    alt text and command); raises ValueError if one of those lines is not committed."""
    pictures = [_committed(f"docs/{p}") for p in
                re.findall(r"\]\((images/[^)\s]+)\)", block.content(text))]
    if picture_only and pictures:
        return _day(max(pictures))
    first, last = (text.count("\n", 0, pos) + 1 for pos in (block.begin[1], block.end[0]))
    lines = range(first + 1, last) if block.multiline else range(first, first + 1)
    blame = subprocess.run(["git", "blame", "-w", "-M", "-C", "-C", "--porcelain", "-L",
                            f"{lines[0]},{lines[-1]}",
                            "--", file], cwd=REPO, capture_output=True, text=True, check=True)
    if re.search(r"^0{40} ", blame.stdout, re.MULTILINE):
        raise ValueError(f"{file}: block {block.name!r} has uncommitted lines: commit first")
    times = [int(t) for t in re.findall(r"^committer-time (\d+)$", blame.stdout, re.MULTILINE)]
    return _day(max(times + pictures))


def _committed(path: str) -> int:
    """When `path` was last committed (s since the epoch); raises ValueError if it has
    uncommitted changes or was never committed."""
    dirty = subprocess.run(["git", "status", "--porcelain", "--", path], cwd=REPO,
                           capture_output=True, text=True, check=True).stdout.strip()
    log = subprocess.run(["git", "log", "-1", "--format=%ct", "--", path], cwd=REPO,
                         capture_output=True, text=True, check=True).stdout.strip()
    if dirty or not log:
        raise ValueError(f"{path} is not committed as it is: commit first")
    return int(log)


def _day(seconds: int) -> str:
    return datetime.datetime.fromtimestamp(seconds, datetime.UTC).strftime("%Y-%m-%d")


def stamp_from_git(specs: list[Spec]) -> int:
    """Dates each undated block without running its command: the day of the last commit that
    changed it (`_last_change`), said so in its date line. 1 if a block could not be dated."""
    status = 0
    for spec in specs:
        path = REPO / spec.file
        text = path.read_text()
        block = find_blocks(text, spec.file)[spec.name]
        content = block.content(text)
        if DATE.search(content):
            print(f"{spec.name}: dated already", flush=True)
            continue
        try:
            day = _last_change(spec.file, block, text, spec.kind == PICTURE)
        except (ValueError, subprocess.CalledProcessError) as e:
            print(f"{spec.name}: not dated: {e}", flush=True)
            status = 1
            continue
        dated = stamp(content, day, [c.text for c in spec.commands], block.multiline,
                      from_git=True)
        if block.multiline:
            body, _, line = dated.rpartition("\n\n")
            dated = f"{body}\n\n{wrap_markdown(line)}"
        path.write_text(replace_block(text, spec.name, dated, None, spec.file))
        print(f"{spec.name}: dated {day} from git in {spec.file}", flush=True)
    return status
