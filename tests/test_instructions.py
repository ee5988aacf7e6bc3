"""Instruction counts (callgrind): the cost measure that the shared machine's noise leaves alone."""

import importlib.util
import shutil
from pathlib import Path

import pytest

from corobot_drake.analysis import instructions

TOOL = Path(__file__).resolve().parent.parent / "tools" / "count_instructions.py"


def _tool_main():
    spec = importlib.util.spec_from_file_location("count_instructions_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main


def test_no_valgrind_is_a_clear_error(monkeypatch, capsys):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(instructions.ValgrindMissingError, match="needs valgrind"):
        instructions.count(instructions.STATION, 0.01)
    assert _tool_main()(["--seconds", "0.01"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.skipif(not shutil.which("valgrind"), reason="valgrind is not installed")
def test_a_count_is_the_same_twice_and_mostly_the_plants_step():
    # Two counts of the same 20 ms of the station: callgrind counts what ran, so they differ
    # only by what lands in the short window besides the steps (Python's garbage collector,
    # the toggling itself): 0.05-0.15% measured. 1% still tells a count from a time, which
    # moves 10-30% between identical runs here.
    (first, step), (second, _) = (instructions.count(instructions.STATION, 0.02)
                                  for _ in range(2))
    assert second == pytest.approx(first, rel=1e-2)
    # The plant's step is most of a step (86% over the first second, tools/count_instructions.py).
    assert 0.6 < step / first < 0.97
