"""`tools/bench_compare.py`'s table: medians, ratios, and cases with no CPU figure."""

import pytest

from conftest import load_tool


@pytest.fixture(scope="module")
def bench_compare():
    return load_tool("bench_compare")


def test_the_table_gives_medians_and_new_over_old(bench_compare):
    runs = {"physics only": {"old": [{"wall": 4.0, "cpu": 5.0}, {"wall": 6.0, "cpu": 5.0},
                                     {"wall": 5.0, "cpu": 5.0}],
                             "new": [{"wall": 10.0, "cpu": 12.0}, {"wall": 11.0, "cpu": 9.0},
                                     {"wall": 12.0, "cpu": 10.0}]}}
    row = bench_compare.table(runs).splitlines()[2]
    assert row == "| physics only | 5.00 (5.00) | 11.00 (10.00) | 2.20x (2.00x) |"


def test_a_case_without_cpu_shows_the_wall_clock_only(bench_compare):
    # The drive test's work is in Ray's worker processes: the case's own CPU says nothing.
    runs = {bench_compare.DRIVE_TEST: {"old": [{"wall": 18.0, "cpu": None}],
                                       "new": [{"wall": 36.0, "cpu": None}]}}
    row = bench_compare.table(runs).splitlines()[2]
    assert row == f"| {bench_compare.DRIVE_TEST} | 18.00 | 36.00 | 2.00x |"
    assert bench_compare.DRIVE_TEST not in bench_compare.DEFAULT_CASES
    assert bench_compare.DRIVE_TEST in bench_compare.CASES
