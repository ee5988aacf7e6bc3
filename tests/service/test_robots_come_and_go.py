"""A robot spawned or deleted while serving (ROS 2's SpawnEntity and DeleteEntity rebuild the
simulation and hand it to `SimRunner.replace`) comes into, and leaves, the HTTP front end: the
runner's robots follow the simulation it runs, the transport tells the HTTP side, the routes
serve the new robot and answer 404 for the one gone. Here without ROS 2: the runner's
`replace` is called with a simulation built from another scenario, as the node's spawn and
delete do, and the app is served over the same pipe as `--serve`'s HTTP process."""

import multiprocessing
import time

import pytest
from fastapi.testclient import TestClient

from conftest import make_sim
from corobot_drake.config import scenario as sc
from corobot_drake.serving.runner import SimRunner, StepJob
from corobot_drake.serving.transport import RemoteRunner, SimSide
from corobot_drake.serving.webapp import create_app
from corobot_drake.simulation import Simulation

BURGER = """robots:
  burger:
    robot: burger
    pose: {translation: [0.0, 1.0, 0.0]}
"""
"""A Burger beside the Corobot, facing +x as it does (SpawnEntity's layer for a robot)."""

GONE = "no robot named 'burger'; robots: corobot"
"""The one line of every route of the deleted Burger (as for a robot never there)."""

WAIT = 30.0
"""s for the HTTP side to hear of a change (a few ms over the pipe; a loaded machine)."""


def _replace(runner: SimRunner, edit) -> None:
    """The runner's simulation replaced, in its thread, by one built from `edit(sim)`'s
    scenario, going on from where it is (as the ROS 2 node's spawn and delete do)."""
    runner.call(lambda sim: runner.replace(Simulation(edit(sim))), timeout=120)


def _with_burger(sim) -> sc.Scenario:
    return sc.load_scenario(data=BURGER, defaults=sim.saved_scenario())


def _without_burger(sim) -> sc.Scenario:
    scenario = sim.saved_scenario()
    del scenario.robots["burger"]
    return scenario


def _until(check, what: str):
    deadline = time.monotonic() + WAIT
    while not (value := check()):
        assert time.monotonic() < deadline, what
        time.sleep(0.02)
    return value


@pytest.fixture
def served():
    """(the runner, paused, the default scene without its camera's frames; an HTTP client of
    its app over the pipe to a `RemoteRunner`, as `--serve` runs it)."""
    runner = SimRunner(make_sim(), paused=True).start()
    sim_end, http_end = multiprocessing.Pipe()
    side = SimSide(runner, sim_end)
    remote = RemoteRunner(http_end, timeout=30)
    try:
        with TestClient(create_app(remote), base_url="http://127.0.0.1") as client:
            yield runner, remote, client
    finally:
        runner.stop()
        side.close()
    assert runner.error is None


def test_a_robot_added_by_a_replace_is_served_until_a_replace_removes_it(served):
    runner, remote, http = served
    assert http.get("/robots").json() == {"robots": ["corobot"]}
    _replace(runner, _with_burger)
    assert list(runner.robots) == ["corobot", "burger"]  # at once in the simulation process
    _until(lambda: "burger" in remote.robots, "the HTTP side never heard of the Burger")
    assert http.get("/robots").json() == {"robots": ["corobot", "burger"]}
    assert http.get("/simulation").json()["robots"] == ["corobot", "burger"]
    assert {s["robot"] for s in http.get("/services").json()["services"]} == {"corobot",
                                                                              "burger"}
    burger = http.get("/robots/burger").json()
    assert burger["capabilities"]["camera"] is False and burger["capabilities"]["ir"] is False
    assert burger["state"]["gps"]["y"] == pytest.approx(1.0, abs=0.01)
    sensors = http.get("/robots/burger/sensors").json()
    assert list(sensors["lidars"]) == ["scan"] and list(sensors["imus"]) == ["imu"]
    assert http.get("/robots/burger/sensors/lidars/scan").status_code == 200
    # driven over HTTP: 0.2 m/s (its top speed is 0.22) for 0.5 s of steps (paused runner)
    x0 = http.get("/robots/burger/gps").json()["x"]
    r = http.post("/robots/burger/drive/set_velocity", json={"linear": 0.2, "angular": 0.0})
    assert r.status_code == 200, r.text
    t = runner.sim.time + 0.5
    runner.step(StepJob(round(0.5 / runner.sim.physics_step))).future.result(60)
    drive = _until(lambda: (d := http.get("/robots/burger/drive").json())["time_stamp"] >= t
                   and d, "no snapshot of the steps")
    # measured: 0.079 m, 0.198 m/s (it reaches its speed in ~0.1 s)
    assert 0.06 < drive["position"]["x"] - x0 < 0.1
    assert drive["velocity"]["forward"] == pytest.approx(0.2, rel=0.02)
    assert drive["position"]["y"] == pytest.approx(1.0, abs=0.001)  # straight on
    corobot = http.get("/robots/corobot/gps").json()
    assert abs(corobot["x"]) < 0.01  # the Corobot was not driven: the command was the Burger's

    _replace(runner, _without_burger)
    assert list(runner.robots) == ["corobot"]
    _until(lambda: "burger" not in remote.robots, "the HTTP side still lists the Burger")
    assert http.get("/robots").json() == {"robots": ["corobot"]}
    for path in ("/robots/burger", "/robots/burger/gps", "/robots/burger/sensors",
                 "/robots/burger/drive", "/robots/burger/subscribe"):
        r = http.get(path)
        assert (r.status_code, r.json()) == (404, {"detail": GONE}), path
    r = http.post("/robots/burger/drive/set_velocity", json={"linear": 0.2, "angular": 0.0})
    assert (r.status_code, r.json()) == (404, {"detail": GONE})
    assert http.get("/robots/corobot/gps").status_code == 200


def test_a_replace_with_the_same_robots_keeps_the_robots_the_http_side_has(served):
    """A rebuild that keeps the robots (a world body spawned, a reset) sends no robot set:
    the runner keeps its dict (the transport compares it by identity)."""
    runner, remote, _ = served
    before = runner.robots
    _replace(runner, lambda sim: sim.saved_scenario())
    assert runner.robots is before
    assert remote.robots == before


def test_a_subscription_ends_when_its_robot_is_deleted():
    """The stream of a robot that leaves the snapshot ends after its next check (the
    dashboard's reader reconnects, gets 404, and its robot list moves on)."""
    import asyncio
    from types import SimpleNamespace

    from corobot_drake.serving.routes.subscriptions import _events

    runner = SimpleNamespace(snapshot={"time": 0.0, "robots": {"burger": {"gps": {"x": 0.5}}}})

    async def read() -> list:
        events = []
        async for event in _events(SimpleNamespace(runner=runner), "burger",
                                   {"gps": lambda snap: snap["gps"]}, {"gps": {}},
                                   period=0.02, limit=None, heartbeat=None):
            events.append(event)
            if "data" in event:  # deleted: a snapshot without it
                runner.snapshot = {"time": 0.02, "robots": {}}
        return events

    events = asyncio.run(asyncio.wait_for(read(), 5))
    assert events == [{"retry": 1000}, {"event": "gps", "data": '{"x": 0.5}'}]
