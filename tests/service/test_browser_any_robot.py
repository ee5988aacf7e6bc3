"""The dashboard in headless Chromium for robots other than the Corobot (the Burger and the
Pioneer side by side): a contact row per wheel of the robot shown, its encoders and powers by
side, the pad drives it, and no camera panel for a robot without a camera."""

import pytest
from test_browser import dashboard_page, number, wait_for

from corobot_drake.serving.serve import ServerProcess

SCENARIO = """
robots:
  burger: {robot: burger}
  pioneer: {robot: pioneer, pose: {translation: [0, -1.5, 0]}}
"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("robots")
    (tmp / "two.yaml").write_text(SCENARIO)
    with ServerProcess([str(tmp / "two.yaml"), "--headless"],
                       stderr_path=str(tmp / "stderr.log")) as s:
        yield s


@pytest.fixture(scope="module")
def page(server):
    with dashboard_page(server.url) as page:
        yield page


def _rows(page) -> list[str]:
    return page.eval_on_selector_all("#contact tr th:first-child",
                                     "cells => cells.slice(1).map(c => c.textContent)")


def test_the_burgers_wheels_and_no_camera(page):
    assert page.locator("#robot").input_value() == "burger"
    wait_for(lambda: _rows(page) == ["L", "R"], 10, "a row per wheel")
    # At rest the two tyres carry what the caster does not: some of its 1 kg, each alike.
    wait_for(lambda: number(page, "#load-l") > 2.0, 10, "the wheel loads")
    assert number(page, "#load-l") == pytest.approx(number(page, "#load-r"), rel=0.05)
    assert page.locator("#camera-panel").is_hidden()
    assert page.locator("#webcam-link").is_hidden()
    page.keyboard.down("ArrowUp")  # the keys drive it: its left encoder counts
    wait_for(lambda: number(page, "#enc-fl") > 500, 15, "the left encoder to count")
    page.keyboard.up("ArrowUp")


def test_the_pioneers_four_wheels(page):
    page.locator("#robot").select_option("pioneer")
    wait_for(lambda: _rows(page) == ["FL", "RL", "FR", "RR"], 10, "a row per wheel")
    wait_for(lambda: number(page, "#load-rr") > 10.0, 10, "the wheel loads")
    assert page.locator("#camera-panel").is_hidden()


def _ir_gauges(page) -> list[str]:
    return page.eval_on_selector_all("#ir-gauges .gauge", "gauges => gauges.map(g => g.id)")


def test_the_ir_panel_follows_the_robot_shown(page):
    """The Pioneer's sonars are IR-kind sensors, the Burger has none: switching back and forth
    shows each robot's own gauges, never the previous robot's."""
    page.locator("#robot").select_option("pioneer")
    wait_for(lambda: len(_ir_gauges(page)) == 8, 10, "a gauge per sonar")
    assert page.locator("#ir-none").count() == 0
    page.locator("#robot").select_option("burger")
    wait_for(lambda: _ir_gauges(page) == [], 10, "the Pioneer's gauges to go")
    assert page.locator("#ir-none").is_visible()
    page.wait_for_timeout(500)  # a reading still on its way from the Pioneer's stream adds none
    assert _ir_gauges(page) == [] and page.locator("#ir-none").is_visible()
    page.locator("#robot").select_option("pioneer")
    wait_for(lambda: len(_ir_gauges(page)) == 8, 10, "the Pioneer's gauges again")
    assert page.locator("#ir-none").count() == 0
