"""The live services: a real server (`python -m corobot_drake --serve --headless
--port 0`) in a child process, driven over HTTP.

One server serves the whole module (building the simulation takes seconds); tests that change
the robot's state put it back (set_pose / all_stop / enable) so they don't depend on order.
"""

import io
import itertools
import json
import math
import os
import re
import time

import httpx
import pytest

from corobot_drake.serving.serve import ServerProcess
from lab import server_load
from lab.processes import alive, children_by_parent, listening_sockets, sockets_held

ROBOT = "/robots/corobot"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    log = tmp_path_factory.mktemp("server") / "stderr.log"
    with ServerProcess(["--headless"], stderr_path=str(log)) as s:
        yield s
    if s.process.returncode not in (0, None):
        print(log.read_text()[-3000:])


@pytest.fixture(scope="module")
def http(server):
    with httpx.Client(base_url=server.url, timeout=60) as client:
        yield client


@pytest.fixture(scope="module")
def caps(http):
    return http.get(ROBOT).json()["capabilities"]


def need(caps, capability):
    """The default robot has every part of the API: a missing one is a regression."""
    assert caps[capability], f"{capability} missing from the default robot's capabilities"


def sim_time(http) -> float:
    return http.get("/simulation").json()["time"]


def wait_sim(http, seconds: float) -> None:
    """Waits until the server's simulation has advanced `seconds`."""
    end = sim_time(http) + seconds
    deadline = time.monotonic() + 10 * seconds + 5
    while sim_time(http) < end:
        assert time.monotonic() < deadline, "the simulation stopped advancing"
        time.sleep(0.05)


def reset(http, caps):
    http.post(f"{ROBOT}/drive/enable", json={"enabled": True})
    if caps["set_pose"]:
        r = http.post(f"{ROBOT}/drive/set_pose", json={"x": 0, "y": 0, "yaw_deg": 0})
        assert r.json()["status"] == "succeeded", r.json()
    else:
        http.post(f"{ROBOT}/drive/all_stop", json={})
        wait_sim(http, 0.5)


# --- directory and documents ----------------------------------------------------------------


def test_default_robot_has_every_capability(caps):
    """The branches below on caps[...] are for scenarios without a camera or IR; the default
    robot has all of it, so none of them may be skipped here."""
    assert caps and all(caps.values()), caps



def test_service_directory_lists_services_with_contracts_and_working_urls(http, caps):
    directory = http.get("/services").json()
    services = {s["name"]: s for s in directory["services"] if s["robot"] == "corobot"}
    expected = {"drive", "encoders", "compass", "gps"}
    if caps["ir"]:
        expected |= {"front_ir", "rear_ir"}
    if caps["camera"]:
        expected.add("camera")
    assert expected <= set(services)
    assert services["drive"]["contract"] == "corobot-drake/drive/v1"
    for s in services.values():
        assert s["contract"].startswith("corobot-drake/")
        r = http.get(s["state_url"])
        assert r.status_code == 200, (s, r.text)
        assert r.headers["content-type"].startswith("application/json")
    html = http.get("/services", headers={"Accept": "text/html"})
    assert html.headers["content-type"].startswith("text/html")
    assert "<table" in html.text and "corobot-drake/drive/v1" in html.text
    assert http.get("/services?format=html").text == html.text


def test_openapi_document_is_served_and_valid(http):
    from openapi_spec_validator import validate

    doc = http.get("/openapi.json").json()
    validate(doc)
    paths = doc["paths"]
    for command in ("set_power", "set_speed", "set_velocity", "all_stop", "enable",
                    "drive_distance", "rotate_degrees", "set_pose"):
        assert f"/robots/{{robot}}/drive/{command}" in paths
    assert "/robots/{robot}/drive" in paths and "/services" in paths
    power = doc["components"]["schemas"]["PowerRequest"]["properties"]["left"]
    assert power["minimum"] == -1 and power["maximum"] == 1
    assert http.get("/docs").status_code == 200


def test_pages_are_served(http):
    for path in ("/dashboard", "/static/dashboard.js", "/static/style.css"):
        assert http.get(path).status_code == 200, path
    icon = http.get("/favicon.ico")  # what browsers ask for, and what the pages link
    assert icon.status_code == 200 and icon.headers["content-type"] == "image/svg+xml"
    assert icon.content.startswith(b"<svg ")
    for page in ("/dashboard", f"{ROBOT}/camera/page", "/services?format=html"):
        assert '<link rel="icon" href="/favicon.ico"' in http.get(page).text, page
    assert http.get("/", follow_redirects=False).status_code in (302, 307)


# --- drive contract -----------------------------------------------------------------------------


def test_drive_state_four_wheel_and_two_wheel(http):
    d = http.get(f"{ROBOT}/drive").json()
    assert set(d["wheels"]) == {"front_left", "front_right", "rear_left", "rear_right"}
    assert d["distance_between_wheels"] == pytest.approx(0.22352)
    assert d["power_scaling_factor"] > 0 and d["encoder_ticks_per_revolution"] == 600
    assert isinstance(d["is_enabled"], bool) and d["time_stamp"] >= 0
    assert set(d["position"]) == {"x", "y", "z"} and "heading" in d
    assert d["wheels"]["front_left"]["encoder_ticks"] is not None
    assert d["wheels"]["rear_left"]["encoder_ticks"] is None
    two = http.get(f"{ROBOT}/drive/two_wheel").json()
    assert set(two["left"]) == set(d["wheels"]["front_left"])
    assert two["distance_between_wheels"] == d["distance_between_wheels"]
    encoders = http.get(f"{ROBOT}/encoders").json()
    assert encoders["ticks_per_revolution"] == 600 and "front_left" in encoders


def test_drive_state_carries_the_contact_telemetry(http, caps):
    reset(http, caps)
    wait_sim(http, 0.5)  # settled on its tyres
    d = http.get(f"{ROBOT}/drive").json()
    wheels = d["wheels"].values()
    # At rest: the loads carry the robot's 4.03 kg (3%: the tolerance; a set_pose
    # just before may leave it settling), no slip (creep ~1e-5 m/s against a 1 cm/s floor),
    # the upright tip margin (37.4 deg; 0.1 deg for the settling).
    assert sum(w["load"] for w in wheels) == pytest.approx(4.03 * 9.81, rel=0.03)
    assert all(abs(w["slip_ratio"]) < 1e-3 and abs(w["slip_angle_deg"]) < 0.2 for w in wheels)
    assert d["tip_margin_deg"] == pytest.approx(37.41, abs=0.1)
    assert http.get(f"{ROBOT}/drive/two_wheel").json()["left"]["load"] == \
        pytest.approx(d["wheels"]["front_left"]["load"], rel=0.05)
    assert "heading" in http.get(f"{ROBOT}/compass").json()
    assert {"x", "y", "z"} <= set(http.get(f"{ROBOT}/gps").json())


def test_set_power_drives_forward_and_all_stop_stops(http, caps):
    reset(http, caps)
    x0 = http.get(f"{ROBOT}/drive").json()["position"]["x"]
    r = http.post(f"{ROBOT}/drive/set_power", json={"left": 0.5, "right": 0.5})
    assert r.status_code == 200 and r.json()["status"] == "accepted"
    wait_sim(http, 1.5)
    d = http.get(f"{ROBOT}/drive").json()
    assert d["position"]["x"] - x0 > 0.2
    assert d["wheels"]["front_left"]["commanded_power"] == 0.5
    assert d["wheels"]["front_left"]["encoder_ticks"] > 100
    assert http.post(f"{ROBOT}/drive/all_stop", json={}).status_code == 200
    wait_sim(http, 1.0)
    assert abs(http.get(f"{ROBOT}/drive").json()["velocity"]["forward"]) < 0.01


def test_set_speed(http, caps):
    reset(http, caps)
    assert http.post(f"{ROBOT}/drive/set_speed", json={"left": 0.2, "right": 0.2}).is_success
    wait_sim(http, 1.5)
    v = http.get(f"{ROBOT}/drive").json()["velocity"]["forward"]
    assert v == pytest.approx(0.2, abs=0.03)
    http.post(f"{ROBOT}/drive/all_stop", json={})


def test_set_velocity(http, caps):
    reset(http, caps)
    body = {"linear": 0.2, "angular": 0.0}
    assert http.post(f"{ROBOT}/drive/set_velocity", json=body).is_success
    wait_sim(http, 1.5)
    v = http.get(f"{ROBOT}/drive").json()["velocity"]["forward"]
    assert v == pytest.approx(0.2, abs=0.03)  # as test_set_speed
    assert http.post(f"{ROBOT}/drive/set_velocity",
                     json={"linear": 0.2}).status_code == 422  # both fields required
    http.post(f"{ROBOT}/drive/all_stop", json={})


def test_disabled_drive_ignores_power(http, caps):
    reset(http, caps)
    assert http.post(f"{ROBOT}/drive/enable", json={"enabled": False}).is_success
    http.post(f"{ROBOT}/drive/set_power", json={"left": 1, "right": 1})
    wait_sim(http, 0.5)
    d = http.get(f"{ROBOT}/drive").json()
    assert d["is_enabled"] is False
    assert abs(d["velocity"]["forward"]) < 0.01
    assert http.post(f"{ROBOT}/drive/enable", json={"enabled": True}).is_success
    wait_sim(http, 0.1)  # the drive acts on it at its next update (60 Hz)
    assert http.get(f"{ROBOT}/drive").json()["is_enabled"] is True
    http.post(f"{ROBOT}/drive/all_stop", json={})


def test_completing_commands_wait_or_answer_at_once(http, caps):
    need(caps, "drive_distance")
    reset(http, caps)
    r = http.post(f"{ROBOT}/drive/drive_distance", json={"distance": 0.3, "power": 0.4})
    assert r.status_code == 200, r.text
    op = r.json()
    assert op["status"] == "succeeded" and op["end_time"] > op["start_time"]
    assert http.get(f"{ROBOT}/drive").json()["position"]["x"] == pytest.approx(0.3, abs=0.03)

    r = http.post(f"{ROBOT}/drive/rotate_degrees",
                  json={"degrees": 30, "power": 0.3, "wait": False})
    assert r.status_code == 202 and r.json()["status"] == "running"
    url = r.json()["status_url"]
    assert r.headers["location"] == url
    deadline = time.monotonic() + 30
    while (op := http.get(url).json())["status"] == "running":
        assert time.monotonic() < deadline
        time.sleep(0.1)
    assert op["status"] == "succeeded", op
    heading = http.get(f"{ROBOT}/drive").json()["heading_deg"]
    assert heading == pytest.approx(30, abs=2)


def test_a_new_command_supersedes_a_running_one(http, caps):
    need(caps, "drive_distance")
    reset(http, caps)
    r = http.post(f"{ROBOT}/drive/drive_distance",
                  json={"distance": 2.0, "power": 0.2, "wait": False})
    url = r.json()["status_url"]
    wait_sim(http, 0.3)
    http.post(f"{ROBOT}/drive/all_stop", json={})
    wait_sim(http, 0.1)
    op = http.get(url).json()
    assert op["status"] == "failed" and op["reason"] == "superseded"


def test_set_pose_teleports(http, caps):
    need(caps, "set_pose")
    r = http.post(f"{ROBOT}/drive/set_pose", json={"x": 0.5, "y": -0.4, "yaw_deg": 90})
    assert r.status_code == 200 and r.json()["status"] == "succeeded", r.text
    d = http.get(f"{ROBOT}/drive").json()
    assert d["position"]["x"] == pytest.approx(0.5, abs=0.01)
    assert d["position"]["y"] == pytest.approx(-0.4, abs=0.01)
    assert d["heading_deg"] == pytest.approx(90, abs=1)
    reset(http, caps)


# --- sensors ----------------------------------------------------------------------------------


def test_ir_analog_sensor_contract(http, caps):
    need(caps, "ir")
    reset(http, caps)
    wait_sim(http, 0.3)
    front = http.get(f"{ROBOT}/front_ir").json()
    rear = http.get(f"{ROBOT}/rear_ir").json()
    assert set(front) == {"raw", "range", "normalized", "time_stamp"}
    assert rear["normalized"] == pytest.approx(rear["raw"] / rear["range"])
    if caps["set_pose"]:  # back at the start: the SPEC's figures
        assert front["raw"] == pytest.approx(0.762) and front["normalized"] == pytest.approx(1)
        assert rear["raw"] == pytest.approx(0.62865, abs=0.002)


def test_every_sensor_reading_by_kind_and_name(http, caps):
    """`/sensors` gives each sensor's latest reading by kind and name, `/sensors/<kind>/<name>`
    one of them (the kind's reading fields), as the Python client's `sensor_json`; a sensor the
    robot lacks is a 404 naming those it has."""
    from corobot_drake.serving.client import CorobotClient

    need(caps, "ir")
    reset(http, caps)
    wait_sim(http, 0.3)
    sensors = http.get(f"{ROBOT}/sensors").json()
    assert set(sensors["ir_sensors"]) == {"front", "rear"}
    rear = http.get(f"{ROBOT}/sensors/ir_sensors/rear").json()
    assert set(rear) == {"raw", "range", "normalized", "time"}
    if caps["set_pose"]:  # back at the start: the SPEC's figure
        assert rear["raw"] == pytest.approx(0.62865, abs=0.002)
    if caps["camera"]:
        camera = http.get(f"{ROBOT}/sensors/cameras/front").json()
        assert (camera["width"], camera["height"], camera["encoding"]) == (320, 240, "rgba8")
        assert camera["time"] > 0
    missing = http.get(f"{ROBOT}/sensors/ir_sensors/side")
    assert missing.status_code == 404 and "ir_sensors/rear" in missing.json()["detail"]
    with CorobotClient(str(http.base_url)) as client:
        bot = client.robot()
        assert set(bot.sensor_json("rear")) == set(rear)
        assert bot.sensor_readings().keys() == sensors.keys()


def read_events(lines, want: int, timeout: float) -> list[tuple[str, dict, float]]:
    """Up to `want` events from an SSE line iterator: (name, data, arrival time)."""
    events, name, deadline = [], None, time.monotonic() + timeout
    for line in lines:
        if line.startswith("event: "):
            name = line[7:]
        elif line.startswith("data: "):
            events.append((name, json.loads(line[6:]), time.monotonic()))
            if len(events) >= want:
                break
        if time.monotonic() > deadline:
            break
    return events


def test_subscription_sends_changes(http, server, caps):
    reset(http, caps)
    services = "drive,front_ir,rear_ir" if caps["ir"] else "drive"
    with httpx.Client(base_url=server.url, timeout=30) as client, client.stream(
            "GET", f"{ROBOT}/subscribe?services={services}&limit=6") as response:
        assert response.headers["content-type"].startswith("text/event-stream")
        lines = response.iter_lines()
        first = read_events(lines, 3 if caps["ir"] else 1, 5)
        names = {e[0] for e in first}
        assert "drive" in names
        if caps["ir"]:
            assert {"front_ir", "rear_ir"} <= names
        http.post(f"{ROBOT}/drive/set_power", json={"left": -0.4, "right": -0.4})
        events = read_events(lines, 30, 4)
    http.post(f"{ROBOT}/drive/all_stop", json={})
    drive = [e for e in events if e[0] == "drive"]
    assert len(drive) >= 5  # the robot moves, so its state changes at every check
    assert any(e[1]["wheels"]["front_left"]["commanded_power"] == -0.4 for e in drive)
    # Each event a newer state than the last, in the order the simulation reached them (how
    # closely a loaded host keeps the 0.1 s check period is not asserted: wall-clock timing).
    stamps = [e[1]["time_stamp"] for e in drive]
    assert all(a < b for a, b in itertools.pairwise(stamps)), stamps
    if caps["ir"] and caps["set_pose"]:  # from the start, backing toward the box: the rear
        # reading falls, so it is sent
        rear = [e[1]["raw"] for e in events if e[0] == "rear_ir"]
        assert len(rear) >= 2 and rear[-1] < rear[0]


def test_change_thresholds_ignore_creep_and_time_stamps():
    from corobot_drake.serving.routes.subscriptions import CHANGE_THRESHOLDS, changed

    gps = {"time_stamp": 1.0, "x": 0.5, "y": 0.25, "z": 0.0}
    assert not changed(gps, {**gps, "time_stamp": 2.0, "x": 0.5 + 1e-9}, CHANGE_THRESHOLDS)
    assert changed(gps, {**gps, "x": 0.5 + 2e-4}, CHANGE_THRESHOLDS)  # 0.2 mm > 0.1 mm
    ir = {"raw": 0.6, "range": 0.762, "normalized": 0.6 / 0.762, "time_stamp": 0.05}
    ir_thresholds = {**CHANGE_THRESHOLDS, "raw": 1e-4}
    assert not changed(ir, {**ir, "raw": 0.6 + 1e-10, "normalized": 0.7874}, ir_thresholds)
    assert changed(ir, {**ir, "raw": 0.6 - 2e-4}, ir_thresholds)
    drive = {"wheels": {"front_left": {"commanded_power": 0.0, "encoder_ticks": 3}},
             "command": None}
    assert changed(drive, {"wheels": {"front_left": {"commanded_power": 0.0, "encoder_ticks": 4}},
                           "command": None}, CHANGE_THRESHOLDS)  # ticks: any change
    assert changed(drive, {**drive, "command": {"status": "running"}}, CHANGE_THRESHOLDS)


def test_subscription_of_a_robot_at_rest_sends_only_the_first_state_and_heartbeats(
        http, server, caps):
    """At rest the IR readings move by ~1e-10 m and the pose creeps by
    nanometres; none of that is a change, so each service sends its first state only."""
    reset(http, caps)
    wait_sim(http, 0.5)  # settled after the teleport
    services = "drive,front_ir,rear_ir,encoders,compass,gps" if caps["ir"] else "drive,gps"
    with httpx.Client(base_url=server.url, timeout=30) as client, client.stream(
            "GET", f"{ROBOT}/subscribe?services={services}&limit=3") as response:
        events = read_events(response.iter_lines(), 100, 6)
    names = [e[0] for e in events]
    assert sorted(names) == sorted(services.split(",")), names  # one each
    with httpx.Client(base_url=server.url, timeout=30) as client, client.stream(
            "GET", f"{ROBOT}/gps/subscribe?limit=2.2&heartbeat=0.5") as response:
        beats = read_events(response.iter_lines(), 100, 6)
    # The first state, then one every 0.5 s of a 2.2 s stream checked every 0.1 s: 4 or 5.
    assert 4 <= len(beats) <= 6, [round(b[2] - beats[0][2], 2) for b in beats]


def test_single_service_subscription_and_unknown(http, server):
    with httpx.Client(base_url=server.url, timeout=30) as client, client.stream(
            "GET", f"{ROBOT}/compass/subscribe?limit=1") as response:
        events = read_events(response.iter_lines(), 1, 5)
    assert events[0][0] == "compass" and "heading" in events[0][1]
    r = http.get(f"{ROBOT}/nothing/subscribe")
    assert r.status_code == 404 and "nothing" in r.json()["detail"]


# --- webcam -------------------------------------------------------------------------------------


def test_webcam_frames_and_page(http, caps):
    need(caps, "camera")
    from PIL import Image

    png = http.get(f"{ROBOT}/camera/frame.png")
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    image = Image.open(io.BytesIO(png.content))
    assert image.size == (320, 240)
    assert max(image.convert("L").getextrema()) > 0  # not black
    jpg = http.get(f"{ROBOT}/camera/frame.jpg")
    assert jpg.headers["content-type"] == "image/jpeg"
    assert Image.open(io.BytesIO(jpg.content)).size == (320, 240)
    assert float(jpg.headers["x-frame-time"]) >= 0
    info = http.get(f"{ROBOT}/camera").json()
    assert info["frame_png_url"].endswith("frame.png")
    page = http.get(f"{ROBOT}/camera/page?interval=250")
    assert page.status_code == 200 and 'value="250"' in page.text
    assert http.get(f"{ROBOT}/camera/page?interval=1").status_code == 422


# --- bad input ------------------------------------------------------------------------------------

BAD = [
    # (method, path, raw body, status, words the message must contain)
    ("POST", "/drive/set_power", "{left: 1", 400, "malformed JSON"),
    ("POST", "/drive/set_power", "[1, 2", 400, "malformed JSON"),
    ("POST", "/drive/set_power", '{"left": NaN, "right": 0}', 422, "left: Input should be a fin"),
    ("POST", "/drive/set_power", '{"left": Infinity, "right": 0}', 422, "finite"),
    ("POST", "/drive/set_power", '{"left": 1.5, "right": 0}', 422, "less than or equal to 1"),
    ("POST", "/drive/set_power", '{"left": -3, "right": 0}', 422, "greater than or equal to -1"),
    ("POST", "/drive/set_power", '{"left": "fast", "right": 0}', 422, "valid number"),
    ("POST", "/drive/set_power", '{"left": true, "right": 0}', 422, "valid number"),
    ("POST", "/drive/set_power", '{"left": 0.5}', 422, "right: required"),
    ("POST", "/drive/set_power", '{"left": 0, "right": 0, "turbo": 1}', 422, "turbo: unknown"),
    ("POST", "/drive/set_power", "[0.5, 0.5]", 422, "valid dictionary"),
    ("POST", "/drive/set_power", "", 422, "required"),
    ("POST", "/drive/set_speed", '{"left": 1e308, "right": 0}', 422, "less than or equal"),
    ("POST", "/drive/enable", '{"enabled": "yes"}', 422, "valid boolean"),
    ("POST", "/drive/drive_distance", '{"distance": 1, "power": 0}', 422, "power"),
    ("POST", "/drive/drive_distance", '{"distance": NaN}', 422, "finite"),
    ("POST", "/drive/rotate_degrees", '{"degrees": 90, "power": 2}', 422, "power"),
    ("POST", "/drive/rotate_degrees", '{"degrees": 90, "wait": 3}', 422, "wait"),
    ("POST", "/drive/set_pose", '{"x": 1}', 422, "y: required"),
    ("POST", "/drive/fly", "{}", 404, "no command 'fly'"),
    ("GET", "/drive/operations/999999", None, 404, "no operation 999999"),
    ("GET", "/drive/operations/abc", None, 422, "valid integer"),
    ("GET", "/sonar", None, 404, "no service 'sonar'"),
    ("GET", "/camera/page?interval=abc", None, 422, "interval"),
    ("PUT", "/drive", "{}", 405, "not allowed"),
]


@pytest.mark.parametrize(("method", "path", "body", "status", "words"), BAD,
                         ids=[f"{m} {p} {b}" for m, p, b, *_ in BAD])
def test_bad_input_gets_a_clear_4xx(http, method, path, body, status, words):
    r = http.request(method, ROBOT + path, content=body,
                     headers={"Content-Type": "application/json"})
    assert r.status_code == status, r.text
    assert words in r.json()["detail"], r.json()


@pytest.mark.parametrize("path", ["/robots/nobody/drive", "/robots/nobody/front_ir",
                                  "/robots/nobody/drive/two_wheel"])
def test_unknown_robot_is_404_naming_the_robots(http, path):
    r = http.get(path)
    assert r.status_code == 404
    assert r.json()["detail"] == "no robot named 'nobody'; robots: corobot"
    r = http.post("/robots/nobody/drive/set_power", json={"left": 0, "right": 0})
    assert r.status_code == 404 and "nobody" in r.json()["detail"]


def test_unknown_path_is_404_pointing_at_the_directory(http):
    r = http.get("/nowhere")
    assert r.status_code == 404 and "/services" in r.json()["detail"]


# --- load -----------------------------------------------------------------------------------------


def test_malformed_flood_and_pollers_are_answered_and_the_simulation_runs_on(http, server, caps):
    """1000 malformed requests and 20 clients polling state at once: every bad request gets
    a 4xx, every poll a 200, the server survives and the simulation goes on advancing. (The
    real-time factor it keeps under this load is a benchmark: docs/costs.md's
    `server-flood` block.)"""
    reset(http, caps)
    http.post(f"{ROBOT}/drive/set_power", json={"left": 0.3, "right": -0.3})  # spin in place
    paths = [p for p in server_load.POLL_PATHS if caps["ir"] or not p.endswith("_ir")]
    t0 = sim_time(http)
    answers = server_load.run(server.url, ROBOT, paths)
    deadline = time.monotonic() + 60
    while sim_time(http) <= t0:  # it advances under the load
        assert time.monotonic() < deadline, "the simulation stopped advancing"
        time.sleep(0.1)
    codes = answers.flood_codes
    assert len(codes) == 1000 and all(400 <= c < 500 for c in codes), set(codes)
    assert answers.polls_bad == 0 and answers.polls_ok > 20 * 10
    stats = http.get("/simulation").json()
    assert stats["running"] and stats["error"] is None
    http.post(f"{ROBOT}/drive/all_stop", json={})
    assert server.process.poll() is None
    assert math.isfinite(http.get(f"{ROBOT}/drive").json()["heading"])


# --- the client ---------------------------------------------------------------------------------


def test_client_has_the_python_apis_methods(server, http, caps):
    from corobot_drake.serving.client import CorobotClient, CorobotValueError
    from corobot_drake.simulation import Robot, Simulation

    reset(http, caps)
    with CorobotClient(server.url) as sim:
        bot = sim.robot()
        for name in ("set_power", "set_speed", "set_velocity", "all_stop", "enable", "pose",
                     "velocity", "axle_speeds", "is_enabled", "summary"):
            assert callable(getattr(bot, name)) and hasattr(Robot, name), name
        for name in ("robot", "advance", "advance_to", "summary"):
            assert hasattr(Simulation, name) and callable(getattr(sim, name)), name
        t0, x0, ticks0 = sim.time, bot.pose().x, bot.encoders()["front_left"]
        assert isinstance(bot.set_power(0.4, 0.4), int)
        sim.advance(1.0)
        assert sim.time >= t0 + 1.0
        assert bot.pose().x > x0 + 0.1 and bot.velocity().forward > 0.1
        assert bot.encoders()["front_left"] > ticks0 + 50 and bot.position()[0] > x0 + 0.1
        bot.all_stop()
        with pytest.raises(CorobotValueError, match="less than or equal to 1"):
            bot.set_power(2, 0)
        with pytest.raises(ValueError):
            bot.set_power(math.nan, 0)
        with pytest.raises(KeyError, match="no robot named 'ghost'"):
            sim.robot("ghost")
        assert {s["name"] for s in sim.services()} >= {"drive", "encoders"}
        if caps["drive_distance"]:
            reset(http, caps)
            result = bot.drive_distance(0.2, 0.4)
            assert result.succeeded and result.end_time > result.start_time
            handle = bot.rotate_degrees_async(-20, 0.3)
            assert re.fullmatch(rf"<RemoteCommandHandle seq {handle.seq}: rotate_degrees "
                                r"running, since t = \d+\.\d{3} s, as last fetched>",
                                repr(handle))
            assert not handle.done()
            assert handle.wait(30).succeeded
            assert re.fullmatch(r"<.*: rotate_degrees succeeded, t = [\d.]+ to [\d.]+ s, as last "
                                r"fetched>", repr(handle))
            assert math.degrees(bot.heading()) == pytest.approx(-20, abs=2)
        if caps["ir"]:
            assert bot.ir("front").raw == pytest.approx(bot.ir_distances()["front"])
        if caps["camera"]:
            image = bot.camera_image()
            assert image.shape == (240, 320, 4) and image.dtype.name == "uint8"


# --- the command line and the in-process form ---------------------------------------------------


def test_serve_reports_a_taken_port(server):
    import subprocess
    import sys

    port = server.url.rsplit(":", 1)[1]
    run = subprocess.run([sys.executable, "-m", "corobot_drake", "--serve", "--headless",
                          "--port", port], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert f"error: cannot listen on 127.0.0.1:{port}" in run.stderr


def test_serve_at_a_rate_runs_faster_than_the_wall_clock(tmp_path):
    """`--serve --rate 4`: simulated time goes 4 s a wall-clock second, as measured from
    outside (two `/simulation` answers 1 s apart) and as the server says
    (`recent_realtime_factor`). The tolerance: at most 10% over (the runner paces to 4x the
    wall clock; the snapshots' 1/30 s and the requests' milliseconds are ~1% of the 4 s), at
    most 25% under (this machine keeps ~10x headless; a busy core may slow it, and a
    real-time server's 1.0 stays far outside)."""
    with ServerProcess(["--headless", "--rate", "4"],
                       stderr_path=str(tmp_path / "stderr.log")) as server, \
            httpx.Client(base_url=server.url, timeout=60) as client:
        first, wall0 = client.get("/simulation").json(), time.monotonic()
        time.sleep(1.0)
        last, wall1 = client.get("/simulation").json(), time.monotonic()
    assert last["rate"] == 4.0
    measured = (last["time"] - first["time"]) / (wall1 - wall0)
    assert 3.0 < measured < 4.4, (measured, last)
    assert 3.0 < last["recent_realtime_factor"] < 4.4, last


@pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
def test_in_process_runner_serves_from_a_thread():
    """`create_app(SimRunner(...))`: the same app in one process (for embedding)."""
    from fastapi.testclient import TestClient

    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.serving.runner import SimRunner
    from corobot_drake.serving.webapp import create_app
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO)
    runner = SimRunner(lambda: Simulation(scenario)).start()
    try:
        with TestClient(create_app(runner), base_url="http://127.0.0.1") as client:
            assert client.get(f"{ROBOT}/drive").status_code == 200
            assert client.post(f"{ROBOT}/drive/set_power",
                               json={"left": 2, "right": 0}).status_code == 422
            r = client.post(f"{ROBOT}/drive/drive_distance",
                            json={"distance": 0.1, "power": 0.5})
            assert r.status_code == 200 and r.json()["status"] == "succeeded", r.text
            assert client.get("/simulation").json()["running"]
    finally:
        runner.stop()
    assert runner.error is None


@pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")
def test_each_camera_is_served_at_its_own_routes():
    """Two cameras: the front one at /camera (and /cameras/front), the other at
    /cameras/<name>, each in the directory, each frame its own camera's; a camera the robot
    lacks is a 404 naming those it has."""
    import io

    import numpy as np
    from fastapi.testclient import TestClient
    from PIL import Image

    from conftest import TWO_CAMERAS
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.serving.runner import SimRunner
    from corobot_drake.serving.webapp import create_app
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[TWO_CAMERAS])
    runner = SimRunner(lambda: Simulation(scenario)).start()
    try:
        with TestClient(create_app(runner), base_url="http://127.0.0.1") as client:
            directory = client.get("/services").json()["services"]
            pages = {s["name"]: s["page_url"] for s in directory if "page_url" in s}
            assert pages == {"camera": f"{ROBOT}/camera/page",
                             "cameras/rear": f"{ROBOT}/cameras/rear/page"}
            assert client.get(f"{ROBOT}/cameras/rear").json()["frame_png_url"] == (
                f"{ROBOT}/cameras/rear/frame.png")
            # Frames from initialization (no output delay): each camera's image, 64 x 48.
            front, rear, front_again = (
                np.asarray(Image.open(io.BytesIO(client.get(f"{ROBOT}/{path}/frame.png")
                                                  .content)).convert("RGB"), dtype=int)
                for path in ("camera", "cameras/rear", "cameras/front"))
            assert front.shape == rear.shape == (48, 64, 3)
            assert np.abs(front - rear).mean() > 20  # the two views (test_camera.py)
            assert np.abs(front - front_again).mean() < 20  # one view, moments apart
            assert "__FRAME_URL__" not in client.get(f"{ROBOT}/cameras/rear/page").text
            missing = client.get(f"{ROBOT}/cameras/top/frame.jpg")
            assert missing.status_code == 404
            assert missing.json()["detail"] == ("robot 'corobot' has no camera 'top'; "
                                                "cameras: front, rear")
    finally:
        runner.stop()
    assert runner.error is None


def test_a_cameras_description_has_its_latest_frame_time_before_any_fetch():
    """`GET .../camera` reports the latest frame the camera has rendered, which advances with
    the simulation, though no one has fetched a frame."""
    from fastapi.testclient import TestClient

    from conftest import TWO_CAMERAS
    from corobot_drake.config.scenario import load_scenario
    from corobot_drake.resources import DEFAULT_SCENARIO
    from corobot_drake.serving.runner import SimRunner
    from corobot_drake.serving.webapp import create_app
    from corobot_drake.simulation import Simulation

    scenario = load_scenario(DEFAULT_SCENARIO, overrides=[TWO_CAMERAS])
    runner = SimRunner(lambda: Simulation(scenario)).start()
    try:
        with TestClient(create_app(runner), base_url="http://127.0.0.1") as client:
            first = client.get(f"{ROBOT}/camera").json()["latest_frame_time"]
            assert first is not None and first >= 0
            deadline = time.monotonic() + 30
            while client.get("/simulation").json()["time"] < first + 0.2:
                assert time.monotonic() < deadline, "the simulation stopped advancing"
                time.sleep(0.05)
            later = client.get(f"{ROBOT}/cameras/rear").json()["latest_frame_time"]
            assert later > first
    finally:
        runner.stop()
    assert runner.error is None


def test_transport_carries_calls_watches_and_snapshots():
    """`RemoteRunner` over a pipe to `SimSide` is the `Runner` that `SimRunner` is: same
    robots, calls answered (exceptions too), watches resolved when the command log says the
    command ended, a cancelled watch dropped, snapshots kept up to date."""
    import multiprocessing
    from functools import partial

    from conftest import make_sim
    from corobot_drake.serving import calls
    from corobot_drake.serving.runner import Runner, SimRunner
    from corobot_drake.serving.transport import RemoteRunner, SimSide

    runner = SimRunner(make_sim()).start()
    sim_end, http_end = multiprocessing.Pipe()
    try:
        side = SimSide(runner, sim_end)
        remote = RemoteRunner(http_end, timeout=30)
        assert isinstance(runner, Runner) and isinstance(remote, Runner)
        assert remote.robots == runner.robots and remote.alive
        start = partial(calls.start_operation, "corobot", "drive_distance",
                        {"distance": 0.05, "power": 0.5})
        started = remote.submit(start).result(10)
        assert started.status == "running" and started.end_time is None
        ended = remote.watch(partial(calls.ended_command, "corobot", started.seq)).result(30)
        assert ended.status == "succeeded" and ended.end_time > started.start_time
        assert ended == remote.submit(partial(calls.command_result, "corobot",
                                              started.seq)).result(10)
        with pytest.raises(KeyError, match="no command 99999"):
            remote.submit(partial(calls.command_result, "corobot", 99999)).result(10)
        started = remote.submit(partial(calls.start_operation, "corobot", "drive_distance",
                                        {"distance": 2.0, "power": 0.2})).result(10)
        watch = remote.watch(partial(calls.ended_command, "corobot", started.seq))
        assert watch.cancel()  # long before the 2 m are driven
        t0 = remote.snapshot["time"]
        deadline = time.monotonic() + 10
        while remote.snapshot["time"] < t0 + 0.5:
            assert time.monotonic() < deadline, "no new snapshots"
            time.sleep(0.05)
        assert not runner._watches  # the cancelled watch was dropped in the simulation
        http_end.send(("stop",))
        assert side.closed.wait(5)
    finally:
        runner.stop()
        sim_end.close()
    deadline = time.monotonic() + 5
    while remote.alive:
        assert time.monotonic() < deadline, "the remote runner did not see the pipe close"
        time.sleep(0.05)
    assert remote.submit(start).exception(1) is not None


# --- one process dies, the other stops --------------------------------------------------------

def _http_process(server: ServerProcess) -> int:
    """The PID of the served simulation's HTTP process (its `multiprocessing` child)."""
    from pathlib import Path

    (pid,) = [p for p in children_by_parent().get(server.process.pid, [])
              if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()]
    return pid


def test_a_served_simulation_stops_when_its_http_process_dies(tmp_path):
    """The HTTP process killed (SIGKILL, by its PID): the simulation process stops too, in one
    line naming what happened, exit status 1."""
    import signal

    log = tmp_path / "stderr.log"
    with ServerProcess(["--headless"], stderr_path=str(log)) as server:
        os.kill(_http_process(server), signal.SIGKILL)
        assert server.process.wait(30) == 1
    lines = log.read_text().splitlines()
    assert any(line.startswith("error: the HTTP server process (") and line.endswith(
        "was killed by SIGKILL: the simulation stopped with it") for line in lines), lines


def test_an_http_process_that_dies_before_it_listens_is_one_line():
    """The HTTP process killed (SIGKILL, by its PID) as soon as it exists, before it has
    imported its server and reported its port: the simulation process does not wait for the
    report forever; exit status 2 and one line saying what happened."""
    import signal
    import subprocess
    import sys
    from pathlib import Path

    run = subprocess.Popen([sys.executable, "-m", "corobot_drake", "--headless", "--serve",
                            "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           text=True)
    try:
        deadline = time.monotonic() + 60
        while True:  # the spawned child: a second or more of imports before it listens
            http = [p for p in children_by_parent().get(run.pid, [])
                    if b"spawn_main" in Path(f"/proc/{p}/cmdline").read_bytes()]
            if http:
                break
            assert time.monotonic() < deadline and run.poll() is None, "no HTTP process"
            time.sleep(0.01)
        os.kill(http[0], signal.SIGKILL)
        out, err = run.communicate(timeout=60)
    finally:
        if run.poll() is None:
            run.kill()
            run.wait()
    assert run.returncode == 2, err
    assert err.strip().splitlines()[-1] == (f"error: the HTTP server process ({http[0]}) was "
                                            "killed by SIGKILL before it listened")
    assert not out


def test_the_http_side_stops_when_the_simulation_stops_while_it_starts():
    """The simulation's end of the pipe closes right after its hello, while the HTTP side
    is still building its app (a Ctrl-C at once; on a busy machine the niced HTTP process
    takes seconds to start): the HTTP side returns instead of serving on until it is
    terminated."""
    import multiprocessing
    import threading

    from conftest import make_sim
    from corobot_drake.serving.runner import SimRunner
    from corobot_drake.serving.security import Access
    from corobot_drake.serving.serve import http_main

    sim_end, http_end = multiprocessing.Pipe()
    http = threading.Thread(target=http_main, args=(
        http_end, Access.for_host("127.0.0.1", None), 0, "warning", 0), daemon=True)
    http.start()
    assert sim_end.poll(60) and sim_end.recv()[0] == "listening"
    runner = SimRunner(make_sim()).start()
    hello = ("hello", {"robots": runner.robots, "snapshot": runner.snapshot,
                       "stats": runner.stats(), "meshcat_url": runner.meshcat_url})
    runner.stop()
    sim_end.send(hello)  # and at once the end: the HTTP side sees it while it builds its app
    sim_end.close()
    http.join(30)  # a server that missed the close would serve on: the join times out
    assert not http.is_alive(), "the HTTP side serves on after the simulation stopped"


def test_ctrl_c_stops_both_processes_in_turn(tmp_path):
    """Ctrl-C (SIGINT to the simulation process): the simulation stops, closes the pipe, and
    the HTTP process sees it closed and ends by itself (it is not terminated), exit status 0.
    The closing line says the time simulated, not the end time (the run starts at t = 3 s, as a
    resumed saved scenario does)."""
    import re
    import signal

    log = tmp_path / "stderr.log"
    with ServerProcess(["--headless", "--override", "simulator_config: {start_time: 3.0}"],
                       stderr_path=str(log)) as server:
        assert httpx.get(f"{server.url}/simulation").status_code == 200
        http_pid = _http_process(server)
        server.process.send_signal(signal.SIGINT)
        assert server.process.wait(30) == 0
    assert not alive(http_pid)
    lines = log.read_text().splitlines()
    assert not [line for line in lines if "HTTP server process" in line], lines
    simulated = re.match(r"simulated (\S+) s \(t = 3\.00 to (\S+) s\) at ", lines[-1])
    assert simulated, lines
    assert float(simulated[1]) == pytest.approx(float(simulated[2]) - 3.0, abs=0.011), lines


def test_the_http_process_stops_when_its_served_simulation_dies(tmp_path):
    """The simulation process killed (SIGKILL, by the PID this test started): its HTTP process
    ends too (the kernel's parent-death signal), and its listening socket is closed. The
    socket is followed by its inode, not its port: another test's process may bind the freed
    port number at once."""
    import signal

    with ServerProcess(["--headless"], stderr_path=str(tmp_path / "stderr.log")) as server:
        http_pid = _http_process(server)
        (listener,) = sockets_held(http_pid) & listening_sockets()
        server.process.send_signal(signal.SIGKILL)
        server.process.wait(30)
    deadline = time.monotonic() + 30
    while alive(http_pid):
        assert time.monotonic() < deadline, "the HTTP process outlived its simulation"
        time.sleep(0.05)
    assert listener not in listening_sockets(), "the HTTP process's port still listens"
