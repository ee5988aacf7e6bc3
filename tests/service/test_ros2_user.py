"""The ROS 2 user's path: a Python with only ROS 2's wheels and the interface packages built
there from the clone (tools/setup's .venv-ros: `pip install -r tools/ros2_user_requirements.txt`
then `python -m corobot_drake.ros2.build`, docs/ros2.md), never corobot-drake nor Drake, drives
the simulation (`python -m corobot_drake --ros2 --headless`, the project's Python), reads every
topic of the node's table, calls every service and sends every action goal of the command
table and the Simulation Interfaces.

It subscribes as the docs' recipes do: each display of examples/corobot.rviz with the QoS it
is saved with (RViz's defaults: reliable, volatile, keep last 5; RobotModel's transient local;
tf2_ros's listener for the TF display), and every topic as foxglove_bridge does (the
publishers' offer). The scenario is the RViz recipe's (scenarios/corobot_lidar.yaml) with an
IMU and a bumper besides: a topic of every sensor kind. All in a private network
(`ros2_probe`).

The commands are docs/ros2.md's own, read from its blocks marked as run here: the ROS user's
environment (what tools/setup makes, and the build run again from the clone), the node's
command, the inspection tool's lines (run against the node once the client is done) and the
RViz recipe's file.
"""

import contextlib
import json
import os
import re
import shlex
import subprocess
import sys
import tomllib
from functools import partial
from pathlib import Path

import pytest
import yaml

from conftest import REPO
from ros2_probe import ONE_GRAPH_AT_A_TIME, private_domain, simulation_process

ROS_USER_ENV = REPO / ".venv-ros"
REQUIREMENTS = REPO / "tools" / "ros2_user_requirements.txt"
CLIENT = Path(__file__).with_name("ros2_user_client.py")
SCENARIO = REPO / "scenarios" / "corobot_lidar.yaml"
EVERY_KIND = "robots: {corobot: {imus: {imu: {}}, bumpers: {front_bumper: {}}}}"
"""The lidar scenario has IR sensors, a camera and a lidar: with these, every sensor kind."""
PAGE = REPO / "docs" / "ros2.md"
BLOCK = re.compile(r"^<!-- no-test: (?P<reason>[^\n]*) -->\n```sh\n(?P<body>.*?)^```$",
                   re.MULTILINE | re.DOTALL)
LIVE_ONLY = {"/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"}
"""What the live node publishes beside the bus's topics (`ros2.node`: a bag has none)."""
RCL_OWN = {"/rosout", "/parameter_events"}
"""Every rclpy node's own publishers."""
WAIT = 20.0
"""s (wall clock) each of the client's waits may take: discovery takes up to ~5 s."""
HANG = 120.0
"""s (wall clock) after which the client is a hang."""
DRIVE = {"linear": 0.3, "seconds": 1.0, "pose_topic": "/ground_truth"}
"""/cmd_vel at 0.3 m/s for 1 s of wall clock, measured on the true pose."""
MOVED = 0.05
"""m the robot must have gone forwards: 0.3 m/s for 1 s less the wheels' spin-up is ~0.25 m
at real time; a loaded machine's simulation may run at a third of it."""
OK = 1
"""simulation_interfaces/msg/Result's RESULT_OK."""

STEPS = 20
"""Physics steps of the SimulateSteps goal: a feedback after each (rclpy's client may drop
those it hands on after the result)."""
BOX = "shape: !Box {size: [0.2, 0.2, 0.2]}"
AT = {"pose": {"position": {"x": -1.0, "y": -1.0, "z": 0.1}, "orientation": {"w": 1.0}}}
REQUESTS = {
    # the command table's services and actions
    "/all_stop": {},
    "/enable_drive": {"data": True},
    "/drive_distance": {"distance": 0.1, "power": 0.5},  # feedback every 0.1 s: about 3
    "/rotate_degrees": {"degrees": 15.0, "power": 0.5},
    "/set_pose": {"x": 0.0, "y": 0.0, "yaw": 0.0},
    # the Simulation Interfaces, in the order they are made
    "/get_simulator_features": {},
    "/get_simulation_state": {},
    "/get_entities": {},
    "/get_entity_info": {"entity": "corobot"},
    "/get_entity_state": {"entity": "corobot"},
    "/get_entities_states": {},
    "/get_spawnables": {},
    "/set_entity_state": {"entity": "crate", "set_pose": True, "state": {"pose": {
        "position": {"x": 1.5, "y": 0.6, "z": 0.2}, "orientation": {"w": 1.0}}}},
    "/spawn_entity": {"name": "user_box", "entity_resource": {"resource_string": BOX},
                      "initial_pose": AT},
    "/delete_entity": {"entity": "user_box"},
    "/set_simulation_state": {"state": {"state": 2}},  # paused
    "/step_simulation": {"steps": 5},
    "/simulate_steps": {"steps": STEPS},
    "/reset_simulation": {},
}
"""Each service's request and action's goal (fields by name); the calls go in this order."""
ONCE = {"/set_pose", "/spawn_entity", "/delete_entity", "/step_simulation"}
"""Asked once (asked again, they would act again); the others again without an answer."""
PLAYING = {"name": "/set_simulation_state", "request": {"state": {"state": 1}}}
"""After the steps: the simulation plays again before it is reset."""


def page_lines(*start: str) -> list[list[str]]:
    """The command lines (argument lists) starting with `start` of docs/ros2.md's shell blocks
    whose no-test comment names this test: the page's commands this test runs or reads."""
    found = [shlex.split(line) for m in BLOCK.finditer(PAGE.read_text())
             if "tests/service/test_ros2_user.py" in m["reason"]
             for line in m["body"].splitlines() if line.strip()]
    lines = [argv for argv in found if argv[:len(start)] == list(start)]
    assert lines, f"docs/ros2.md has no block this test reads with a line `{shlex.join(start)}`"
    return lines


def page_line(*start: str) -> list[str]:
    (line,) = page_lines(*start)
    return line


def ros_user_python() -> Path:
    """.venv-ros's Python, with the interface packages built; the test fails (never skips:
    CI runs tools/setup) when it is not there."""
    python = ROS_USER_ENV / "bin" / "python"
    if not python.exists():
        pytest.fail(f"{python} not found: tools/setup makes the ROS 2 user's environment "
                    "(ROS 2's wheels alone, docs/ros2.md)", pytrace=False)
    from corobot_drake.ros2.build import PACKAGES, up_to_date

    stale = [p for p in PACKAGES if not up_to_date(ROS_USER_ENV, p)]
    if stale:
        build = shlex.join(page_line(f"{ROS_USER_ENV.name}/bin/python", "-m"))
        pytest.fail(f"{', '.join(stale)} not built in {ROS_USER_ENV} from the current sources: "
                    f"run `{build}` in the clone (tools/setup does)", pytrace=False)
    return python


def node_topics() -> dict[str, str]:
    """{topic: type} the node publishes for the scenario: its table, as the simulation
    declares it on the bus (`publishers.add_ros2_topics`), and the live node's own."""
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.ros2.bus import Bus
    from corobot_drake.ros2.publishers import add_ros2_topics
    from corobot_drake.station import build_station

    bus = Bus()
    build_station(load_scenario(SCENARIO, overrides=[EVERY_KIND]),
                  extras=[partial(add_ros2_topics, bus)])
    return {**{topic: msgtype for topic, (msgtype, _) in bus.topics.items()}, **LIVE_ONLY}


def calls() -> list[dict]:
    """Every service and action of the command table (`interfaces.SERVICES`, `ACTIONS`) and
    the Simulation Interfaces (`simulation_services.SERVICES`, `ACTION`), in `REQUESTS`' order."""
    from corobot_drake.ros2 import interfaces as ifc
    from corobot_drake.ros2 import simulation_services as si

    kinds = {f"/{s.name}": ("service", s.type) for s in ifc.SERVICES}
    kinds.update((f"/{a.name}", ("action", a.type)) for a in ifc.ACTIONS)
    kinds.update((f"/{name}", ("service", f"{si.PACKAGE}/srv/{t}"))
                 for name, t in si.SERVICES.items())
    kinds[f"/{si.ACTION[0]}"] = ("action", f"{si.PACKAGE}/action/{si.ACTION[1]}")
    assert set(REQUESTS) == set(kinds), "a service or action without its request here"
    out = []
    for name, fields in REQUESTS.items():
        kind, msgtype = kinds[name]
        call = {"name": name, "kind": kind, "type": msgtype, "idempotent": name not in ONCE,
                "goal" if kind == "action" else "request": fields}
        out.append(call)
        if name == "/simulate_steps":
            out.append({**call, **PLAYING, "kind": "service", "idempotent": True,
                        "type": kinds["/set_simulation_state"][1]})
    return out


def ros_user_environment(domain: int) -> dict:
    """The variables a ROS user's shell has: none of the project's Python's (its ROS
    libraries' path, the wheels' start-up hook's mark), this test's domain."""
    keep = ("PATH", "HOME", "LANG", "TMPDIR")
    return {**{k: os.environ[k] for k in keep if k in os.environ},
            "ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> dict:
    """The client's JSON report of a run against the simulation."""
    pytest.importorskip("rosbags", reason="the [ros2] extra (tools/setup installs it)")
    python = ros_user_python()
    rviz = REPO / page_line("rviz2", "-d")[2]  # the RViz recipe's file
    plan = {"node": "corobot_drake", "topics": node_topics(), "rviz": str(rviz),
            "cmd_vel": ["/cmd_vel", "geometry_msgs/msg/Twist"], "drive": DRIVE,
            "calls": calls(), "timeout": WAIT}
    work = tmp_path_factory.mktemp("ros2_user")
    (work / "plan.json").write_text(json.dumps(plan))
    with contextlib.ExitStack() as stack:
        domain = stack.enter_context(private_domain())
        log = work / "simulation.log"
        sim = stack.enter_context(simulation_process([*node_arguments(), "--override", EVERY_KIND,
                                              "--camera-rate", "10"], log))
        client = subprocess.run([str(python), str(CLIENT), str(work / "plan.json")], cwd=work,
                                env=ros_user_environment(domain), capture_output=True,
                                text=True, timeout=HANG)
        looked = inspection() if client.returncode == 0 else []
        assert sim.poll() is None, f"the simulation ended: {log.read_text()[-3000:]}"
    assert client.returncode == 0, client.stderr
    (work / "report.json").write_text(client.stdout)  # what a failure is read from
    return {**json.loads(client.stdout), "plan": plan, "inspection": looked}


def node_arguments() -> list[str]:
    """The page's node command's arguments (`python -m corobot_drake ARGS`), its scenario
    the one `node_topics` builds."""
    args = page_line("python", "-m", "corobot_drake")[3:]
    assert REPO / args[0] == SCENARIO and "--ros2" in args, args
    return [str(SCENARIO), *args[1:]]


def inspection() -> list[dict]:
    """The page's `python -m corobot_drake.ros2 ...` lines, each a process of its own (this
    Python: the project's) run at once against the node, bounded by `--timeout`."""
    lines = page_lines("python", "-m", "corobot_drake.ros2")
    processes = [subprocess.Popen([sys.executable, *argv[1:], "--timeout", "60"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for argv in lines]
    done = []
    for argv, process in zip(lines, processes, strict=True):
        try:
            out, err = process.communicate(timeout=HANG)
        except subprocess.TimeoutExpired:
            process.kill()
            out, err = process.communicate()
        done.append({"command": argv[3], "returncode": process.returncode, "stdout": out,
                     "stderr": err})
    return done


@ONE_GRAPH_AT_A_TIME
def test_the_client_has_ros_alone(report):
    """Its rclpy and ROS libraries are .venv-ros's; the project and Drake are out of reach."""
    env = report["environment"]
    assert Path(env["python"]) == ROS_USER_ENV
    assert Path(env["rclpy"]).is_relative_to(ROS_USER_ENV)
    assert env["librcl"] and all(Path(p).is_relative_to(ROS_USER_ENV) for p in env["librcl"])
    assert (env["corobot_drake"], env["pydrake"]) == (False, False)


@ONE_GRAPH_AT_A_TIME
def test_the_node_publishes_its_table_and_every_topic_arrives(report):
    topics = report["plan"]["topics"]
    published = {topic: types for topic, types in report["published"].items()
                 if topic not in RCL_OWN and "/_action/" not in topic}
    assert published == {topic: [msgtype] for topic, msgtype in topics.items()}
    via = {}
    for s in report["subscriptions"]:
        via.setdefault(s["via"], {})[s["topic"]] = s
    assert set(via["foxglove_bridge"]) == set(topics)
    silent = [(s["topic"], s["via"]) for s in report["subscriptions"] if s["received"] == 0]
    assert silent == []
    # foxglove_bridge asks for what every publisher offers: the latched topics' one message
    for topic in ("/tf_static", "/robot_description"):
        assert via["foxglove_bridge"][topic]["qos"] == {
            "reliability": "reliable", "durability": "transient_local", "depth": 1}
    assert via["foxglove_bridge"]["/camera/image_raw"]["qos"]["reliability"] == "reliable"


@ONE_GRAPH_AT_A_TIME
def test_the_rviz_recipe_sees_the_robot(report):
    """Each display of examples/corobot.rviz got its topic with its saved QoS (RViz's
    defaults: reliable, volatile), and the TF display has the fixed frame's tree."""
    subscriptions = [s for s in report["subscriptions"] if s["via"].startswith("rviz:")]
    topics = {s["topic"] for s in subscriptions}
    rviz = {s["via"]: s for s in subscriptions}
    assert {"/robot_description", "/tf", "/tf_static", "/odom", "/ir/front", "/ir/rear",
            "/scan/top", "/camera/image_raw"} <= topics
    for name in ("rviz:Odometry", "rviz:IR front", "rviz:Lidar", "rviz:Camera"):
        assert rviz[name]["qos"] == {"reliability": "reliable", "durability": "volatile",
                                     "depth": 5}, name
    assert rviz["rviz:RobotModel"]["qos"]["durability"] == "transient_local"
    frames = {tuple(f) for s in report["subscriptions"] if s["via"] == "rviz:TF"
              for f in s.get("frames", ())}
    assert ("odom", "base_link") in frames  # the recipe's fixed frame holds the robot
    assert ("base_link", "camera_link") in frames  # /tf_static, latched


@ONE_GRAPH_AT_A_TIME
def test_cmd_vel_moves_the_robot(report):
    (x0, y0), (x1, y1) = report["before"], report["after"]
    assert x1 - x0 > MOVED and abs(y1 - y0) < 0.02


@ONE_GRAPH_AT_A_TIME
def test_every_service_answers_and_every_action_succeeds(report):
    done = {}
    for call in report["calls"]:
        assert call["answered"], call
        done.setdefault(call["name"], []).append(call)
    assert set(done) == set(REQUESTS)
    for name in ("/all_stop", "/enable_drive", "/set_pose"):
        assert done[name][0]["response"]["success"], done[name]
    for name in ("/drive_distance", "/rotate_degrees"):
        assert done[name][0]["result"]["success"], done[name]
        assert done[name][0]["feedback_count"] > 0
    steps = done["/simulate_steps"][0]
    assert steps["accepted"] and steps["result"]["result"]["result"] == OK
    assert steps["feedback"] and all(f["completed_steps"] + f["remaining_steps"] == STEPS
                                     for f in steps["feedback"])
    features = done["/get_simulator_features"][0]["response"]["features"]
    assert "yaml" in features["spawn_formats"]  # (the one call without a Result)
    for name in set(REQUESTS) - {"/all_stop", "/enable_drive", "/set_pose", "/drive_distance",
                                 "/rotate_degrees", "/simulate_steps", "/get_simulator_features"}:
        for call in done[name]:
            result = call["response"]["result"]
            assert result["result"] == OK, (name, result["error_message"])
    entities = done["/get_entities"][0]["response"]["entities"]
    assert {"corobot", "crate"} <= set(entities)
    assert done["/spawn_entity"][0]["response"]["entity_name"] == "user_box"


@ONE_GRAPH_AT_A_TIME
def test_the_pages_inspection_commands_answer(report):
    """docs/ros2.md's list, echo and hz lines, against the node the client drove."""
    done = {run["command"]: run for run in report["inspection"]}
    assert set(done) == {"list", "echo", "hz"}
    for run in done.values():
        assert run["returncode"] == 0, run
    assert "  /odom [nav_msgs/msg/Odometry]" in done["list"]["stdout"]
    assert "  /simulate_steps\n" in done["list"]["stdout"]
    odom = yaml.safe_load(done["echo"]["stdout"].split("---")[0])
    assert (odom["header"]["frame_id"], odom["child_frame_id"]) == ("odom", "base_link")
    # the camera at the node's --camera-rate 10: its stamps 100 ms apart
    assert done["hz"]["stdout"].splitlines()[-1].endswith(
        "over 10 messages, stamps 100.0 ms apart at the closest")


def test_the_pages_ros_user_environment_is_the_one_setup_makes():
    """docs/ros2.md's venv, pip and build lines are tools/setup's: the same folder, the same
    requirements file, the same build module run with that environment's Python."""
    venv = page_line("python3", "-m", "venv")[3]
    requirements = page_line(f"{venv}/bin/pip", "install", "-r")[3]
    assert (REPO / venv, REPO / requirements) == (ROS_USER_ENV, REQUIREMENTS)
    assert page_line(f"{venv}/bin/python", "-m")[2:] == ["corobot_drake.ros2.build"]
    setup = (REPO / "tools" / "setup").read_text()
    assert f"ROS_USER_ENV={venv}\n" in setup
    assert f"local requirements={requirements}\n" in setup
    assert '"$ROS_USER_ENV/bin/python" -m pip install -r "$requirements"' in setup
    assert '"$ROS_USER_ENV/bin/python" -m corobot_drake.ros2.build' in setup


def test_the_pages_build_command_runs_in_the_ros_users_environment():
    """The page's build line, from the clone's root in a ROS user's shell: with the packages
    built from these sources (`ros_user_python`), it finds nothing to build."""
    ros_user_python()
    build = page_line(f"{ROS_USER_ENV.name}/bin/python", "-m")
    done = subprocess.run(build, cwd=REPO, env=ros_user_environment(0), capture_output=True,
                          text=True, timeout=HANG)
    assert (done.returncode, done.stdout, done.stderr) == (0, "", "")


def test_the_ros_users_wheels_are_the_extras():
    """tools/ros2_user_requirements.txt is the `[ros2]` extra's ROS wheels (its other
    packages are the project's: rosbags writes bags without ROS)."""
    extra = tomllib.loads((REPO / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]["ros2"]
    listed = [line for line in REQUIREMENTS.read_text().splitlines()
              if line and not line.startswith("#")]
    assert listed == [r for r in extra if r.startswith(("ros-", "catkin"))]
