"""docs/gallery.md's blocks: a picture of every shipped robot and scenario (`tools/snapshot.py`)
and the shipped robots' figures (`tools/robot_figures.py`).

    python tools/refresh_docs.py --only 'gallery-*'     # every picture of the gallery
"""

from __future__ import annotations

from lab.refresh import renders as r
from lab.refresh.runner import DETERMINISTIC, PICTURE, TIMING, Command, Spec
from lab.refresh.text import picture

GALLERY = "docs/gallery.md"
SIZE = "--width 800 --height 500"
PICTURES = (
    # (block name, alt text, PNG under docs/images, snapshot.py's arguments)
    ("gallery-corobot", "The Corobot", "gallery_corobot.png",
     "--eye 0.75,-0.65,0.45 --target=0,0,0.1"),
    ("gallery-burger", "The Burger", "gallery_burger.png",
     "--scenario scenarios/burger.yaml --eye=-0.02,-0.62,0.3 --target=-0.4,-0.4,0.09"),
    ("gallery-pioneer", "The Pioneer", "gallery_pioneer.png",
     "--scenario scenarios/pioneer.yaml --eye 1.2,-1.3,0.9 --target=0,0,0.15"),
    ("gallery-scenario-corobot", "scenarios/corobot.yaml", "gallery_scenario_corobot.png",
     "--scenario scenarios/corobot.yaml --eye 1.5,-1.6,1.0 --target=-0.7,0,0.4"),
    ("gallery-scenario-corobot-lidar", "scenarios/corobot_lidar.yaml",
     "gallery_scenario_corobot_lidar.png",
     "--scenario scenarios/corobot_lidar.yaml --eye 2.2,-4.2,3.4 --target=0,0,0"),
    ("gallery-scenario-camera-view", "scenarios/camera_view.yaml",
     "gallery_scenario_camera_view.png",
     "--scenario scenarios/camera_view.yaml --eye=-0.6,-0.7,0.75 --target=1.4,0.2,0.1"),
    ("gallery-scenario-drive-square", "scenarios/drive_square.yaml",
     "gallery_scenario_drive_square.png",
     "--scenario scenarios/drive_square.yaml --time 9 --eye 2.5,-1.2,1.8 --target=0.5,0.5,0"),
    ("gallery-scenario-maze", "scenarios/maze.yaml", "gallery_scenario_maze.png",
     "--scenario scenarios/maze.yaml --eye 0.5,-3.4,3.6 --target=0.5,0,0"),
    ("gallery-scenario-two-robots", "scenarios/two_robots.yaml",
     "gallery_scenario_two_robots.png",
     "--scenario scenarios/two_robots.yaml --robot corobot --eye 1.2,-2.4,1.6 "
     "--target=1.2,0,0"),
    ("gallery-scenario-burger", "scenarios/burger.yaml", "gallery_scenario_burger.png",
     "--scenario scenarios/burger.yaml --eye 1.3,-3.2,2.6 --target=0,0,0"),
    ("gallery-scenario-pioneer", "scenarios/pioneer.yaml", "gallery_scenario_pioneer.png",
     "--scenario scenarios/pioneer.yaml --eye 0.2,-3.8,2.4 --target=1.3,0,0.3"),
    ("gallery-scenario-robo-magellan", "scenarios/robo_magellan.yaml",
     "gallery_scenario_robo_magellan.png",
     "--scenario scenarios/robo_magellan.yaml --eye=-1.6,-1.2,1.3 --target=2.5,0,0.1"),
    ("gallery-scenario-three-robots", "scenarios/three_robots.yaml",
     "gallery_scenario_three_robots.png",
     "--scenario scenarios/three_robots.yaml --robot corobot --eye=-0.9,-2.4,1.2 "
     "--target=0.8,0,0.1"),
)


def gallery_specs() -> list[Spec]:
    """The gallery's pictures, then the robots' figures and their real-time factors."""
    specs = []
    for name, alt, png, arguments in PICTURES:
        command = (f"python tools/snapshot.py {arguments} {SIZE} "
                   f"--output docs/images/{png}")
        specs.append(Spec(name, GALLERY, (Command(command),),
                          picture(alt, f"images/{png}", command), PICTURE, 5))
    specs += [
        Spec("robot-figures", GALLERY, (Command("python tools/robot_figures.py"),),
             r.render_command_table, DETERMINISTIC, 60),
        Spec("robot-realtime", "docs/performance.md",
             (Command("python tools/robot_figures.py --realtime"),),
             r.render_table_with_load, TIMING, 20),
    ]
    return specs
