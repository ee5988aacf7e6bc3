"""The run as a Meshcat replay: Drake's Meshcat recording written as static HTML.

Drake's visualizers (`MeshcatVisualizer`, `ContactVisualizer`, the inertia layer) stamp each
transform and property they send with the simulation time; while a Meshcat is recording
(`Meshcat.StartRecording`) it keeps them as frames of a `MeshcatAnimation` at
`RECORDING_FPS`. `write_recording` publishes that animation to the Meshcat scene and writes
`Meshcat.StaticHtml()`: the scene, its meshes and textures, Meshcat's JavaScript and the
animation in one file that a browser opens offline, with the Animations panel's play/pause
and time slider. Objects drawn without a time stamp (the sensors' markers) are not animated:
the file shows them as they were at the end.

The recording lives in the Meshcat object, beside the Context, like a file being written:
`Simulation.reset` starts it again.
"""

from pathlib import Path

from pydrake.geometry import Meshcat, MeshcatParams

from corobot_drake.station import visualization_config

RECORDING_FPS = 1.0 / visualization_config().publish_period
"""Animation frames per second: Drake's visualizer publish rate (64 Hz). On a continuous
plant they publish every 0.02 s (`station.meshcat_publish_period`): each publish still has a
frame of its own (a frame is floor(t x 64)), and a frame keeps its publish's time to 1/64 s
(50 Hz frames would put two publishes in one frame: floor(0.06 x 50) is 2)."""


def offline_meshcat() -> Meshcat:
    """A Meshcat for a run without a browser (`--headless --record`): it listens on the
    loopback interface only (Meshcat always serves; nobody needs to connect)."""
    return Meshcat(MeshcatParams(host="localhost", show_stats_plot=False))


def start_recording(meshcat: Meshcat, live: bool) -> None:
    """Starts the recording afresh (earlier frames are dropped). `live`: also send each frame
    to the browser as it is made (False when nobody watches: recording only)."""
    meshcat.StartRecording(frames_per_second=RECORDING_FPS,
                           set_visualizations_while_recording=live)


def write_recording(meshcat: Meshcat, path: str | Path) -> int:
    """Publishes the recording so far as the scene's animation (a browser watching gets it
    too) and writes the scene as a self-contained HTML file at `path`; returns its size in
    bytes. The animation plays once (Meshcat's Animations panel replays it and scrubs through
    it). The recording goes on (Drake's StartRecording would start a new one)."""
    meshcat.PublishRecording()
    html = meshcat.StaticHtml()
    Path(path).write_text(html, encoding="utf-8")
    return len(html.encode("utf-8"))
