"""The dashboard and the webcam page in headless Chromium (Debian's `chromium` package, driven
by Playwright; `tools/setup` installs both). Screenshots go to `out/` (git-ignored).
"""

import contextlib
import itertools
import os
import shutil
import time
from pathlib import Path

import pytest

from conftest import REPO
from corobot_drake.serving.serve import ServerProcess

OUT = REPO / "out"
CHROMIUM = os.environ.get("COROBOT_CHROMIUM", "/usr/bin/chromium")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"]

playwright_api = pytest.importorskip("playwright.sync_api")
if not (Path(CHROMIUM).exists() or shutil.which(CHROMIUM)):
    pytest.skip(f"no Chromium at {CHROMIUM} (tools/setup installs it)", allow_module_level=True)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    log = tmp_path_factory.mktemp("server") / "stderr.log"
    with ServerProcess(["--headless"], stderr_path=str(log)) as s:
        yield s


@pytest.fixture(scope="module")
def browser():
    with playwright_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        yield b
        b.close()


@pytest.fixture
def page(browser):
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    yield page
    context.close()
    assert not errors, errors


@contextlib.contextmanager
def dashboard_page(url: str):
    """A Chromium of its own on `url`'s dashboard, once it is ready; on leaving, closed, and
    no error raised on the page meanwhile."""
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(f"{url}/dashboard")
        page.wait_for_selector("body[data-ready='1']", timeout=30000)
        yield page
        browser.close()
    assert not errors, errors


def number(page, selector: str) -> float:
    return float(page.locator(selector).inner_text())


def wait_for(predicate, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what}")


def test_dashboard_drives_with_the_pad_and_shows_the_camera(page, server):
    page.goto(f"{server.url}/dashboard")
    page.wait_for_selector("body[data-ready='1']", timeout=30000)
    wait_for(lambda: page.locator("#pos-x").inner_text() != "-", 10, "the first state")
    x0 = number(page, "#pos-x")
    # The contact panel: at rest the four loads carry the 4.03 kg robot (3%), upright.
    loads = [f"#load-{w}" for w in ("fl", "fr", "rl", "rr")]
    wait_for(lambda: abs(sum(number(page, w) for w in loads) - 4.03 * 9.81) < 1.2, 10,
             "the wheel loads")
    assert number(page, "#tip-margin") == pytest.approx(37.4, abs=0.2)
    camera = page.locator("#camera")
    has_camera = "no camera" not in page.locator("#camera-info").inner_text() or \
        wait_for(lambda: int(camera.get_attribute("data-frames")) > 0, 10, "a camera frame")
    frames0 = int(camera.get_attribute("data-frames"))
    frame_time0 = camera.get_attribute("data-frame-time")

    # Drag the pad's knob forward (up) and hold it there.
    box = page.locator("#pad").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx, cy - box["height"] * 0.4, steps=5)
    wait_for(lambda: number(page, "#pos-x") > x0 + 0.15, 15, "the robot to move forward")
    assert float(page.locator("#power-l").inner_text()) > 0.2
    page.mouse.up()  # releasing the pad stops the robot
    wait_for(lambda: abs(float(page.locator("#speed").inner_text())) < 0.02, 10, "a stop")
    x1 = number(page, "#pos-x")
    assert x1 > x0 + 0.15
    assert int(page.locator("#enc-fl").inner_text()) > 100

    # The keyboard drives too: hold the up arrow.
    page.locator("body").click(position={"x": 5, "y": 5})
    page.keyboard.down("ArrowUp")
    wait_for(lambda: number(page, "#pos-x") > x1 + 0.05, 15, "the arrow key to drive")
    page.keyboard.up("ArrowUp")  # releasing the key stops the robot (hold to drive)
    wait_for(lambda: "all_stop" in page.locator("#sent").inner_text(), 10, "all_stop on release")
    wait_for(lambda: abs(float(page.locator("#speed").inner_text())) < 0.02, 10, "a stop")
    # A key held while the window loses focus never sees its release: the blur stops it.
    page.keyboard.down("ArrowUp")
    wait_for(lambda: "set_power" in page.locator("#sent").inner_text(), 10, "driving again")
    page.evaluate("() => window.dispatchEvent(new Event('blur'))")
    wait_for(lambda: "all_stop" in page.locator("#sent").inner_text(), 10, "all_stop on blur")
    page.keyboard.up("ArrowUp")

    if has_camera:
        wait_for(lambda: int(camera.get_attribute("data-frames")) > frames0 + 3, 15,
                 "new camera frames")
        assert camera.get_attribute("data-frame-time") != frame_time0
        size = page.evaluate("() => [document.getElementById('camera').naturalWidth,"
                             " document.getElementById('camera').naturalHeight]")
        assert size == [320, 240]
    ir = page.request.get(f"{server.url}/robots/corobot").json()["state"]["ir"]
    for name in ir:  # every IR sensor has its gauge
        assert 0 < float(page.locator(f"#ir-{name}-raw").inner_text()) <= ir[name]["range"]
    OUT.mkdir(exist_ok=True)
    page.screenshot(path=str(OUT / "dashboard.png"), full_page=True)


def test_dashboard_stop_and_enable_buttons(page, server):
    page.goto(f"{server.url}/dashboard")
    page.wait_for_selector("body[data-ready='1']", timeout=30000)
    page.locator("#enable").click()  # enabled -> disabled
    wait_for(lambda: page.locator("#enabled").inner_text() == "disabled", 10, "disabled")
    page.locator("#enable").click()
    wait_for(lambda: page.locator("#enabled").inner_text() == "enabled", 10, "enabled")
    page.locator("#stop").click()
    wait_for(lambda: "all_stop" in page.locator("#sent").inner_text(), 5, "all_stop sent")


def test_webcam_page_refreshes_at_the_chosen_interval(page, server):
    status = page.request.get(f"{server.url}/robots/corobot/camera")
    if status.status == 501:
        pytest.skip("no camera in this build")
    page.goto(f"{server.url}/robots/corobot/camera/page?interval=300")
    wait_for(lambda: page.evaluate("() => window.webcam.frames") >= 8, 20, "8 frames")
    starts = page.evaluate("() => window.webcam.starts")
    gaps = [b - a for a, b in itertools.pairwise(starts)]
    # One frame at a time, the next started the interval after the last one's start (or
    # later, when a frame takes longer): never sooner. (How close to the interval a loaded
    # machine keeps it is a benchmark's figure, not asserted here.) 1 ms: the timer's grain.
    assert len(starts) >= 8 and min(gaps) >= 300 - 1, gaps
    assert page.evaluate("() => document.getElementById('frame').naturalWidth") == 320

    page.locator("#stop").click()
    frames = page.evaluate("() => window.webcam.frames")
    time.sleep(1.0)
    assert page.evaluate("() => window.webcam.frames") <= frames + 1  # one may be in flight
    assert page.locator("#status").inner_text() == "stopped"

    page.locator("#interval").fill("100")
    page.locator("#start").click()
    f0 = page.evaluate("() => window.webcam.frames")
    wait_for(lambda: page.evaluate("() => window.webcam.frames") >= f0 + 5, 20, "5 more frames")
    # (the rate it keeps is the interval's: a benchmark's figure, not asserted here)
    assert "interval=100" in page.url
    OUT.mkdir(exist_ok=True)
    page.screenshot(path=str(OUT / "webcam.png"))


@pytest.fixture(scope="module")
def meshcat_server(tmp_path_factory):
    """A server with Meshcat (and its teleop), the camera off (it is not what is tested)."""
    log = tmp_path_factory.mktemp("meshcat_server") / "stderr.log"
    with ServerProcess(["--override", "robots: {corobot: {cameras: {front: {rgb: false}}}}"],
                       stderr_path=str(log)) as s:
        yield s


def _view_target(page):
    """Where Meshcat's camera looks, in Drake's z-up world (from three.js's y-up scene)."""
    import numpy as np

    x, y, z = page.evaluate("() => viewer.controls.target.toArray()")
    return np.array([x, -z, y])


@pytest.fixture
def meshcat_page(page, meshcat_server):
    """Meshcat's page of `meshcat_server`, loaded and framing the default scene at rest, with
    its console messages: loading it (software WebGL) is the test's setup, which runs beside
    the other worker's tests; only the key press is awaited alone on the machine."""
    import numpy as np

    from conftest import make_sim
    from corobot_drake.serving.view import framing, scene_points

    meshcat_url = page.request.get(f"{meshcat_server.url}/simulation").json()["meshcat_url"]
    page.set_viewport_size({"width": 480, "height": 360})  # software WebGL: fewer pixels
    _, target = framing(scene_points(make_sim()))  # the default scene's, at rest
    console = []
    page.on("console", lambda m: console.append(m.text))
    page.goto(meshcat_url)
    # Generous waits: a page on a loaded machine (software WebGL) lags Meshcat's messages.
    page.wait_for_selector("text=Forward (Up)", state="attached", timeout=90000)
    wait_for(lambda: np.allclose(_view_target(page), target, atol=1e-3), 90, "the initial view")
    return page, console


@pytest.mark.realtime  # the move a key press starts, awaited in real time (software WebGL)
def test_meshcat_view_and_a_key_press_that_stops_by_itself(meshcat_page, meshcat_server):
    """Meshcat's page: the initial view frames the robot and the giant box (sent again to a
    page that connects late: the fixture waits for it), the sun is the scenario's, an arrow
    key drives and the move ends by itself (Meshcat sends no key release: the teleop holds a
    move only while the key repeats). Holding the key (its auto-repeat, timed in wall-clock
    tenths of a second) and the follow camera are tested in tests/simulation/test_teleop.py
    with a clock of its own: on a loaded machine this page (software WebGL) falls ever further
    behind the visualizer's stream of poses, so what it shows of a moving robot cannot be
    waited for."""
    import numpy as np

    from corobot_drake.config.scenario import BOOK_SUN_DIRECTION
    from corobot_drake.station import MESHCAT_DIRECTIONAL_INTENSITY

    page, console = meshcat_page
    url = meshcat_server.url
    # The sun: Meshcat's directional light at the scenario's direction and intensity, and no
    # property sent to a path that is no light (the browser warns "has no property").
    sun = ["Lights", "FillLight", "<object>"]
    wait_for(lambda: page.evaluate(
        "p => viewer.scene_tree.find(p).object.intensity", sun) == pytest.approx(
            MESHCAT_DIRECTIONAL_INTENSITY), 90, "the sun's intensity")
    x, y, z = page.evaluate("p => viewer.scene_tree.find(p).object.position.toArray()", sun)
    assert np.array([x, y, z]) / np.linalg.norm([x, y, z]) == pytest.approx(
        -np.array(BOOK_SUN_DIRECTION) / np.linalg.norm(BOOK_SUN_DIRECTION), abs=1e-6)
    assert not [m for m in console if "has no property" in m], console
    x0 = page.request.get(f"{url}/robots/corobot/drive").json()["position"]["x"]
    page.keyboard.press("ArrowUp")

    def command():
        return (page.request.get(f"{url}/robots/corobot/drive").json()["command"] or {}).get(
            "command")

    wait_for(lambda: command() == "SetPower", 30, "the key to drive")
    wait_for(lambda: command() == "AllStop", 30, "the move to end without a key release")

    def drive():
        return page.request.get(f"{url}/robots/corobot/drive").json()

    wait_for(lambda: abs(drive()["velocity"]["forward"]) < 0.005, 30, "the robot to stop")
    # It drove forward: HOLD_FIRST (0.7 s of wall clock) at power 0.5 is ~0.2 m at real time;
    # how far a loaded host's simulation gets in that wall time is not this test's to assert.
    assert drive()["position"]["x"] - x0 > 0.01


def offline(page, server_url: str) -> list[tuple[str, str]]:
    """Aborts every request the page makes to anywhere but the server (no network: a CDN
    asset would fail); returns the list of what was blocked: (resource type, URL)."""
    blocked = []

    def route(r):
        if r.request.url.startswith(server_url):
            r.continue_()
        else:
            blocked.append((r.request.resource_type, r.request.url))
            r.abort()

    page.route("**/*", route)
    return blocked


def test_api_docs_render_offline(page, server):
    """/docs (Swagger UI) and /redoc (ReDoc) load their scripts from the server itself."""
    blocked = offline(page, server.url)
    page.goto(f"{server.url}/docs")
    page.wait_for_selector(".swagger-ui .info .title", timeout=30000)
    assert "corobot-drake live services" in page.locator(".swagger-ui .info .title").inner_text()
    page.wait_for_selector("#operations-drive-set_power_robots__robot__drive_set_power_post",
                           timeout=10000)
    assert page.locator(".opblock").count() >= 20  # every endpoint listed
    assert page.locator(".btn.authorize").count() == 1  # where a token goes
    page.goto(f"{server.url}/redoc")
    page.wait_for_selector("text=corobot-drake live services", timeout=30000)
    assert page.locator("[data-section-id]").count() >= 20
    # Nothing the pages need came from elsewhere: only ReDoc's "powered by" logo asks for
    # cdn.redoc.ly (an image; the page renders without it).
    assert all(kind == "image" for kind, _ in blocked), blocked
    OUT.mkdir(exist_ok=True)
    page.screenshot(path=str(OUT / "redoc.png"))


@pytest.fixture(scope="module")
def token_server(tmp_path_factory):
    log = tmp_path_factory.mktemp("token_server") / "stderr.log"
    with ServerProcess(["--headless", "--token", "browser-test-token"],
                       stderr_path=str(log)) as s:
        yield s


def test_dashboard_carries_the_token(page, token_server):
    """A server with a token: the dashboard opened with the printed URL (#token=...) gets its
    state and drives the robot; opened without it, it gets nothing."""
    url = token_server.url
    page.goto(f"{url}/dashboard#token={token_server.token}")
    page.wait_for_selector("body[data-ready='1']", timeout=30000)
    wait_for(lambda: page.locator("#pos-x").inner_text() != "-", 10, "the first state")
    x0 = number(page, "#pos-x")
    page.locator("body").click(position={"x": 5, "y": 5})
    page.keyboard.down("ArrowUp")
    wait_for(lambda: number(page, "#pos-x") > x0 + 0.05, 15, "the arrow key to drive")
    page.keyboard.up("ArrowUp")
    page.keyboard.press("Space")
    link = page.locator("#webcam-link").get_attribute("href")
    assert link.endswith(f"#token={token_server.token}") or link == "#"
    refused = page.request.get(f"{url}/robots/corobot/drive")
    assert refused.status == 401


def _replay_colour_tracks(html: str) -> dict[str, tuple[float, list]]:
    """{slip ball's path (its `<object>`): (the clip's fps, its `material.color` keys)} of a
    replay's animation."""
    import base64
    import re

    import msgpack

    for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        message = msgpack.unpackb(base64.b64decode(blob), strict_map_key=False)
        if message.get("type") == "set_animation":
            return {a["path"]: (a["clip"]["fps"], track["keys"])
                    for a in message["animations"] if a["path"].startswith("/slip/")
                    for track in a["clip"]["tracks"] if track["name"] == ".material.color"}
    raise AssertionError("the replay has no animation")


def test_a_replay_opens_without_console_errors_and_replays_the_slip_colours(page, tmp_path):
    """`--record`'s replay, opened: nothing on the console but the software renderer's own
    performance notes (it logged a three.js error for each slip ball, whose colour track named
    a property the scene node lacks, and two warnings about the sky's colours), and each ball
    takes its recorded colour at its time (spinning in place: red; at rest: green)."""
    from corobot_drake.cli import main

    replay = tmp_path / "replay.html"
    spin = ("robots: {corobot: {cameras: {front: {rgb: false}}, commands: [!SetPower {left: 1, "
            "right: -1}, !Wait {seconds: 0.6}, !AllStop {}]}}")
    assert main(["--headless", "--duration", "1", "--override", spin, "--record",
                 str(replay)]) == 0
    tracks = _replay_colour_tracks(replay.read_text())
    assert len(tracks) == 4
    console = []
    page.on("console", lambda m: console.append(f"{m.type}: {m.text}"))
    page.set_viewport_size({"width": 320, "height": 240})  # software WebGL: fewer pixels
    page.goto(replay.as_uri())
    wait_for(lambda: page.evaluate("() => typeof viewer !== 'undefined' "
                                   "&& viewer.animator.duration > 0"), 60, "the replay's animation")
    for path, (fps, keys) in tracks.items():
        for key in (keys[0], keys[len(keys) // 2], keys[-1]):
            colour = page.evaluate(
                "([path, t]) => { viewer.animator.seek(t); return viewer.scene_tree.find("
                "path.split('/').filter(p => p)).object.material.color.toArray(); }",
                [path, key["time"] / fps])
            assert colour == pytest.approx(key["value"], abs=1e-6), (path, key)
    reds = [keys[len(keys) // 2]["value"] for _, keys in tracks.values()]
    assert all(r > 0.9 and g < 0.5 for r, g, _ in reds), reds  # mid-spin: sliding
    page.wait_for_timeout(2000)  # the messages of the frames rendered meanwhile
    assert [m for m in console if m.startswith(("error", "warning"))
            and "GL Driver Message" not in m] == []
