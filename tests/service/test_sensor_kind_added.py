"""The sensor kinds' contract: a kind is one module and one line in `sensors.registry.KINDS`,
and every front end finds it (`sensor_kind_added.py`, in a process of its own: the scenario's
robot is made from the registry when it is imported)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def added() -> dict:
    script = Path(__file__).with_name("sensor_kind_added.py")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=300, check=False, cwd=script.parent)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_a_kind_added_to_the_registry_is_a_map_of_the_scenarios_robots(added):
    """Its map is in the schema (no sensor by default); `{}` is a working sensor and its
    bounded fields load over the kind's new sensor."""
    assert added["schema"] == "dict[str, __main__.LightSensorConfig]"
    assert added["default"] == []
    assert added["loaded"] == {"top": 10.0, "side": 20.0}


@pytest.mark.parametrize(("bad", "line"), [
    ("inverted", "--override:1: robots.corobot.light_sensors.top.high: must be more than low "
                 "(50 lx); got 5"),
    ("unknown_link", "--override:1: robots.corobot.light_sensors.top.X_PB.base_frame: "
                     "'antenna' is not a link of the robot"),
    ("rate", "--override:1: robots.corobot.light_sensors.top.rate_hz: must be in (0, 1000] Hz; "
             "got 0"),
    ("file", "bad.yaml:6: robots.corobot.light_sensors.top.high: must be more than low (50 lx)"),
])
def test_a_bad_sensor_of_the_added_kind_is_one_line_naming_file_line_and_field(added, bad, line):
    """The kind's own check, the mount every kind has, a field's bound; from an override and
    from a file (line 6: `high`)."""
    error = added["errors"][bad]
    assert error.startswith(line) and "\n" not in error


def test_every_front_end_carries_the_added_kinds_readings(added):
    """The station built its frame before finalizing the plant; the Python `Robot` lists the
    sensors and reads them by name (the sample at 0.2 s, read at 0.25 s); the summary, the
    snapshot and the HTTP routes carry the same reading as JSON."""
    assert added["frame"] is True
    assert added["sensors"]["light_sensors"] == ["top", "side"]
    assert list(added["sensors"])[:2] == ["ir_sensors", "cameras"]
    expected = added["expected"]
    assert added["reading"] == pytest.approx(expected, abs=1e-12)
    assert added["reading_type"] == "Illuminance"
    for front_end in ("summary", "snapshot", "http_all"):
        assert added[front_end] == {"top": added["reading"], "side": added["reading"]}, front_end
    assert added["http"] == added["reading"]


def test_the_added_kinds_run_log_columns_follow_the_robots_own_in_the_csv(added):
    """The kind declares a column per sensor (`light_<name>`, lx, from its state port): the
    robot's CSV has them after its own columns and the IR sensors', and the row at 0.25 s
    holds the reading read then (the sample at 0.2 s; the CSV's 6 decimals)."""
    columns, last = added["run_log"]["columns"], added["run_log"]["last"]
    assert columns[-4:] == ["ir_front", "ir_rear", "light_top", "light_side"]
    assert columns.index("tip_margin") == len(columns) - 5
    row = dict(zip(columns, last, strict=True))
    assert float(row["time"]) == pytest.approx(0.25, abs=1e-9)
    for name in ("top", "side"):
        assert float(row[f"light_{name}"]) == pytest.approx(added["reading"]["illuminance"],
                                                            abs=1e-6)


def test_the_added_kinds_readings_are_on_its_topics_in_the_mcap_and_the_ros2_bag(added):
    """One publisher per sensor, whatever its kind: each light sensor's readings are on its
    own topic (`light/<name>`) in the MCAP file (its JSON schema) and the bag
    (sensor_msgs/Illuminance), each sample once, logged at its time in its frame: the
    looks up to 0.25 s publish the samples before them (`top`'s at 10 Hz, `side`'s at 20 Hz;
    a look at t sees [t - period, t)). /tf and /tf_static mount both frames on base_link at
    the sensors' X_PB."""
    for name, rate, count in (("top", 10.0, 2), ("side", 20.0, 5)):
        times = [k / rate for k in range(count)]
        for wire, schema in (("mcap", "toy.Illuminance"), ("bag", "sensor_msgs/msg/Illuminance")):
            got = added[wire][f"/light/{name}"]
            assert [(t, s, f) for t, s, f, _ in got] == [
                (round(t * 1e9), schema, f"light_{name}") for t in times], wire
            assert [lx for *_, lx in got] == pytest.approx([100.0 + 10.0 * t for t in times],
                                                           abs=1e-9), wire
    for wire, tf in (("mcap", "/tf"), ("bag", "/tf_static")):
        for name in ("top", "side"):
            parent, xyz = added[wire][tf][f"light_{name}"]
            assert parent == "base_link"
            assert xyz == pytest.approx([0.05, 0.0, 0.3], abs=1e-12), (wire, name)


def test_a_studys_sensors_metric_and_meshcat_carry_the_added_kind(added):
    """A study's `sensors` metric has a column per number of each light sensor's summary JSON
    (the sample at 0.2 s), and Meshcat shows the kind's drawing of each sensor."""
    assert added["study"] == {
        "corobot.sensors.light_sensors.top.illuminance": added["expected"]["illuminance"],
        "corobot.sensors.light_sensors.top.time": 0.2,
        "corobot.sensors.light_sensors.side.illuminance": added["expected"]["illuminance"],
        "corobot.sensors.light_sensors.side.time": 0.2}
    assert added["meshcat"] == {"top": True, "side": True}
