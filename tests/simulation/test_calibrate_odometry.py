"""`tools/calibrate_odometry.py` as a user runs it: its outputs go where `--out` says (default
a new temporary directory, never the working directory), and its progress bar ends at 100%."""

import re
import tempfile

from conftest import load_tool


def test_outputs_go_in_out_or_a_temporary_directory_and_the_bar_ends_full(
        tmp_path, monkeypatch, capsys):
    main = load_tool("calibrate_odometry").main
    cwd, out, temporary = tmp_path / "cwd", tmp_path / "out", tmp_path / "tmp"
    cwd.mkdir()
    temporary.mkdir()
    monkeypatch.chdir(cwd)
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    assert main(["--simulate", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    # the simulated squares run 103.5 s, under the bar's 110 s estimate: it ends at 100%
    bars = re.findall(r"UMBmark squares: +(\d+)%\|[^|]*\| (\d+)/(\d+)", captured.err)
    percent, done, total = bars[-1]
    assert percent == "100" and done == total == "104"
    assert sorted(p.name for p in out.iterdir()) == ["calibrate_odometry.png",
                                                     "odometry_squares_log.csv"]
    # From a log, without --out: a new temporary directory, named.
    assert main([str(out / "odometry_squares_log.csv")]) == 0
    (made,) = temporary.iterdir()
    assert f"outputs in {made}" in capsys.readouterr().out
    assert [p.name for p in made.iterdir()] == ["calibrate_odometry.png"]
    assert list(cwd.iterdir()) == []
