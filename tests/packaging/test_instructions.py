"""Instruction counts (callgrind): the cost measure that the shared machine's noise leaves alone.

How repeatable a count is, is the measure's own figure, not a behaviour: `python
tools/count_instructions.py --repeatability --seconds 0.02` (two counts, ~30 s)."""

import shutil

import pytest

from conftest import load_tool
from lab import instructions


def _tool_main():
    return load_tool("count_instructions").main


def test_no_valgrind_is_a_clear_error(monkeypatch, capsys):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(instructions.ValgrindMissingError, match="needs valgrind"):
        instructions.count(instructions.STATION, 0.01)
    assert _tool_main()(["--seconds", "0.01"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_the_counts_are_read_from_callgrind_annotates_totals_and_the_plants_step():
    # The lines callgrind_annotate --inclusive=yes prints (numbers with their percentages).
    step = "MultibodyPlant<double>::CalcStepDiscrete(drake::systems::Context<double> const&)"
    handle = "drake::systems::Simulator<double>::Handle{}(drake::systems::EventCollection<...>)"
    one = (f"690,107,262 (100.0%)  PROGRAM TOTALS\n"
           f"580,000,001 (84.04%)  ???:{handle.format('DiscreteUpdate')}\n"
           f"572,900,001 (83.01%)  ???:drake::multibody::{step} [libdrake.so]\n"
           f"1,000 ( 0.00%)  ???:drake::multibody::{step}'2 [libdrake.so]\n")
    # A discrete plant's step is one of the updates: the systems' events are the rest.
    assert instructions._parse("station", one, cache=False) == (
        690107262, 572900001, None, 580000001 - 572900001, None)
    cenic = "CenicIntegrator<double>::DoStep(double const&)"
    two = ("690,107,262 (100.0%) 4,150,000 (100.0%)  PROGRAM TOTALS\n"
           f"572,900,001 (83.01%) 2,000,000 (48.2%)  ???:drake::multibody::{cenic}\n"
           f"3,000,000 ( 0.43%) 900,000 (21.7%)  ???:{handle.format('DiscreteUpdate')}\n"
           f"2,000,000 ( 0.29%) 800,000 (19.3%)  ???:{handle.format('UnrestrictedUpdate')}\n"
           f"5 ( 0.00%) 1 ( 0.00%)  ???:{handle.format('UnrestrictedUpdate')}'2\n"
           f"1,000 ( 0.00%) 10 ( 0.00%)  ???:{handle.format('Publish')}\n")
    assert instructions._parse("station", two, cache=True) == (
        690107262, 572900001, 4150000, 5001000, 1700010)
    with pytest.raises(RuntimeError, match="counted nothing"):
        instructions._parse("station", "no totals here\n", cache=False)
