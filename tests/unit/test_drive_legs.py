"""`examples/drive_legs.py` drives the drive test's legs: a seed gives the legs
`tools/drive_test.py` and a study's `drive_test` drive (`DriveTest.commands`)."""

import importlib.util
import types

import pytest

from conftest import REPO
from corobot_drake.commands import RotateDegrees
from corobot_drake.study.programs import DriveTest


def _example():
    spec = importlib.util.spec_from_file_location("drive_legs",
                                                  REPO / "examples" / "drive_legs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class _Robot:
    """Records the commands it is given; never moves."""

    def __init__(self):
        self.calls = []

    def position(self):
        return 0.0, 0.0, 0.0

    def heading(self):
        return 0.0

    def rotate_degrees(self, degrees, power):
        self.calls.append(("rotate_degrees", degrees, power))
        return types.SimpleNamespace(succeeded=True)

    def drive_distance(self, distance, power):
        self.calls.append(("drive_distance", distance, power))
        return types.SimpleNamespace(succeeded=True)


def test_the_example_drives_the_drive_tests_legs_of_a_seed():
    legs = _example().legs
    for seed in (0, 1, 7):
        robot = _Robot()
        assert legs(robot, 2, seed, power=0.3, out=lambda _: None) == [0.0, 0.0]
        expected = [("rotate_degrees", c.degrees, c.power) if isinstance(c, RotateDegrees)
                    else ("drive_distance", c.distance, c.power)
                    for c in DriveTest(2, 0.3).commands(seed)]
        assert robot.calls == expected
        assert len(expected) == 10


def test_the_examples_flags_are_the_drive_tests_bounds(capsys):
    """A loop count of 0 crashed on the empty drift list; each bad flag is one line, exit 2,
    before any server starts."""
    main = _example().main
    for argv, flag in ((["--loops", "0"], "--loops"), (["--power", "2"], "--power"),
                       (["--seed", "x"], "--seed"), (["--rate", "0"], "--rate"),
                       (["--rate", "fast"], "--rate")):
        with pytest.raises(SystemExit) as stop:
            main(["--local", *argv])
        assert stop.value.code == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"error: argument {flag}:") and "\n" not in err


@pytest.mark.parametrize("where", [["--local"], ["--url", "http://127.0.0.1:9"]])
def test_a_rate_is_for_the_examples_own_server_only(where, capsys):
    """--rate paces the server the example starts: with a server it does not start (or none),
    one line, exit 2, before anything runs."""
    with pytest.raises(SystemExit) as stop:
        _example().main([*where, "--rate", "max"])
    assert stop.value.code == 2
    assert capsys.readouterr().err == ("error: --rate: only for the server this example "
                                       "starts (not with --url or --local)\n")
