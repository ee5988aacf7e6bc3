"""Where a robot's sensors are added: what every kind's `add` (`registry.py`) is given.

No module of a kind imports `config.scenario` when it is imported: the scenario's `Robot` is
made from the registered kinds (`scenario.with_sensor_maps`).
"""

from __future__ import annotations

import dataclasses as dc
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from corobot_drake.config import scenario as sc


def _default_world() -> sc.World:
    from corobot_drake.config import scenario as sc

    return sc.World()


@dc.dataclass
class SensorSite:
    """One robot in a diagram being built: the builder, the finalized plant and its scene
    graph, the robot's name and model instance (its own links carry its sensors, and its own
    geometry is not seen by them), and what a sensor of any kind may need of the scenario."""

    builder: object
    plant: object
    scene_graph: object
    robot: str
    model_instance: object
    world: sc.World = dc.field(default_factory=_default_world)
    """The sun and sky the cameras are lit by."""
    random_seed: int = 0
    """The scenario's, mixed into each noisy sensor's own key."""
    step: float | None = None
    """s: the physics' step (`scenario.physics_step`; None: the plant's time step)."""
    save_dir: Path | None = None
    """Where the cameras' frames are written as PNG (None: nowhere)."""
    renderers: dict = dc.field(default_factory=dict)
    """The render engines made so far: renderer name -> "RenderEngineGl" or
    "RenderEngineVtk" (cameras with one renderer name share its engine)."""
    renderer_classes: dict = dc.field(default_factory=dict)
    """Renderer name -> the `CameraConfig.renderer_class` its engine was made from (the
    first camera's of that name): what a render worker's copy makes its engine from."""
    add_scene_copy: Callable | None = None
    """`add_scene_copy(builder)` adds a copy of the diagram's scene to another builder
    (returns its plant, scene graph and this robot's model instance): what a camera's render
    worker renders from (`sensors.render_worker`); None: cameras render in place."""
    render_workers: list = dc.field(default_factory=list)
    """The cameras' render workers made so far (the station closes them)."""

    @property
    def physics_step(self) -> float:
        return self.plant.time_step() if self.step is None else self.step

    @property
    def continuous_step(self) -> float:
        """s: a continuous plant's step, on which its sensors sample; 0 on a discrete one
        (`scenario.continuous_step`)."""
        return self.physics_step if self.plant.time_step() == 0 else 0.0
