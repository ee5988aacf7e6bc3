"""The live server is safe by default: loopback unless --host says
otherwise, a bearer token off loopback, the Host header checked (DNS rebinding), JSON bodies
for every state-changing request (no cross-site form or empty POST drives the robot), 503 for
a request whose simulation stopped, and /docs and /redoc served offline.

The in-process tests run the app on a real simulation (`SimRunner`) through FastAPI's
TestClient; one test runs the real server on 0.0.0.0 in a child process.
"""

import re
import signal
import socket
import threading
import time

import httpx
import pytest

from conftest import make_sim
from corobot_drake.serving.security import Access, is_loopback

ROBOT = "/robots/corobot"
pytestmark = pytest.mark.filterwarnings("ignore:Using `httpx` with `starlette.testclient`")


@pytest.fixture(scope="module")
def runner():
    from corobot_drake.serving.runner import SimRunner

    runner = SimRunner(make_sim()).start()
    yield runner
    runner.stop()


def client(runner, access=None, base_url="http://127.0.0.1:50000", **kwargs):
    from fastapi.testclient import TestClient

    from corobot_drake.serving.webapp import create_app

    return TestClient(create_app(runner, access), base_url=base_url, **kwargs)


def last_seq(c, headers=None) -> int:
    """The robot's latest command's sequence number (what a refused request must not move)."""
    command = c.get(f"{ROBOT}/drive", headers=headers).json()["command"]
    return 0 if command is None else command["seq"]


# --- the rules, alone -------------------------------------------------------------------------


def test_loopback_needs_no_token_and_any_other_address_gets_one():
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("[::1]")
    assert is_loopback("127.0.0.5") and not is_loopback("0.0.0.0")
    assert not is_loopback("192.168.1.5") and not is_loopback("example.com")
    assert Access.for_host("127.0.0.1").token is None
    generated = Access.for_host("0.0.0.0").token
    assert generated and len(generated) >= 32  # 24 random bytes, URL-safe base64
    assert generated != Access.for_host("0.0.0.0").token
    assert Access.for_host("192.168.1.5", "s3cret").token == "s3cret"
    assert Access.for_host("127.0.0.1", "s3cret").token == "s3cret"  # asked for: enforced
    with pytest.raises(ValueError, match="--token must not be empty"):
        Access.for_host("0.0.0.0", "  ")


def test_host_names_the_server_answers_to():
    loopback = Access.for_host("127.0.0.1")
    for name in ("127.0.0.1", "localhost", "::1"):
        assert loopback.host_allowed(name), name
    for name in ("attacker.example", "192.168.1.5", "127.0.0.1.nip.io", ""):
        assert not loopback.host_allowed(name), name
    lan = Access.for_host("192.168.1.5")
    assert lan.host_allowed("192.168.1.5") and not lan.host_allowed("localhost")
    everywhere = Access.for_host("0.0.0.0")
    # Any address literal (DNS cannot re-point one) or the machine's names, but no domain.
    assert everywhere.host_allowed("10.1.2.3") and everywhere.host_allowed("::1")
    assert not everywhere.host_allowed("attacker.example")


# --- through the app --------------------------------------------------------------------------


def test_a_foreign_host_header_is_refused_before_anything_runs(runner):
    """DNS rebinding: the attacker's page, re-pointed at 127.0.0.1, sends its own domain."""
    with client(runner) as c:
        seq = last_seq(c)
        for host in ("attacker.example", "attacker.example:50000", "127.0.0.1.nip.io"):
            r = c.post(f"{ROBOT}/drive/set_power", json={"left": 1, "right": 1},
                       headers={"Host": host})
            assert r.status_code == 421, (host, r.text)
            assert "does not answer to host" in r.json()["detail"]
            assert c.get(f"{ROBOT}/drive", headers={"Host": host}).status_code == 421
        assert c.get(f"{ROBOT}/drive", headers={"Host": "localhost:50000"}).status_code == 200
        assert last_seq(c) == seq  # nothing reached the robot


def test_a_token_is_required_on_the_api_but_not_on_the_page_shells(runner):
    access = Access("192.168.1.5", "s3cret-token")
    good = {"Authorization": "Bearer s3cret-token"}
    with client(runner, access, base_url="http://192.168.1.5:50000") as c:
        seq = last_seq(c, good)
        for path in (f"{ROBOT}/drive", "/robots", "/services", "/simulation", f"{ROBOT}/gps",
                     f"{ROBOT}/camera/frame.png", f"{ROBOT}/subscribe"):
            r = c.get(path)
            assert r.status_code == 401, (path, r.status_code)
            assert r.headers["www-authenticate"] == "Bearer"
            assert "Authorization: Bearer" in r.json()["detail"]
        for headers in ({"Authorization": "Bearer wrong"}, {"Authorization": "s3cret-token"},
                        {"Authorization": "Basic s3cret-token"}):
            assert c.get(f"{ROBOT}/drive", headers=headers).status_code == 401
            assert c.post(f"{ROBOT}/drive/all_stop", json={},
                          headers=headers).status_code == 401
        assert last_seq(c, good) == seq
        assert c.get(f"{ROBOT}/drive", headers=good).status_code == 200
        r = c.post(f"{ROBOT}/drive/all_stop", json={}, headers=good)
        assert r.status_code == 200 and r.json()["seq"] == seq + 1
        for path in ("/dashboard", "/static/dashboard.js", "/static/token.js", "/docs",
                     "/redoc", "/openapi.json"):
            assert c.get(path).status_code == 200, path
        # The webcam page's shell is public too (this robot has no camera: 501, not 401).
        assert c.get(f"{ROBOT}/camera/page").status_code == 501
        assert c.get(f"{ROBOT}/cameras/rear/page").status_code == 404  # any camera's: no rear
        doc = c.get("/openapi.json").json()
        assert doc["components"]["securitySchemes"]["bearer"]["scheme"] == "bearer"


def test_state_changing_requests_need_a_json_body(runner):
    """What a cross-site form can send (urlencoded, multipart, text/plain) or an empty POST
    never reaches the robot; JSON does."""
    with client(runner) as c:
        seq = last_seq(c)
        refused = [
            dict(),  # an empty POST, no Content-Type
            dict(data={"left": "1", "right": "1"}),  # an HTML form
            dict(files={"left": ("x", b"1")}),  # a multipart form
            dict(content=b'{"left": 1, "right": 1}', headers={"Content-Type": "text/plain"}),
        ]
        for kwargs in refused:
            for command in ("all_stop", "set_power"):
                r = c.post(f"{ROBOT}/drive/{command}", **kwargs)
                assert r.status_code == 415, (command, kwargs, r.text)
                assert "needs a JSON body" in r.json()["detail"]
        # JSON with no body at all is still not a command.
        r = c.post(f"{ROBOT}/drive/all_stop", headers={"Content-Type": "application/json"})
        assert r.status_code == 422 and "required" in r.json()["detail"]
        assert last_seq(c) == seq
        r = c.post(f"{ROBOT}/drive/all_stop", json={})
        assert r.status_code == 200 and r.json()["seq"] == seq + 1
        assert c.post(f"{ROBOT}/drive/set_power", json={"left": 0, "right": 0},
                      headers={"Content-Type": "application/json; charset=utf-8"}).is_success


def test_docs_and_redoc_are_served_offline(runner):
    """Their pages load Swagger UI and ReDoc from this server, not from a CDN (the browser
    test renders /docs)."""
    with client(runner) as c:
        for page in ("/docs", "/redoc"):
            html = c.get(page).text
            assets = re.findall(r'(?:src|href)="([^"]+)"', html)
            assert assets, page
            for url in assets:
                assert not url.startswith(("http:", "https:", "//")), (page, url)
                if url.startswith("/"):
                    r = c.get(url)
                    assert r.status_code == 200 and len(r.content) > 1000, (page, url)


def test_a_request_waiting_on_a_command_gets_503_when_the_simulation_stops():
    from corobot_drake.serving.runner import SimRunner

    runner = SimRunner(make_sim()).start()
    try:
        with client(runner) as c:
            threading.Timer(1.0, runner.stop).start()
            r = c.post(f"{ROBOT}/drive/drive_distance", json={"distance": 2.0, "power": 0.2})
            assert r.status_code == 503, r.text
            assert r.json()["detail"] == "the simulation stopped"
            r = c.post(f"{ROBOT}/drive/set_power", json={"left": 0.2, "right": 0.2})
            assert r.status_code == 503 and "not running" in r.json()["detail"]
    finally:
        runner.stop()


# --- the real server --------------------------------------------------------------------------


def test_serving_on_every_address_prints_a_token_and_enforces_it(tmp_path):
    """`--host 0.0.0.0` without --token: a token is generated and printed with the dashboard
    URL; the API refuses requests without it; the client takes the printed URL; Ctrl-C while a
    request waits on a command answers it 503."""
    from corobot_drake.serving.client import CorobotClient, CorobotError
    from corobot_drake.serving.serve import ServerProcess

    stderr = tmp_path / "stderr.log"
    with ServerProcess(["--headless", "--host", "0.0.0.0"], stderr_path=str(stderr)) as s:
        token = s.printed_token()
        assert token and len(token) >= 32
        dashboard = next(line.split()[1] for line in s.lines if line.startswith("  dashboard"))
        assert dashboard.endswith(f"/dashboard#token={token}")
        # Printed URLs are reachable ones (no client connects to 0.0.0.0): loopback, and
        # this machine's name for the others, each answered.
        port = s.url.rpartition(":")[2]
        assert s.url == f"http://127.0.0.1:{port}" and dashboard.startswith(s.url)
        other = next(line.split()[3] for line in s.lines
                     if line.startswith("  from other machines "))
        assert other == f"http://{socket.gethostname()}:{port}/dashboard#token={token}"
        assert httpx.get(f"{s.url}{ROBOT}/drive", headers={
            "Authorization": f"Bearer {token}", "Host": f"{socket.gethostname()}:{port}"}
        ).status_code == 200
        assert httpx.get(f"{s.url}{ROBOT}/drive").status_code == 401
        with CorobotClient(dashboard) as sim:  # the printed URL carries the token
            sim.robot().all_stop()
            assert sim.robot().pose().z < 0.01
        with pytest.raises(CorobotError, match="401"):
            CorobotClient(s.url)
        good = {"Authorization": f"Bearer {token}"}
        r = httpx.get(f"{s.url}{ROBOT}/drive", headers={**good, "Host": "attacker.example"})
        assert r.status_code == 421
        answers = []

        def wait_on_a_command():
            answers.append(httpx.post(f"{s.url}{ROBOT}/drive/drive_distance", headers=good,
                                      json={"distance": 3.0, "power": 0.2}, timeout=60))

        waiter = threading.Thread(target=wait_on_a_command)
        waiter.start()
        deadline = time.monotonic() + 30
        while (httpx.get(f"{s.url}{ROBOT}/drive", headers=good).json()["command"] or {}).get(
                "command") != "DriveDistance":
            assert time.monotonic() < deadline, "the command did not start"
            time.sleep(0.1)
        s.process.send_signal(signal.SIGINT)
        waiter.join(30)
        assert s.process.wait(30) == 0
    assert answers and answers[0].status_code == 503, answers
    assert answers[0].json()["detail"] == "the simulation stopped"
    assert "warning: serving on 0.0.0.0" in stderr.read_text()


def test_the_foxglove_server_on_every_address_prints_a_reachable_url():
    """`--foxglove` on 0.0.0.0 prints a loopback URL (no client connects to 0.0.0.0)."""
    pytest.importorskip("foxglove")
    from corobot_drake.recording.foxglove_live import FoxgloveLive

    with FoxgloveLive(port=0, host="0.0.0.0") as live:
        assert live.url == f"ws://127.0.0.1:{live.port}/?token={live.token}"
    from corobot_drake.serving.security import reachable_host

    assert [reachable_host(h) for h in ("0.0.0.0", "::", "[::]", "::1", "10.0.0.5", "box")] == [
        "127.0.0.1", "[::1]", "[::1]", "[::1]", "10.0.0.5", "box"]
