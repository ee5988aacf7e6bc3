"""Instruction counts (callgrind): the cost measure that the shared machine's noise leaves alone."""

import importlib.util
import shutil

import pytest

from conftest import REPO
from lab import instructions

TOOL = REPO / "tools" / "count_instructions.py"


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
    (first, step, _), (second, _, _) = (instructions.count(instructions.STATION, 0.02)
                                        for _ in range(2))
    assert second == pytest.approx(first, rel=1e-2)
    # The plant's step is most of a step (86% over the first second, tools/count_instructions.py).
    assert 0.6 < step / first < 0.97


def test_the_counts_are_read_from_callgrind_annotates_totals_and_the_plants_step():
    # The lines callgrind_annotate --inclusive=yes prints (numbers with their percentages).
    step = "MultibodyPlant<double>::CalcStepDiscrete(drake::systems::Context<double> const&)"
    one = (f"690,107,262 (100.0%)  PROGRAM TOTALS\n"
           f"572,900,001 (83.01%)  ???:drake::multibody::{step} [libdrake.so]\n"
           f"1,000 ( 0.00%)  ???:drake::multibody::{step}'2 [libdrake.so]\n")
    assert instructions._parse("station", one, cache=False) == (690107262, 572900001, None)
    two = ("690,107,262 (100.0%) 4,150,000 (100.0%)  PROGRAM TOTALS\n"
           f"572,900,001 (83.01%) 2,000,000 (48.2%)  ???:drake::multibody::{step}\n")
    assert instructions._parse("station", two, cache=True) == (690107262, 572900001, 4150000)
    with pytest.raises(RuntimeError, match="counted nothing"):
        instructions._parse("station", "no totals here\n", cache=False)
