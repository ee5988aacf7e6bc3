"""Sampled CPU profiles (Linux perf): what the tool reads from `perf report`, and its errors.

A profile itself is a measurement (`python tools/profile_step.py`, about a minute a round),
not a behaviour: these tests check how its numbers are read."""

import shutil

import pytest

from conftest import load_tool
from lab import profile_step


def test_no_perf_is_a_clear_error(monkeypatch, capsys):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(profile_step.PerfMissingError, match="needs Linux perf"):
        profile_step.profile(1.0, 1)
    assert load_tool("profile_step").main(["--seconds", "1", "--repeats", "1"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_samples_are_shared_out_by_where_they_landed():
    # What `perf report --no-children --sort=dso,sym -F sample,dso,sym --stdio` prints: the
    # total (cpu-clock's event count, ns; the sample count abbreviated), then each function's
    # samples with its library.
    report = """# Samples: 1K of event 'cpu-clock'
# Event count (approx.): 2000000000
#
   500  libdrake.so           [.] drake::multibody::contact_solvers::icf::IcfSolver::Solve
   300  libdrake.so           [.] drake::geometry::internal::SliceTetWithPlane<double>
   400  libdrake.so           [.] drake::systems::DependencyTracker::NotePrerequisiteChange
   100  libdrake.so           [.] drake::systems::Context<double>::PropagateTimeChange
   200  libdrake.so           [.] drake::systems::LeafEventCollection<double>::Clear
   250  libpython3.13.so.1.0  [.] _PyEval_EvalFrameDefault
    50  libdrake_nanobind.so  [.] nanobind::detail::nb_type_put
   150  libc.so.6             [.] malloc
    50  libdrake.so           [.] 0x0000000001b1bca9
"""
    kinds = profile_step.parse(report)
    physics, tracking, framework, python, rest = (kinds[k] for k in profile_step.KINDS)
    assert kinds[profile_step.ALL] == pytest.approx(2000.0)  # ms: the event count
    assert physics == pytest.approx(800.0)  # 2000 samples share 2 s: 1 ms each
    assert tracking == pytest.approx(500.0)
    assert framework == pytest.approx(200.0)
    assert python == pytest.approx(300.0)
    assert rest == pytest.approx(200.0)  # malloc and an unnamed address


def test_a_report_without_samples_is_an_error():
    with pytest.raises(RuntimeError, match="no samples"):
        profile_step.parse("# nothing\n")
