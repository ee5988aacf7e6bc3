"""`--rate` paces a live run (`--serve` or `--ros2`), and only a live one; `--paused` stays
the ROS 2 node's (only it can play a paused run). A real server at a rate:
tests/service/test_server.py."""

import math

import pytest

from corobot_drake import cli


@pytest.mark.parametrize(("argv", "rate"), [
    (["--serve"], 1.0),
    (["--serve", "--rate", "4"], 4.0),
    (["--serve", "--rate", "0.5"], 0.5),
    (["--serve", "--rate", "MAX"], math.inf),
    (["--rate", "1"], 1.0),  # the default, said: nothing to refuse
])
def test_serve_takes_a_rate(argv, rate):
    args = cli._parser().parse_args(["--headless", *argv])
    cli.check_arguments(args)
    assert args.rate == rate


@pytest.mark.parametrize(("argv", "line"), [
    (["--rate", "2"], "error: --rate: only with --serve or --ros2"),
    (["--rate", "max"], "error: --rate: only with --serve or --ros2"),
    (["--serve", "--rate", "0"], "error: --rate: must be in (0, 1000]"),
    (["--serve", "--rate", "fast"], "error: --rate: expected a number or max, got 'fast'"),
    (["--paused"], "error: --paused: only with --ros2"),
    (["--serve", "--paused"], "error: --paused: only with --ros2"),
])
def test_rate_and_paused_are_refused_in_one_line_before_a_run(argv, line, capsys):
    assert cli.main(["--headless", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(line) and err.count("\n") == 1, err
