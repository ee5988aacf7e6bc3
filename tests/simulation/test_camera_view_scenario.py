"""scenarios/camera_view.yaml: the camera sees something from its first frame. The first three
frames are each more than a tenth things (neither the scenario's sky nor the ground right in
front of the robot), among them the blue box and the yellow pillar the scenario places
ahead."""

import numpy as np
import pytest

from conftest import REPO
from corobot_drake.config.scenario import load_scenario
from corobot_drake.simulation import Simulation

SCENARIO = REPO / "scenarios" / "camera_view.yaml"
NEAR = 30
"""Colour distance (sum over RGB, 0-255 each) within which a pixel is the sky's or the
ground's: the sky is drawn flat in its colour, the lit ground within a few units of its own."""


def shares(image: np.ndarray, sky_color) -> dict[str, float]:
    """Shares of the image: sky (the scenario's colour), ground (the bottom middle pixel's
    colour: the ground just ahead), things (the rest), and the box's blue and the pillar's
    yellow among the things."""
    rgb = image[..., :3].astype(int)
    sky = np.abs(rgb - np.round(255 * np.asarray(sky_color[:3]))).sum(-1) < NEAR
    ground = np.abs(rgb - rgb[-1, rgb.shape[1] // 2]).sum(-1) < NEAR
    things = ~sky & ~ground
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return {"things": things.mean(),
            "blue": (things & (b > 2 * r) & (b > 1.5 * g)).mean(),
            "yellow": (things & (r > 2 * b) & (g > 2 * b)).mean()}


@pytest.fixture(scope="module")
def frames():
    scenario = load_scenario(SCENARIO)
    sim = Simulation(scenario)
    robot, out = sim.robot(), []
    while len(out) < 3:
        sim.advance(0.01)
        image, when = robot.camera_image(), robot.camera_image_time()
        if image is not None and (not out or when > out[-1][0]):
            out.append((when, image))
    return scenario.world.sky_color, out


def test_the_first_frames_show_the_box_and_the_pillar(frames):
    sky_color, taken = frames
    assert taken[0][0] < 0.1  # s: the first frame, not one after a wait
    for when, image in taken:
        seen = shares(image, sky_color)
        assert seen["things"] > 0.1, (when, seen)
        assert seen["blue"] > 0.05, (when, seen)
        assert seen["yellow"] > 0.01, (when, seen)


def test_the_default_scene_shows_the_camera_only_sky_and_ground():
    """The check's own control: the default scene's robot faces open ground (the giant box
    behind it), so its first frame is sky and ground alone."""
    scenario = load_scenario(REPO / "scenarios" / "corobot.yaml")
    sim = Simulation(scenario)
    sim.advance(0.1)
    seen = shares(sim.robot().camera_image(), scenario.world.sky_color)
    assert seen["things"] < 0.01, seen
