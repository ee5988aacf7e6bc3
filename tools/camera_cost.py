"""Camera frame cost, visual meshes vs collision boxes (run: python tools/camera_cost.py).

The robot drives a circle beside the giant box; between frames the simulation advances one
camera period (1/30 s) and only the render call is timed: one 320x240 colour frame (the Corobot's
camera) rendered by VTK with the camera's lighting (sun + fill, no shadows). Views: the
robot's own camera (`robot-camera`) and a 320x240 chase camera that looks at the robot
(`chase`). The two visuals are rendered alternately, frame by frame, so load from other
processes slows both alike; the median of each is reported
(`lab.camera_cost`).
"""

import argparse

from lab.camera_cost import VIEWS, meshes_vs_boxes_ms


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--frames", type=int, default=300, help="frames of each, alternated")
    args = parser.parse_args()
    print("| view (320x240) | boxes, ms/frame | meshes, ms/frame | meshes / boxes |")
    print("|---|---|---|---|")
    for view in VIEWS:
        ms = meshes_vs_boxes_ms(view, args.frames)
        print(f"| {view} | {ms['boxes']:.2f} | {ms['meshes']:.2f} | "
              f"{ms['meshes'] / ms['boxes']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
