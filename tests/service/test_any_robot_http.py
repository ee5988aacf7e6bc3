"""The HTTP services and the dashboard's state for robots other than the Corobot: the Burger
(two wheels, a caster, a lidar and an IMU; no IR sensor, no camera) and the Pioneer (four
skid-steer wheels, eight sonars as IR sensors), side by side in one simulation the test
advances itself. Each robot's drive state is by its own wheels, each with its side; the
two-wheel view and the encoders are its wheels with an encoder; what it lacks is not
offered; the commands (SetPose, DriveDistance, RotateDegrees, SetVelocity) drive each."""

import pytest
from fastapi.testclient import TestClient
from step_runner import StepRunner

from corobot_drake.config.scenario import load_scenario
from corobot_drake.serving.webapp import create_app
from corobot_drake.simulation import Simulation

SCENARIO = """
robots:
  burger: {robot: burger}
  pioneer: {robot: pioneer, pose: {translation: [0, -1.5, 0]}}
"""


@pytest.fixture(scope="module")
def sim():
    return Simulation(load_scenario(data=SCENARIO))


@pytest.fixture(scope="module")
def http(sim):
    with TestClient(create_app(StepRunner(sim)), base_url="http://127.0.0.1") as client:
        yield client


@pytest.mark.parametrize("robot", ["burger", "pioneer"])
def test_the_drive_state_is_by_the_robots_wheels(sim, http, robot):
    spec = sim.robot(robot).spec
    d = http.get(f"/robots/{robot}/drive").json()
    assert list(d["wheels"]) == list(spec.wheel_names)
    assert [w["side"] for w in d["wheels"].values()] == [
        "left" if w.side > 0 else "right" for w in spec.wheels]
    assert d["wheel_radius"] == spec.wheel_radius
    assert d["encoder_ticks_per_revolution"] == spec.encoder_ticks_per_revolution
    left, right = (spec.wheel_names[i] for i in spec.encoded)
    assert http.get(f"/robots/{robot}/encoders").json().keys() >= {left, right}
    two = http.get(f"/robots/{robot}/drive/two_wheel").json()
    assert two["left"] == d["wheels"][left] and two["right"] == d["wheels"][right]


def test_power_drives_every_wheel_and_the_encoders_count(sim, http):
    for robot in ("burger", "pioneer"):
        answer = http.post(f"/robots/{robot}/drive/set_power", json={"left": 0.5, "right": 0.5})
        assert answer.status_code == 200, answer.text
    sim.advance_to(sim.time + 0.3)
    for robot in ("burger", "pioneer"):
        d = http.get(f"/robots/{robot}/drive").json()
        # Every wheel turns forward (past the slew in 0.3 s); loads on every wheel.
        assert all(w["axle_speed"] > 1.0 and w["commanded_power"] == 0.5
                   for w in d["wheels"].values())
        assert all(w["load"] > 0 for w in d["wheels"].values())
        assert all(t > 0 for k, t in http.get(f"/robots/{robot}/encoders").json().items()
                   if k not in ("time_stamp", "ticks_per_revolution"))


def test_what_a_robot_lacks_is_not_offered(http):
    burger = http.get("/robots/burger").json()
    assert burger["capabilities"]["ir"] is False and burger["capabilities"]["camera"] is False
    names = {s["name"] for s in burger["services"]}
    assert not any(n.endswith("_ir") for n in names) and "camera" not in names
    assert http.get("/robots/burger/camera").status_code == 501  # as for a Corobot without
    sensors = http.get("/robots/burger/sensors").json()
    assert set(sensors["lidars"]) == {"scan"} and set(sensors["imus"]) == {"imu"}
    assert sensors["ir_sensors"] == {} and sensors["cameras"] == {}
    pioneer = http.get("/robots/pioneer").json()
    assert pioneer["capabilities"]["ir"] is True
    sonars = {s["name"] for s in pioneer["services"] if s["name"].endswith("_ir")}
    assert sonars == {f"sonar_{side}_{deg}_ir" for side in ("left", "right")
                      for deg in (10, 30, 50, 90)}


def _finish(sim, http, answer, limit: float = 10.0) -> dict:
    """Advances the simulation until the operation `answer` (a 202) ends; its state."""
    assert answer.status_code == 202, answer.text
    url, end = answer.json()["status_url"], sim.time + limit
    while (op := http.get(url).json())["status"] == "running" and sim.time < end:
        sim.advance(0.1)
    return op


@pytest.mark.parametrize("robot", ["burger", "pioneer"])
def test_the_commands_drive_each_robot(sim, http, robot):
    base = f"/robots/{robot}/drive"
    y0 = 0.0 if robot == "burger" else -1.5
    op = _finish(sim, http, http.post(f"{base}/set_pose", json={
        "x": 0.0, "y": y0, "yaw_deg": 0.0, "wait": False}))
    assert op["status"] == "succeeded", op
    sim.advance(0.3)  # settles on its wheels
    x0 = http.get(base).json()["position"]["x"]
    op = _finish(sim, http, http.post(f"{base}/drive_distance",
                                      json={"distance": 0.2, "power": 0.5, "wait": False}))
    assert op["status"] == "succeeded", op
    d = http.get(base).json()
    # The landings R2's figures measure are a few mm at most: 1 cm.
    assert d["position"]["x"] - x0 == pytest.approx(0.2, abs=0.01)
    op = _finish(sim, http, http.post(f"{base}/rotate_degrees",
                                      json={"degrees": 45, "power": 0.5, "wait": False}))
    assert op["status"] == "succeeded", op
    assert http.get(base).json()["heading_deg"] == pytest.approx(45, abs=2)  # as the Corobot's
    assert http.post(f"{base}/set_velocity", json={"linear": 0.1, "angular": 0.0}).is_success
    sim.advance(1.0)
    assert http.get(base).json()["velocity"]["forward"] == pytest.approx(0.1, abs=0.015)
    assert http.post(f"{base}/all_stop", json={}).is_success
