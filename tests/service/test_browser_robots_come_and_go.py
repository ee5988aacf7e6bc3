"""The dashboard in headless Chromium while a robot comes and goes (ROS 2's SpawnEntity and
DeleteEntity rebuild the simulation through `SimRunner.replace`; here the test calls it): its
robot list follows the server's without a reload, and a robot shown that is deleted gives way
to the first one. The server is --serve's two halves in this process: the runner and its end
of the pipe here, the HTTP side (`serve.http_main`) in a thread."""

import multiprocessing
import threading

import pytest
from test_browser import dashboard_page, wait_for
from test_robots_come_and_go import _replace, _with_burger, _without_burger

from conftest import make_sim
from corobot_drake.serving.runner import SimRunner
from corobot_drake.serving.security import Access
from corobot_drake.serving.serve import http_main
from corobot_drake.serving.transport import SimSide

POLL = 2.0
"""s between the dashboard's polls of /simulation, which carry the robot list."""


@pytest.fixture
def served():
    """(the runner, paused: nothing moves; the server's URL)."""
    sim_end, http_end = multiprocessing.Pipe()
    http = threading.Thread(target=http_main, args=(
        http_end, Access.for_host("127.0.0.1", None), 0, "warning", 0), daemon=True)
    http.start()
    assert sim_end.poll(60)
    kind, port = sim_end.recv()
    assert kind == "listening", port
    runner = SimRunner(make_sim(), paused=True).start()
    side = SimSide(runner, sim_end)
    try:
        yield runner, f"http://127.0.0.1:{port}"
    finally:
        runner.stop()
        side.close()  # the HTTP side sees the pipe close and stops serving
        http.join(30)
    assert not http.is_alive() and runner.error is None


def _options(page) -> list[str]:
    return page.eval_on_selector_all("#robot option", "options => options.map(o => o.value)")


def test_the_dashboards_robot_list_follows_the_server(served):
    runner, url = served
    with dashboard_page(url) as page:
        assert _options(page) == ["corobot"]
        _replace(runner, _with_burger)
        wait_for(lambda: _options(page) == ["corobot", "burger"], 3 * POLL + 5,
                 "the Burger in the robot list")
        assert page.locator("#robot").input_value() == "corobot"  # the robot shown stays
        page.locator("#robot").select_option("burger")
        wait_for(lambda: page.evaluate("window.dashboard.robot") == "burger"
                 and page.locator("#camera-panel").is_hidden(), 10, "the Burger shown")
        _replace(runner, _without_burger)
        wait_for(lambda: _options(page) == ["corobot"], 3 * POLL + 5,
                 "the Burger gone from the robot list")
        wait_for(lambda: page.evaluate("window.dashboard.robot") == "corobot"
                 and page.locator("#robot").input_value() == "corobot", 10,
                 "the Corobot shown in the Burger's place")
